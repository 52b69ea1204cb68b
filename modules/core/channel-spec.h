/*
 *  FILE[:ID]: how command lines name a channel of a file.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_CHANNEL_SPEC_H
#define LOCALSCAN_CHANNEL_SPEC_H

#include <glib.h>

G_BEGIN_DECLS

#define CHANNEL_SPEC_ERROR channel_spec_error_quark()

typedef enum {
    CHANNEL_SPEC_ERROR_RANGE,     /* an id beyond what a gint holds */
} ChannelSpecError;

/* No ID was given: the caller's default channel. */
#define CHANNEL_SPEC_NO_ID (-1)

GQuark    channel_spec_error_quark  (void);

/* Splits FILE[:ID].  A file name may hold colons, so only a non-empty,
 * all-digit tail after the last colon is an id (0 to G_MAXINT), and only
 * when no file of the whole name exists; otherwise the whole text is the
 * file and id gets CHANNEL_SPEC_NO_ID.  filename (a
 * new string) may be empty, as in ":2"; what that means is the caller's
 * business.  Fails, setting neither output, when the id is out of range. */
gboolean  channel_spec_parse        (const gchar *text,
                                     gchar **filename,
                                     gint *id,
                                     GError **error);

G_END_DECLS

#endif
