/*
 *  The N sweep drawn as a PNG.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <math.h>
#include <string.h>
#include <cairo.h>
#include <fontconfig/fontconfig.h>
#include "output-files.h"
#include "sweep-plot.h"
#include "simscan-i18n.h"

#define WIDTH 720
#define HEIGHT 480
#define LEFT 70.0
#define RIGHT 20.0
#define TOP 40.0
#define BOTTOM 60.0

typedef struct {
    cairo_t *cr;
    gdouble xmin, xmax, ymax;   /* log2 N range, error range in px */
} Axes;

static gdouble
to_x(const Axes *axes, gdouble n)
{
    gdouble f = (axes->xmax > axes->xmin)
                ? (log2(n) - axes->xmin)/(axes->xmax - axes->xmin) : 0.5;

    return LEFT + f*(WIDTH - LEFT - RIGHT);
}

static gdouble
to_y(const Axes *axes, gdouble e)
{
    return HEIGHT - BOTTOM - e/axes->ymax*(HEIGHT - TOP - BOTTOM);
}

static void
draw_text(cairo_t *cr, gdouble x, gdouble y, const gchar *text, gdouble align)
{
    cairo_text_extents_t ext;

    cairo_text_extents(cr, text, &ext);
    cairo_move_to(cr, x - align*ext.width, y);
    cairo_show_text(cr, text);
}

static void
draw_axes(const Axes *axes, const SweepPoint *points, gint n_points)
{
    cairo_t *cr = axes->cr;
    gchar buf[32];
    gdouble e;
    gint i;

    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_set_line_width(cr, 1.0);
    cairo_rectangle(cr, LEFT, TOP, WIDTH - LEFT - RIGHT,
                    HEIGHT - TOP - BOTTOM);
    cairo_stroke(cr);
    cairo_set_font_size(cr, 12.0);
    for (i = 0; i < n_points; i++) {
        g_snprintf(buf, sizeof(buf), "%d", points[i].n);
        draw_text(cr, to_x(axes, points[i].n), HEIGHT - BOTTOM + 16, buf, 0.5);
    }
    for (e = 0.0; e <= axes->ymax + 1e-9; e += axes->ymax/5.0) {
        g_snprintf(buf, sizeof(buf), "%.2f", e);
        draw_text(cr, LEFT - 6, to_y(axes, e) + 4, buf, 1.0);
    }
    draw_text(cr, 0.5*WIDTH, HEIGHT - 18, _("stripes N"), 0.5);
    cairo_save(cr);
    cairo_translate(cr, 24, 0.5*HEIGHT);
    cairo_rotate(cr, -G_PI/2);
    draw_text(cr, 0, 0, _("particle-centre error (px)"), 0.5);
    cairo_restore(cr);
}

static void
draw_curve(const Axes *axes, const SweepPoint *points, gint n_points,
           gsize offset, gdouble r, gdouble g, gdouble b, gboolean dashed,
           const gchar *label, gint legend_row)
{
    static const gdouble dash[] = { 6.0, 4.0 };
    cairo_t *cr = axes->cr;
    gdouble lx = LEFT + 16, ly = TOP + 18 + 18*legend_row;
    gint i;

    /* Text leaves a current point; a curve must not start from it. */
    cairo_new_path(cr);
    cairo_set_source_rgb(cr, r, g, b);
    cairo_set_line_width(cr, 2.0);
    cairo_set_dash(cr, dash, dashed ? 2 : 0, 0.0);
    for (i = 0; i < n_points; i++) {
        gdouble e = *(const gdouble*)((const gchar*)(points + i) + offset);

        /* No measurement at this N: a gap in the curve. */
        if (!isfinite(e))
            cairo_new_sub_path(cr);
        else
            cairo_line_to(cr, to_x(axes, points[i].n), to_y(axes, e));
    }
    cairo_stroke(cr);
    for (i = 0; i < n_points; i++) {
        gdouble e = *(const gdouble*)((const gchar*)(points + i) + offset);

        if (!isfinite(e))
            continue;
        cairo_new_sub_path(cr);
        cairo_arc(cr, to_x(axes, points[i].n), to_y(axes, e), 3.0, 0, 2*G_PI);
        cairo_fill(cr);
    }
    cairo_set_dash(cr, dash, dashed ? 2 : 0, 0.0);
    cairo_set_source_rgb(cr, r, g, b);
    cairo_move_to(cr, lx, ly);
    cairo_line_to(cr, lx + 30, ly);
    cairo_stroke(cr);
    cairo_set_dash(cr, dash, 0, 0.0);
    cairo_set_source_rgb(cr, 0, 0, 0);
    draw_text(cr, lx + 38, ly + 4, label, 0.0);
}

static cairo_status_t
append_png(void *closure, const unsigned char *data, unsigned int length)
{
    g_byte_array_append((GByteArray*)closure, data, length);
    return CAIRO_STATUS_SUCCESS;
}

gboolean
sweep_plot_write_png(const SweepPoint *points, gint n_points,
                     const gchar *title, const gchar *filename, GError **error)
{
    cairo_surface_t *surface;
    GByteArray *png = g_byte_array_new();
    Axes axes;
    gboolean ok;
    gint i;

    surface = cairo_image_surface_create(CAIRO_FORMAT_RGB24, WIDTH, HEIGHT);
    axes.cr = cairo_create(surface);
    axes.xmin = log2(points[0].n);
    axes.xmax = log2(points[n_points-1].n);
    axes.ymax = 0.0;
    for (i = 0; i < n_points; i++) {
        axes.xmin = fmin(axes.xmin, log2(points[i].n));
        axes.xmax = fmax(axes.xmax, log2(points[i].n));
        axes.ymax = fmax(axes.ymax, fmax(points[i].before.rms_px,
                                         points[i].after.max_px));
    }
    /* Headroom for the legend above the curves. */
    axes.ymax = (axes.ymax > 0.0) ? 1.3*axes.ymax : 1.0;
    cairo_set_source_rgb(axes.cr, 1, 1, 1);
    cairo_paint(axes.cr);
    draw_axes(&axes, points, n_points);
    draw_curve(&axes, points, n_points, G_STRUCT_OFFSET(SweepPoint, before)
               + G_STRUCT_OFFSET(CentreError, rms_px), 0.5, 0.5, 0.5, TRUE,
               _("before compensation, RMS"), 0);
    draw_curve(&axes, points, n_points, G_STRUCT_OFFSET(SweepPoint, after)
               + G_STRUCT_OFFSET(CentreError, rms_px), 0.1, 0.3, 0.8, FALSE,
               _("after, RMS"), 1);
    draw_curve(&axes, points, n_points, G_STRUCT_OFFSET(SweepPoint, after)
               + G_STRUCT_OFFSET(CentreError, max_px), 0.8, 0.2, 0.1, FALSE,
               _("after, max"), 2);
    cairo_set_font_size(axes.cr, 14.0);
    draw_text(axes.cr, 0.5*WIDTH, 24, title, 0.5);
    cairo_destroy(axes.cr);
    cairo_surface_write_to_png_stream(surface, append_png, png);
    cairo_surface_destroy(surface);
    /* The toy font API caches fonts for the life of the process; nothing
     * else draws afterwards, so let leak checkers see a clean exit. */
    cairo_debug_reset_static_data();
    FcFini();
    ok = output_files_write_one(filename, png->data, png->len, error);
    g_byte_array_free(png, TRUE);
    return ok;
}
