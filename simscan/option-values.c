/*
 *  Numbers given on simscan's command lines.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <math.h>
#include <stdio.h>
#include "option-values.h"
#include "quoted-input.h"
#include "simscan-i18n.h"

gboolean
option_value_refuse(const gchar *option, const gchar *what, GError **error)
{
    g_set_error(error, G_OPTION_ERROR, G_OPTION_ERROR_BAD_VALUE,
                _("--%s: %s"), option, what);
    return FALSE;
}

gboolean
option_value_check_range(gdouble value, gdouble min, gdouble max,
                         gboolean min_open, const gchar *option,
                         GError **error)
{
    gchar *msg;

    if (isfinite(value) && (min_open ? value > min : value >= min)
        && value <= max)
        return TRUE;
    msg = g_strdup_printf(_("%g is out of range (%s %g to %g)"), value,
                          min_open ? _("above") : _("from"), min, max);
    option_value_refuse(option, msg, error);
    g_free(msg);
    return FALSE;
}

gboolean
option_value_parse_double(const gchar *text, gdouble min, gdouble max,
                          gboolean min_open, const gchar *option,
                          gdouble *value, GError **error)
{
    gchar *end, *msg;
    gdouble v;

    v = g_ascii_strtod(text, &end);
    if (end == text || *end) {
        msg = g_strdup_printf(_("'%s' is not a number"), text);
        option_value_refuse(option, msg, error);
        g_free(msg);
        return FALSE;
    }
    if (!option_value_check_range(v, min, max, min_open, option, error))
        return FALSE;
    *value = v;
    return TRUE;
}

gboolean
option_value_parse_int(const gchar *text, gint min, gint max,
                       const gchar *option, gint *value, GError **error)
{
    GError *err = NULL;
    gint64 v;
    gchar *msg;

    if (!g_ascii_string_to_signed(text, 10, min, max, &v, &err)) {
        if (g_error_matches(err, G_NUMBER_PARSER_ERROR,
                            G_NUMBER_PARSER_ERROR_OUT_OF_BOUNDS))
            msg = g_strdup_printf(_("%s is out of range (from %d to %d)"),
                                  text, min, max);
        else
            msg = g_strdup_printf(_("'%s' is not a whole number"), text);
        g_error_free(err);
        option_value_refuse(option, msg, error);
        g_free(msg);
        return FALSE;
    }
    *value = (gint)v;
    return TRUE;
}

void
simscan_print_error(const gchar *prefix, const GError *error)
{
    gchar *line = quoted_input_message_line(error->message);

    fprintf(stderr, "%s: %s\n", prefix, line);
    g_free(line);
}
