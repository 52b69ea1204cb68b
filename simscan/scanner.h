/*
 *  The simulated scanner: raster frames of a SimSample under drift, with the
 *  timing of docs/conventions.md (scan-timing.h).
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef SIMSCAN_SCANNER_H
#define SIMSCAN_SCANNER_H

#include <glib.h>
#include <libprocess/datafield.h>
#include "scan-timing.h"
#include "drift-model.h"
#include "sample.h"

G_BEGIN_DECLS

/*
 * A frame of xres x yres pixels covering [xoff, xoff + xreal] x
 * [yoff, yoff + yreal] of the sample (sample coordinates, metres).  Pixel
 * (row r, col c) is commanded to the nominal position
 *     X = (xoff + (c + 0.5) xreal/xres,  yoff + (r + 0.5) yreal/yres)
 * (sim_scan_pixel_position)
 * at t = scan_timing_pixel_time(r, c) (frame_start, line_time, direction),
 * and records the sample at X - p(t): a feature truly at X appears at X + p(t).
 */
typedef struct {
    gint xres, yres;
    gdouble xreal, yreal;      /* m */
    gdouble xoff, yoff;        /* m, top left corner in sample coordinates */
    gdouble line_time;         /* s per line, trace and retrace together */
    ScanDirection direction;
    gdouble frame_start;       /* s */
    gdouble noise_rms;         /* m, Gaussian measurement noise; 0 = none */
    gdouble tip_radius;        /* m, spherical tip; <= 0 = sharp */
    guint32 noise_seed;
} SimScanParams;

/* Defaults: the whole sample at xres x yres, the paper's 300 s per 256 lines
 * (line_time = 300/256 s, whatever yres), scanning down from t = 0, no noise,
 * sharp tip, noise_seed 1. */
void           sim_scan_params_init    (SimScanParams *params,
                                        const SimSample *sample,
                                        gint xres,
                                        gint yres);

/* ScanTiming of the frame described by params. */
void           sim_scan_params_timing  (const SimScanParams *params,
                                        ScanTiming *timing);

/* Nominal position of pixel (row, col), metres, computed exactly as the
 * scans do: xoff + (col + 0.5)*(xreal/xres), likewise for y. */
void           sim_scan_pixel_position (const SimScanParams *params,
                                        gdouble row,
                                        gdouble col,
                                        gdouble *x_m,
                                        gdouble *y_m);

/* The drift-contaminated frame, noise included.  drift may be NULL (no
 * drift); a random-walk model must have been prepared over the frame's time.
 * The field has xreal, yreal, xoffset = xoff, yoffset = yoff and SI unit "m"
 * for xy and z.  Same inputs, same bytes.  NULL (g_warning) on bad params. */
GwyDataField*  sim_scan_frame          (const SimSample *sample,
                                        const DriftModel *drift,
                                        const SimScanParams *params);

/* The same scan with no drift and no noise: the truth the frame is judged
 * against (tip dilation included). */
GwyDataField*  sim_scan_truth          (const SimSample *sample,
                                        const SimScanParams *params);

/* What the tip records when commanded to (x, y) at time t: the (tip-dilated)
 * sample height at (x, y) - p(t).  No noise.  drift may be NULL. */
gdouble        sim_probe_height        (const SimSample *sample,
                                        const DriftModel *drift,
                                        gdouble tip_radius,
                                        gdouble x_m,
                                        gdouble y_m,
                                        gdouble t_s);

/* Gaussian noise of the given RMS added to every pixel of field, seeded
 * (same seed, same bytes); for callers that build their own scans. */
void           sim_scan_add_noise      (GwyDataField *field,
                                        gdouble noise_rms,
                                        guint32 seed);

/* The paper's Figure 6 contamination: no time model, stripe s of n (the
 * stripes of docs/paper-mode.md, stripe-geometry.h) displaced by (dx_px[s],
 * dy_px[s]) pixels, i.e. a feature truly at (r, c) appears at (r + dy, c + dx).
 * Fractional displacements are sampled exactly.  Noise and tip as in params;
 * timing fields are ignored. */
GwyDataField*  sim_scan_frame_stripes  (const SimSample *sample,
                                        const SimScanParams *params,
                                        gint n,
                                        const gdouble *dx_px,
                                        const gdouble *dy_px);

G_END_DECLS

#endif
