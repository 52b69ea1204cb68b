/*
 *  Writing a .gwy file without building it in memory first: the file is
 *  what Gwyddion's own writer makes of the container (Gwyddion loads it
 *  alike), but large data fields go from their own memory to the file, so
 *  saving takes no more memory than a few kilobytes.  Little-endian hosts.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef GWY_STREAM_SAVE_H
#define GWY_STREAM_SAVE_H

#include <glib.h>
#include <libgwyddion/gwycontainer.h>

G_BEGIN_DECLS

/* Writes data to filename as a .gwy file (created or truncated); on
 * failure the file may be partial: write to a temporary name. */
gboolean gwy_stream_save(GwyContainer *data,
                         const gchar *filename,
                         GError **error);
/* The same, its messages naming shown_name: the output a temporary file
 * filename stands for until it is renamed. */
gboolean gwy_stream_save_as(GwyContainer *data,
                            const gchar *filename,
                            const gchar *shown_name,
                            GError **error);

G_END_DECLS

#endif
