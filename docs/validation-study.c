/*
 *  The validation study of the drift model on measured AFM series: writes
 *  docs/validation.md and its figures (run by `make validation`).
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <math.h>
#include <cairo.h>
#include <glib/gstdio.h>
#include <libgwyddion/gwyddion.h>
#include <libprocess/gwyprocess.h>
#include <libgwymodule/gwymodule.h>
#include <app/gwyapp.h>
#include "fit-report.h"
#include "series-correction.h"
#include "frame-series-load.h"
#include "drift-table.h"
#include "stripe-geometry.h"
#include "paper-compensate.h"
#include "continuous-compensate.h"
#include "localscan-params.h"
#include "sample.h"
#include "scanner.h"
#include "median.h"

#define N_BLOCKS 16
#define PLOT_W 1000
#define PLOT_H 700

typedef struct {
    const gchar *name;
    const gchar *files[4];
    const gchar *channel;
    gint first_id, last_id;
    const gchar *what;
} SeriesSpec;

static const SeriesSpec specs[] = {
    { "fastscan-series",
      { "fastscan-series/09261606.001", "fastscan-series/09261609.001",
        "fastscan-series/09261616.001", NULL },
      "Phase", -1, -1,
      "Bruker Dimension FastScan" },
    { "hsafm-sample0",
      { "hsafm-minicircles/hsafm_sample0_frames50-140.gwy", NULL },
      NULL, -1, -1,
      "High-speed AFM (Ando), sample_0" },
    { "hsafm-extra",
      { "hsafm-minicircles/hsafm_extra_frames14-62.gwy", NULL },
      NULL, -1, -1,
      "High-speed AFM (Ando), extra_sample" },
    { "afmir-film",
      { "afmir-film/PEA_BDA_film.axz", NULL },
      "Height", 9, 17,
      "Anasys nanoIR2, channels Height 9..17" },
};

/* What the study found for one series. */
typedef struct {
    const gchar *name;
    FrameSeries *series;
    FitReport report;
    gint extended;            /* index of the extension model (settling) */
    gdouble cv_paper, cv_none, cv_ext;
    gdouble ncc_raw, ncc_paper, ncc_ext;
    gdouble ncc1[3];          /* the same for frames 0 and 1 alone */
    DriftFit creep[2];        /* constant acceleration, logarithmic creep */
    gdouble cv_settling;      /* drift_fit_cross_validate of settling */
    gchar *plot, *images;
} SeriesResult;

/* The registration and fit settings of the study, shared by every series
 * and printed in the document's header. */
static void
study_options(const SeriesFrame *f0, DisplacementOptions *dopt,
              DriftFitOptions *fopt)
{
    displacement_options_init(dopt);
    dopt->n_blocks = N_BLOCKS;
    drift_fit_options_init(fopt);
    if (f0)
        fopt->min_period = drift_fit_min_period(f0->timing.line_time,
                                                f0->timing.yres,
                                                dopt->n_blocks);
}

/* The paper's model: constant velocity, one drift per stripe, whole
 * pixels.  Its prediction of a measurement. */
static void
paper_predict(const DriftFit *none, const DriftMeasurement *m,
              gdouble xstep, gdouble ystep, gdouble *dx, gdouble *dy)
{
    drift_fit_predict(none, m, dx, dy);
    *dx = xstep*drift_px_round(*dx/xstep);
    *dy = ystep*drift_px_round(*dy/ystep);
}

static gint
fold_of(const DriftMeasurement *m, gint folds)
{
    return (m->group % folds + folds) % folds;
}

/* Cross-validated RMS (nm) of the paper model: v from the other folds, the
 * folds of drift_fit_cross_validate. */
static gdouble
paper_cross_validate(const DriftMeasurement *meas, gint n,
                     const DriftFitOptions *options, gdouble xstep,
                     gdouble ystep)
{
    DriftMeasurement *train = g_new(DriftMeasurement, n);
    gdouble sum = 0.0, wsum = 0.0, dx, dy;
    gint f, i, folds = MAX(options->n_folds, 2);
    DriftFit fit;

    for (f = 0; f < folds; f++) {
        memcpy(train, meas, n*sizeof(DriftMeasurement));
        for (i = 0; i < n; i++) {
            if (fold_of(meas + i, folds) == f)
                train[i].weight = 0.0;
        }
        if (!drift_fit_model(train, n, DRIFT_MODEL_NONE, options, &fit))
            continue;
        for (i = 0; i < n; i++) {
            if (fold_of(meas + i, folds) != f || !(meas[i].weight > 0.0))
                continue;
            paper_predict(&fit, meas + i, xstep, ystep, &dx, &dy);
            sum += meas[i].weight*1e18*((meas[i].dx - dx)*(meas[i].dx - dx)
                                        + (meas[i].dy - dy)*(meas[i].dy - dy));
            wsum += 2.0*meas[i].weight;
        }
    }
    g_free(train);
    return wsum > 0.0 ? sqrt(sum/wsum) : NAN;
}

static gdouble*
leveled_copy(GwyDataField *field)
{
    gint xres = gwy_data_field_get_xres(field), yres = gwy_data_field_get_yres(field);
    const gdouble *d = gwy_data_field_get_data_const(field);
    gdouble *out = g_new(gdouble, xres*yres), *row = g_new(gdouble, xres), med;
    gint i, j;

    for (i = 0; i < yres; i++) {
        memcpy(row, d + i*xres, xres*sizeof(gdouble));
        med = median_in_place(row, xres);
        for (j = 0; j < xres; j++)
            out[i*xres + j] = d[i*xres + j] - med;
    }
    g_free(row);
    return out;
}

/* Drift-free image of a frame by the product's compensation: with stripes
 * > 0 paper mode (paper_compensate) with each stripe's drift the fit's at
 * the stripe's centre time, rounded to whole pixels by drift_px_round;
 * else continuous mode (continuous_compensate_trajectory with B-spline,
 * the sub-pixel kernel: the study is about positions, and the module's
 * default nearest pixel keeps heights instead) along the fit.  fit NULL: no compensation.  NaN
 * where the frame has no data. */
static gdouble*
compensate(const SeriesFrame *frame, const gdouble *data, const DriftFit *fit,
           gint stripes)
{
    const ScanTiming *tm = &frame->timing;
    gint xres = tm->xres, yres = tm->yres, s;
    gdouble xstep = gwy_data_field_get_dx(frame->field);
    gdouble ystep = gwy_data_field_get_dy(frame->field);
    gdouble *out = g_new(gdouble, xres*yres), px, py;
    DriftTrajectory *trajectory;
    gint *dx, *dy;

    if (!fit) {
        memcpy(out, data, xres*yres*sizeof(gdouble));
        return out;
    }
    if (stripes > 0) {
        dx = g_new(gint, stripes);
        dy = g_new(gint, stripes);
        for (s = 0; s < stripes; s++) {
            drift_fit_eval(fit, scan_timing_rows_time(tm,
                                                      stripe_first_row(s, stripes, yres),
                                                      stripe_end_row(s, stripes, yres)),
                           &px, &py);
            dx[s] = (gint)drift_px_round(px/xstep);
            dy[s] = (gint)drift_px_round(py/ystep);
        }
        paper_compensate(data, xres, yres, stripes, dx, dy, NAN, out, NULL);
        g_free(dx);
        g_free(dy);
        return out;
    }
    trajectory = series_fit_trajectory(fit, xstep, ystep, tm, NULL);
    if (!trajectory
        || !continuous_compensate_trajectory(data, xres, yres, trajectory, tm,
                                             GWY_INTERPOLATION_BSPLINE,
                                             NAN, out, NULL, NULL)) {
        for (s = 0; s < xres*yres; s++)
            out[s] = NAN;
    }
    if (trajectory)
        drift_trajectory_free(trajectory);
    return out;
}

static gdouble
overlap_ncc(const gdouble *a, const gdouble *b, gint n)
{
    gdouble sa = 0, sb = 0, saa = 0, sbb = 0, sab = 0;
    gint i, m = 0;

    for (i = 0; i < n; i++) {
        if (isnan(a[i]) || isnan(b[i]))
            continue;
        sa += a[i];
        sb += b[i];
        m++;
    }
    if (m < 16)
        return NAN;
    sa /= m;
    sb /= m;
    for (i = 0; i < n; i++) {
        if (isnan(a[i]) || isnan(b[i]))
            continue;
        saa += (a[i] - sa)*(a[i] - sa);
        sbb += (b[i] - sb)*(b[i] - sb);
        sab += (a[i] - sa)*(b[i] - sb);
    }
    return sab/sqrt(saa*sbb);
}

/* Mean alignment (NCC) of consecutive frames after compensation; the
 * difference image of frames 1 and 0 and their NCC. */
static gdouble
alignment(const FrameSeries *series, const DriftFit *fit, gint stripes,
          gdouble **diff_image, gdouble *first_ncc)
{
    gint k, n = series->frames[0].timing.xres*series->frames[0].timing.yres;
    gdouble sum = 0.0;
    gint count = 0;

    for (k = 1; k < series->n_frames; k++) {
        gdouble *da = leveled_copy(series->frames[k].field);
        gdouble *db = leveled_copy(series->frames[k-1].field);
        gdouble *ca = compensate(series->frames + k, da, fit, stripes);
        gdouble *cb = compensate(series->frames + k-1, db, fit, stripes);
        gdouble v = overlap_ncc(ca, cb, n);
        gint i;

        if (isfinite(v)) {
            sum += v;
            count++;
        }
        if (k == 1)
            *first_ncc = v;
        if (k == 1 && diff_image) {
            *diff_image = g_new(gdouble, n);
            for (i = 0; i < n; i++)
                (*diff_image)[i] = ca[i] - cb[i];
        }
        g_free(da);
        g_free(db);
        g_free(ca);
        g_free(cb);
    }
    return count ? sum/count : NAN;
}

/* ---- Plots ---- */

typedef struct {
    cairo_t *cr;
    gdouble x0, y0, w, h;        /* panel in device units */
    gdouble tmin, tmax, vmin, vmax;
} Panel;

static gdouble
px_x(const Panel *p, gdouble t)
{
    return p->x0 + p->w*(t - p->tmin)/(p->tmax - p->tmin);
}

static gdouble
px_y(const Panel *p, gdouble v)
{
    return p->y0 + p->h*(1.0 - (v - p->vmin)/(p->vmax - p->vmin));
}

/* A tick spacing of 1, 2 or 5 times a power of ten giving about target
 * intervals over span. */
static gdouble
nice_step(gdouble span, gint target)
{
    gdouble raw = span/target, mag, norm;

    if (!(raw > 0.0) || !isfinite(raw))
        return 1.0;
    mag = pow(10.0, floor(log10(raw)));
    norm = raw/mag;
    if (norm < 1.5)
        return mag;
    if (norm < 3.5)
        return 2.0*mag;
    if (norm < 7.5)
        return 5.0*mag;
    return 10.0*mag;
}

/* Widens [*lo, *hi] (padded a little, so no point sits on the frame) to
 * whole ticks; returns the tick spacing. */
static gdouble
nice_range(gdouble *lo, gdouble *hi, gint target)
{
    gdouble pad = 0.03*(*hi - *lo), step;

    if (!(pad > 0.0))
        pad = MAX(0.5*fabs(*lo), 0.5);
    *lo -= pad;
    *hi += pad;
    step = nice_step(*hi - *lo, target);
    *lo = step*floor(*lo/step + 1e-9);
    *hi = step*ceil(*hi/step - 1e-9);
    return step;
}

