/*
 *  One compensation run in words.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <string.h>
#include <libgwyddion/gwymacros.h>
#include <libgwyddion/gwyutils.h>
#include "run-description.h"

const gchar*
run_description_source_name(LocalscanSource source)
{
    if (source == LOCALSCAN_SOURCE_STORED)
        return "stored table";
    if (source == LOCALSCAN_SOURCE_FILE)
        return "table file";
    if (source == LOCALSCAN_SOURCE_REFERENCE)
        return "reference";
    return "unknown";
}

const gchar*
run_description_mode_name(LocalscanMode mode)
{
    if (mode == LOCALSCAN_MODE_PAPER)
        return "paper";
    if (mode == LOCALSCAN_MODE_CONTINUOUS)
        return "continuous";
    return "unknown";
}

/* Lower-case forms of Gwyddion's own names of the kernels that resample. */
static const GwyEnum interpolation_names[] = {
    { "round",   GWY_INTERPOLATION_ROUND,   },
    { "linear",  GWY_INTERPOLATION_LINEAR,  },
    { "key",     GWY_INTERPOLATION_KEY,     },
    { "bspline", GWY_INTERPOLATION_BSPLINE, },
    { "omoms",   GWY_INTERPOLATION_OMOMS,   },
    { "nna",     GWY_INTERPOLATION_NNA,     },
    { "schaum",  GWY_INTERPOLATION_SCHAUM,  },
};

const gchar*
run_description_interpolation_name(GwyInterpolationType interpolation)
{
    const gchar *name = gwy_enum_to_string(interpolation, interpolation_names,
                                           G_N_ELEMENTS(interpolation_names));

    return *name ? name : "unknown";
}

gint
run_description_interpolation_from_name(const gchar *name)
{
    return gwy_string_to_enum(name, interpolation_names, G_N_ELEMENTS(interpolation_names));
}

gchar*
run_description_interpolation_names(void)
{
    GString *names = g_string_new(NULL);
    guint i;

    for (i = 0; i < G_N_ELEMENTS(interpolation_names); i++)
        g_string_append_printf(names, i ? ", %s" : "%s", interpolation_names[i].name);
    return g_string_free(names, FALSE);
}

const gchar*
run_description_fill_name(LocalscanFill fill)
{
    static const gchar *const names[] = { "mean", "zero", "minimum", "maximum", };

    if ((guint)fill < G_N_ELEMENTS(names))
        return names[fill];
    return "unknown";
}

gint
run_description_parse_mode(const gchar *text)
{
    static const gchar key[] = "mode=";
    const gchar *p, *value;
    gchar *end;
    gint mode;

    for (p = text; (p = strstr(p, key)); p++) {
        if (p != text && p[-1] != '(' && p[-1] != ' ')
            continue;
        value = p + strlen(key);
        if (g_str_has_prefix(value, run_description_mode_name(LOCALSCAN_MODE_PAPER)))
            return LOCALSCAN_MODE_PAPER;
        if (g_str_has_prefix(value, run_description_mode_name(LOCALSCAN_MODE_CONTINUOUS)))
            return LOCALSCAN_MODE_CONTINUOUS;
        mode = (gint)g_ascii_strtoll(value, &end, 10);
        return end == value ? -1 : mode;
    }
    return -1;
}

static const gchar *const masking_names[] = {
    [GWY_MASK_EXCLUDE] = "exclude",
    [GWY_MASK_INCLUDE] = "include",
    [GWY_MASK_IGNORE] = "ignore",
};

const gchar*
run_description_masking_name(GwyMaskingType masking)
{
    if ((guint)masking < G_N_ELEMENTS(masking_names))
        return masking_names[masking];
    return "?";
}

gint
run_description_masking_from_name(const gchar *name)
{
    guint i;

    for (i = 0; name && i < G_N_ELEMENTS(masking_names); i++) {
        if (g_str_equal(name, masking_names[i]))
            return i;
    }
    return -1;
}

gchar*
run_description_format(const RunDescription *run)
{
    GString *text = g_string_new(NULL);

    g_string_append_printf(text, "source=%s", run_description_source_name(run->source));
    if (run->source == LOCALSCAN_SOURCE_FILE && run->table_file)
        g_string_append_printf(text, ", table=%s", run->table_file);
    if (run->source == LOCALSCAN_SOURCE_REFERENCE) {
        g_string_append_printf(text, ", reference=%s, stripes=%d, masking=%s",
                               run->reference ? run->reference : "none", run->stripes,
                               run_description_masking_name(run->masking));
    }
    g_string_append_printf(text, ", mode=%s", run_description_mode_name(run->mode));
    if (run->mode == LOCALSCAN_MODE_CONTINUOUS) {
        g_string_append_printf(text, ", interpolation=%s",
                               run_description_interpolation_name(run->interpolation));
    }
    g_string_append_printf(text, ", fill=%s", run_description_fill_name(run->fill));
    return g_string_free(text, FALSE);
}
