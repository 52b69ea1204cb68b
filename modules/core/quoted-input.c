/*
 *  Untrusted input quoted in messages: a short printable excerpt, and a
 *  message made one bounded printable line.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <string.h>
#include "quoted-input.h"

/* Appends at most max_chars printable characters of text to out (each
 * unprintable byte counts as one character, shown as \xNN); returns
 * whether all of text fitted.  Walking at most max_chars characters keeps
 * the work bounded whatever the length of the input (a 10 MB line). */
static gboolean
append_printable(GString *out, const gchar *text, gsize length, gsize max_chars,
                 gboolean spaces_for_breaks)
{
    const gchar *p = text, *end = text + length;
    gsize chars = 0;
    gunichar c;

    while (p < end && chars < max_chars) {
        c = g_utf8_get_char_validated(p, end - p);
        if (c == (gunichar)-1 || c == (gunichar)-2) {
            g_string_append_printf(out, "\\x%02X", (guchar)*p);
            p++;
        }
        else {
            if (spaces_for_breaks && (c == '\n' || c == '\r' || c == '\t'))
                g_string_append_c(out, ' ');
            else if (g_unichar_isprint(c) || c == ' ')
                g_string_append_len(out, p, g_utf8_next_char(p) - p);
            else if (c < 0x80)
                g_string_append_printf(out, "\\x%02X", c);
            else
                g_string_append_printf(out, "\\u%04X", c);
            p = g_utf8_next_char(p);
        }
        chars++;
    }
    return p >= end;
}

gchar*
quoted_input_excerpt(const gchar *text, gssize length)
{
    GString *out = g_string_new(NULL);

    if (!text)
        return g_string_free(out, FALSE);
    if (length < 0)
        length = strlen(text);
    if (!append_printable(out, text, length, QUOTED_INPUT_EXCERPT_CHARS, FALSE))
        g_string_append(out, "...");
    return g_string_free(out, FALSE);
}

gchar*
quoted_input_message_line(const gchar *message)
{
    GString *out = g_string_new(NULL);
    gsize length;

    if (!message)
        return g_string_free(out, FALSE);
    while (g_ascii_isspace(*message))
        message++;
    length = strlen(message);
    while (length && g_ascii_isspace(message[length-1]))
        length--;
    if (!append_printable(out, message, length, QUOTED_INPUT_MESSAGE_CHARS, TRUE))
        g_string_append(out, "...");
    return g_string_free(out, FALSE);
}