static void
tick_label(gchar *buf, gsize size, gdouble v, gdouble step)
{
    gint decimals = MAX(0, (gint)-floor(log10(step) + 1e-9));

    if (fabs(v) < 1e-9*step)
        v = 0.0;
    g_snprintf(buf, size, "%.*f", decimals, v);
}

static void
show_text_at(cairo_t *cr, const gchar *text, gdouble x, gdouble y,
             gdouble halign)
{
    cairo_text_extents_t ext;

    cairo_text_extents(cr, text, &ext);
    cairo_move_to(cr, x - halign*ext.x_advance, y);
    cairo_show_text(cr, text);
}

/* Frame, light grid, ticks at nice values, labels and titles.  The panel's
 * ranges must already be nice (nice_range). */
static void
panel_frame(Panel *p, gdouble tstep, gdouble vstep, const gchar *title,
            const gchar *xlabel)
{
    cairo_t *cr = p->cr;
    gchar buf[64];
    gdouble v, t;

    cairo_set_line_width(cr, 1.0);
    cairo_set_source_rgb(cr, 0.88, 0.88, 0.88);
    for (v = p->vmin; v <= p->vmax + 1e-9*vstep; v += vstep) {
        cairo_move_to(cr, p->x0, px_y(p, v));
        cairo_line_to(cr, p->x0 + p->w, px_y(p, v));
    }
    for (t = p->tmin; t <= p->tmax + 1e-9*tstep; t += tstep) {
        cairo_move_to(cr, px_x(p, t), p->y0);
        cairo_line_to(cr, px_x(p, t), p->y0 + p->h);
    }
    cairo_stroke(cr);
    if (p->vmin < 0 && p->vmax > 0) {
        cairo_set_source_rgb(cr, 0.55, 0.55, 0.55);
        cairo_move_to(cr, p->x0, px_y(p, 0));
        cairo_line_to(cr, p->x0 + p->w, px_y(p, 0));
        cairo_stroke(cr);
    }
    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_rectangle(cr, p->x0, p->y0, p->w, p->h);
    cairo_stroke(cr);
    cairo_set_font_size(cr, 12);
    for (v = p->vmin; v <= p->vmax + 1e-9*vstep; v += vstep) {
        cairo_move_to(cr, p->x0 - 4, px_y(p, v));
        cairo_line_to(cr, p->x0, px_y(p, v));
        cairo_stroke(cr);
        tick_label(buf, sizeof(buf), v, vstep);
        show_text_at(cr, buf, p->x0 - 7, px_y(p, v) + 4, 1.0);
    }
    for (t = p->tmin; t <= p->tmax + 1e-9*tstep; t += tstep) {
        cairo_move_to(cr, px_x(p, t), p->y0 + p->h);
        cairo_line_to(cr, px_x(p, t), p->y0 + p->h + 4);
        cairo_stroke(cr);
        tick_label(buf, sizeof(buf), t, tstep);
        show_text_at(cr, buf, px_x(p, t), p->y0 + p->h + 17, 0.5);
    }
    cairo_set_font_size(cr, 13);
    show_text_at(cr, title, p->x0, p->y0 - 8, 0.0);
    if (xlabel)
        show_text_at(cr, xlabel, p->x0 + 0.5*p->w, p->y0 + p->h + 34, 0.5);
}

static void
dot(cairo_t *cr, gdouble x, gdouble y, gdouble r, const gdouble *rgb,
    gboolean filled)
{
    cairo_set_source_rgb(cr, rgb[0], rgb[1], rgb[2]);
    cairo_new_sub_path(cr);
    cairo_arc(cr, x, y, r, 0, 2*G_PI);
    if (filled)
        cairo_fill(cr);
    else
        cairo_stroke(cr);
}

/* A legend entry at x; returns where the next one may start. */
static gdouble
legend(cairo_t *cr, gdouble x, gdouble y, const gdouble *rgb,
       gboolean filled, const gchar *text)
{
    cairo_text_extents_t ext;

    cairo_set_line_width(cr, 1.2);
    dot(cr, x + 4, y - 4, filled ? 3.0 : 4.0, rgb, filled);
    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_move_to(cr, x + 14, y);
    cairo_show_text(cr, text);
    cairo_text_extents(cr, text, &ext);
    return x + 14 + ext.x_advance + 28;
}

/* A used measurement's displacement (nm) and the paper and extension
 * models' predictions of it (m); FALSE for a measurement not used. */
static gboolean
plotted_values(const DriftMeasurement *m, const DriftFit *none,
               const DriftFit *ext, gdouble xstep, gdouble ystep,
               gdouble *md, gdouble *pd, gdouble *ed)
{
    if (!(m->weight > 0.0))
        return FALSE;
    md[0] = 1e9*m->dx;
    md[1] = 1e9*m->dy;
    paper_predict(none, m, xstep, ystep, pd, pd + 1);
    drift_fit_predict(ext, m, ed, ed + 1);
    return TRUE;
}

/* A used measurement as plotted_values() gives it, with the later block's
 * scan time it is drawn at. */
typedef struct {
    gdouble t;
    gdouble md[2], pd[2], ed[2];
} PlotPoint;

/* The used measurements of the series' report, in its order; both passes
 * over them (the panels' ranges, then the dots) see the same points. */
static PlotPoint*
plot_points(const SeriesResult *res, gint *n)
{
    const FitReport *rep = &res->report;
    const DriftFit *none = rep->fits, *ext = rep->fits + res->extended;
    gdouble xstep = frame_series_dx(res->series), ystep = frame_series_dy(res->series);
    PlotPoint *points = g_new(PlotPoint, MAX(rep->n_meas, 1));
    gint i;

    *n = 0;
    for (i = 0; i < rep->n_meas; i++) {
        const DriftMeasurement *m = rep->meas + i;
        PlotPoint *q = points + *n;

        if (plotted_values(m, none, ext, xstep, ystep, q->md, q->pd, q->ed)) {
            q->t = m->t_a;
            (*n)++;
        }
    }
    return points;
}

/* Measured and predicted displacement (x and y) over the later scan time,
 * and the residuals of both models. */
static void
plot_displacements(const SeriesResult *res, const gchar *path,
                   const gchar *title)
{
    static const gdouble black[3] = { 0, 0, 0 }, red[3] = { 0.85, 0.1, 0.1 },
                         blue[3] = { 0.1, 0.3, 0.9 };
    const DriftFit *ext = res->report.fits + res->extended;
    cairo_surface_t *sf = cairo_image_surface_create(CAIRO_FORMAT_RGB24,
                                                     PLOT_W, PLOT_H);
    cairo_t *cr = cairo_create(sf);
    Panel p[4];
    gdouble vstep[4], tstep[4], x;
    gchar *model;
    PlotPoint *points;
    gint i, ax, k, n;

    cairo_set_source_rgb(cr, 1, 1, 1);
    cairo_paint(cr);
    for (k = 0; k < 4; k++) {
        p[k].cr = cr;
        p[k].x0 = 80 + (k % 2)*480;
        p[k].y0 = 88 + (k/2)*290;
        p[k].w = 400;
        p[k].h = 215;
        p[k].tmin = G_MAXDOUBLE;
        p[k].tmax = -G_MAXDOUBLE;
        p[k].vmin = G_MAXDOUBLE;
        p[k].vmax = -G_MAXDOUBLE;
    }
    points = plot_points(res, &n);
    for (i = 0; i < n; i++) {
        const gdouble *md = points[i].md, *pd = points[i].pd, *ed = points[i].ed;
        gdouble t = points[i].t;

        for (ax = 0; ax < 2; ax++) {
            Panel *a = p + ax, *b = p + 2 + ax;
            gdouble r1 = md[ax] - 1e9*pd[ax], r2 = md[ax] - 1e9*ed[ax];

            a->tmin = b->tmin = MIN(a->tmin, t);
            a->tmax = b->tmax = MAX(a->tmax, t);
            a->vmin = MIN(a->vmin, MIN(md[ax], 1e9*MIN(pd[ax], ed[ax])));
            a->vmax = MAX(a->vmax, MAX(md[ax], 1e9*MAX(pd[ax], ed[ax])));
            b->vmin = MIN(b->vmin, MIN(r1, r2));
            b->vmax = MAX(b->vmax, MAX(r1, r2));
        }
    }
    cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL,
                           CAIRO_FONT_WEIGHT_NORMAL);
    for (k = 0; k < 4; k++) {
        vstep[k] = nice_range(&p[k].vmin, &p[k].vmax, 5);
        tstep[k] = nice_range(&p[k].tmin, &p[k].tmax, 5);
    }
    panel_frame(p + 0, tstep[0], vstep[0], "x displacement p(t_a) - p(t_b) (nm)",
                NULL);
    panel_frame(p + 1, tstep[1], vstep[1], "y displacement p(t_a) - p(t_b) (nm)",
                NULL);
    panel_frame(p + 2, tstep[2], vstep[2], "x residual, measured - model (nm)",
                "scan time t_a of the later block (s)");
    panel_frame(p + 3, tstep[3], vstep[3], "y residual, measured - model (nm)",
                "scan time t_a of the later block (s)");
    cairo_set_line_width(cr, 1.2);
    for (i = 0; i < n; i++) {
        const gdouble *md = points[i].md, *pd = points[i].pd, *ed = points[i].ed;
        gdouble t = points[i].t;

        for (ax = 0; ax < 2; ax++) {
            dot(cr, px_x(p + ax, t), px_y(p + ax, md[ax]), 2.5, black, TRUE);
            dot(cr, px_x(p + ax, t), px_y(p + ax, 1e9*pd[ax]), 3.5, red, FALSE);
            dot(cr, px_x(p + ax, t), px_y(p + ax, 1e9*ed[ax]), 3.5, blue, FALSE);
            dot(cr, px_x(p + 2 + ax, t),
                px_y(p + 2 + ax, md[ax] - 1e9*pd[ax]), 3.0, red, FALSE);
            dot(cr, px_x(p + 2 + ax, t),
                px_y(p + 2 + ax, md[ax] - 1e9*ed[ax]), 3.0, blue, FALSE);
        }
    }
    g_free(points);
    cairo_set_font_size(cr, 16);
    cairo_set_source_rgb(cr, 0, 0, 0);
    show_text_at(cr, title, 80, 28, 0.0);
    cairo_set_font_size(cr, 12);
    cairo_set_source_rgb(cr, 0.3, 0.3, 0.3);
    show_text_at(cr, "Each point: one block of a later frame registered "
                 "against one earlier frame, drawn at the later block's scan "
                 "time; points stacked at one time are", 80, 46, 0.0);
    show_text_at(cr, "that block against different earlier frames.  "
                 "Residuals of a good model scatter about 0 with no trend "
                 "in time.", 80, 61, 0.0);
    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_set_font_size(cr, 13);
    model = g_strdup_printf("%s model (continuous, fitted)",
                            drift_model_type_name(ext->type));
    x = legend(cr, 80, PLOT_H - 18, black, TRUE, "measured (block registration)");
    x = legend(cr, x, PLOT_H - 18, red, FALSE,
               "paper model (constant v, whole px per stripe)");
    legend(cr, x, PLOT_H - 18, blue, FALSE, model);
    g_free(model);
    cairo_surface_write_to_png(sf, path);
    cairo_destroy(cr);
    cairo_surface_destroy(sf);
}

