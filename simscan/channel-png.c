/*
 *  A height channel drawn as a grey PNG.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <cairo.h>
#include <libprocess/stats.h>
#include "simscan-output.h"
#include "channel-png.h"

static cairo_status_t
append_png(void *closure, const unsigned char *data, unsigned int length)
{
    g_byte_array_append((GByteArray*)closure, data, length);
    return CAIRO_STATUS_SUCCESS;
}

gboolean
channel_png_write(GwyDataField *field, const gchar *filename, GError **error)
{
    gint xres = gwy_data_field_get_xres(field);
    gint yres = gwy_data_field_get_yres(field);
    const gdouble *d = gwy_data_field_get_data_const(field);
    gdouble base = gwy_data_field_get_median(field);
    gdouble top = gwy_data_field_get_max(field);
    gdouble low = base - 0.1*(top - base), scale;
    cairo_surface_t *surface;
    GByteArray *png = g_byte_array_new();
    guchar *pixels;
    gint stride, i, j;
    gboolean ok;

    scale = (top > low) ? 255.0/(top - low) : 0.0;
    surface = cairo_image_surface_create(CAIRO_FORMAT_RGB24, xres, yres);
    cairo_surface_flush(surface);
    pixels = cairo_image_surface_get_data(surface);
    stride = cairo_image_surface_get_stride(surface);
    for (i = 0; i < yres; i++) {
        guint32 *row = (guint32*)(pixels + i*stride);

        for (j = 0; j < xres; j++) {
            gint v = (gint)((d[i*xres + j] - low)*scale);
            guint32 g = CLAMP(v, 0, 255);

            row[j] = (g << 16) | (g << 8) | g;
        }
    }
    cairo_surface_mark_dirty(surface);
    cairo_surface_write_to_png_stream(surface, append_png, png);
    cairo_surface_destroy(surface);
    ok = simscan_write_file(filename, png->data, png->len, error);
    g_byte_array_free(png, TRUE);
    return ok;
}
