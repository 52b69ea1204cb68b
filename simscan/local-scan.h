/*
 *  The paper's local-scan procedure (its Figure 1): after the image, the
 *  tip scans short lines over one particle per stripe to find where the
 *  particle actually is now; displayed minus actual centre is the stripe's
 *  drift.  The instrument is any probe function, so the procedure runs on
 *  the simulator (sim_probe_height) or on an ideal test sample alike.  What
 *  the lines tell (chords, centres, the drift table) is the core's
 *  local-scan-analysis.h.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef SIMSCAN_LOCAL_SCAN_H
#define SIMSCAN_LOCAL_SCAN_H

#include <glib.h>
#include <libprocess/datafield.h>
#include "drift-table.h"
#include "scan-timing.h"
#include "particle-detect.h"
#include "local-scan-analysis.h"

G_BEGIN_DECLS

/* Height the instrument records with the tip commanded to (x, y), metres in
 * the image's coordinates (the data field's offsets included), at time t. */
typedef gdouble (*LocalScanProbe)(gpointer user_data,
                                  gdouble x_m,
                                  gdouble y_m,
                                  gdouble t_s);

typedef struct {
    gdouble radius;            /* expected particle radius R, m (25 nm) */
    gdouble r_max;             /* largest drift expected, m (100 nm) */
    gint points;               /* samples per line (64) */
    gdouble tip_speed;         /* m/s along a line (4 um/s) */
    gdouble line_overhead;     /* s per line: moving there, settling (0) */
    gdouble threshold_fraction;/* chord threshold, fraction of the particle's
                                  height above the substrate (0.75:
                                  clear of a sphere's vertical equator) */
    ParticleChoice choice;     /* which particle of a stripe is scanned
                                  (PARTICLE_CHOICE_CLOSEST, the paper's) */
} LocalScanParams;

/* LocalScanParticle, one particle's result: local-scan-analysis.h. */

void         local_scan_params_init   (LocalScanParams *params);

/* Length of every local-scan line, 2 (R + r_max), and its duration. */
gdouble      local_scan_line_length   (const LocalScanParams *params);
gdouble      local_scan_line_time     (const LocalScanParams *params);

/* Scans one particle displayed at (x_px, y_px) of field (whose geometry maps
 * pixels to positions), starting at t_start.  threshold is the absolute
 * chord height.  Line L0 runs along x through the displayed centre; when it
 * misses, it moves up and down alternately by 1.5 R until it hits or has
 * covered r_max + R; the chord's midpoint gives x, the perpendicular line V
 * through it gives y.  A centre found farther than r_max (plus the lines'
 * sample spacing, their resolution) from the displayed one is a neighbour,
 * not the particle: the search goes on past it (the next chord of that line,
 * nearest first, then the next line).  Returns the time the scan ended. */
gdouble      local_scan_particle      (GwyDataField *field,
                                       const LocalScanParams *params,
                                       LocalScanProbe probe,
                                       gpointer probe_data,
                                       gdouble x_px,
                                       gdouble y_px,
                                       gdouble threshold,
                                       gdouble t_start,
                                       LocalScanParticle *result);

/* The whole procedure over n stripes: choose a particle per stripe
 * (particle_choose_for_stripes_by with params->choice), scan them in stripe
 * order starting at t_start, and return the px drift table.  When the
 * particle radius spans at least 1.5 px, the displayed centre is measured
 * in the image (bicubic) by the same chords as the actual one, along the
 * row where the instrument's line cut the particle, so that a non-spherical
 * particle's chord bias cancels; otherwise it is the detected centre.  The
 * table: dx, dy rounded to whole pixels
 * (blank for a stripe without a particle or whose particle was not found),
 * extra columns dx_exact, dy_exact, t_image, t_local, x, y, lines.
 * results (may be NULL) gets n entries; a stripe without a particle has
 * lines = 0.  *t_end (may be NULL) gets the time the last scan ended. */
DriftTable*  local_scan_run           (GwyDataField *field,
                                       const ScanTiming *timing,
                                       const GArray *particles,
                                       gdouble substrate,
                                       gint n,
                                       const LocalScanParams *params,
                                       LocalScanProbe probe,
                                       gpointer probe_data,
                                       gdouble t_start,
                                       LocalScanParticle *results,
                                       gdouble *t_end);

G_END_DECLS

#endif
