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
#include "fit-command.h"

#define N_BLOCKS 16
#define PLOT_W 1000
#define PLOT_H 680

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
      "Bruker FastScan, 3 frames 768 x 486 (0.130 x 0.206 nm pixels), "
      "209 s each, channel Phase" },
    { "hsafm-sample0",
      { "hsafm-minicircles/hsafm_sample0_frames50-140.gwy", NULL },
      NULL, -1, -1,
      "HS-AFM, 7 frames 256 x 256 of 200 nm, 0.41 s each, 6.2 s apart" },
    { "hsafm-extra",
      { "hsafm-minicircles/hsafm_extra_frames14-62.gwy", NULL },
      NULL, -1, -1,
      "HS-AFM, 7 frames 256 x 256 of 500 nm, 1.01 s each, 8.1 s apart" },
    { "afmir-film",
      { "afmir-film/PEA_BDA_film.axz", NULL },
      "Height", 9, 17,
      "Anasys nanoIR, channels Height 9..17 (128 x 128, 2 um), duplicates "
      "dropped" },
};

/* What the study found for one series. */
typedef struct {
    FrameSeries *series;
    FitReport report;
    gint extended;            /* index of the best effect model by CV */
    gdouble cv_paper, cv_none, cv_ext;
    gdouble ncc_raw, ncc_paper, ncc_ext;
    gchar *plot, *images;
} SeriesResult;

/* The paper's model: constant velocity, one drift per stripe, whole
 * pixels.  Its prediction of a measurement. */
static void
paper_predict(const DriftFit *none, const DriftMeasurement *m,
              gdouble xstep, gdouble ystep, gdouble *dx, gdouble *dy)
{
    drift_fit_predict(none, m, dx, dy);
    *dx = xstep*floor(*dx/xstep + 0.5);
    *dy = ystep*floor(*dy/ystep + 0.5);
}

