/*
 *  The simulated scanner: raster frames of a sample under drift.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <math.h>
#include <libgwyddion/gwysiunit.h>
#include "stripe-geometry.h"
#include "scanner.h"
#include "sim-random.h"

/* Where the scanner's error puts the tip, for each pixel of one row:
 * displacement (dx, dy) such that the pixel records the sample at X - d. */
typedef void (*RowDisplacementFunc)(gpointer user_data, gint row, gint xres,
                                    gdouble *dx, gdouble *dy);

typedef struct {
    const DriftModel *drift;
    ScanTiming timing;
} DriftDisplacement;

typedef struct {
    gint n, yres;
    gdouble pixel_w, pixel_h;
    const gdouble *dx_px, *dy_px;
} StripeDisplacement;

void
sim_scan_params_init(SimScanParams *params, const SimSample *sample,
                     gint xres, gint yres)
{
    params->xres = xres;
    params->yres = yres;
    sim_sample_get_extent(sample, &params->xreal, &params->yreal);
    params->xoff = params->yoff = 0.0;
    params->line_time = 300.0/256.0;
    params->direction = SCAN_DIRECTION_DOWN;
    params->frame_start = 0.0;
    params->noise_rms = 0.0;
    params->tip_radius = 0.0;
    params->noise_seed = 1;
}

void
sim_scan_params_timing(const SimScanParams *params, ScanTiming *timing)
{
    scan_timing_init(timing, params->xres, params->yres, params->frame_start,
                     params->line_time, params->direction);
}

void
sim_scan_pixel_position(const SimScanParams *params, gdouble row, gdouble col,
                        gdouble *x_m, gdouble *y_m)
{
    *x_m = params->xoff + (col + 0.5)*(params->xreal/params->xres);
    *y_m = params->yoff + (row + 0.5)*(params->yreal/params->yres);
}

static gboolean
scan_params_are_valid(const SimScanParams *params, gboolean need_timing)
{
    if (params->xres < 1 || params->yres < 1
        || (gdouble)params->xres*params->yres > 1e9) {
        g_warning("simscan: scan size %dx%d is out of range",
                  params->xres, params->yres);
        return FALSE;
    }
    if (!(params->xreal > 0.0 && params->yreal > 0.0)
        || !isfinite(params->xreal) || !isfinite(params->yreal)
        || !isfinite(params->xoff) || !isfinite(params->yoff)) {
        g_warning("simscan: scan area must be finite and positive");
        return FALSE;
    }
    if (!(params->noise_rms >= 0.0) || !isfinite(params->noise_rms)
        || !isfinite(params->tip_radius)) {
        g_warning("simscan: noise and tip radius must be finite");
        return FALSE;
    }
    if (need_timing
        && (!(params->line_time > 0.0) || !isfinite(params->line_time)
            || !isfinite(params->frame_start)
            || (params->direction != SCAN_DIRECTION_DOWN
                && params->direction != SCAN_DIRECTION_UP))) {
        g_warning("simscan: line time must be positive and the direction "
                  "down or up");
        return FALSE;
    }
    return TRUE;
}

static void
drift_row_displacement(gpointer user_data, gint row, gint xres,
                       gdouble *dx, gdouble *dy)
{
    const DriftDisplacement *dd = (const DriftDisplacement*)user_data;
    gint c;

    for (c = 0; c < xres; c++) {
        if (dd->drift)
            drift_model_eval(dd->drift,
                             scan_timing_pixel_time(&dd->timing, row, c),
                             dx + c, dy + c);
        else
            dx[c] = dy[c] = 0.0;
    }
}

static void
stripe_row_displacement(gpointer user_data, gint row, gint xres,
                        gdouble *dx, gdouble *dy)
{
    const StripeDisplacement *sd = (const StripeDisplacement*)user_data;
    gint s = stripe_of_row(row, sd->n, sd->yres), c;

    for (c = 0; c < xres; c++) {
        dx[c] = sd->dx_px[s]*sd->pixel_w;
        dy[c] = sd->dy_px[s]*sd->pixel_h;
    }
}

static GwyDataField*
scan_field_new(const SimScanParams *params)
{
    GwyDataField *field = gwy_data_field_new(params->xres, params->yres,
                                             params->xreal, params->yreal,
                                             FALSE);

    gwy_data_field_set_xoffset(field, params->xoff);
    gwy_data_field_set_yoffset(field, params->yoff);
    gwy_si_unit_set_from_string(gwy_data_field_get_si_unit_xy(field), "m");
    gwy_si_unit_set_from_string(gwy_data_field_get_si_unit_z(field), "m");
    return field;
}

