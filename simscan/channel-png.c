/*
 *  A height channel drawn as a grey PNG.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <math.h>
#include <cairo.h>
#include <fontconfig/fontconfig.h>
#include <libprocess/stats.h>
#include "channel-png.h"

#define CAPTION_FONT_SIZE 14.0
#define CAPTION_LINE_HEIGHT 18.0
/* Ring radius around a true place, data pixels: a particle of the paper
 * (2.6 px across) sits well inside, one a few pixels off shows outside. */
#define RING_RADIUS 3.0

static cairo_status_t
append_png(void *closure, const unsigned char *data, unsigned int length)
{
    g_byte_array_append((GByteArray*)closure, data, length);
    return CAIRO_STATUS_SUCCESS;
}

void
channel_png_style_init(ChannelPngStyle *style, GwyDataField *field)
{
    gdouble base = gwy_data_field_get_median(field);

    style->high = gwy_data_field_get_max(field);
    style->low = base - 0.1*(style->high - base);
    style->scale = 1;
    style->rings = NULL;
    style->n_rings = 0;
    style->mask = NULL;
    style->caption = NULL;
}

/* Grey from low to high; filled pixels are drawn in a blue of the same
 * brightness, so they read as "no data" without hiding the seams. */
static void
draw_heights(cairo_surface_t *surface, GwyDataField *field,
             const ChannelPngStyle *style)
{
    gint xres = gwy_data_field_get_xres(field);
    gint yres = gwy_data_field_get_yres(field);
    const gdouble *d = gwy_data_field_get_data_const(field);
    const gdouble *m = style->mask ? gwy_data_field_get_data_const(style->mask)
                                   : NULL;
    guchar *pixels = cairo_image_surface_get_data(surface);
    gint stride = cairo_image_surface_get_stride(surface);
    gint sc = style->scale, i, j;
    gdouble k = (style->high > style->low) ? 255.0/(style->high - style->low)
                                           : 0.0;

    cairo_surface_flush(surface);
    for (i = 0; i < yres*sc; i++) {
        guint32 *row = (guint32*)(pixels + i*stride);

        for (j = 0; j < xres*sc; j++) {
            gint p = (i/sc)*xres + j/sc;
            gint v = (gint)((d[p] - style->low)*k);
            guint32 g = CLAMP(v, 0, 255);

            if (m && m[p] > 0.0)
                row[j] = ((g/2) << 16) | ((g/2 + 40) << 8) | MIN(g + 110, 255);
            else
                row[j] = (g << 16) | (g << 8) | g;
        }
    }
    cairo_surface_mark_dirty(surface);
}

static void
draw_rings(cairo_t *cr, const ChannelPngStyle *style)
{
    gint i;

    cairo_set_source_rgb(cr, 1.0, 0.2, 0.15);
    cairo_set_line_width(cr, 1.5);
    for (i = 0; i < style->n_rings; i++) {
        gdouble x = (style->rings[2*i] + 0.5)*style->scale;
        gdouble y = (style->rings[2*i + 1] + 0.5)*style->scale;

        cairo_new_sub_path(cr);
        cairo_arc(cr, x, y, RING_RADIUS*style->scale, 0.0, 2.0*G_PI);
    }
    cairo_stroke(cr);
}

static void
draw_caption(cairo_t *cr, gchar **lines, gint width, gint top)
{
    gint i;

    cairo_set_source_rgb(cr, 1.0, 1.0, 1.0);
    cairo_rectangle(cr, 0, top, width, g_strv_length(lines)*CAPTION_LINE_HEIGHT
                                       + 8);
    cairo_fill(cr);
    cairo_set_source_rgb(cr, 0.0, 0.0, 0.0);
    cairo_set_font_size(cr, CAPTION_FONT_SIZE);
    for (i = 0; lines[i]; i++) {
        cairo_move_to(cr, 6, top + (i + 1)*CAPTION_LINE_HEIGHT);
        cairo_show_text(cr, lines[i]);
    }
}

GByteArray*
channel_png_render(GwyDataField *field, const ChannelPngStyle *style)
{
    gint width = gwy_data_field_get_xres(field)*MAX(style->scale, 1);
    gint height = gwy_data_field_get_yres(field)*MAX(style->scale, 1);
    gchar **lines = g_strsplit(style->caption ? style->caption : "", "\n", -1);
    gint caption_height = style->caption
                          ? (gint)(g_strv_length(lines)*CAPTION_LINE_HEIGHT
                                   + 8) : 0;
    ChannelPngStyle own = *style;
    cairo_surface_t *surface;
    GByteArray *png = g_byte_array_new();
    cairo_t *cr;

    own.scale = MAX(style->scale, 1);
    surface = cairo_image_surface_create(CAIRO_FORMAT_RGB24, width,
                                         height + caption_height);
    draw_heights(surface, field, &own);
    cr = cairo_create(surface);
    if (own.rings && own.n_rings)
        draw_rings(cr, &own);
    if (style->caption)
        draw_caption(cr, lines, width, height);
    cairo_destroy(cr);
    cairo_surface_write_to_png_stream(surface, append_png, png);
    cairo_surface_destroy(surface);
    g_strfreev(lines);
    return png;
}

void
channel_png_release_fonts(void)
{
    cairo_debug_reset_static_data();
    FcFini();
}