/* Grey value of v on a scale of +-2.5 rms (mid grey 0); NaN dark red. */
static guint32
grey_pixel(gdouble v, gdouble rms)
{
    gint g;

    if (isnan(v))
        return 0x400000;
    g = CLAMP((gint)(128 + 51*v/rms), 0, 255);
    return (guint32)g*0x010101;
}

static gdouble
tile_rms(const gdouble *tile, gint n)
{
    gdouble s2 = 0.0;
    gint i, m = 0;

    for (i = 0; i < n; i++) {
        if (!isnan(tile[i])) {
            s2 += tile[i]*tile[i];
            m++;
        }
    }
    return (m && s2 > 0.0) ? sqrt(s2/m) : 1.0;
}

static void
paint_tile(cairo_t *cr, const gdouble *tile, gint xres, gint yres,
           gdouble rms, gdouble x, gdouble y, gdouble w, gdouble h)
{
    cairo_surface_t *img = cairo_image_surface_create(CAIRO_FORMAT_RGB24,
                                                      xres, yres);
    guint32 *px = (guint32*)cairo_image_surface_get_data(img);
    gint stride = cairo_image_surface_get_stride(img)/4, r, c;

    cairo_surface_flush(img);
    for (r = 0; r < yres; r++) {
        for (c = 0; c < xres; c++)
            px[r*stride + c] = grey_pixel(tile[r*xres + c], rms);
    }
    cairo_surface_mark_dirty(img);
    cairo_save(cr);
    cairo_translate(cr, x, y);
    cairo_scale(cr, w/xres, h/yres);
    cairo_set_source_surface(cr, img, 0, 0);
    cairo_paint(cr);
    cairo_restore(cr);
    cairo_surface_destroy(img);
}

/* The later frame, then difference images side by side, each drawn with
 * its physical aspect; the differences share one grey scale (the raw
 * difference's), so that a better compensation looks flatter. */
static void
image_strip(gdouble **tiles, gint n, gint xres, gint yres, gdouble aspect,
            const gchar *title, gchar **labels, const gchar *path)
{
    gint tile_h = 240, tile_w = (gint)(tile_h*aspect*xres/yres + 0.5);
    gint gap = 16, w, h = tile_h + 110, k;
    cairo_surface_t *sf;
    cairo_t *cr;
    gdouble diff_rms = tile_rms(tiles[1], xres*yres);

    tile_w = MAX(tile_w, 180);
    w = n*(tile_w + gap) + gap;
    sf = cairo_image_surface_create(CAIRO_FORMAT_RGB24, w, h);
    cr = cairo_create(sf);
    cairo_set_source_rgb(cr, 1, 1, 1);
    cairo_paint(cr);
    cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL,
                           CAIRO_FONT_WEIGHT_NORMAL);
    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_set_font_size(cr, 14);
    show_text_at(cr, title, gap, 22, 0.0);
    for (k = 0; k < n; k++) {
        gdouble x = gap + k*(tile_w + gap);
        gchar **lines = g_strsplit(labels[k], "\n", -1);
        gint l;

        paint_tile(cr, tiles[k], xres, yres,
                   k ? diff_rms : tile_rms(tiles[k], xres*yres),
                   x, 36, tile_w, tile_h);
        cairo_set_source_rgb(cr, 0, 0, 0);
        cairo_set_font_size(cr, 12);
        for (l = 0; lines[l]; l++)
            show_text_at(cr, lines[l], x, 36 + tile_h + 18 + 15*l, 0.0);
        g_strfreev(lines);
    }
    cairo_set_font_size(cr, 11);
    cairo_set_source_rgb(cr, 0.3, 0.3, 0.3);
    show_text_at(cr, "Differences: mid grey = the frames agree; black/white "
                 "edges = content misaligned; dark red = outside the "
                 "overlap.  One grey scale for all differences.", gap,
                 h - 10, 0.0);
    cairo_surface_write_to_png(sf, path);
    cairo_destroy(cr);
    cairo_surface_destroy(sf);
}

/* ---- The study of one series ---- */

/* The extension the study measures: settling, the velocity relaxing (see
 * the findings in the document for why this one). */
static gint
extension_model(const FitReport *rep)
{
    gint i;

    for (i = 0; i < rep->n_fits; i++) {
        if (rep->fits[i].type == DRIFT_MODEL_SETTLING && rep->fits[i].ok)
            return i;
    }
    return 0;
}

static FrameSeries*
load_measured_series(const SeriesSpec *spec, const gchar *measured,
                     const gchar *channel, GError **error)
{
    FrameSeriesOptions so;
    FrameSeries *series;
    gchar *files[4];
    gint n, k;

    frame_series_options_init(&so);
    so.channel = channel ? channel : spec->channel;
    so.first_id = spec->first_id;
    so.last_id = spec->last_id;
    for (n = 0; spec->files[n]; n++)
        files[n] = g_build_filename(measured, spec->files[n], NULL);
    series = frame_series_load(files, n, &so, error);
    for (k = 0; k < n; k++)
        g_free(files[k]);
    return series;
}

/* The creep forms tried beside settling, on the measurements simscan fit
 * kept, held out the same way. */
static void
try_creep_forms(SeriesResult *res)
{
    const FitReport *rep = &res->report;

    drift_fit_creep(rep->meas, rep->n_meas, DRIFT_FIT_CREEP_ACCELERATION,
                    &rep->fit_options, res->creep);
    drift_fit_creep(rep->meas, rep->n_meas, DRIFT_FIT_CREEP_LOGARITHMIC,
                    &rep->fit_options, res->creep + 1);
    res->cv_settling = drift_fit_cross_validate(rep->meas, rep->n_meas,
                                                DRIFT_MODEL_SETTLING,
                                                &rep->fit_options);
}

static void
write_alignment_figure(SeriesResult *res, const gchar *docdir,
                       gdouble **diff)
{
    const SeriesFrame *f1 = res->series->frames + 1;
    const gchar *ext = drift_model_type_name(res->report.fits[res->extended].type);
    gdouble *tiles[4];
    gchar *labels[4], *title, *path;
    gint k;

    tiles[0] = leveled_copy(f1->field);
    for (k = 0; k < 3; k++)
        tiles[k+1] = diff[k];
    labels[0] = g_strdup("frame 1 as measured\n(each line levelled)");
    labels[1] = g_strdup_printf("frame 1 - frame 0, no compensation\n"
                                "correlation %.3f", res->ncc1[0]);
    labels[2] = g_strdup_printf("both compensated, paper model\n"
                                "correlation %.3f", res->ncc1[1]);
    labels[3] = g_strdup_printf("both compensated, %s model\n"
                                "correlation %.3f", ext, res->ncc1[2]);
    title = g_strdup_printf("%s: frame 1 minus frame 0, before and after "
                            "drift compensation", res->name);
    path = g_build_filename(docdir, res->images, NULL);
    image_strip(tiles, 4, f1->timing.xres, f1->timing.yres,
                frame_series_dx(res->series)/frame_series_dy(res->series),
                title, labels, path);
    g_free(tiles[0]);
    for (k = 0; k < 4; k++)
        g_free(labels[k]);
    g_free(title);
    g_free(path);
}

/* Measures, fits and draws one series (res->series already loaded). */
static void
analyse_series(SeriesResult *res, const gchar *docdir)
{
    DisplacementOptions dopt;
    DriftFitOptions fopt;
    gdouble *diff[3] = { NULL, NULL, NULL };
    gchar *path, *title;
    gint k;

    study_options(res->series->frames, &dopt, &fopt);
    fit_report_compute(res->series, &dopt, &fopt, &res->report);
    res->extended = extension_model(&res->report);
    res->cv_none = res->report.fits[0].cv_rms_nm;
    res->cv_ext = res->report.fits[res->extended].cv_rms_nm;
    res->cv_paper = paper_cross_validate(res->report.meas, res->report.n_meas,
                                         &res->report.fit_options,
                                         frame_series_dx(res->series),
                                         frame_series_dy(res->series));
    try_creep_forms(res);
    res->ncc_raw = alignment(res->series, NULL, 0, diff, res->ncc1);
    res->ncc_paper = alignment(res->series, res->report.fits, dopt.n_blocks,
                               diff + 1, res->ncc1 + 1);
    res->ncc_ext = alignment(res->series, res->report.fits + res->extended, 0,
                             diff + 2, res->ncc1 + 2);

    res->plot = g_strdup_printf("figures/%s-displacement.png", res->name);
    path = g_build_filename(docdir, res->plot, NULL);
    title = g_strdup_printf("%s: displacement of each block against an "
                            "earlier frame, measured and predicted", res->name);
    plot_displacements(res, path, title);
    g_free(title);
    g_free(path);
    res->images = g_strdup_printf("figures/%s-alignment.png", res->name);
    write_alignment_figure(res, docdir, diff);
    for (k = 0; k < 3; k++)
        g_free(diff[k]);
}

static gboolean
study_series(const SeriesSpec *spec, const gchar *measured,
             const gchar *docdir, SeriesResult *res, GError **error)
{
    memset(res, 0, sizeof(SeriesResult));
    res->name = spec->name;
    if (!(res->series = load_measured_series(spec, measured, NULL, error)))
        return FALSE;
    analyse_series(res, docdir);
    return TRUE;
}

/* ---- Why the FastScan series is registered on Phase ---- */

/* How well the registrations of three frames close: (2 vs 0) should equal
 * (2 vs 1) + (1 vs 0).  Registered as displacement-measure.c does:
 * consecutive pairs blind, 2 vs 0 around the sum of their whole-frame
 * shifts (a blind search would not reach that far). */
typedef struct {
    const gchar *channel;
    gint n_blocks;            /* blocks accepted in all three pairs */
    gdouble median[2];        /* median |misclosure| over them, px */
    gdouble whole[2];         /* misclosure of the whole-frame shifts, px */
} RegistrationTriangle;

static gdouble
median_of(gdouble *v, gint n)
{
    return n ? median_in_place(v, n) : NAN;
}

static gboolean
registration_triangle(const SeriesSpec *spec, const gchar *measured,
                      const gchar *channel, RegistrationTriangle *tri,
                      GError **error)
{
    static const gint pairs[3][2] = { { 1, 0 }, { 2, 1 }, { 2, 0 } };
    FrameSeries *series;
    DisplacementOptions dopt;
    DriftFitOptions fopt;
    gdouble dx[3][N_BLOCKS], dy[3][N_BLOCKS], score[3][N_BLOCKS],
            whole[3][3], mis[2][N_BLOCKS];
    gint p, b, xres, yres;

    memset(tri, 0, sizeof(RegistrationTriangle));
    tri->channel = channel;
    if (!(series = load_measured_series(spec, measured, channel, error)))
        return FALSE;
    if (series->n_frames < 3) {
        g_set_error(error, FRAME_SERIES_ERROR, FRAME_SERIES_ERROR_CHANNEL,
                    "%s: fewer than three frames", channel);
        frame_series_free(series);
        return FALSE;
    }
    study_options(series->frames, &dopt, &fopt);
    xres = series->frames[0].timing.xres;
    yres = series->frames[0].timing.yres;
    for (p = 0; p < 3; p++) {
        const SeriesFrame *fa = series->frames + pairs[p][0];
        const SeriesFrame *fb = series->frames + pairs[p][1];
        gdouble guess[2] = { whole[0][0] + whole[1][0],
                             whole[0][1] + whole[1][1] };

        displacement_register_blocks(gwy_data_field_get_data_const(fa->field),
                                     gwy_data_field_get_data_const(fb->field),
                                     xres, yres, N_BLOCKS, &dopt,
                                     frame_series_dy(series)/frame_series_dx(series),
                                     p == 2 ? guess : NULL,
                                     dx[p], dy[p], score[p], whole[p]);
    }
    for (b = 0; b < N_BLOCKS; b++) {
        if (score[0][b] < dopt.min_score || score[1][b] < dopt.min_score
            || score[2][b] < dopt.min_score)
            continue;
        mis[0][tri->n_blocks] = fabs(dx[2][b] - dx[1][b] - dx[0][b]);
        mis[1][tri->n_blocks] = fabs(dy[2][b] - dy[1][b] - dy[0][b]);
        tri->n_blocks++;
    }
    tri->median[0] = median_of(mis[0], tri->n_blocks);
    tri->median[1] = median_of(mis[1], tri->n_blocks);
    tri->whole[0] = whole[2][0] - whole[1][0] - whole[0][0];
    tri->whole[1] = whole[2][1] - whole[1][1] - whole[0][1];
    frame_series_free(series);
    return TRUE;
}

