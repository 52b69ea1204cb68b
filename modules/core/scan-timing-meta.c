/*
 *  A channel's scan timing as its file's metadata states it.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <stdio.h>
#include <string.h>
#include <math.h>
#include <libgwyddion/gwymacros.h>
#include <libprocess/datafield.h>
#include "scan-timing-meta.h"
#include "localscan-params.h"

/* The SI prefixes a time or rate is written with. */
static const struct {
    const gchar *prefix;
    gint power10;
} si_prefixes[] = {
    { "", 0 }, { "k", 3 }, { "M", 6 }, { "G", 9 }, { "m", -3 }, { "u", -6 },
    { "\xc2\xb5", -6 }, { "\xce\xbc", -6 }, { "n", -9 }, { "p", -12 },
};

/* The power of ten of a unit written as an SI prefix and unit ("ms",
 * "kHz", "µs"); FALSE for anything else.  Matched against the table, not
 * parsed by Gwyddion, which keeps every unit name it ever parsed for the
 * life of the process: hostile metadata would grow that without bound. */
static gboolean
unit_power10(const gchar *text, const gchar *unit, gint *power10)
{
    gsize len = strlen(text), ulen = strlen(unit);
    guint i;

    if (len < ulen || strcmp(text + len - ulen, unit) != 0)
        return FALSE;
    for (i = 0; i < G_N_ELEMENTS(si_prefixes); i++) {
        if (strlen(si_prefixes[i].prefix) == len - ulen
            && strncmp(text, si_prefixes[i].prefix, len - ulen) == 0) {
            *power10 = si_prefixes[i].power10;
            return TRUE;
        }
    }
    return FALSE;
}

/* A metadata value such as "2.325 Hz", "0.5 s" or "0.413": the number in
 * base SI units of the given unit, or the bare number when no unit follows.
 * FALSE when the text is no finite number or carries another unit. */
static gboolean
parse_meta_quantity(const gchar *text, const gchar *unit, gdouble *value)
{
    gchar *end, *rest;
    gint power10 = 0;
    gboolean ok;
    gdouble v;

    v = g_ascii_strtod(text, &end);
    if (end == text || !isfinite(v))
        return FALSE;
    rest = g_strstrip(g_strdup(end));
    ok = (!*rest || unit_power10(rest, unit, &power10));
    g_free(rest);
    if (ok)
        *value = v*pow(10.0, power10);
    return ok;
}

static const gchar*
meta_string(GwyContainer *meta, const gchar *key)
{
    const guchar *text = NULL;

    if (gwy_container_gis_string_by_name(meta, key, &text))
        return (const gchar*)text;
    return NULL;
}

/* The first of the keys (NULL-terminated) whose value parses. */
static gboolean
meta_quantity(GwyContainer *meta, const gchar *const *keys, const gchar *unit, gdouble *value)
{
    const gchar *text;

    for (; *keys; keys++) {
        if ((text = meta_string(meta, *keys)) && parse_meta_quantity(text, unit, value))
            return TRUE;
    }
    return FALSE;
}

static gboolean
meta_positive(GwyContainer *meta, const gchar *const *keys, const gchar *unit, gdouble *value)
{
    gdouble v;

    if (!meta_quantity(meta, keys, unit, &v) || v <= 0.0)
        return FALSE;
    *value = v;
    return TRUE;
}

static const gchar *const line_time_keys[] = { "Line time (s)", "Line time", "Line Time", NULL };
static const gchar *const line_rate_keys[] = { "Scan rate", "Scan Rate", "ScanRate", NULL };
static const gchar *const frame_time_keys[] = { "Frame time (s)", NULL };
static const gchar *const frame_start_keys[] = {
    "Frame start (s)", "Time since first kept frame (s)", "Relative frame time", NULL
};
static const gchar *const frame_date_keys[] = { "TimeStamp", "Date", NULL };

static gboolean
meta_line_time(GwyContainer *meta, gint yres, gdouble *line_time)
{
    gdouble v, t;

    if (meta_positive(meta, line_time_keys, "s", &v))
        t = v;
    else if (meta_positive(meta, line_rate_keys, "Hz", &v))
        t = 1.0/v;
    else if (yres > 0 && meta_positive(meta, frame_time_keys, "s", &v))
        t = v/yres;
    else
        return FALSE;
    /* A line time no instrument has (1e300 s, a rate of 1e-300 Hz) is a
     * damaged file: it counts as absent, so the fallback is used and the
     * tools say they assumed it. */
    if (!(t >= LOCALSCAN_LINE_TIME_MIN && t <= LOCALSCAN_LINE_TIME_MAX))
        return FALSE;
    *line_time = t;
    return TRUE;
}

/* The text begins with the word (any case), perhaps followed by more. */
static gboolean
starts_with_word(const gchar *text, const gchar *word)
{
    gsize len = strlen(word);

    while (g_ascii_isspace(*text))
        text++;
    return !g_ascii_strncasecmp(text, word, len) && !g_ascii_isalnum(text[len]);
}

static gboolean
meta_direction(GwyContainer *meta, ScanDirection *direction)
{
    static const gchar *const keys[] = { "Slow scan", "Frame direction", NULL };
    const gchar *const *key;
    const gchar *text;

    for (key = keys; *key; key++) {
        if (!(text = meta_string(meta, *key)))
            continue;
        if (starts_with_word(text, "down")) {
            *direction = SCAN_DIRECTION_DOWN;
            return TRUE;
        }
        if (starts_with_word(text, "up")) {
            *direction = SCAN_DIRECTION_UP;
            return TRUE;
        }
    }
    return FALSE;
}

