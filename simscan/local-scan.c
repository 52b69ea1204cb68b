/*
 *  The paper's local-scan procedure on a probe function.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <string.h>
#include <math.h>
#include "local-scan.h"

/* The search moves L0 by this many particle radii: any particle whose centre
 * lies within 0.75 R of some line is cut above 1.66 R, over the default
 * threshold of 1.5 R. */
#define SEARCH_STEP_RADII 1.5
/* The displayed centre is measured in the image by the local scan's own
 * chords when the particle's radius spans at least this many pixels (its
 * chord at the default cut then 2.6 px).  A smaller particle's top is too
 * coarsely sampled for chords in the image: on simscan's paper scenario
 * (radius 1.28 px) they find the displayed centre within 0.16 px RMS, the
 * detector within 0.13 px, and a sphere has no shape bias to cancel.  The
 * measured film (radius 1.7 px) needs them: its shape bias is 0.7 px. */
#define IMAGE_CHORD_MIN_RADIUS_PX 1.5
/* The chords in the image start again from the centre they found, so that
 * their line along x runs through it, as the local scan's L0 does. */
#define IMAGE_CHORD_ITERATIONS 2

typedef struct {
    const LocalScanParams *params;
    LocalScanProbe probe;
    gpointer probe_data;
    gdouble threshold;
    gdouble t;          /* instrument clock, advanced by every line */
    gint lines;
    gdouble *heights;   /* points samples of the current line */
} LineScanner;

void
local_scan_params_init(LocalScanParams *params)
{
    params->radius = 25e-9;
    params->r_max = 100e-9;
    params->points = 64;
    params->tip_speed = 4e-6;
    params->line_overhead = 0.0;
    params->threshold_fraction = 0.75;
    params->choice = PARTICLE_CHOICE_CLOSEST;
}

gdouble
local_scan_line_length(const LocalScanParams *params)
{
    return 2.0*(params->radius + params->r_max);
}

gdouble
local_scan_line_time(const LocalScanParams *params)
{
    return params->line_overhead
           + local_scan_line_length(params)/params->tip_speed;
}

/* Samples one line of the instrument centred at (xc, yc) along x or y; the
 * drift goes on while the tip moves, so each sample has its own time. */
static void
scan_line(LineScanner *scanner, gdouble xc, gdouble yc, gboolean along_x)
{
    const LocalScanParams *params = scanner->params;
    gint n = params->points, i;
    gdouble length = local_scan_line_length(params);
    gdouble step = length/(n - 1);
    gdouble t0 = scanner->t + params->line_overhead;
    gdouble dt = (length/params->tip_speed)/(n - 1);

    for (i = 0; i < n; i++) {
        gdouble s = -0.5*length + i*step;
        gdouble x = along_x ? xc + s : xc;
        gdouble y = along_x ? yc : yc + s;

        scanner->heights[i] = scanner->probe(scanner->probe_data, x, y,
                                             t0 + i*dt);
    }
    scanner->t += local_scan_line_time(params);
    scanner->lines++;
}

/* The chords of the last line scanned (local-scan-analysis.h). */
static void
find_line_chords(const LineScanner *scanner, GArray *mids)
{
    local_scan_chord_midpoints(scanner->heights, scanner->params->points,
                               local_scan_line_length(scanner->params),
                               scanner->threshold, mids);
}

/* The line V along y through a horizontal chord's midpoint x_mid, offset
 * y_line from y0: the centre's y offset from y0 when V finds the chord. */
static gboolean
measure_vertical(LineScanner *scanner, gdouble x_mid, gdouble y0,
                 gdouble y_line, gdouble *y_mid)
{
    GArray *mids = g_array_new(FALSE, FALSE, sizeof(gdouble));
    gboolean found;

    scan_line(scanner, x_mid, y0, FALSE);
    find_line_chords(scanner, mids);
    found = local_scan_take_nearest_chord(mids, y_line - y0, G_MAXDOUBLE,
                                          y_mid);
    g_array_free(mids, TRUE);
    return found;
}

/* L0 and its up/down moves, each chord of a line nearest first, measured
 * with V.  The lines are 2 (R + r_max) long and the search reaches r_max + R,
 * so they also cut neighbours farther than r_max from the displayed centre
 * (x0, y0): the particle cannot be there by the definition of r_max, so such
 * a centre is refused and the search goes on.  A particle exactly r_max off
 * is measured up to the lines' sample spacing, which is allowed for.
 * Returns the centre found. */