/* Cross-validated RMS (nm) of the paper model: v from the other folds. */
static gdouble
paper_cross_validate(const DriftMeasurement *meas, gint n, gdouble xstep,
                     gdouble ystep)
{
    DriftMeasurement *train = g_new(DriftMeasurement, n);
    gdouble sum = 0.0, wsum = 0.0, dx, dy;
    gint f, i, folds = 5;
    DriftFit fit;

    for (f = 0; f < folds; f++) {
        memcpy(train, meas, n*sizeof(DriftMeasurement));
        for (i = 0; i < n; i++) {
            if (meas[i].group % folds == f)
                train[i].weight = 0.0;
        }
        if (!drift_fit_model(train, n, DRIFT_MODEL_NONE, NULL, &fit))
            continue;
        for (i = 0; i < n; i++) {
            if (meas[i].group % folds != f || !(meas[i].weight > 0.0))
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
        med = gwy_math_median(xres, row);
        for (j = 0; j < xres; j++)
            out[i*xres + j] = d[i*xres + j] - med;
    }
    g_free(row);
    return out;
}

/* Drift-free image of a frame: output (r, c) reads the frame where the
 * content of (r, c) appeared, row r's scan time giving the drift.  With
 * stripes > 0 the drift is one whole-pixel value per stripe (paper mode);
 * fit NULL: no compensation.  NaN where the frame has no data. */
static gdouble*
compensate(const SeriesFrame *frame, const gdouble *data, const DriftFit *fit,
           gint stripes)
{
    const ScanTiming *tm = &frame->timing;
    gint xres = tm->xres, yres = tm->yres, r, c;
    gdouble xstep = gwy_data_field_get_dx(frame->field);
    gdouble ystep = gwy_data_field_get_dy(frame->field);
    gdouble *out = g_new(gdouble, xres*yres);

    for (r = 0; r < yres; r++) {
        gdouble px = 0.0, py = 0.0, t;

        if (fit && stripes > 0) {
            gint s = r*stripes/yres;
            t = scan_timing_rows_time(tm, s*yres/stripes, (s + 1)*yres/stripes);
            drift_fit_eval(fit, t, &px, &py);
            px = floor(px/xstep + 0.5);
            py = floor(py/ystep + 0.5);
        }
        else if (fit) {
            t = scan_timing_pixel_time(tm, r, 0.5*xres);
            drift_fit_eval(fit, t, &px, &py);
            px /= xstep;
            py /= ystep;
        }
        for (c = 0; c < xres; c++) {
            gdouble sr = r + py, sc = c + px, fr, fc;
            gint ir = (gint)floor(sr), ic = (gint)floor(sc);

            if (ir < 0 || ic < 0 || ir + 1 >= yres || ic + 1 >= xres) {
                out[r*xres + c] = NAN;
                continue;
            }
            fr = sr - ir;
            fc = sc - ic;
            out[r*xres + c] = ((1 - fr)*((1 - fc)*data[ir*xres + ic]
                                         + fc*data[ir*xres + ic + 1])
                               + fr*((1 - fc)*data[(ir + 1)*xres + ic]
                                     + fc*data[(ir + 1)*xres + ic + 1]));
        }
    }
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

/* Mean alignment (NCC) of consecutive frames after compensation. */
static gdouble
alignment(const FrameSeries *series, const DriftFit *fit, gint stripes,
          gdouble **diff_image)
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

/* Measured and predicted displacement (x and y) over the later scan time,
 * and the residuals of both models. */
static void
plot_displacements(const SeriesResult *res, const gchar *path,
                   const gchar *title)
{
    static const gdouble black[3] = { 0, 0, 0 }, red[3] = { 0.85, 0.1, 0.1 },
                         blue[3] = { 0.1, 0.3, 0.9 };
    const FitReport *rep = &res->report;
    const DriftFit *none = rep->fits, *ext = rep->fits + res->extended;
    gdouble xstep = frame_series_dx(res->series), ystep = frame_series_dy(res->series);
    cairo_surface_t *sf = cairo_image_surface_create(CAIRO_FORMAT_RGB24,
                                                     PLOT_W, PLOT_H);
    cairo_t *cr = cairo_create(sf);
    Panel p[4];
    gdouble vstep[4], tstep[4], x;
    gchar *model;
    gint i, ax, k;

    cairo_set_source_rgb(cr, 1, 1, 1);
    cairo_paint(cr);
    for (k = 0; k < 4; k++) {
        p[k].cr = cr;
        p[k].x0 = 80 + (k % 2)*480;
        p[k].y0 = 70 + (k/2)*290;
        p[k].w = 400;
        p[k].h = 215;
        p[k].tmin = G_MAXDOUBLE;
        p[k].tmax = -G_MAXDOUBLE;
        p[k].vmin = G_MAXDOUBLE;
        p[k].vmax = -G_MAXDOUBLE;
    }
    for (i = 0; i < rep->n_meas; i++) {
        const DriftMeasurement *m = rep->meas + i;
        gdouble pd[2], ed[2], md[2] = { 1e9*m->dx, 1e9*m->dy };

        if (!(m->weight > 0.0))
            continue;
        paper_predict(none, m, xstep, ystep, pd, pd + 1);
        drift_fit_predict(ext, m, ed, ed + 1);
        for (ax = 0; ax < 2; ax++) {
            Panel *a = p + ax, *b = p + 2 + ax;
            gdouble r1 = md[ax] - 1e9*pd[ax], r2 = md[ax] - 1e9*ed[ax];

            a->tmin = b->tmin = MIN(a->tmin, m->t_a);
            a->tmax = b->tmax = MAX(a->tmax, m->t_a);
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
    for (i = 0; i < rep->n_meas; i++) {
        const DriftMeasurement *m = rep->meas + i;
        gdouble pd[2], ed[2], md[2] = { 1e9*m->dx, 1e9*m->dy };

        if (!(m->weight > 0.0))
            continue;
        paper_predict(none, m, xstep, ystep, pd, pd + 1);
        drift_fit_predict(ext, m, ed, ed + 1);
        for (ax = 0; ax < 2; ax++) {
            dot(cr, px_x(p + ax, m->t_a), px_y(p + ax, md[ax]), 2.5, black, TRUE);
            dot(cr, px_x(p + ax, m->t_a), px_y(p + ax, 1e9*pd[ax]), 3.5, red, FALSE);
            dot(cr, px_x(p + ax, m->t_a), px_y(p + ax, 1e9*ed[ax]), 3.5, blue, FALSE);
            dot(cr, px_x(p + 2 + ax, m->t_a),
                px_y(p + 2 + ax, md[ax] - 1e9*pd[ax]), 3.0, red, FALSE);
            dot(cr, px_x(p + 2 + ax, m->t_a),
                px_y(p + 2 + ax, md[ax] - 1e9*ed[ax]), 3.0, blue, FALSE);
        }
    }
    cairo_set_font_size(cr, 16);
    cairo_set_source_rgb(cr, 0, 0, 0);
    show_text_at(cr, title, 80, 28, 0.0);
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

/* Greyscale tiles side by side (NaN black), one common scale. */
static void
image_strip(gdouble **tiles, gint n, gint xres, gint yres, gdouble aspect,
            const gchar *const *labels, const gchar *path)
{
    gint scale_h = MAX(200, MIN(320, yres)), tile_w = (gint)(scale_h/aspect*xres/yres);
    gint w = n*(tile_w + 10) + 10, h = scale_h + 40, k, r, c;
    cairo_surface_t *sf = cairo_image_surface_create(CAIRO_FORMAT_RGB24, w, h);
    cairo_t *cr = cairo_create(sf);
    gdouble s2 = 0.0;
    gint m = 0;

    for (k = 0; k < n; k++) {
        for (r = 0; r < xres*yres; r++) {
            if (!isnan(tiles[k][r])) {
                s2 += tiles[k][r]*tiles[k][r];
                m++;
            }
        }
    }
    s2 = m ? sqrt(s2/m) : 1.0;
    cairo_set_source_rgb(cr, 1, 1, 1);
    cairo_paint(cr);
    for (k = 0; k < n; k++) {
        cairo_surface_t *img = cairo_image_surface_create(CAIRO_FORMAT_RGB24,
                                                          xres, yres);
        guint32 *px = (guint32*)cairo_image_surface_get_data(img);
        gint stride = cairo_image_surface_get_stride(img)/4;

        cairo_surface_flush(img);
        for (r = 0; r < yres; r++) {
            for (c = 0; c < xres; c++) {
                gdouble v = tiles[k][r*xres + c];
                gint g = isnan(v) ? 0 : CLAMP((gint)(128 + 40*v/s2), 0, 255);
                px[r*stride + c] = isnan(v) ? 0x400000 : (guint32)g*0x010101;
            }
        }
        cairo_surface_mark_dirty(img);
        cairo_save(cr);
        cairo_translate(cr, 10 + k*(tile_w + 10), 10);
        cairo_scale(cr, (gdouble)tile_w/xres, (gdouble)scale_h/yres);
        cairo_set_source_surface(cr, img, 0, 0);
        cairo_paint(cr);
        cairo_restore(cr);
        cairo_surface_destroy(img);
        cairo_set_source_rgb(cr, 0, 0, 0);
        cairo_set_font_size(cr, 12);
        cairo_move_to(cr, 10 + k*(tile_w + 10), scale_h + 28);
        cairo_show_text(cr, labels[k]);
    }
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

static gboolean
study_series(const SeriesSpec *spec, const gchar *measured,
             const gchar *figdir, SeriesResult *res, GError **error)
{
    FrameSeriesOptions so;
    DisplacementOptions dopt;
    DriftFitOptions fopt;
    gchar *files[4];
    gint n = 0, k;
    gdouble *diff[3] = { NULL, NULL, NULL };
    const gchar *labels[3] = {
        "frame 1 - frame 0, raw", "after paper-model compensation",
        "after settling-model compensation",
    };
    const SeriesFrame *f0;
    gchar *path, *title;

    memset(res, 0, sizeof(SeriesResult));
    frame_series_options_init(&so);
    so.channel = spec->channel;
    so.first_id = spec->first_id;
    so.last_id = spec->last_id;
    for (n = 0; spec->files[n]; n++)
        files[n] = g_build_filename(measured, spec->files[n], NULL);
    res->series = frame_series_load(files, n, &so, error);
    for (k = 0; k < n; k++)
        g_free(files[k]);
    if (!res->series)
        return FALSE;
    f0 = res->series->frames;
    displacement_options_init(&dopt);
    dopt.n_blocks = N_BLOCKS;
    drift_fit_options_init(&fopt);
    fopt.min_period = drift_fit_min_period(f0->timing.line_time,
                                           f0->timing.yres, N_BLOCKS);
    fit_report_compute(res->series, &dopt, &fopt, &res->report);
    res->extended = extension_model(&res->report);
    res->cv_none = res->report.fits[0].cv_rms_nm;
    res->cv_ext = res->report.fits[res->extended].cv_rms_nm;
    res->cv_paper = paper_cross_validate(res->report.meas, res->report.n_meas,
                                         frame_series_dx(res->series),
                                         frame_series_dy(res->series));
    res->ncc_raw = alignment(res->series, NULL, 0, diff);
    res->ncc_paper = alignment(res->series, res->report.fits, N_BLOCKS,
                               diff + 1);
    res->ncc_ext = alignment(res->series, res->report.fits + res->extended, 0,
                             diff + 2);

    res->plot = g_strdup_printf("figures/%s-displacement.png", spec->name);
    path = g_build_filename(figdir, "..", res->plot, NULL);
    title = g_strdup_printf("%s: displacement of each block against an earlier "
                            "frame", spec->name);
    plot_displacements(res, path, title);
    g_free(title);
    g_free(path);
    res->images = g_strdup_printf("figures/%s-alignment.png", spec->name);
    path = g_build_filename(figdir, "..", res->images, NULL);
    image_strip(diff, 3, f0->timing.xres, f0->timing.yres,
                frame_series_dx(res->series)/frame_series_dy(res->series),
                labels, path);
    g_free(path);
    for (k = 0; k < 3; k++)
        g_free(diff[k]);
    return TRUE;
}

/* ---- The document ---- */

static void
write_pair_velocities(GString *md, const SeriesResult *res)
{
    const FitReport *rep = &res->report;
    gint k, i;

    g_string_append(md, "\n| frames | mid time (s) | apparent v_x (nm/s) | "
                    "apparent v_y (nm/s) | blocks used |\n|---|---|---|---|---|\n");
    for (k = 1; k < res->series->n_frames; k++) {
        gdouble sx = 0, sy = 0, st = 0, sw = 0;
        gint used = 0;

        for (i = 0; i < rep->n_meas; i++) {
            const DriftMeasurement *m = rep->meas + i;
            gdouble dt = m->t_a - m->t_b;

            if (m->frame_a != k || m->frame_b != k-1 || !(m->weight > 0.0))
                continue;
            sx += m->weight*1e9*m->dx/dt;
            sy += m->weight*1e9*m->dy/dt;
            st += m->weight*0.5*(m->t_a + m->t_b);
            sw += m->weight;
            used++;
        }
        if (sw > 0)
            g_string_append_printf(md, "| %d-%d | %.1f | %.4f | %.4f | %d |\n",
                                   k-1, k, st/sw, sx/sw, sy/sw, used);
    }
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
    g_string_append_printf(md, "\n## %s\n\n%s.  %d frames kept",
                           spec->name, spec->what, res->series->n_frames);
    for (i = 0; i < (gint)res->series->notes->len; i++)
        g_string_append_printf(md, "; %s",
                               (gchar*)g_ptr_array_index(res->series->notes, i));
    g_string_append_printf(md, ".  Frame starts (s):");
    for (i = 0; i < res->series->n_frames; i++)
        g_string_append_printf(md, " %.2f", res->series->frames[i].timing.frame_start);
    g_string_append_printf(md, "; line time %.4g s.  %d block measurements, "
                           "%d used.\n\n", res->series->frames[0].timing.line_time,
                           rep->n_meas, used);
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
                           "(5-fold over blocks, never on the data fitted): paper "
                           "model **%.3f nm**, constant velocity without "
                           "rounding %.3f nm, %s model **%.3f nm**.\n",
                           res->cv_paper, res->cv_none,
                           drift_model_type_name(rep->fits[res->extended].type),
                           res->cv_ext);
    g_string_append_printf(md, "Alignment of consecutive frames (normalised "
                           "correlation over the overlap, mean over pairs): raw "
                           "%.4f, paper-compensated %.4f, %s-compensated "
                           "%.4f.\n", res->ncc_raw, res->ncc_paper,
                           drift_model_type_name(rep->fits[res->extended].type),
                           res->ncc_ext);
    g_string_append(md, "\nApparent velocity of each consecutive pair (mean of "
                    "its blocks' displacement over their time difference):\n");
    write_pair_velocities(md, res);
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
        g_string_append(md, "  No oscillation period is observable: 1.5 "
                        "cycles over the series would be shorter than twice "
                        "its longest gap between measured times.");
    g_string_append(md, "\n");
}

/* The apparent velocity of the first and the last consecutive pair (nm/s);
 * FALSE without two pairs. */
static gboolean
pair_velocity_trend(const SeriesResult *res, gdouble *first, gdouble *last)
{
    const FitReport *rep = &res->report;
    gint k, i, found = 0;

    for (k = 1; k < res->series->n_frames; k++) {
        gdouble sx = 0, sy = 0, sw = 0;

        for (i = 0; i < rep->n_meas; i++) {
            const DriftMeasurement *m = rep->meas + i;
            gdouble dt = m->t_a - m->t_b;

            if (m->frame_a != k || m->frame_b != k-1 || !(m->weight > 0.0))
                continue;
            sx += m->weight*1e9*m->dx/dt;
            sy += m->weight*1e9*m->dy/dt;
            sw += m->weight;
        }
        if (!(sw > 0))
            continue;
        if (!found++) {
            first[0] = sx/sw;
            first[1] = sy/sw;
        }
        last[0] = sx/sw;
        last[1] = sy/sw;
    }
    return found >= 2;
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
    g_string_append_printf(md, "%s the periods it can observe.  "
                    "The whole-pixel rounding of the paper model costs "
                    "little by comparison (paper model against unrounded "
                    "constant velocity in each table).\n",
                    oscillations ? "An oscillation is named in some series within"
                    : "No series shows an oscillation that `simscan fit` "
                      "accepts within");
}

static gchar*
read_text(const gchar *path)
{
    gchar *text = NULL;

    if (path && g_file_get_contents(path, &text, NULL, NULL))
        return text;
    return g_strdup("(not generated: run `make validation`)\n");
}

int
main(int argc, char **argv)
{
    const gchar *measured = argc > 1 ? argv[1] : "../shared/data/measured";
    const gchar *docdir = argc > 2 ? argv[2] : "docs";
    gchar *figdir = g_build_filename(docdir, "figures", NULL);
    gchar *out = g_build_filename(docdir, "validation.md", NULL);
    gchar *confusion = read_text(argc > 3 ? argv[3] : NULL);
    SeriesResult results[G_N_ELEMENTS(specs)];
    GString *md = g_string_new(NULL);
    GError *error = NULL;
    guint i;

    gwy_app_init_nongui("enable-threads", FALSE, NULL);
    g_mkdir_with_parents(figdir, 0755);
    if (!g_file_test(measured, G_FILE_TEST_IS_DIR)) {
        g_printerr("validation-study: %s: no measured data there\n", measured);
        return 1;
    }
    g_string_append(md, "# Validation of the drift model on measured AFM data\n\n"
        "Generated by `make validation` (docs/validation-study.c); do not edit.\n"
        "Each series is cut into 16 blocks of lines per frame; every block of "
        "every frame is registered against every earlier frame with the "
        "project's stripe registration (modules/core/stripe-registration.c: "
        "zero-mean normalised cross-correlation over the overlap, searched "
        "around the frame's overall shift, chained across frames; frames "
        "line-levelled and blurred by 1 % of the frame first; a block counts "
        "only when its peak stands clear of rival peaks), which measures "
        "p(t_a) - p(t_b) at the two scan times of its content (interfaces.md "
        "section 4).  All models are fitted to all measurements of a series "
        "at once; `simscan fit` names an effect only when it beats constant "
        "velocity by 20 in BIC, predicts held-out blocks 10 % better and "
        "explains 1.5 times its own residual, and an oscillation only with a "
        "period it can observe: at least 1.5 cycles over the measured time "
        "span, no shorter than twice the longest gap between measured times, "
        "not cancelling between frames, and not the longest such period.\n");
    for (i = 0; i < G_N_ELEMENTS(specs); i++) {
        if (!study_series(specs + i, measured, figdir, results + i, &error)) {
            g_printerr("validation-study: %s: %s\n", specs[i].name,
                       error->message);
            g_clear_error(&error);
            results[i].series = NULL;
            continue;
        }
        write_series(md, specs + i, results + i);
        fprintf(stderr, "%s done\n", specs[i].name);
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
        "model (continuous, sub-pixel, per line).  Slow creep was tried as "
        "a further candidate while this study was written: constant "
        "acceleration (p = v t + b t^2, one parameter less than settling per "
        "axis) and logarithmic creep (p = v t + c t0 log(1 + t/t0)).  Neither "
        "is among `simscan fit`'s models, because neither wins on held-out "
        "error: against settling, constant acceleration was 0.2 % better on "
        "afmir-film (22.22 against 22.27 nm, where settling's tau already sits "
        "at the top of its range and acts as constant acceleration), 4 % "
        "worse on hsafm-extra; logarithmic creep was within 0.8 % of settling "
        "on every series (the numbers are in the commit message that added "
        "this paragraph).\n\n"
        "**Limits.**  A drift component with a whole number of cycles per "
        "frame interval repeats identically in every frame and cancels in "
        "every frame-to-frame measurement: no frame series can see it "
        "(`simscan fit` does not search such periods and the hidden-effect "
        "tests do not draw them).  For the "
        "HS-AFM series the slow-scan direction is not in the metadata and is "
        "taken as down; for the Anasys series the time stamp is taken as the "
        "end of each frame.  Registration of the FastScan series uses the "
        "Phase channel: in ZSensor the periodic background and line streaks "
        "pin blocks to wrong peaks (its frame-to-frame shifts do not add up: "
        "frame 2 vs 0 differs from (2 vs 1) + (1 vs 0) by tens of pixels in x).\n");
    g_string_append(md, "\n## Effects hidden in simulated series "
                    "(bench/bench-effect-confusion)\n\n");
    g_string_append(md, confusion);
    if (!g_file_set_contents(out, md->str, -1, &error)) {
        g_printerr("validation-study: %s\n", error->message);
        return 1;
    }
    for (i = 0; i < G_N_ELEMENTS(specs); i++) {
        if (results[i].series) {
            fit_report_clear(&results[i].report);
            frame_series_free(results[i].series);
            g_free(results[i].plot);
            g_free(results[i].images);
        }
    }
    g_string_free(md, TRUE);
    g_free(confusion);
    g_free(figdir);
    g_free(out);
    return 0;
}
