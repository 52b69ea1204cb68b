/*
 *  Files made by the built simscan for the end-to-end tests of continuous
 *  mode: the scan timing simscan was told, the truth each compensated
 *  channel is judged against, and which seeds' local scans all measured
 *  their own particle.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_SIMSCAN_FILE_CASE_H
#define LOCALSCAN_SIMSCAN_FILE_CASE_H

#include <glib.h>
#include <libgwyddion/gwycontainer.h>
#include <libprocess/datafield.h>
#include "drift-table.h"
#include "scan-timing.h"

G_BEGIN_DECLS

#define SIMSCAN_PROGRAM TEST_BUILDDIR "/simscan/simscan"

/* simscan's drift model "none" without offset: p(t) = v t. */
typedef struct {
    const gchar *name;
    const gchar *const *args;   /* simscan options besides --seed and -o */
    gdouble velocity[2];        /* nm/s, what args say */
    gdouble line_time;          /* s, what args say */
    ScanDirection direction;    /* what args say */
} SimscanFileCase;

/* simscan's defaults; 0.3,0.15 nm/s scanning up at 1.5 s per line. */
extern const SimscanFileCase simscan_file_default;
extern const SimscanFileCase simscan_file_up;

/* Runs simscan with the case's options and seed, writing filename. */
gboolean      simscan_file_write           (const SimscanFileCase *fcase,
                                            guint32 seed,
                                            const gchar *filename,
                                            GError **error);

/* The timing simscan was told (frame start 0). */
void          simscan_file_timing          (const SimscanFileCase *fcase,
                                            GwyDataField *field,
                                            ScanTiming *timing);

/* How far the local scan of stripe s of the file's table (its dx_exact,
 * dy_exact) lies from the true p(t_image) - p(t_local), px; NAN for a
 * stripe without one. */
gdouble       simscan_file_stripe_error_px (const SimscanFileCase *fcase,
                                            const DriftTable *table,
                                            GwyDataField *field,
                                            gint s);
/* The largest of them: a few tenths when every local scan measured its
 * own particle, pixels when one measured a neighbour. */
gdouble       simscan_file_worst_stripe_px (const SimscanFileCase *fcase,
                                            const DriftTable *table,
                                            GwyDataField *field);

/* Continuous mode's reference time: the earliest t_local measured. */
gdouble       simscan_file_reference_time  (const DriftTable *table);

/* RMS difference (z unit) between channel id and the truth (channel 1)
 * shifted to the sample as it was at t_ref, over pixels 12 px or more from
 * the edges and outside the channel's mask. */
gdouble       simscan_file_truth_rms       (const SimscanFileCase *fcase,
                                            GwyContainer *data,
                                            gint id,
                                            gdouble t_ref);

/* What continuous mode gives channel 0 of data with its stored table, this
 * timing, interpolation and the image mean as fill:
 * continuous_compensate_table()'s result, or NULL when it refuses. */
GwyDataField* simscan_file_expected_continuous(GwyContainer *data,
                                               const ScanTiming *timing,
                                               GwyInterpolationType interpolation);

G_END_DECLS

#endif