/* Pixel (r, c) records the sample at its nominal position minus the row's
 * displacement; a whole row goes to the sample at once. */
static GwyDataField*
scan_with_displacement(const SimSample *sample, const SimScanParams *params,
                       RowDisplacementFunc displacement, gpointer user_data,
                       gdouble noise_rms)
{
    GwyDataField *field = scan_field_new(params);
    gint xres = params->xres, r, c;
    gdouble x, y;
    gdouble *data = gwy_data_field_get_data(field);
    gdouble *dx = g_new(gdouble, 4*xres), *dy = dx + xres;
    gdouble *xs = dy + xres, *ys = xs + xres;

    for (r = 0; r < params->yres; r++) {
        displacement(user_data, r, xres, dx, dy);
        for (c = 0; c < xres; c++) {
            sim_scan_pixel_position(params, r, c, &x, &y);
            xs[c] = x - dx[c];
            ys[c] = y - dy[c];
        }
        sim_sample_heights_tip(sample, params->tip_radius, xres, xs, ys,
                               data + (gsize)r*xres);
    }
    g_free(dx);
    gwy_data_field_invalidate(field);
    if (noise_rms > 0.0)
        sim_scan_add_noise(field, noise_rms, params->noise_seed);
    return field;
}

GwyDataField*
sim_scan_frame(const SimSample *sample, const DriftModel *drift,
               const SimScanParams *params)
{
    DriftDisplacement dd;

    g_return_val_if_fail(sample && params, NULL);
    if (!scan_params_are_valid(params, TRUE))
        return NULL;
    dd.drift = drift;
    sim_scan_params_timing(params, &dd.timing);
    return scan_with_displacement(sample, params, drift_row_displacement, &dd,
                                  params->noise_rms);
}

GwyDataField*
sim_scan_truth(const SimSample *sample, const SimScanParams *params)
{
    DriftDisplacement dd;

    g_return_val_if_fail(sample && params, NULL);
    if (!scan_params_are_valid(params, FALSE))
        return NULL;
    dd.drift = NULL;
    return scan_with_displacement(sample, params, drift_row_displacement, &dd,
                                  0.0);
}

GwyDataField*
sim_scan_frame_stripes(const SimSample *sample, const SimScanParams *params,
                       gint n, const gdouble *dx_px, const gdouble *dy_px)
{
    StripeDisplacement sd;
    gint s;

    g_return_val_if_fail(sample && params && dx_px && dy_px, NULL);
    if (!scan_params_are_valid(params, FALSE))
        return NULL;
    if (n < 1 || n > params->yres) {
        g_warning("simscan: stripe count %d is not within 1..%d",
                  n, params->yres);
        return NULL;
    }
    for (s = 0; s < n; s++) {
        if (!isfinite(dx_px[s]) || !isfinite(dy_px[s])) {
            g_warning("simscan: stripe %d has a non-finite drift", s);
            return NULL;
        }
    }
    sd.n = n;
    sd.yres = params->yres;
    sd.pixel_w = params->xreal/params->xres;
    sd.pixel_h = params->yreal/params->yres;
    sd.dx_px = dx_px;
    sd.dy_px = dy_px;
    return scan_with_displacement(sample, params, stripe_row_displacement, &sd,
                                  params->noise_rms);
}

gdouble
sim_probe_height(const SimSample *sample, const DriftModel *drift,
                 gdouble tip_radius, gdouble x_m, gdouble y_m, gdouble t_s)
{
    gdouble px = 0.0, py = 0.0;

    if (drift)
        drift_model_eval(drift, t_s, &px, &py);
    return sim_sample_height_tip(sample, tip_radius, x_m - px, y_m - py);
}

void
sim_scan_add_noise(GwyDataField *field, gdouble noise_rms, guint32 seed)
{
    SimRandom rng;
    gdouble *data;
    gsize k, n;

    g_return_if_fail(GWY_IS_DATA_FIELD(field));
    if (!(noise_rms > 0.0))
        return;
    data = gwy_data_field_get_data(field);
    n = (gsize)gwy_data_field_get_xres(field)*gwy_data_field_get_yres(field);
    sim_random_init(&rng, seed, 3);
    for (k = 0; k < n; k++)
        data[k] += noise_rms*sim_random_gaussian(&rng);
    gwy_data_field_invalidate(field);
}