static gboolean
search_particle(LineScanner *scanner, gdouble x0, gdouble y0,
                gdouble *x_centre, gdouble *y_centre, gdouble *y_line)
{
    const LocalScanParams *params = scanner->params;
    gdouble step = SEARCH_STEP_RADII*params->radius;
    gdouble reach = params->r_max + params->radius;
    gdouble limit = params->r_max
                    + local_scan_line_length(params)/(params->points - 1);
    GArray *mids = g_array_new(FALSE, FALSE, sizeof(gdouble));
    gboolean found = FALSE;
    gint k;

    for (k = 0; !found && (k == 0 || ((k + 1)/2)*step <= reach); k++) {
        /* 0, -1, +1, -2, +2, ... steps: up first, then down. */
        gdouble offset = ((k + 1)/2)*step*((k % 2) ? -1.0 : 1.0);
        gdouble mid, y_mid;

        scan_line(scanner, x0, y0 + offset, TRUE);
        find_line_chords(scanner, mids);
        while (!found
               && local_scan_take_nearest_chord(mids, 0.0, limit, &mid)) {
            if (measure_vertical(scanner, x0 + mid, y0, y0 + offset, &y_mid)
                && hypot(mid, y_mid) <= limit) {
                *x_centre = x0 + mid;
                *y_centre = y0 + y_mid;
                *y_line = y0 + offset;
                found = TRUE;
            }
        }
    }
    g_array_free(mids, TRUE);
    return found;
}

gdouble
local_scan_particle(GwyDataField *field, const LocalScanParams *params,
                    LocalScanProbe probe, gpointer probe_data,
                    gdouble x_px, gdouble y_px, gdouble threshold,
                    gdouble t_start, LocalScanParticle *result)
{
    gdouble dx = gwy_data_field_get_dx(field);
    gdouble dy = gwy_data_field_get_dy(field);
    gdouble xoff = gwy_data_field_get_xoffset(field);
    gdouble yoff = gwy_data_field_get_yoffset(field);
    gdouble x0 = xoff + (x_px + 0.5)*dx, y0 = yoff + (y_px + 0.5)*dy;
    gdouble x_centre = 0.0, y_centre = 0.0, y_line = 0.0;
    LineScanner scanner;

    g_return_val_if_fail(params->points >= 3 && params->tip_speed > 0.0,
                         t_start);
    scanner.params = params;
    scanner.probe = probe;
    scanner.probe_data = probe_data;
    scanner.threshold = threshold;
    scanner.t = t_start;
    scanner.lines = 0;
    scanner.heights = g_new(gdouble, params->points);

    result->found = FALSE;
    result->x_disp = x_px;
    result->y_disp = y_px;
    result->x_act = result->y_act = result->dx = result->dy = NAN;
    result->y_line = NAN;
    if (search_particle(&scanner, x0, y0, &x_centre, &y_centre, &y_line)) {
        result->found = TRUE;
        result->x_act = (x_centre - xoff)/dx - 0.5;
        result->y_act = (y_centre - yoff)/dy - 0.5;
        result->y_line = (y_line - yoff)/dy - 0.5;
        result->dx = x_px - result->x_act;
        result->dy = y_px - result->y_act;
    }
    result->lines = scanner.lines;
    result->t_start = t_start;
    result->t_end = scanner.t;
    result->t_local = 0.5*(t_start + scanner.t);
    g_free(scanner.heights);
    return scanner.t;
}

static gboolean
uses_image_chords(GwyDataField *field, const LocalScanParams *params)
{
    return (params->radius/gwy_data_field_get_dx(field)
            >= IMAGE_CHORD_MIN_RADIUS_PX
            && params->radius/gwy_data_field_get_dy(field)
               >= IMAGE_CHORD_MIN_RADIUS_PX);
}

/* The image as a probe: the height the image shows at (x_m, y_m), bicubic
 * between pixels; the image is one moment, so t does not matter. */
static gdouble
image_probe(gpointer user_data, gdouble x_m, gdouble y_m,
            G_GNUC_UNUSED gdouble t_s)
{
    GwyDataField *field = (GwyDataField*)user_data;

    return gwy_data_field_get_dval_real(field,
                                        x_m - gwy_data_field_get_xoffset(field),
                                        y_m - gwy_data_field_get_yoffset(field),
                                        GWY_INTERPOLATION_KEY);
}

/* The displayed centre of a particle detected at (*x, *y) px, measured in
 * the image with the same lines, chords and threshold as the local scan
 * measures the actual centre on the instrument.  A real particle is no
 * sphere: its chords' midpoints miss its detected centre by up to 0.7 px,
 * and only the same chords in the image cancel that bias in displayed minus
 * actual.  Left as detected for small particles (see
 * IMAGE_CHORD_MIN_RADIUS_PX) or when the chords fail. */