/* ---- The FastScan residual against the measurement noise ---- */

/* The channels of one FastScan frame are recorded on the same scan lines,
 * so they share one drift.  Each channel is measured and fitted as the
 * study fits a series; where two channels or more keep a block of a pair,
 * its residuals against one model (the same type for every channel) split
 * into what the channels share (the mean product of two channels'
 * residuals: drift the model leaves, content that changed alike in every
 * channel, or registration error the channels have in common) and what
 * they do not (half the mean square of their difference: registration
 * error of one channel alone, a lower bound of the registration's error). */
#define AGREEMENT_CHANNELS 3
#define MAX_PAIRS 64

typedef struct {
    gint pair;                /* index of (frame_a, frame_b) among the pairs */
    gint group;               /* the block's place in the frame */
    gint n;                   /* channels that keep the block */
    gdouble r[AGREEMENT_CHANNELS][2];
} BlockResidual;

typedef struct {
    DriftModelType type;      /* the model the residuals are taken against */
    gint n_blocks, n_pairs;   /* blocks kept by two channels or more */
    gdouble residual2;        /* mean square of the residuals, nm^2 */
    gdouble noise2;           /* not shared */
    gdouble shared2;          /* shared (may come out negative) */
    gdouble slope[2];         /* the shared part's slope along the rows, nm
                                 per block of lines, x and y */
    gdouble slope_se[2];
} ResidualSplit;

/* The same block of the same pair: the series' measurements come in the
 * same order whatever the channel (displacement-measure.c), their times
 * not quite (a block's time is that of its detail). */
static gboolean
same_block(const DriftMeasurement *a, const DriftMeasurement *b)
{
    return (a->frame_a == b->frame_a && a->frame_b == b->frame_b
            && a->group == b->group);
}

static gint
pair_index(gint (*pairs)[2], gint *n_pairs, const DriftMeasurement *m)
{
    gint p;

    for (p = 0; p < *n_pairs; p++) {
        if (pairs[p][0] == m->frame_a && pairs[p][1] == m->frame_b)
            return p;
    }
    if (*n_pairs == MAX_PAIRS)
        return -1;
    pairs[*n_pairs][0] = m->frame_a;
    pairs[*n_pairs][1] = m->frame_b;
    return (*n_pairs)++;
}

/* The blocks kept by two channels or more, with their residuals (nm)
 * against fit number model of each channel's report. */
static BlockResidual*
collect_block_residuals(const FitReport *rep, gint nc, gint model, gint *n,
                        gint *n_pairs)
{
    gint pairs[MAX_PAIRS][2], n_meas = rep[0].n_meas, i, c;
    BlockResidual *blocks, *b;
    gdouble px, py;

    for (c = 1; c < nc; c++)
        n_meas = MIN(n_meas, rep[c].n_meas);
    blocks = g_new0(BlockResidual, MAX(n_meas, 1));
    *n = *n_pairs = 0;
    for (i = 0; i < n_meas; i++) {
        b = blocks + *n;
        b->n = 0;
        for (c = 0; c < nc; c++) {
            const DriftMeasurement *m = rep[c].meas + i;

            if (!(m->weight > 0.0) || !same_block(rep[0].meas + i, m))
                continue;
            drift_fit_predict(rep[c].fits + model, m, &px, &py);
            b->r[b->n][0] = 1e9*(m->dx - px);
            b->r[b->n][1] = 1e9*(m->dy - py);
            b->n++;
        }
        if (b->n < 2 || (b->pair = pair_index(pairs, n_pairs, rep[0].meas + i)) < 0)
            continue;
        b->group = rep[0].meas[i].group;
        (*n)++;
    }
    return blocks;
}

/* The residual's mean square split into what the block's channels share
 * and what they do not, averaged over the blocks. */
static void
split_mean_squares(const BlockResidual *blocks, gint n, ResidualSplit *rs)
{
    gdouble r2, d2, x, np;
    gint k, c, d;

    for (k = 0; k < n; k++) {
        const BlockResidual *b = blocks + k;

        r2 = d2 = x = 0.0;
        np = 0.5*b->n*(b->n - 1);
        for (c = 0; c < b->n; c++) {
            r2 += b->r[c][0]*b->r[c][0] + b->r[c][1]*b->r[c][1];
            for (d = c + 1; d < b->n; d++) {
                d2 += ((b->r[c][0] - b->r[d][0])*(b->r[c][0] - b->r[d][0])
                       + (b->r[c][1] - b->r[d][1])*(b->r[c][1] - b->r[d][1]));
                x += b->r[c][0]*b->r[d][0] + b->r[c][1]*b->r[d][1];
            }
        }
        rs->residual2 += r2/b->n/n;
        rs->noise2 += 0.5*d2/np/n;
        rs->shared2 += x/np/n;
    }
}

/* The shared part of each block (the mean of its channels' residuals)
 * against the block's place in the frame, one slope per axis common to
 * the pairs, an offset per pair (a pair's mean residual is the
 * trajectory's business).  A drift that repeats in every frame, or a
 * slow axis that misplaces lines, shows as such a slope; so does a drift
 * the model leaves that grows with time, such as an acceleration left to
 * a constant velocity. */
static void
shared_row_trend(const BlockResidual *blocks, gint n, gint n_pairs, ResidualSplit *rs)
{
    gdouble mean_g[MAX_PAIRS] = { 0 }, mean_s[2][MAX_PAIRS] = { { 0 } }, s[2], dg, sgg = 0.0;
    gdouble sgs[2] = { 0.0, 0.0 }, rss[2] = { 0.0, 0.0 }, e;
    gint count[MAX_PAIRS] = { 0 }, k, c, ax, dof = n - n_pairs - 1;

    for (k = 0; k < n; k++) {
        const BlockResidual *b = blocks + k;

        for (ax = 0; ax < 2; ax++) {
            for (c = 0, s[ax] = 0.0; c < b->n; c++)
                s[ax] += b->r[c][ax]/b->n;
            mean_s[ax][b->pair] += s[ax];
        }
        mean_g[b->pair] += b->group;
        count[b->pair]++;
    }
    for (k = 0; k < n_pairs; k++) {
        mean_g[k] /= MAX(count[k], 1);
        mean_s[0][k] /= MAX(count[k], 1);
        mean_s[1][k] /= MAX(count[k], 1);
    }
    for (k = 0; k < n; k++) {
        dg = blocks[k].group - mean_g[blocks[k].pair];
        sgg += dg*dg;
        for (ax = 0; ax < 2; ax++) {
            for (c = 0, s[ax] = 0.0; c < blocks[k].n; c++)
                s[ax] += blocks[k].r[c][ax]/blocks[k].n;
            sgs[ax] += dg*(s[ax] - mean_s[ax][blocks[k].pair]);
        }
    }
    for (ax = 0; ax < 2; ax++)
        rs->slope[ax] = (sgg > 0.0) ? sgs[ax]/sgg : NAN;
    for (k = 0; k < n && sgg > 0.0; k++) {
        dg = blocks[k].group - mean_g[blocks[k].pair];
        for (ax = 0; ax < 2; ax++) {
            for (c = 0, s[ax] = 0.0; c < blocks[k].n; c++)
                s[ax] += blocks[k].r[c][ax]/blocks[k].n;
            e = s[ax] - mean_s[ax][blocks[k].pair] - rs->slope[ax]*dg;
            rss[ax] += e*e;
        }
    }
    for (ax = 0; ax < 2; ax++)
        rs->slope_se[ax] = (sgg > 0.0 && dof > 0) ? sqrt(rss[ax]/dof/sgg) : NAN;
}

static void
split_residuals(const FitReport *rep, gint nc, gint model, ResidualSplit *rs)
{
    BlockResidual *blocks;

    memset(rs, 0, sizeof(ResidualSplit));
    blocks = collect_block_residuals(rep, nc, model, &rs->n_blocks, &rs->n_pairs);
    if (rs->n_blocks) {
        split_mean_squares(blocks, rs->n_blocks, rs);
        shared_row_trend(blocks, rs->n_blocks, rs->n_pairs, rs);
    }
    g_free(blocks);
}

/* Every channel measured and fitted as the study does, and the split
 * against each model type every channel fitted; *chosen gets the index
 * of the first channel's chosen model.  FALSE when a channel cannot be
 * loaded or fitted. */
static gboolean
channel_agreement(const SeriesSpec *spec, const gchar *measured,
                  const gchar *const *channels, ResidualSplit *splits,
                  gboolean *fitted, gint *n_models, gint *chosen, GError **error)
{
    FitReport rep[AGREEMENT_CHANNELS];
    FrameSeries *series;
    DisplacementOptions dopt;
    DriftFitOptions fopt;
    gint c, m, done = 0;
    gboolean ok = TRUE;

    memset(rep, 0, sizeof(rep));
    for (c = 0; c < AGREEMENT_CHANNELS && ok; c++, done++) {
        if (!(series = load_measured_series(spec, measured, channels[c], error)))
            ok = FALSE;
        else {
            study_options(series->frames, &dopt, &fopt);
            if (!(ok = fit_report_compute(series, &dopt, &fopt, rep + c)))
                g_set_error(error, FRAME_SERIES_ERROR, FRAME_SERIES_ERROR_CHANNEL,
                            "%s: no fit", channels[c]);
            frame_series_free(series);
        }
    }
    if (ok) {
        *n_models = rep[0].n_fits;
        *chosen = rep[0].chosen;
        for (m = 0; m < *n_models; m++) {
            for (c = 0, fitted[m] = TRUE; c < AGREEMENT_CHANNELS; c++)
                fitted[m] = fitted[m] && rep[c].fits[m].ok;
            if (fitted[m])
                split_residuals(rep, AGREEMENT_CHANNELS, m, splits + m);
            splits[m].type = rep[0].fits[m].type;
        }
    }
    for (c = 0; c < done; c++)
        fit_report_clear(rep + c);
    return ok;
}

/* How many standard errors the larger of a split's two slopes lies from 0
 * (0 where there is none). */
static gdouble
slope_z(const ResidualSplit *rs)
{
    gdouble z = 0.0;
    gint ax;

    for (ax = 0; ax < 2; ax++) {
        if (isfinite(rs->slope[ax]) && rs->slope_se[ax] > 0.0)
            z = MAX(z, fabs(rs->slope[ax])/rs->slope_se[ax]);
    }
    return z;
}

/* A model missing from the table is said to be so, and why: a table
 * that silently loses a row reads as if the model had been judged. */