/* Nanoscope "Date": "04:06:25 PM Thu Sep 26 2019", as s since 1970 (UTC,
 * the file does not say its zone; only differences matter). */
static gboolean
parse_nanoscope_date(const gchar *text, gdouble *t)
{
    static const gchar months[] = "JanFebMarAprMayJunJulAugSepOctNovDec";
    gint h, m, sec, day, year;
    gchar ampm[4], wday[4], mon[4];
    const gchar *p;
    GDateTime *dt;

    if (sscanf(text, "%d:%d:%d %2s %3s %3s %d %d", &h, &m, &sec, ampm, wday, mon, &day, &year) != 8)
        return FALSE;
    if (strlen(mon) != 3 || !(p = strstr(months, mon)) || (p - months) % 3)
        return FALSE;
    h %= 12;
    if (g_ascii_toupper(ampm[0]) == 'P')
        h += 12;
    if (!(dt = g_date_time_new_utc(year, (p - months)/3 + 1, day, h, m, sec)))
        return FALSE;
    *t = (gdouble)g_date_time_to_unix(dt);
    g_date_time_unref(dt);
    return TRUE;
}

static gboolean
parse_iso_time(const gchar *text, gdouble *t)
{
    GDateTime *dt = g_date_time_new_from_iso8601(text, NULL);

    if (!dt)
        return FALSE;
    *t = g_date_time_to_unix(dt) + 1e-6*g_date_time_get_microsecond(dt);
    g_date_time_unref(dt);
    return TRUE;
}

static gboolean
meta_frame_start(GwyContainer *meta, ScanMetaTiming *timing)
{
    const gchar *text;
    gdouble t;

    if (meta_quantity(meta, frame_start_keys, "s", &t)) {
        timing->frame_start = t;
        timing->start_is_end = timing->wall_clock = FALSE;
        return TRUE;
    }
    /* Anasys nanoIR stamps an image when it is stored, that is when its
     * last line has been scanned. */
    if ((text = meta_string(meta, "TimeStamp")) && parse_iso_time(text, &t)) {
        timing->frame_start = t;
        timing->start_is_end = timing->wall_clock = TRUE;
        return TRUE;
    }
    if ((text = meta_string(meta, "Date")) && parse_nanoscope_date(text, &t)) {
        timing->frame_start = t;
        timing->start_is_end = FALSE;
        timing->wall_clock = TRUE;
        return TRUE;
    }
    return FALSE;
}

ScanMetaFound
scan_timing_meta_read(GwyContainer *meta, gint yres, ScanMetaTiming *timing)
{
    ScanMetaFound found = 0;

    if (!meta)
        return 0;
    if (meta_line_time(meta, yres, &timing->line_time))
        found |= SCAN_META_LINE_TIME;
    if (meta_direction(meta, &timing->direction))
        found |= SCAN_META_DIRECTION;
    if (meta_frame_start(meta, timing))
        found |= SCAN_META_FRAME_START;
    return found;
}

ScanMetaFound
scan_timing_meta_read_channel(GwyContainer *data, gint id, ScanMetaTiming *timing)
{
    GwyContainer *meta = NULL;
    GObject *field = NULL;
    gchar key[32];
    gint yres = 0;

    g_snprintf(key, sizeof(key), "/%d/data", id);
    if (gwy_container_gis_object_by_name(data, key, &field) && GWY_IS_DATA_FIELD(field))
        yres = gwy_data_field_get_yres(GWY_DATA_FIELD(field));
    g_snprintf(key, sizeof(key), "/%d/meta", id);
    if (!gwy_container_gis_object_by_name(data, key, &meta) || !GWY_IS_CONTAINER(meta))
        return 0;
    return scan_timing_meta_read(meta, yres, timing);
}

/* The first of keys that meta holds, as "'KEY' is 'VALUE'". */
static gchar*
describe_first_key(GwyContainer *meta, const gchar *const *keys)
{
    const gchar *text;
    gchar *valid, *shown;
    glong len;

    for (; *keys; keys++) {
        if (!(text = meta_string(meta, *keys)))
            continue;
        /* A damaged file's value may be any bytes, and of any length. */
        valid = g_utf8_make_valid(text, -1);
        len = g_utf8_strlen(valid, -1);
        shown = g_utf8_substring(valid, 0, MIN(len, SCAN_META_SHOWN_CHARS));
        g_free(valid);
        valid = g_strdup_printf("'%s' is '%s%s'", *keys, shown, (len > SCAN_META_SHOWN_CHARS) ? "..." : "");
        g_free(shown);
        return valid;
    }
    return NULL;
}

gchar*
scan_timing_meta_unusable(GwyContainer *meta, ScanMetaFound part)
{
    const gchar *const *const line_time[] = { line_time_keys, line_rate_keys, frame_time_keys, NULL };
    const gchar *const *const frame_start[] = { frame_start_keys, frame_date_keys, NULL };
    const gchar *const *const direction[] = { NULL };
    const gchar *const *const *lists;
    gchar *found = NULL;

    if (!meta)
        return NULL;
    if (part == SCAN_META_LINE_TIME)
        lists = line_time;
    else if (part == SCAN_META_FRAME_START)
        lists = frame_start;
    else
        lists = direction;
    for (; *lists && !found; lists++)
        found = describe_first_key(meta, *lists);
    return found;
}
