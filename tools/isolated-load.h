/*
 *  A file loaded by Gwyddion's file modules in a child process: a loader
 *  that crashes, aborts or never ends on a damaged file (Gwyddion 1's
 *  deserialiser loops on some) costs the child, not the tool, which reports
 *  it in one line.  The one loader of gwy-localscan and simscan.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_ISOLATED_LOAD_H
#define LOCALSCAN_ISOLATED_LOAD_H

#include <glib.h>
#include <libgwyddion/gwycontainer.h>

G_BEGIN_DECLS

#define ISOLATED_LOAD_ERROR isolated_load_error_quark()

typedef enum {
    ISOLATED_LOAD_ERROR_SCREENED,   /* refused by file-screening.h */
    ISOLATED_LOAD_ERROR_LOADER,     /* the loader refused it */
    ISOLATED_LOAD_ERROR_CRASHED,    /* the loader died on it */
    ISOLATED_LOAD_ERROR_TIMEOUT,    /* the loader took too long */
    ISOLATED_LOAD_ERROR_SYSTEM,     /* no process or pipe */
} IsolatedLoadError;

/* A loader gets this long for one file (LOCALSCAN_LOAD_SECONDS may give
 * it less, as tests do). */
#define ISOLATED_LOAD_SECONDS 30

GQuark        isolated_load_error_quark(void);

/* Screens filename (file-screening.h), then loads it with gwy_file_load()
 * in a child process, which hands the data back serialised.  Gwyddion's
 * file modules must be registered (gwy_app_init_nongui()).  Messages read
 * "FILE: problem". */
GwyContainer* isolated_load            (const gchar *filename,
                                        GError **error);

G_END_DECLS

#endif
