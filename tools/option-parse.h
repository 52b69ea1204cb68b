/*
 *  GLib's command-line parsing for the tools, with a refusal that names
 *  the option whose value is not text.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_OPTION_PARSE_H
#define LOCALSCAN_OPTION_PARSE_H

#include <glib.h>

G_BEGIN_DECLS

/* g_option_context_parse(); where a string option's value is not text in
 * the locale's encoding, GLib says only "Invalid byte sequence in
 * conversion input": the error then names the argument. */
gboolean option_parse_naming(GOptionContext *context,
                             gint *argc,
                             gchar ***argv,
                             GError **error);
/* The same for g_option_context_parse_strv(). */
gboolean option_parse_naming_strv(GOptionContext *context,
                                  gchar ***args,
                                  GError **error);

/* The message for an option's value that is not text: which option's
 * value it is ("--line-time" for "--line-time=V" or for V after
 * "--line-time"; arguments of their own, file names GLib takes as bytes,
 * are passed over).  args (NULL-terminated) as given, the program's name
 * first; NULL when no such value is found. */
gchar*   option_parse_unconvertible(gchar **args,
                                    const gchar *reason);

/* A value taken as bytes (G_OPTION_ARG_FILENAME) that is compared with
 * UTF-8 text (a channel's title), in place: kept when it is UTF-8,
 * whatever the locale (in the C locale of a container GLib converts
 * nothing beyond ASCII, and "-c Höhe" was refused), else converted from
 * the locale's encoding; FALSE with an error naming option when neither
 * makes text of it. */
gboolean option_value_to_utf8(gchar **value,
                              const gchar *option,
                              GError **error);

/* A whole argument that is a finite decimal number, space around it
 * allowed ("0.5 " from a script's variable), hexadecimal not (strtod
 * reads "0x10" as 16: not what anyone types for a time or a size). */
gboolean option_parse_number(const gchar *text,
                             gdouble *value);

G_END_DECLS

#endif
