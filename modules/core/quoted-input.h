/*
 *  Untrusted input quoted in messages: a short printable excerpt, and a
 *  message made one bounded printable line, whatever a file or a library
 *  put into it.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_QUOTED_INPUT_H
#define LOCALSCAN_QUOTED_INPUT_H

#include <glib.h>

G_BEGIN_DECLS

/* At most this many characters of a bad line are quoted. */
#define QUOTED_INPUT_EXCERPT_CHARS 40
/* A whole message line is cut at this many characters. */
#define QUOTED_INPUT_MESSAGE_CHARS 400

/* A newly allocated excerpt of text (length bytes, -1: NUL-terminated) fit
 * to quote in a message: valid UTF-8, control and invalid bytes shown as
 * \xNN, at most QUOTED_INPUT_EXCERPT_CHARS characters, "..." appended when
 * cut. */
gchar*   quoted_input_excerpt     (const gchar *text,
                                   gssize length);

/* message as one line: surrounding space stripped, line breaks and tabs
 * made spaces, other control and invalid bytes shown as \xNN, cut to
 * QUOTED_INPUT_MESSAGE_CHARS characters.  Newly allocated. */
gchar*   quoted_input_message_line(const gchar *message);

G_END_DECLS

#endif
