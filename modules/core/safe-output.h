/*
 *  Kill-safe temporary files for outputs: every output is written to a
 *  temporary file beside its target and renamed over it when complete.
 *  The temporaries are named so they can be recognised
 *  (".TARGET.PID.XXXXXX.localscan-tmp"), removed when the program is stopped
 *  by SIGTERM, SIGINT or SIGHUP, and swept by the next run writing the
 *  same target when a SIGKILL left them (their PID no longer runs).
 *  The one temporary-file maker of the tools and simscan.  GTK-free.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_SAFE_OUTPUT_H
#define LOCALSCAN_SAFE_OUTPUT_H

#include <glib.h>

G_BEGIN_DECLS

#define SAFE_OUTPUT_SUFFIX ".localscan-tmp"

/* Creates an empty temporary file beside target (same folder, so a rename
 * puts it in place atomically), with role (may be "") in its name, after
 * sweeping the folder of target's temporaries left by dead runs.  Returns
 * its name and an open descriptor in fd (fd NULL: closed), or NULL with
 * errno set.  The file is registered for removal on a signal until
 * safe_output_forget(); the first call installs the signal handlers. */
gchar*   safe_output_temp_new     (const gchar *target,
                                   const gchar *role,
                                   gint *fd);

/* A private temporary folder in the system's temporary place, registered
 * like a file (it must be empty when a signal comes, or is left). */
gchar*   safe_output_temp_dir_new (const gchar *what);

/* Registers path for removal on a signal (a file made in a temporary
 * folder), or stops doing so once it is renamed, removed or kept. */
void     safe_output_register     (const gchar *path);
void     safe_output_forget       (const gchar *path);

/* Removes path and forgets it. */
void     safe_output_discard      (const gchar *path);

/* Holds back the signals the handlers catch while a set of outputs is
 * renamed into place, so that a signal finds either none or all of them
 * committed; release delivers what came meanwhile.  Not nested. */
void     safe_output_hold_signals   (void);
void     safe_output_release_signals(void);

/* Removes the temporaries of target whose run is dead; returns how many. */
guint    safe_output_sweep        (const gchar *target);

/* Whether name is a temporary this module makes. */
gboolean safe_output_is_temp_name (const gchar *name);

G_END_DECLS

#endif