static void
measure_displayed_centre(GwyDataField *field, const LocalScanParams *params,
                         gdouble threshold, gdouble *x, gdouble *y)
{
    LocalScanParticle in_image;
    gint k;

    if (!uses_image_chords(field, params))
        return;
    for (k = 0; k < IMAGE_CHORD_ITERATIONS; k++) {
        local_scan_particle(field, params, image_probe, field, *x, *y,
                            threshold, 0.0, &in_image);
        if (!in_image.found)
            return;
        *x = in_image.x_act;
        *y = in_image.y_act;
    }
}

/* The chords in the image along the row that cuts the displayed particle
 * where the local scan's hitting line cut the actual one (y_line - y_act
 * from its centre), and the column through their midpoint: a real
 * particle's chord midpoints move with the row, by up to a pixel on the
 * measured film when a large drift makes L0 miss the centre by two radii,
 * and only the same row in both cancels that. */
static void
remeasure_displayed_centre(GwyDataField *field, const LocalScanParams *params,
                           gdouble threshold, LocalScanParticle *r)
{
    gdouble dx = gwy_data_field_get_dx(field);
    gdouble dy = gwy_data_field_get_dy(field);
    gdouble xoff = gwy_data_field_get_xoffset(field);
    gdouble yoff = gwy_data_field_get_yoffset(field);
    gdouble x0 = xoff + (r->x_disp + 0.5)*dx;
    gdouble y0 = yoff + (r->y_disp + 0.5)*dy;
    gdouble y_row = y0 + (r->y_line - r->y_act)*dy;
    GArray *mids = g_array_new(FALSE, FALSE, sizeof(gdouble));
    LineScanner scanner;
    gdouble mid, y_mid;

    scanner.params = params;
    scanner.probe = image_probe;
    scanner.probe_data = field;
    scanner.threshold = threshold;
    scanner.t = 0.0;
    scanner.lines = 0;
    scanner.heights = g_new(gdouble, params->points);
    scan_line(&scanner, x0, y_row, TRUE);
    find_line_chords(&scanner, mids);
    if (local_scan_take_nearest_chord(mids, 0.0, 0.5*params->radius, &mid)
        && measure_vertical(&scanner, x0 + mid, y0, y_row, &y_mid)
        && fabs(y_mid) <= 0.5*params->radius) {
        r->x_disp += mid/dx;
        r->y_disp += y_mid/dy;
        r->dx = r->x_disp - r->x_act;
        r->dy = r->y_disp - r->y_act;
    }
    g_array_free(mids, TRUE);
    g_free(scanner.heights);
}

DriftTable*
local_scan_run(GwyDataField *field, const ScanTiming *timing,
               const GArray *particles, gdouble substrate, gint n,
               const LocalScanParams *params,
               LocalScanProbe probe, gpointer probe_data,
               gdouble t_start, LocalScanParticle *results, gdouble *t_end)
{
    gint xres = gwy_data_field_get_xres(field);
    gint yres = gwy_data_field_get_yres(field);
    LocalScanParticle *res;
    DriftTable *table;
    gint *chosen;
    gdouble t = t_start;
    gint s;

    g_return_val_if_fail(n >= 1 && n <= yres, NULL);
    chosen = g_new(gint, n);
    particle_choose_for_stripes_by(particles, n, xres, yres, params->choice,
                                   chosen);
    res = results ? results : g_new(LocalScanParticle, n);
    table = drift_table_new(n, DRIFT_UNIT_PX);
    for (s = 0; s < n; s++) {
        const DetectedParticle *p;
        gdouble threshold, x_disp, y_disp;

        if (chosen[s] < 0) {
            memset(res + s, 0, sizeof(LocalScanParticle));
            local_scan_table_set_row(table, s, NULL);
            continue;
        }
        p = &g_array_index(particles, DetectedParticle, chosen[s]);
        threshold = substrate + params->threshold_fraction*(p->peak - substrate);
        x_disp = p->x;
        y_disp = p->y;
        measure_displayed_centre(field, params, threshold, &x_disp, &y_disp);
        t = local_scan_particle(field, params, probe, probe_data,
                                x_disp, y_disp, threshold, t, res + s);
        if (res[s].found && uses_image_chords(field, params))
            remeasure_displayed_centre(field, params, threshold, res + s);
        res[s].t_image = scan_timing_pixel_time(timing, p->y, p->x);
        local_scan_table_set_row(table, s, res + s);
    }
    if (res != results)
        g_free(res);
    g_free(chosen);
    if (t_end)
        *t_end = t;
    return table;
}