static void
write_models_left_out(GString *md, const ResidualSplit *splits, const gboolean *fitted,
                      gint n_models)
{
    const gchar *sep = "\nNot in the table, not fitted in every channel (a period or time "
                       "constant outside what the channel's blocks can show): ";
    gint m;

    for (m = 0; m < n_models; m++) {
        if (fitted[m] && splits[m].n_blocks)
            continue;
        g_string_append_printf(md, "%s%s", sep, drift_model_type_name(splits[m].type));
        sep = ", ";
    }
    if (*sep == ',')
        g_string_append(md, ".\n");
}

static void
write_agreement_verdicts(GString *md, const ResidualSplit *splits, const gboolean *fitted,
                         gint n_models, gint chosen)
{
    const ResidualSplit *rs = splits + chosen;
    gint m, flat = -1;

    g_string_append_printf(md, "\nAgainst the model `simscan fit` chooses (%s), at least "
        "%.0f %% of the residual's mean square is the registration's own error (the part "
        "the channels do not share; errors they share, such as the same rims sampled at "
        "the same phase, count as shared).",
        drift_model_type_name(splits[chosen].type),
        100.0*rs->noise2/MAX(rs->residual2, 1e-300));
    for (m = 0; m < n_models; m++) {
        if (fitted[m] && slope_z(splits + m) < 3.0 && (flat < 0 || splits[m].shared2 < splits[flat].shared2))
            flat = m;
    }
    if (slope_z(rs) < 3.0)
        g_string_append(md, "  Its shared part shows no slope along the rows beyond 3 standard "
                        "errors.");
    else if (flat >= 0)
        g_string_append_printf(md, "  Its shared part changes with the row (beyond 3 standard "
            "errors), but not against %s (%.2f standard errors): a drift that changes over "
            "the series as that model does explains the slope as well as a drift that "
            "repeats in every frame.", drift_model_type_name(splits[flat].type),
            slope_z(splits + flat));
    else
        g_string_append(md, "  Its shared part changes with the row beyond 3 standard errors "
            "against every model: a drift that repeats in every frame (creep after each "
            "fly-back, seen because the content lies rows apart in the frames) or a slow "
            "axis that misplaces lines, which no model of the drift in time follows.");
    g_string_append(md, "  The slopes' standard errors take the blocks as independent; the "
                    "pairs share frames, so they are if anything too small.\n");
}

static void
write_channel_agreement(GString *md, const gchar *const *channels, const ResidualSplit *splits,
                        const gboolean *fitted, gint n_models, gint chosen, gint block_lines)
{
    gint m;

    g_string_append_printf(md, "\n**Residual against the measurement noise (fastscan-series).**  "
        "The channels %s, %s and %s of a FastScan frame are recorded on the same scan lines "
        "and share one drift.  Each is measured and fitted as above; where two channels or "
        "more keep a block, its residuals against one model (the same for every channel) "
        "split into what the channels share (the mean product of two channels' residuals) "
        "and what they do not (half the mean square of their difference).  The shared part "
        "of each block (the mean of its channels' residuals), with an offset per pair, is "
        "fitted one slope per axis along the rows (nm per block of %d lines).\n\n"
        "| model | blocks (pairs) | residual RMS (nm) | not shared (nm) | shared (nm) | "
        "slope x | slope y |\n|---|---|---|---|---|---|---|\n",
        channels[0], channels[1], channels[2], block_lines);
    for (m = 0; m < n_models; m++) {
        const ResidualSplit *rs = splits + m;

        if (!fitted[m] || !rs->n_blocks)
            continue;
        g_string_append_printf(md, "| %s%s | %d (%d) | %.3f | %.3f | %s%.3f | %.3f ± %.3f | "
                               "%.3f ± %.3f |\n",
                               drift_model_type_name(rs->type), m == chosen ? " (chosen)" : "",
                               rs->n_blocks, rs->n_pairs, sqrt(rs->residual2), sqrt(rs->noise2),
                               rs->shared2 < 0.0 ? "-" : "", sqrt(fabs(rs->shared2)),
                               rs->slope[0], rs->slope_se[0], rs->slope[1], rs->slope_se[1]);
    }
    write_models_left_out(md, splits, fitted, n_models);
    if (!splits[chosen].n_blocks) {
        g_string_append(md, "\nNo block is kept by two channels: the residual cannot be split.\n");
        return;
    }
    write_agreement_verdicts(md, splits, fitted, n_models, chosen);
}

/* ---- A simulated series on the measured particle film ---- */

#define SIM_FILE "particles-film/PTO_110_Virgin0001.gwy"
#define SIM_FRAMES 4
#define SIM_RES 128
#define SIM_LINE_TIME 1.0
#define SIM_FRAME_INTERVAL 160.0
#define SIM_NOISE 0.5e-9
/* The part of the sample scanned, leaving room for the drift. */
#define SIM_FIELD_FRACTION 0.6

/* The hidden effect: settling of the size hsafm-extra shows, relative to
 * the frame time. */
static void
sim_truth(DriftModel *truth)
{
    drift_model_init(truth, DRIFT_MODEL_SETTLING);
    truth->v[0] = 0.15e-9;
    truth->v[1] = -0.10e-9;
    truth->u[0] = 1.5e-9;
    truth->u[1] = 1.0e-9;
    truth->tau = 150.0;
}

static GwyDataField*
load_first_channel(const gchar *filename, gchar **title, GError **error)
{
    GwyContainer *data;
    GwyDataField *field = NULL;
    const guchar *s;

    if (!(data = gwy_file_load(filename, GWY_RUN_NONINTERACTIVE, error)))
        return NULL;
    if (gwy_container_gis_object_by_name(data, "/0/data", &field))
        g_object_ref(field);
    else
        g_set_error(error, FRAME_SERIES_ERROR, FRAME_SERIES_ERROR_CHANNEL,
                    "%s: no channel 0", filename);
    *title = g_strdup(gwy_container_gis_string_by_name(data, "/0/data/title",
                                                       &s)
                      ? (const gchar*)s : "channel 0");
    g_object_unref(data);
    return field;
}

/* SIM_FRAMES frames of the measured film under the truth's drift, scanned
 * down, back to back every SIM_FRAME_INTERVAL s. */
static FrameSeries*
simulate_particles_series(const gchar *measured, const DriftModel *truth,
                          gchar **what, GError **error)
{
    gchar *path = g_build_filename(measured, SIM_FILE, NULL), *title = NULL;
    GwyDataField *field = load_first_channel(path, &title, error);
    FrameSeries *series;
    SimSample *sample;
    SimScanParams sp;
    ScanTiming timing;
    gdouble xreal, yreal;
    gint k;

    g_free(path);
    if (!field) {
        g_free(title);
        return NULL;
    }
    sample = sim_sample_new_from_field(field);
    sim_sample_get_extent(sample, &xreal, &yreal);
    series = frame_series_new();
    for (k = 0; k < SIM_FRAMES; k++) {
        GwyDataField *frame;
        gchar *label = g_strdup_printf("simulated frame %d", k);

        sim_scan_params_init(&sp, sample, SIM_RES, SIM_RES);
        sp.xreal = SIM_FIELD_FRACTION*xreal;
        sp.yreal = SIM_FIELD_FRACTION*yreal;
        sp.xoff = 0.5*(1.0 - SIM_FIELD_FRACTION)*xreal;
        sp.yoff = 0.5*(1.0 - SIM_FIELD_FRACTION)*yreal;
        sp.line_time = SIM_LINE_TIME;
        sp.frame_start = k*SIM_FRAME_INTERVAL;
        sp.noise_rms = SIM_NOISE;
        sp.noise_seed = k + 1;
        frame = sim_scan_frame(sample, truth, &sp);
        sim_scan_params_timing(&sp, &timing);
        frame_series_append(series, frame, label, &timing);
        g_object_unref(frame);
        g_free(label);
    }
    *what = g_strdup_printf("%s, channel %s (%d x %d px, %.3g x %.3g um) "
                            "as simscan's sample; %d frames of %d x %d px "
                            "over its central %.3g x %.3g um, %.3g s per line, "
                            "one every %.0f s, noise %.2g nm",
                            SIM_FILE, title,
                            gwy_data_field_get_xres(field),
                            gwy_data_field_get_yres(field),
                            1e6*xreal, 1e6*yreal, SIM_FRAMES, SIM_RES,
                            SIM_RES, 1e6*sp.xreal, 1e6*sp.yreal,
                            SIM_LINE_TIME, SIM_FRAME_INTERVAL, 1e9*SIM_NOISE);
    sim_sample_free(sample);
    g_object_unref(field);
    g_free(title);
    return series;
}

/* RMS (nm, both axes) of a fit's trajectory against the truth's over the
 * scanned lines of the series; rounded: whole pixels (the paper model). */
static gdouble
trajectory_error(const FrameSeries *series, const DriftFit *fit,
                 const DriftModel *truth, gboolean rounded)
{
    gdouble xstep = frame_series_dx(series), ystep = frame_series_dy(series);
    gdouble sum = 0.0, px, py, tx, ty;
    gint k, r, m = 0;

    for (k = 0; k < series->n_frames; k++) {
        const ScanTiming *tm = &series->frames[k].timing;

        for (r = 0; r < tm->yres; r++) {
            gdouble t = scan_timing_pixel_time(tm, r, 0.5*tm->xres);

            drift_fit_eval(fit, t, &px, &py);
            if (rounded) {
                px = xstep*drift_px_round(px/xstep);
                py = ystep*drift_px_round(py/ystep);
            }
            drift_model_eval(truth, t, &tx, &ty);
            sum += 1e18*((px - tx)*(px - tx) + (py - ty)*(py - ty));
            m += 2;
        }
    }
    return m ? sqrt(sum/m) : NAN;
}

/* ---- The document ---- */

/* The apparent velocity of consecutive pair k-1, k (nm/s): the mean over
 * its used blocks of displacement over time difference, weighted; t_mid
 * the blocks' mean time, used their count.  FALSE without a used block. */
static gboolean
pair_velocity(const FitReport *rep, gint k, gdouble *v, gdouble *t_mid,
              gint *used)
{
    gdouble sx = 0, sy = 0, st = 0, sw = 0;
    gint i;

    *used = 0;
    for (i = 0; i < rep->n_meas; i++) {
        const DriftMeasurement *m = rep->meas + i;
        gdouble dt = m->t_a - m->t_b;

        if (m->frame_a != k || m->frame_b != k-1 || !(m->weight > 0.0))
            continue;
        sx += m->weight*1e9*m->dx/dt;
        sy += m->weight*1e9*m->dy/dt;
        st += m->weight*0.5*(m->t_a + m->t_b);
        sw += m->weight;
        (*used)++;
    }
    if (!(sw > 0))
        return FALSE;
    v[0] = sx/sw;
    v[1] = sy/sw;
    *t_mid = st/sw;
    return TRUE;
}

static void
write_pair_velocities(GString *md, const SeriesResult *res)
{
    gdouble v[2], t_mid;
    gint k, used;

    g_string_append(md, "\n| frames | mid time (s) | apparent v_x (nm/s) | "
                    "apparent v_y (nm/s) | blocks used |\n|---|---|---|---|---|\n");
    for (k = 1; k < res->series->n_frames; k++) {
        if (pair_velocity(&res->report, k, v, &t_mid, &used))
            g_string_append_printf(md, "| %d-%d | %.1f | %.4f | %.4f | %d |\n",
                                   k-1, k, t_mid, v[0], v[1], used);
    }
}

