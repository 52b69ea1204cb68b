/*
 *  Messages libraries log (GLib criticals and warnings from Gwyddion, its
 *  loaders, GObject) kept from the user of a command-line tool: the tool's
 *  own one-line message is what the user reads; --verbose shows the rest.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_LIBRARY_LOG_H
#define LOCALSCAN_LIBRARY_LOG_H

#include <glib.h>

G_BEGIN_DECLS

/* Routes every log message of every domain (unstructured and structured)
 * to a store instead of the terminal; with verbose they are also printed
 * to stderr as they come, prefixed with program.  Call again after a
 * library that installs its own handlers was initialised (Gwyddion's);
 * calling it again is harmless.  g_error() still aborts, as it must. */
void         library_log_capture (const gchar *program,
                                  gboolean verbose);

/* Whether the last library_log_capture() asked for them printed. */
gboolean     library_log_verbose (void);

/* The last message kept (NULL if none). */
const gchar* library_log_last    (void);

G_END_DECLS

#endif
