/*
 *  Input files screened before Gwyddion's loaders read them: a file that is
 *  missing, empty, not a regular file, absurdly large, truncated, or not what
 *  its extension or its first bytes say is refused with one line naming it,
 *  instead of reaching a loader that may abort or print criticals on it.
 *  The one gate of every file a tool hands to gwy_file_load().  GTK-free.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_FILE_SCREENING_H
#define LOCALSCAN_FILE_SCREENING_H

#include <glib.h>

G_BEGIN_DECLS

#define FILE_SCREENING_ERROR file_screening_error_quark()

typedef enum {
    FILE_SCREENING_ERROR_ACCESS,     /* missing, unreadable, not a file */
    FILE_SCREENING_ERROR_SIZE,       /* empty or larger than the limit */
    FILE_SCREENING_ERROR_TYPE,       /* not what its extension says */
    FILE_SCREENING_ERROR_CORRUPT,    /* truncated or inconsistent */
} FileScreeningError;

/* No input is read if larger (the largest image a tool accepts is far
 * smaller). */
#define FILE_SCREENING_MAX_BYTES ((gint64)4 << 30)
/* Objects nested deeper than this in a .gwy file are refused (Gwyddion's
 * own files nest a few levels). */
#define FILE_SCREENING_MAX_DEPTH 32

GQuark   file_screening_error_quark(void);

/* Screens filename; messages read "FILENAME: problem". */
gboolean file_screening_check      (const gchar *filename,
                                    GError **error);

/* The same on the contents of a file named name, already in memory. */
gboolean file_screening_check_bytes(const gchar *name,
                                    const guchar *bytes,
                                    gsize length,
                                    GError **error);

G_END_DECLS

#endif
