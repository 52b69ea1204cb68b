/*
 *  A height channel drawn as a grey PNG (cairo), scaled from the substrate
 *  to the highest particle so that small particles stand out; optionally
 *  enlarged, on a colour range shared with other pictures, with rings at
 *  the particles' true places, filled pixels tinted and a caption.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef SIMSCAN_CHANNEL_PNG_H
#define SIMSCAN_CHANNEL_PNG_H

#include <glib.h>
#include <libprocess/datafield.h>

G_BEGIN_DECLS

typedef struct {
    gdouble low, high;       /* z drawn black and white */
    gint scale;              /* picture pixels per data pixel, >= 1 */
    const gdouble *rings;    /* 2 n_rings: (column, row) px; may be NULL */
    gint n_rings;
    GwyDataField *mask;      /* pixels > 0 are tinted blue; may be NULL */
    const gchar *caption;    /* lines of text under the picture; may be NULL */
} ChannelPngStyle;

/* The plain look: field's own range (a tenth below the median to the
 * maximum), one pixel per data pixel, nothing drawn over it. */
void      channel_png_style_init  (ChannelPngStyle *style,
                                   GwyDataField *field);

/* The PNG file's bytes (free with g_byte_array_unref()). */
GByteArray* channel_png_render    (GwyDataField *field,
                                   const ChannelPngStyle *style);

/* Lets leak checkers see a clean exit once no more captions are drawn
 * (cairo's toy font API caches fonts for the life of the process). */
void      channel_png_release_fonts (void);

G_END_DECLS

#endif
