/*
 *  A height channel drawn as a grey PNG (cairo), scaled from the substrate
 *  to the highest particle so that small particles stand out.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef SIMSCAN_CHANNEL_PNG_H
#define SIMSCAN_CHANNEL_PNG_H

#include <glib.h>
#include <libprocess/datafield.h>

G_BEGIN_DECLS

/* Written atomically (temporary file, rename). */
gboolean  channel_png_write  (GwyDataField *field,
                              const gchar *filename,
                              GError **error);

G_END_DECLS

#endif