/* Where the paper model departs from the measurement: its residuals (and
 * the extension's) over the blocks of each later frame.  In-sample: the
 * held-out errors are in the text above the table. */
static void
write_departures(GString *md, const SeriesResult *res)
{
    const FitReport *rep = &res->report;
    const DriftFit *none = rep->fits, *ext = rep->fits + res->extended;
    gdouble xstep = frame_series_dx(res->series);
    gdouble ystep = frame_series_dy(res->series);
    gint k, i;

    g_string_append_printf(md, "\nWhere the paper model departs: residual "
                           "(measured - predicted) of the blocks of each "
                           "later frame, mean and RMS, nm (fitted to all "
                           "blocks):\n\n| later frame | scan time (s) | "
                           "blocks | paper mean (x, y) | paper RMS | "
                           "%s mean (x, y) | %s RMS |\n"
                           "|---|---|---|---|---|---|---|\n",
                           drift_model_type_name(ext->type),
                           drift_model_type_name(ext->type));
    for (k = 1; k < res->series->n_frames; k++) {
        gdouble sum[2][3], d[2], md_[2];
        const ScanTiming *tm = &res->series->frames[k].timing;
        gint used = 0, ax, mdl;

        memset(sum, 0, sizeof(sum));
        for (i = 0; i < rep->n_meas; i++) {
            const DriftMeasurement *m = rep->meas + i;

            if (m->frame_a != k || !(m->weight > 0.0))
                continue;
            md_[0] = 1e9*m->dx;
            md_[1] = 1e9*m->dy;
            for (mdl = 0; mdl < 2; mdl++) {
                if (mdl)
                    drift_fit_predict(ext, m, d, d + 1);
                else
                    paper_predict(none, m, xstep, ystep, d, d + 1);
                for (ax = 0; ax < 2; ax++) {
                    gdouble r = md_[ax] - 1e9*d[ax];

                    sum[mdl][ax] += r;
                    sum[mdl][2] += r*r;
                }
            }
            used++;
        }
        if (!used)
            continue;
        g_string_append_printf(md, "| %d | %.4g-%.4g | %d | (%.2f, %.2f) | "
                               "%.3f | (%.2f, %.2f) | %.3f |\n", k,
                               tm->frame_start, scan_timing_frame_end(tm),
                               used, sum[0][0]/used, sum[0][1]/used,
                               sqrt(sum[0][2]/(2*used)), sum[1][0]/used,
                               sum[1][1]/used, sqrt(sum[1][2]/(2*used)));
    }
}

/* What was loaded, from the frames themselves. */
static void
write_series_facts(GString *md, const SeriesSpec *spec,
                   const SeriesResult *res)
{
    const FrameSeries *series = res->series;
    const SeriesFrame *f0 = series->frames;
    const SeriesFrame *last = series->frames + series->n_frames - 1;
    gdouble dx = frame_series_dx(series), dy = frame_series_dy(series);
    gdouble scan = scan_timing_frame_end(&f0->timing) - f0->timing.frame_start;

    g_string_append_printf(md, "%s, %s%s%s; frames of %d x %d px, %.4g x %.4g nm "
                           "(pixels %.3g x %.3g nm), %.3g s of scanning each, "
                           "started over %.4g s.",
                           spec->what, f0->label,
                           spec->channel ? ", channel " : "",
                           spec->channel ? spec->channel : "",
                           f0->timing.xres,
                           f0->timing.yres, 1e9*dx*f0->timing.xres,
                           1e9*dy*f0->timing.yres, 1e9*dx, 1e9*dy, scan,
                           last->timing.frame_start);
}

static void
write_series(GString *md, const SeriesSpec *spec, const SeriesResult *res)
{
    const FitReport *rep = &res->report;
    const DriftFit *chosen = rep->fits + MAX(rep->chosen, 0);
    DriftFitParameters p;
    gint i, used = 0;

    for (i = 0; i < rep->n_meas; i++)
        used += (rep->meas[i].weight > 0.0);
    drift_fit_parameters(chosen, &p);
    g_string_append_printf(md, "\n## %s\n\n", spec->name);
    write_series_facts(md, spec, res);
    g_string_append_printf(md, "  %d frames kept", res->series->n_frames);
    for (i = 0; i < (gint)res->series->notes->len; i++)
        g_string_append_printf(md, "; %s",
                               (gchar*)g_ptr_array_index(res->series->notes, i));
    g_string_append_printf(md, ".  Frame starts (s):");
    for (i = 0; i < res->series->n_frames; i++)
        g_string_append_printf(md, " %.2f", res->series->frames[i].timing.frame_start);
    g_string_append_printf(md, "; line time %.4g s.  %d block measurements, "
                           "%d used.  Shortest period or time constant "
                           "searched: %.3g s (%.3g blocks' scan time, "
                           "drift_fit_min_period).\n\n",
                           res->series->frames[0].timing.line_time,
                           rep->n_meas, used, rep->fit_options.min_period,
                           rep->fit_options.min_period
                           /(res->series->frames[0].timing.line_time
                             *res->series->frames[0].timing.yres
                             /N_BLOCKS));
    g_string_append_printf(md, "`simscan fit` chooses **%s** (its "
                           "velocity (%.4f, %.4f) nm/s).\n\n",
                           drift_model_type_name(chosen->type),
                           p.velocity_nm_per_s[0], p.velocity_nm_per_s[1]);
    g_string_append(md, "| model | params | fit RMS (nm) | held-out RMS (nm) | BIC |"
                    " parameters |\n|---|---|---|---|---|---|\n");
    for (i = 0; i < rep->n_fits; i++) {
        const DriftFit *f = rep->fits + i;
        DriftFitParameters q;
        gchar *par;

        if (!f->ok) {
            g_string_append_printf(md, "| %s | - | - | - | - | not fitted: no "
                                   "observable period |\n",
                                   drift_model_type_name(f->type));
            continue;
        }
        drift_fit_parameters(f, &q);
        switch (f->type) {
            case DRIFT_MODEL_SETTLING:
            par = g_strdup_printf("tau %.4g s, u (%.3g, %.3g) nm/s", q.tau_s,
                                  q.u_nm_per_s[0], q.u_nm_per_s[1]);
            break;
            case DRIFT_MODEL_OSCILLATION:
            par = g_strdup_printf("period %.4g s, a (%.3g, %.3g) nm", q.period_s,
                                  q.amplitude_nm[0], q.amplitude_nm[1]);
            break;
            case DRIFT_MODEL_JUMP:
            par = g_strdup_printf("t %.4g s, step (%.3g, %.3g) nm", q.t_s,
                                  q.step_nm[0], q.step_nm[1]);
            break;
            default:
            par = g_strdup_printf("v (%.4f, %.4f) nm/s", q.velocity_nm_per_s[0],
                                  q.velocity_nm_per_s[1]);
            break;
        }
        g_string_append_printf(md, "| %s | %d | %.3f | %.3f | %.1f | %s |\n",
                               drift_model_type_name(f->type), f->n_params,
                               f->rms_nm, f->cv_rms_nm, f->bic, par);
        g_free(par);
    }
    g_string_append_printf(md, "\nPrediction error of the measured displacements "
                           "(%d-fold over blocks, never on the data fitted): paper "
                           "model **%.3f nm**, constant velocity without "
                           "rounding %.3f nm, %s model **%.3f nm**.\n",
                           rep->fit_options.n_folds, res->cv_paper, res->cv_none,
                           drift_model_type_name(rep->fits[res->extended].type),
                           res->cv_ext);
    g_string_append_printf(md, "Alignment of consecutive frames (normalised "
                           "correlation over the overlap, mean over pairs): raw "
                           "%.4f, paper-compensated %.4f, %s-compensated ",
                           res->ncc_raw, res->ncc_paper,
                           drift_model_type_name(rep->fits[res->extended].type));
    /* The compensation refuses a drift that folds the frames over. */
    if (isfinite(res->ncc_ext))
        g_string_append_printf(md, "%.4f.\n", res->ncc_ext);
    else
        g_string_append(md, "none (the fitted drift is too fast to "
                        "compensate: it would fold the frames over).\n");
    g_string_append(md, "\nThe drift as the data show it: apparent velocity "
                    "of each consecutive pair (mean of its blocks' "
                    "displacement over their time difference):\n");
    write_pair_velocities(md, res);
    write_departures(md, res);
    g_string_append_printf(md, "\n![displacements](%s)\n\n![alignment](%s)\n",
                           res->plot, res->images);
}

static const DriftFit*
fit_of_type(const FitReport *rep, DriftModelType type)
{
    gint i;

    for (i = 0; i < rep->n_fits; i++) {
        if (rep->fits[i].type == type)
            return rep->fits + i;
    }
    return rep->fits;
}

/* Why simscan fit's selection (drift_fit_select) did not name this effect,
 * by its criteria in order; NULL when it passes them all. */
static gchar*
rejection_reason(const FitReport *rep, const DriftFit *none, const DriftFit *f)
{
    const DriftFitOptions *o = &rep->fit_options;
    gdouble explained;

    if (!f->ok)
        return g_strdup("no period is observable in this series");
    if (f->type == DRIFT_MODEL_OSCILLATION && f->at_limit > 0)
        return g_strdup_printf("its best period, %.3g s, is the longest "
                               "observable one: it bends the trajectory, "
                               "it does not repeat", f->nonlinear);
    if (none->bic - f->bic < o->bic_margin)
        return g_strdup_printf("BIC %.1f against %.1f, not %g lower",
                               f->bic, none->bic, o->bic_margin);
    if (!(f->cv_rms_nm < (1.0 - o->cv_gain)*none->cv_rms_nm))
        return g_strdup_printf("held-out error %.3f nm against %.3f nm, not "
                               "%.0f %% lower", f->cv_rms_nm, none->cv_rms_nm,
                               100.0*o->cv_gain);
    explained = sqrt(MAX(none->rms_nm*none->rms_nm - f->rms_nm*f->rms_nm, 0.0));
    if (explained < o->min_explained*f->rms_nm)
        return g_strdup_printf("it explains %.3f nm beyond constant velocity, "
                               "less than %g times its residual %.3f nm",
                               explained, o->min_explained, f->rms_nm);
    return NULL;
}

static void
append_effect(GString *md, const FitReport *rep, const DriftFit *none,
              const DriftFit *f, const DriftFit *chosen)
{
    gchar *why;

    g_string_append_printf(md, "%s", drift_model_type_name(f->type));
    if (f->ok) {
        g_string_append_printf(md, " %.3f nm", f->cv_rms_nm);
        if (f->type == DRIFT_MODEL_SETTLING)
            g_string_append_printf(md, " (tau %.3g s)", f->nonlinear);
        else if (f->type == DRIFT_MODEL_OSCILLATION)
            g_string_append_printf(md, " (period %.3g s)", f->nonlinear);
        else if (f->type == DRIFT_MODEL_JUMP)
            g_string_append_printf(md, " (t_s %.4g s)", f->nonlinear);
    }
    if (!f->ok)
        g_string_append(md, " not fitted: no period is observable");
    else if (f == chosen)
        g_string_append(md, ", named");
    else if ((why = rejection_reason(rep, none, f))) {
        g_string_append_printf(md, ", not named: %s", why);
        g_free(why);
    }
    else
        g_string_append_printf(md, ", passes but has a higher BIC (%.1f) "
                               "than %s", f->bic,
                               drift_model_type_name(chosen->type));
}

