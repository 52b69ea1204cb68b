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
#define PLOT_W 900
#define PLOT_H 620

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

static void
panel_frame(Panel *p, const gchar *title, const gchar *xlabel)
{
    cairo_t *cr = p->cr;
    gchar buf[64];
    gint i;

    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_set_line_width(cr, 1.0);
    cairo_rectangle(cr, p->x0, p->y0, p->w, p->h);
    cairo_stroke(cr);
    cairo_set_font_size(cr, 12);
    cairo_move_to(cr, p->x0, p->y0 - 6);
    cairo_show_text(cr, title);
    for (i = 0; i <= 4; i++) {
        gdouble v = p->vmin + (p->vmax - p->vmin)*i/4.0;
        gdouble t = p->tmin + (p->tmax - p->tmin)*i/4.0;

        g_snprintf(buf, sizeof(buf), "%.3g", v);
        cairo_move_to(cr, p->x0 - 52, px_y(p, v) + 4);
        cairo_show_text(cr, buf);
        g_snprintf(buf, sizeof(buf), "%.4g", t);
        cairo_move_to(cr, px_x(p, t) - 12, p->y0 + p->h + 14);
        cairo_show_text(cr, buf);
    }
    if (xlabel) {
        cairo_move_to(cr, p->x0 + p->w/2 - 60, p->y0 + p->h + 28);
        cairo_show_text(cr, xlabel);
    }
    if (p->vmin < 0 && p->vmax > 0) {
        cairo_set_source_rgb(cr, 0.7, 0.7, 0.7);
        cairo_move_to(cr, p->x0, px_y(p, 0));
        cairo_line_to(cr, p->x0 + p->w, px_y(p, 0));
        cairo_stroke(cr);
    }
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

static void
legend(cairo_t *cr, gdouble x, gdouble y, const gdouble *rgb,
       gboolean filled, const gchar *text)
{
    dot(cr, x, y - 4, 3.5, rgb, filled);
    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_move_to(cr, x + 8, y);
    cairo_show_text(cr, text);
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
    gint i, ax, k;

    cairo_set_source_rgb(cr, 1, 1, 1);
    cairo_paint(cr);
    for (k = 0; k < 4; k++) {
        p[k].cr = cr;
        p[k].x0 = 70 + (k % 2)*430;
        p[k].y0 = 50 + (k/2)*290;
        p[k].w = 380;
        p[k].h = 220;
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
    for (k = 0; k < 4; k++) {
        gdouble pad = 0.05*(p[k].vmax - p[k].vmin) + 1e-3;
        p[k].vmin -= pad;
        p[k].vmax += pad;
        pad = 0.03*(p[k].tmax - p[k].tmin) + 1e-3;
        p[k].tmin -= pad;
        p[k].tmax += pad;
    }
    panel_frame(p + 0, "x displacement p(t_a) - p(t_b), nm", NULL);
    panel_frame(p + 1, "y displacement p(t_a) - p(t_b), nm", NULL);
    panel_frame(p + 2, "x residual, nm", "scan time t_a of the later block, s");
    panel_frame(p + 3, "y residual, nm", "scan time t_a of the later block, s");
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
    cairo_set_font_size(cr, 14);
    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_move_to(cr, 70, 22);
    cairo_show_text(cr, title);
    cairo_set_font_size(cr, 12);
    legend(cr, 90, PLOT_H - 12, black, TRUE, "measured (block registration)");
    legend(cr, 340, PLOT_H - 12, red, FALSE,
           "paper model (constant v, whole px per stripe)");
    {
        gchar *t = g_strdup_printf("%s model", drift_model_type_name(ext->type));
        legend(cr, 680, PLOT_H - 12, blue, FALSE, t);
        g_free(t);
    }
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
        "frame 1 - frame 0, raw", "paper model", "settling model",
    };
    const SeriesFrame *f0;
    gchar *path;

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
    fopt.min_period = 3.0*f0->timing.line_time*f0->timing.yres/N_BLOCKS;
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
    plot_displacements(res, path, spec->name);
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

/* One data-driven line per series: what departs from the paper model and
 * which alternative the evidence rules out. */
static void
write_finding(GString *md, const SeriesSpec *spec, const SeriesResult *res)
{
    const FitReport *rep = &res->report;
    const DriftFit *none = fit_of_type(rep, DRIFT_MODEL_NONE);
    const DriftFit *settle = fit_of_type(rep, DRIFT_MODEL_SETTLING);
    const DriftFit *jump = fit_of_type(rep, DRIFT_MODEL_JUMP);
    const DriftFit *osc = fit_of_type(rep, DRIFT_MODEL_OSCILLATION);
    const SeriesFrame *last = res->series->frames + res->series->n_frames - 1;
    gdouble span = scan_timing_frame_end(&last->timing);

    g_string_append_printf(md, "- **%s**: ", spec->name);
    if (settle->cv_rms_nm > 0.9*none->cv_rms_nm) {
        g_string_append_printf(md, "constant velocity is enough: no effect "
                               "predicts held-out blocks 10 %% better "
                               "(constant %.3f nm, settling %.3f, jump %.3f, "
                               "oscillation %.3f nm).", none->cv_rms_nm,
                               settle->cv_rms_nm, jump->cv_rms_nm,
                               osc->cv_rms_nm);
        if (osc->bic < none->bic - 20.0)
            g_string_append_printf(md, "  The oscillation's BIC gain comes "
                                   "with a period of %.3g s, %.2f cycles per "
                                   "frame interval: a distortion repeated in "
                                   "every frame, not a drift.",
                                   osc->nonlinear,
                                   (res->series->frames[1].timing.frame_start
                                    - res->series->frames[0].timing.frame_start)
                                   /osc->nonlinear);
        g_string_append(md, "\n");
        return;
    }
    g_string_append_printf(md, "the velocity is not constant.  Held-out "
                           "error: constant %.3f nm (paper model %.3f nm), "
                           "settling %.3f nm (tau %.3g s), jump %.3f nm, "
                           "oscillation %.3f nm with a period of %.3g s "
                           "against a series of %.3g s%s.\n",
                           none->cv_rms_nm, res->cv_paper, settle->cv_rms_nm,
                           settle->nonlinear, jump->cv_rms_nm, osc->cv_rms_nm,
                           osc->nonlinear, span,
                           osc->nonlinear > span
                           ? " (longer than the series: no period is seen, it "
                             "acts as a smooth bend of the trajectory)" : "");
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
        "Generated by `make validation` (tools/validation-study.c); do not edit.\n"
        "Each series is cut into 16 blocks of lines per frame; every block of "
        "every frame is registered against every earlier frame (masked "
        "normalised cross-correlation after line levelling and a blur of 1 % "
        "of the frame), which measures p(t_a) - p(t_b) at the two scan times "
        "of its content (interfaces.md section 4).  All models are fitted to "
        "all measurements of a series at once; `simscan fit` names an effect "
        "only when it beats constant velocity by 20 in BIC, predicts held-out "
        "blocks 10 % better and explains 1.5 times its own residual.\n");
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
    g_string_append(md, "\n**Cause.**  Where the paper model departs from "
        "the measurement (hsafm-extra, afmir-film) it is because the drift "
        "velocity changes during the series: the apparent velocity of "
        "consecutive frame pairs moves steadily from pair to pair (tables "
        "above), and the residual of the constant-velocity model is a smooth "
        "bend over scan time, not a step and not a sign-alternating wave.  In "
        "hsafm-extra a jump is ruled out by its held-out error (about twice "
        "that of settling); in afmir-film, five frames with a 2.4 h gap "
        "after the first, a jump in that gap cannot be told from a smooth "
        "change.  An oscillation fits only with a period longer than the "
        "whole series, i.e. as a bend, and no periodicity is seen.  A "
        "velocity relaxing toward a constant (settling: thermal or piezo "
        "creep after the scan or stage was set up) explains it with three "
        "parameters more per series.  The whole-pixel rounding of the paper "
        "model costs little by comparison (paper model vs unrounded "
        "constant velocity above).\n\n"
        "**Extension.**  The settling term p' = v + u exp(-t/tau) is already "
        "one of simscan's drift models (DRIFT_MODEL_SETTLING), so no new "
        "model type was needed; what the paper mode lacks is using it.  The "
        "gain is in the tables: held-out prediction error and the alignment "
        "of compensated consecutive frames, paper model against the settling "
        "model (continuous, sub-pixel, per line).  On the afmir-film series "
        "tau comes out far longer than the series (the velocity changes "
        "almost linearly over 3 h): a constant-acceleration or logarithmic "
        "creep model would describe it with one parameter less; not added.\n\n"
        "**Limits.**  A drift component with a whole number of cycles per "
        "frame interval repeats identically in every frame and cancels in "
        "every frame-to-frame measurement: no frame series can see it (the "
        "hidden-effect tests avoid such periods for that reason).  For the "
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
