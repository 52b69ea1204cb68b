/*
 *  GLib's command-line parsing for the tools, with a refusal that names
 *  the option whose value is not text.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <string.h>
#include <math.h>
#include "option-parse.h"
#include "localscan-intl.h"

/* The option an argument is the value of: the name before '=' of a long
 * option written with its value, else the argument before it when that is
 * an option written alone; NULL for an argument of its own. */
static gchar*
option_of_value(gchar **args, gint i)
{
    const gchar *eq;

    gchar *option = NULL, *shown;

    if (g_str_has_prefix(args[i], "--") && (eq = strchr(args[i], '=')))
        option = g_strndup(args[i], eq - args[i]);
    else if (i > 1 && args[i-1][0] == '-' && args[i-1][1] && !strchr(args[i-1], '='))
        option = g_strdup(args[i-1]);
    if (!option)
        return NULL;
    /* The option's own name may be bytes of any kind too. */
    shown = g_utf8_make_valid(option, -1);
    g_free(option);
    return shown;
}

gchar*
option_parse_unconvertible(gchar **args, const gchar *reason)
{
    gchar *text, *option, *message;
    gint i;

    for (i = 1; args && args[i]; i++) {
        if ((text = g_locale_to_utf8(args[i], -1, NULL, NULL, NULL))) {
            g_free(text);
            continue;
        }
        /* An argument of its own is a file name, which GLib takes as
         * bytes: not the one it could not convert. */
        if (!(option = option_of_value(args, i)))
            continue;
        message = g_strdup_printf(_("the value of %s is not text in this locale's encoding (%s)"),
                                  option, reason);
        g_free(option);
        return message;
    }
    return NULL;
}

/* A conversion error of the parse of given (as it was before the parse)
 * made into one that names the option. */
static void
name_unconvertible(gchar **given, GError **err)
{
    gchar *message;

    if (*err && (*err)->domain == G_CONVERT_ERROR
        && (message = option_parse_unconvertible(given, (*err)->message))) {
        g_clear_error(err);
        g_set_error_literal(err, G_OPTION_ERROR, G_OPTION_ERROR_BAD_VALUE, message);
        g_free(message);
    }
}

/* What both parses end with: a conversion error named, the copy of the
 * arguments freed. */
static gboolean
parse_finish(gboolean ok, gchar **given, GError *err, GError **error)
{
    name_unconvertible(given, &err);
    if (err)
        g_propagate_error(error, err);
    g_strfreev(given);
    return ok;
}

gboolean
option_parse_naming(GOptionContext *context, gint *argc, gchar ***argv, GError **error)
{
    /* The parse takes what it reads out of argv. */
    gchar **given = g_strdupv(*argv);
    GError *err = NULL;
    gboolean ok;

    ok = g_option_context_parse(context, argc, argv, &err);
    return parse_finish(ok, given, err, error);
}

gboolean
option_parse_naming_strv(GOptionContext *context, gchar ***args, GError **error)
{
    gchar **given = g_strdupv(*args);
    GError *err = NULL;
    gboolean ok;

    ok = g_option_context_parse_strv(context, args, &err);
    return parse_finish(ok, given, err, error);
}

gboolean
option_value_to_utf8(gchar **value, const gchar *option, GError **error)
{
    GError *err = NULL;
    gchar *text;

    if (!*value || g_utf8_validate(*value, -1, NULL))
        return TRUE;
    if (!(text = g_locale_to_utf8(*value, -1, NULL, NULL, &err))) {
        g_set_error(error, G_OPTION_ERROR, G_OPTION_ERROR_BAD_VALUE,
                    _("the value of %s is not text in this locale's encoding (%s)"), option, err->message);
        g_clear_error(&err);
        return FALSE;
    }
    g_free(*value);
    *value = text;
    return TRUE;
}

gboolean
option_parse_number(const gchar *text, gdouble *value)
{
    gchar *end;
    gdouble v;

    if (!text || strpbrk(text, "xX"))
        return FALSE;
    v = g_ascii_strtod(text, &end);
    if (end == text)
        return FALSE;
    while (g_ascii_isspace(*end))
        end++;
    if (*end || !isfinite(v))
        return FALSE;
    *value = v;
    return TRUE;
}