/* One data-driven paragraph per series: the held-out error of each model,
 * what simscan fit named, and why each other effect was not named. */
static void
write_finding(GString *md, const SeriesSpec *spec, const SeriesResult *res)
{
    const FitReport *rep = &res->report;
    const DriftFit *none = fit_of_type(rep, DRIFT_MODEL_NONE);
    const DriftFit *chosen = rep->fits + MAX(rep->chosen, 0);
    const SeriesFrame *last = res->series->frames + res->series->n_frames - 1;
    gdouble span = scan_timing_frame_end(&last->timing), lo, hi;
    gint i;

    g_string_append_printf(md, "- **%s** (%.3g s): ", spec->name, span);
    if (chosen->type == DRIFT_MODEL_NONE)
        g_string_append(md, "constant velocity is enough for `simscan fit`.");
    else
        g_string_append_printf(md, "the velocity is not constant: `simscan "
                               "fit` names **%s**.",
                               drift_model_type_name(chosen->type));
    g_string_append_printf(md, "  Held-out error: constant velocity %.3f nm "
                           "(paper model %.3f nm)", none->cv_rms_nm,
                           res->cv_paper);
    for (i = 0; i < rep->n_fits; i++) {
        if (rep->fits + i == none)
            continue;
        g_string_append(md, "; ");
        append_effect(md, rep, none, rep->fits + i, chosen);
    }
    g_string_append(md, ".");
    if (drift_fit_observable_periods(rep->meas, rep->n_meas, &rep->fit_options,
                                     &lo, &hi))
        g_string_append_printf(md, "  Observable oscillation periods: %.3g to "
                               "%.3g s.", lo, hi);
    else
        g_string_append_printf(md, "  No oscillation period is observable: "
                               "%g cycles over the series would be shorter "
                               "than twice its longest gap between measured "
                               "times.", rep->fit_options.min_cycles);
    g_string_append(md, "\n");
}

/* The apparent velocity of the first and the last consecutive pair (nm/s);
 * FALSE without two pairs. */
static gboolean
pair_velocity_trend(const SeriesResult *res, gdouble *first, gdouble *last)
{
    gdouble v[2], t_mid;
    gint k, used, found = 0;

    for (k = 1; k < res->series->n_frames; k++) {
        if (!pair_velocity(&res->report, k, v, &t_mid, &used))
            continue;
        if (!found++) {
            first[0] = v[0];
            first[1] = v[1];
        }
        last[0] = v[0];
        last[1] = v[1];
    }
    return found >= 2;
}

/* What the paper model's whole pixels cost in held-out error, against the
 * same constant velocity unrounded, at most over the series. */
static void
write_rounding_cost(GString *md, const SeriesResult *results, gint n)
{
    gdouble worst = -G_MAXDOUBLE, gap = 0.0;
    const gchar *where = NULL;
    gint i;

    for (i = 0; i < n; i++) {
        gdouble cost;

        if (!results[i].series)
            continue;
        cost = results[i].cv_paper/results[i].cv_none - 1.0;
        if (cost > worst) {
            worst = cost;
            where = results[i].name;
            gap = results[i].cv_none/results[i].cv_ext - 1.0;
        }
    }
    if (where)
        g_string_append_printf(md, "The whole-pixel rounding of the paper "
                               "model costs at most %.1f %% of held-out "
                               "error (%s), where constant velocity itself "
                               "is %.0f %% worse than settling.", 100.0*worst,
                               where, 100.0*gap);
}

/* The cause, from the numbers of the series whose named effect is not
 * constant velocity. */
static void
write_cause(GString *md, const SeriesSpec *specs, const SeriesResult *results,
            gint n)
{
    gint i, count = 0, oscillations = 0;

    g_string_append(md, "\n**Cause.**  ");
    for (i = 0; i < n; i++) {
        const FitReport *rep = &results[i].report;
        const DriftFit *chosen, *settle, *jump, *none;
        gdouble v0[2], v1[2];

        if (!results[i].series || rep->chosen < 0)
            continue;
        chosen = rep->fits + rep->chosen;
        oscillations += (chosen->type == DRIFT_MODEL_OSCILLATION);
        if (chosen->type == DRIFT_MODEL_NONE)
            continue;
        none = fit_of_type(rep, DRIFT_MODEL_NONE);
        settle = fit_of_type(rep, DRIFT_MODEL_SETTLING);
        jump = fit_of_type(rep, DRIFT_MODEL_JUMP);
        count++;
        g_string_append_printf(md, "In %s the named effect is %s, which "
                               "predicts held-out blocks %.0f %% better than "
                               "constant velocity.", specs[i].name,
                               drift_model_type_name(chosen->type),
                               100.0*(1.0 - chosen->cv_rms_nm/none->cv_rms_nm));
        if (pair_velocity_trend(results + i, v0, v1))
            g_string_append_printf(md, "  The apparent velocity of "
                                   "consecutive frames goes from (%.3f, %.3f) "
                                   "to (%.3f, %.3f) nm/s over the series.",
                                   v0[0], v0[1], v1[0], v1[1]);
        if (chosen->type == DRIFT_MODEL_SETTLING && jump->ok) {
            if (jump->cv_rms_nm > 1.25*settle->cv_rms_nm)
                g_string_append_printf(md, "  A jump is ruled out: its "
                                       "held-out error is %.1f times "
                                       "settling's.",
                                       jump->cv_rms_nm/settle->cv_rms_nm);
            else
                g_string_append_printf(md, "  A jump (at %.4g s) predicts "
                                       "nearly as well (%.3f against %.3f "
                                       "nm): these frames cannot tell a "
                                       "sudden step in a gap from a smooth "
                                       "change.", jump->nonlinear,
                                       jump->cv_rms_nm, settle->cv_rms_nm);
        }
        if (chosen->type == DRIFT_MODEL_SETTLING && settle->at_limit > 0)
            g_string_append_printf(md, "  Its tau (%.3g s) is the longest "
                                   "searched: over the series the velocity "
                                   "changes at an almost constant rate, "
                                   "(%.3g, %.3g) nm/s^2.", settle->nonlinear,
                                   -settle->coef[0][1]/settle->nonlinear,
                                   -settle->coef[1][1]/settle->nonlinear);
        g_string_append(md, "  ");
    }
    if (!count)
        g_string_append(md, "No series departs from constant velocity by "
                        "`simscan fit`'s criteria.  ");
    if (count)
        g_string_append(md, "A velocity that changes smoothly during the "
                        "series (settling: thermal or piezo creep after the "
                        "scan or stage was set up) is what the paper model "
                        "(one constant velocity) misses there.  ");
    g_string_append_printf(md, "%s the periods it can observe.  ",
                    oscillations ? "An oscillation is named in some series within"
                    : "No series shows an oscillation that `simscan fit` "
                      "accepts within");
    write_rounding_cost(md, results, n);
    g_string_append(md, "\n");
}

/* The settings of the run, as the registration and the fit use them. */
static void
write_header(GString *md)
{
    DisplacementOptions dopt;
    DriftFitOptions fopt;

    study_options(NULL, &dopt, &fopt);
    g_string_append_printf(md, "# Validation of the drift model on measured "
        "AFM data\n\n"
        "Generated by `make validation` (docs/validation-study.c); do not "
        "edit: every number below comes from that run.\n"
        "Each series is cut into %d blocks of lines per frame; every block of "
        "every frame is registered against every earlier frame with the "
        "project's stripe registration (modules/core/stripe-registration.c: "
        "zero-mean normalised cross-correlation over the overlap, searched "
        "around the frame's overall shift, chained across frames, on frames "
        "conditioned as the registration conditions raw channels; a block "
        "counts only when its peak stands clear of rival peaks and "
        "correlates at least %.2g), which measures p(t_a) - p(t_b) at the "
        "two scan times of its content (conventions.md).  All "
        "models are fitted to all measurements of a series at once, after "
        "gross outliers (beyond %g robust sigmas) are dropped; held-out "
        "errors are %d-fold cross-validated over the blocks.  `simscan fit` "
        "names an effect only when it beats constant velocity by %g in BIC, "
        "predicts held-out blocks %.0f %% better and explains %g times its "
        "own residual, and an oscillation only with a period it can "
        "observe: at least %g cycles over the measured time span, no shorter "
        "than twice the longest gap between measured times, not cancelling "
        "between frames, and not the longest such period.\n\n"
        "The paper model is constant velocity fitted to the same "
        "measurements, applied as one whole-pixel drift per block of lines; "
        "the extended model is simscan's settling drift "
        "p' = v + u exp(-t/tau), continuous and sub-pixel.  Frames are "
        "compensated by the product's own code: paper mode "
        "(paper_compensate, drift rounded by drift_px_round) and "
        "continuous mode (continuous_compensate_trajectory with the "
        "module's sub-pixel B-spline interpolation).\n",
        dopt.n_blocks, dopt.min_score,
        fopt.outlier_sigmas, fopt.n_folds, fopt.bic_margin,
        100.0*fopt.cv_gain, fopt.min_explained, fopt.min_cycles);
}

static void
write_simulation(GString *md, const SeriesResult *res, const gchar *what,
                 const DriftModel *truth)
{
    const FitReport *rep = &res->report;
    const DriftFit *chosen = rep->fits + MAX(rep->chosen, 0);
    const DriftFit *none = fit_of_type(rep, DRIFT_MODEL_NONE);
    const DriftFit *ext = rep->fits + res->extended;
    DriftFitParameters p;
    gint i, used = 0;

    for (i = 0; i < rep->n_meas; i++)
        used += (rep->meas[i].weight > 0.0);
    drift_fit_parameters(ext, &p);
    g_string_append_printf(md, "\n## particles-film: a simulated series on "
        "the measured sample\n\nThe measured particle film serves as the "
        "sample of simscan: %s.  The drift hidden in the frames is "
        "simscan's settling model with v (%.3g, %.3g) nm/s, u (%.3g, %.3g) "
        "nm/s, tau %.4g s.  The frames go through the same pipeline as the "
        "measured series, blind (the fit knows only the frames and their "
        "timing).  %d block measurements, %d used.\n\n",
        what, 1e9*truth->v[0], 1e9*truth->v[1], 1e9*truth->u[0],
        1e9*truth->u[1], truth->tau, rep->n_meas, used);
    g_string_append_printf(md, "`simscan fit` names **%s**.  Its settling "
        "fit: tau %.4g s (hidden %.4g s), u (%.3g, %.3g) nm/s (hidden "
        "(%.3g, %.3g)), v (%.3g, %.3g) nm/s (hidden (%.3g, %.3g)).\n\n",
        drift_model_type_name(chosen->type), p.tau_s, truth->tau,
        p.u_nm_per_s[0], p.u_nm_per_s[1], 1e9*truth->u[0], 1e9*truth->u[1],
        p.velocity_nm_per_s[0], p.velocity_nm_per_s[1], 1e9*truth->v[0],
        1e9*truth->v[1]);
    g_string_append_printf(md, "| model | held-out RMS of the displacements "
        "(nm) | RMS of the trajectory against the hidden one (nm) | "
        "alignment of consecutive frames |\n|---|---|---|---|\n"
        "| none (raw frames) | - | - | %.4f |\n"
        "| paper model | %.3f | %.3f | %.4f |\n"
        "| constant velocity, unrounded | %.3f | %.3f | - |\n"
        "| %s | %.3f | %.3f | %.4f |\n",
        res->ncc_raw, res->cv_paper,
        trajectory_error(res->series, none, truth, TRUE), res->ncc_paper,
        res->cv_none, trajectory_error(res->series, none, truth, FALSE),
        drift_model_type_name(ext->type), res->cv_ext,
        trajectory_error(res->series, ext, truth, FALSE), res->ncc_ext);
    g_string_append_printf(md, "\n![displacements](%s)\n\n![alignment](%s)\n",
                           res->plot, res->images);
}

