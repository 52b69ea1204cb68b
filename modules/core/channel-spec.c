/*
 *  FILE[:ID]: how command lines name a channel of a file.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <string.h>
#include "channel-spec.h"
#include "localscan-intl.h"

G_DEFINE_QUARK(channel-spec-error-quark, channel_spec_error)

static gboolean
all_digits(const gchar *s)
{
    if (!*s)
        return FALSE;
    while (g_ascii_isdigit(*s))
        s++;
    return !*s;
}

gboolean
channel_spec_parse(const gchar *text, gchar **filename, gint *id,
                   GError **error)
{
    const gchar *colon = strrchr(text, ':');
    guint64 value;

    /* A file of the whole name is the file ('scan:1' as it exists), as
     * the documentation promises: its digits were taken for a channel of
     * 'scan', which did not exist. */
    if (!colon || !all_digits(colon + 1) || g_file_test(text, G_FILE_TEST_EXISTS)) {
        *filename = g_strdup(text);
        *id = CHANNEL_SPEC_NO_ID;
        return TRUE;
    }
    if (!g_ascii_string_to_unsigned(colon + 1, 10, 0, G_MAXINT, &value,
                                    NULL)) {
        g_set_error(error, CHANNEL_SPEC_ERROR, CHANNEL_SPEC_ERROR_RANGE,
                    _("%s: channel id %s is out of range (0 to %d)"),
                    text, colon + 1, G_MAXINT);
        return FALSE;
    }
    *filename = g_strndup(text, colon - text);
    *id = (gint)value;
    return TRUE;
}
