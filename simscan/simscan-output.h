/*
 *  simscan's output files: the .gwy (contaminated image carrying its drift
 *  table and timing metadata, the truth), the CSV table and the JSON
 *  summary.  All are written to temporary files first and renamed only
 *  when every one succeeded, so an error leaves no output behind.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef SIMSCAN_OUTPUT_H
#define SIMSCAN_OUTPUT_H

#include <glib.h>
#include <libgwyddion/gwycontainer.h>
#include "simscan-run.h"

G_BEGIN_DECLS

/* Channel titles and metadata keys that other tools read. */
#define SIMSCAN_TITLE_IMAGE      "Simulated scan (drift)"
#define SIMSCAN_TITLE_TRUTH      "Simulated scan (drift-free truth)"
#define SIMSCAN_META_LINE_TIME   "Line time (s)"
#define SIMSCAN_META_SLOW_SCAN   "Slow scan"
#define SIMSCAN_META_FRAME_START "Frame start (s)"
/* True particle positions, px, CSV "x,y,x_shown,y_shown": where each
 * particle belongs in a compensated image and where the scan shows it.  An
 * item of the contaminated channel's metadata (like its drift table), so
 * that Gwyddion's validator accepts the file. */
#define SIMSCAN_META_PARTICLES   "Simulated particles (px)"

/* The container written to the .gwy file (new reference). */
GwyContainer*  simscan_output_container  (const SimscanScene *scene,
                                          const SimscanMeasurement *m);
/* A frame's scan timing into its metadata container, in the keys above
 * (which scan-timing-meta.h reads), numbers as the shortest exact text. */
void           simscan_output_timing_meta(GwyContainer *meta,
                                          gdouble line_time,
                                          ScanDirection direction,
                                          gdouble frame_start);
/* data as the bytes of a .gwy file (Gwyddion's native format). */
GByteArray*    simscan_output_gwy_bytes  (GwyContainer *data);
/* The particle list of a simulator file (SIMSCAN_META_PARTICLES of
 * channel 0), or NULL. */
const gchar*   simscan_output_particles  (GwyContainer *data);
gchar*         simscan_output_json       (const SimscanScene *scene,
                                          const SimscanMeasurement *m);

/* Writes every output the configuration asks for, all or nothing
 * (output-files.h). */
gboolean       simscan_output_write_all  (const SimscanScene *scene,
                                          const SimscanMeasurement *m,
                                          GError **error);

G_END_DECLS

#endif