/* The creep forms against settling: their held-out errors, and whether
 * any gains enough over settling to be worth a model of its own. */
static void
write_creep_forms(GString *md, const SeriesResult *results, gint n)
{
    gdouble best_gain = -G_MAXDOUBLE, worst_gain = G_MAXDOUBLE, cv_gain = 0.1;
    const gchar *best_name = NULL, *worst_name = NULL;
    gint i, j;

    g_string_append(md, "\nSlow creep was tried as a further candidate, "
        "fitted and held out exactly like the models above "
        "(drift_fit_creep, drift_fit_cross_validate): constant acceleration "
        "(p = v t + b t^2, one parameter less than settling per axis) and "
        "logarithmic creep (p = v t + c t0 log(1 + t/t0)).  Held-out RMS "
        "(nm):\n\n| series | constant velocity | settling | constant "
        "acceleration | logarithmic creep |\n|---|---|---|---|---|\n");
    for (i = 0; i < n; i++) {
        const SeriesResult *res = results + i;

        if (!res->series)
            continue;
        cv_gain = res->report.fit_options.cv_gain;
        g_string_append_printf(md, "| %s | %.3f | %.3f | %.3f | %.3f |\n",
                               res->name, res->cv_none, res->cv_settling,
                               res->creep[0].cv_rms_nm,
                               res->creep[1].cv_rms_nm);
        for (j = 0; j < 2; j++) {
            gdouble gain = 1.0 - res->creep[j].cv_rms_nm/res->cv_settling;

            if (!isfinite(gain))
                continue;
            if (gain > best_gain) {
                best_gain = gain;
                best_name = res->name;
            }
            if (gain < worst_gain) {
                worst_gain = gain;
                worst_name = res->name;
            }
        }
    }
    if (!best_name)
        return;
    g_string_append_printf(md, "\nAgainst settling, the better creep form "
        "gains at most %.1f %% of held-out error (%s) and loses up to "
        "%.1f %% (%s).  ", 100.0*best_gain, best_name, -100.0*worst_gain,
        worst_name);
    if (best_gain < cv_gain)
        g_string_append_printf(md, "That is less than the %.0f %% an effect "
            "must gain over constant velocity to be named, so neither form "
            "is among `simscan fit`'s models.", 100.0*cv_gain);
    else
        g_string_append_printf(md, "That exceeds the %.0f %% an effect must "
            "gain over constant velocity to be named: the creep form "
            "deserves a model of its own in simscan.", 100.0*cv_gain);
    for (i = 0; i < n; i++) {
        const DriftFit *settle;

        if (!results[i].series)
            continue;
        settle = fit_of_type(&results[i].report, DRIFT_MODEL_SETTLING);
        if (settle->ok && settle->at_limit > 0)
            g_string_append_printf(md, "  In %s settling's tau (%.3g s) is "
                "the longest searched, %.1f times the series' duration: there it "
                "acts as constant acceleration (held-out %.3f against "
                "%.3f nm).", results[i].name, settle->nonlinear,
                settle->nonlinear/scan_timing_frame_end(
                    &results[i].series->frames[results[i].series->n_frames
                                               - 1].timing),
                results[i].creep[0].cv_rms_nm, results[i].cv_settling);
    }
    g_string_append(md, "\n");
}

static void
write_triangles(GString *md, const RegistrationTriangle *tri, gint n)
{
    gint i, zsensor = -1, phase = -1;

    g_string_append(md, "  Registration of the FastScan series uses the "
        "Phase channel.  Three frames must close: frame 2 against 0 equals "
        "(2 against 1) + (1 against 0).  Registered as the study does "
        "(consecutive pairs searched blind, 2 against 0 around the sum of "
        "their whole-frame shifts), the misclosure in px (median of |2-0 "
        "minus (2-1 + 1-0)| over the blocks accepted in all three pairs; "
        "the whole-frame shifts' misclosure in brackets) is:");
    for (i = 0; i < n; i++) {
        if (!tri[i].channel)
            continue;
        g_string_append_printf(md, " %s %.2f in x, %.2f in y over %d "
                               "of %d blocks (%.2f, %.2f);",
                               tri[i].channel, tri[i].median[0],
                               tri[i].median[1], tri[i].n_blocks, N_BLOCKS,
                               tri[i].whole[0], tri[i].whole[1]);
        if (g_str_equal(tri[i].channel, "ZSensor"))
            zsensor = i;
        if (g_str_equal(tri[i].channel, "Phase"))
            phase = i;
    }
    g_string_truncate(md, md->len - 1);
    g_string_append(md, ".");
    if (zsensor >= 0 && phase >= 0) {
        gdouble mz = MAX(tri[zsensor].median[0], tri[zsensor].median[1]);
        gdouble mp = MAX(tri[phase].median[0], tri[phase].median[1]);
        gdouble wz = MAX(fabs(tri[zsensor].whole[0]),
                         fabs(tri[zsensor].whole[1]));
        gdouble wp = MAX(fabs(tri[phase].whole[0]),
                         fabs(tri[phase].whole[1]));

        if (tri[zsensor].n_blocks < tri[phase].n_blocks || mz > mp
            || wz > wp)
            g_string_append(md, "  ZSensor closes worse or keeps fewer "
                            "blocks than Phase: hence Phase.");
        else
            g_string_append(md, "  ZSensor closes as well as Phase here; "
                            "Phase is kept for its sharper blobs.");
    }
    g_string_append(md, "\n");
}

static gchar*
read_text(const gchar *path)
{
    gchar *text = NULL;

    if (path && g_file_get_contents(path, &text, NULL, NULL))
        return text;
    return g_strdup("(not generated: run `make validation`)\n");
}

static void
series_result_free(SeriesResult *res)
{
    if (!res->series)
        return;
    fit_report_clear(&res->report);
    frame_series_free(res->series);
    g_free(res->plot);
    g_free(res->images);
}

int
main(int argc, char **argv)
{
    static const gchar *triangle_channels[] = { "ZSensor", "Phase" };
    static const gchar *const agreement_channels[AGREEMENT_CHANNELS] = {
        "ZSensor", "AmplitudeActual", "Phase"
    };
    ResidualSplit splits[FIT_REPORT_MAX_MODELS];
    gboolean split_fitted[FIT_REPORT_MAX_MODELS];
    gint n_models = 0, chosen = 0;
    const gchar *measured = argc > 1 ? argv[1] : "../shared/data/measured";
    const gchar *docdir = argc > 2 ? argv[2] : "docs";
    gchar *figdir = g_build_filename(docdir, "figures", NULL);
    gchar *out = g_build_filename(docdir, "validation.md", NULL);
    gchar *confusion = read_text(argc > 3 ? argv[3] : NULL);
    SeriesResult results[G_N_ELEMENTS(specs)], sim;
    RegistrationTriangle tri[G_N_ELEMENTS(triangle_channels)];
    DriftModel truth;
    GString *md = g_string_new(NULL);
    GError *error = NULL;
    gchar *sim_what = NULL;
    guint i;

    gwy_app_init_nongui("enable-threads", FALSE, NULL);
    g_mkdir_with_parents(figdir, 0755);
    if (!g_file_test(measured, G_FILE_TEST_IS_DIR)) {
        g_printerr("validation-study: %s: no measured data there\n", measured);
        return 1;
    }
    write_header(md);
    for (i = 0; i < G_N_ELEMENTS(specs); i++) {
        if (!study_series(specs + i, measured, docdir, results + i, &error)) {
            g_printerr("validation-study: %s: %s\n", specs[i].name,
                       error->message);
            g_clear_error(&error);
            results[i].series = NULL;
            continue;
        }
        write_series(md, specs + i, results + i);
        fprintf(stderr, "%s done\n", specs[i].name);
    }
    memset(&sim, 0, sizeof(sim));
    sim.name = "particles-film-simulated";
    sim_truth(&truth);
    if ((sim.series = simulate_particles_series(measured, &truth, &sim_what,
                                                &error))) {
        analyse_series(&sim, docdir);
        write_simulation(md, &sim, sim_what, &truth);
        fprintf(stderr, "%s done\n", sim.name);
    }
    else {
        g_printerr("validation-study: particles-film: %s\n", error->message);
        g_clear_error(&error);
    }
    g_string_append(md, "\n## Findings\n\n");
    for (i = 0; i < G_N_ELEMENTS(specs); i++) {
        if (results[i].series)
            write_finding(md, specs + i, results + i);
    }
    write_cause(md, specs, results, G_N_ELEMENTS(specs));
    g_string_append(md, "\n"
        "**Extension.**  The settling term p' = v + u exp(-t/tau) is already "
        "one of simscan's drift models (DRIFT_MODEL_SETTLING), so no new "
        "model type was needed; what the paper mode lacks is using it.  The "
        "gain is in the tables: held-out prediction error and the alignment "
        "of compensated consecutive frames, paper model against the settling "
        "model (continuous, sub-pixel, per line)");
    if (sim.series)
        g_string_append(md, "; the simulated particles-film series shows "
                        "that the pipeline finds a known settling back on a "
                        "real surface");
    g_string_append(md, ".\n");
    write_creep_forms(md, results, G_N_ELEMENTS(specs));
    g_string_append(md, "\n"
        "**Limits.**  A drift component with a whole number of cycles per "
        "frame interval repeats identically in every frame and cancels in "
        "every frame-to-frame measurement: no frame series can see it "
        "(`simscan fit` does not search such periods and the hidden-effect "
        "tests do not draw them).  For the "
        "HS-AFM series the slow-scan direction is not in the metadata and is "
        "taken as down; for the Anasys series the time stamp is taken as the "
        "end of each frame.");
    for (i = 0; i < G_N_ELEMENTS(triangle_channels); i++) {
        if (!registration_triangle(specs + 0, measured, triangle_channels[i],
                                   tri + i, &error)) {
            g_printerr("validation-study: %s: %s\n", triangle_channels[i],
                       error->message);
            g_clear_error(&error);
            tri[i].channel = NULL;
        }
    }
    write_triangles(md, tri, G_N_ELEMENTS(triangle_channels));
    if (channel_agreement(specs + 0, measured, agreement_channels, splits, split_fitted,
                          &n_models, &chosen, &error)) {
        if (results[0].series)
            write_channel_agreement(md, agreement_channels, splits, split_fitted, n_models,
                                    chosen, results[0].series->frames[0].timing.yres/N_BLOCKS);
    }
    else {
        g_printerr("validation-study: channel agreement: %s\n", error->message);
        g_clear_error(&error);
    }
    g_string_append(md, "\n## Effects hidden in simulated series "
                    "(bench/bench-effect-confusion)\n\n");
    g_string_append(md, confusion);
    if (!g_file_set_contents(out, md->str, -1, &error)) {
        g_printerr("validation-study: %s\n", error->message);
        return 1;
    }
    for (i = 0; i < G_N_ELEMENTS(specs); i++)
        series_result_free(results + i);
    series_result_free(&sim);
    g_string_free(md, TRUE);
    g_free(sim_what);
    g_free(confusion);
    g_free(figdir);
    g_free(out);
    return 0;
}
