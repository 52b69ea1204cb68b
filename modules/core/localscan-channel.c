/*
 *  Local-scan compensation of one channel (a GwyDataField in a container).
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <string.h>
#include <math.h>
#include <libgwyddion/gwymacros.h>
#include <libgwyddion/gwysiunit.h>
#include <libprocess/stats.h>
#include "localscan-channel.h"
#include "paper-compensate.h"
#include "continuous-compensate.h"
#include "stripe-geometry.h"

GQuark
localscan_channel_error_quark(void)
{
    return g_quark_from_static_string("localscan-channel-error-quark");
}

gchar*
localscan_channel_result_title(const gchar *source_title)
{
    return g_strconcat(source_title, LOCALSCAN_TITLE_SUFFIX, NULL);
}

gchar*
localscan_channel_table_label(const gchar *filename, gint id)
{
    if (filename)
        return g_strdup_printf("%s, channel %d drift table", filename, id);
    return g_strdup_printf("channel %d drift table", id);
}

static GwyContainer*
channel_meta(GwyContainer *data, gint id, gboolean create)
{
    GwyContainer *meta = NULL;
    gchar key[32];

    g_snprintf(key, sizeof(key), "/%d/meta", id);
    if (gwy_container_gis_object_by_name(data, key, &meta) && GWY_IS_CONTAINER(meta))
        return meta;
    if (!create)
        return NULL;
    meta = gwy_container_new();
    gwy_container_set_object_by_name(data, key, meta);
    g_object_unref(meta);
    return meta;
}

const gchar*
localscan_channel_stored_table_text(GwyContainer *data, gint id)
{
    GwyContainer *meta = channel_meta(data, id, FALSE);
    const guchar *text = NULL;

    if (meta && gwy_container_gis_string_by_name(meta, DRIFT_TABLE_META_KEY, &text))
        return (const gchar*)text;
    return NULL;
}

DriftTable*
localscan_channel_stored_table(GwyContainer *data, gint id, GError **error)
{
    const gchar *text = localscan_channel_stored_table_text(data, id);
    DriftTable *table = NULL;
    gchar *label;

    if (text) {
        label = localscan_channel_table_label(NULL, id);
        table = drift_table_parse(text, -1, label, error);
        g_free(label);
    }
    else {
        g_set_error(error, LOCALSCAN_CHANNEL_ERROR, LOCALSCAN_CHANNEL_ERROR_NO_TABLE,
                    "Channel %d has no stored drift table (metadata item '%s').", id, DRIFT_TABLE_META_KEY);
    }
    return table;
}

void
localscan_channel_store_table_text(GwyContainer *data, gint id, const gchar *text)
{
    gwy_container_set_string_by_name(channel_meta(data, id, TRUE), DRIFT_TABLE_META_KEY,
                                     (const guchar*)g_strdup(text));
}

void
localscan_channel_store_table(GwyContainer *data, gint id, const DriftTable *table)
{
    gwy_container_set_string_by_name(channel_meta(data, id, TRUE), DRIFT_TABLE_META_KEY,
                                     (const guchar*)drift_table_to_string(table));
}

/* A metadata value such as "2.325 Hz", "0.5 s" or "0.413": the number in
 * base SI units of the given unit, or the bare number when no unit follows.
 * FALSE when the text is no finite number or carries another unit. */
static gboolean
parse_meta_quantity(const gchar *text, const gchar *unit, gdouble *value)
{
    GwySIUnit *siunit;
    gchar *end, *rest;
    gint power10 = 0;
    gboolean ok;
    gdouble v;

    v = g_ascii_strtod(text, &end);
    if (end == text || !isfinite(v))
        return FALSE;
    rest = g_strstrip(g_strdup(end));
    if (!*rest) {
        g_free(rest);
        *value = v;
        return TRUE;
    }
    siunit = gwy_si_unit_new_parse(rest, &power10);
    ok = gwy_si_unit_equal_string(siunit, unit);
    g_object_unref(siunit);
    g_free(rest);
    if (ok)
        *value = v*pow(10.0, power10);
    return ok;
}

/* The first of the keys (NULL-terminated) whose value parses. */
static gboolean
meta_quantity(GwyContainer *meta, const gchar *const *keys, const gchar *unit, gdouble *value)
{
    const guchar *text;

    for (; *keys; keys++) {
        if (gwy_container_gis_string_by_name(meta, *keys, &text)
            && parse_meta_quantity((const gchar*)text, unit, value))
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

static gboolean
meta_line_time(GwyContainer *meta, gint yres, gdouble *line_time)
{
    static const gchar *const line_time_keys[] = { "Line time (s)", "Line time", "Line Time", NULL };
    static const gchar *const line_rate_keys[] = { "Scan rate", "Scan Rate", "ScanRate", NULL };
    static const gchar *const frame_time_keys[] = { "Frame time (s)", NULL };
    gdouble v;

    if (meta_positive(meta, line_time_keys, "s", line_time))
        return TRUE;
    if (meta_positive(meta, line_rate_keys, "Hz", &v)) {
        *line_time = 1.0/v;
        return TRUE;
    }
    if (yres > 0 && meta_positive(meta, frame_time_keys, "s", &v)) {
        *line_time = v/yres;
        return TRUE;
    }
    return FALSE;
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
    const guchar *text;

    for (key = keys; *key; key++) {
        if (!gwy_container_gis_string_by_name(meta, *key, &text))
            continue;
        if (starts_with_word((const gchar*)text, "down")) {
            *direction = SCAN_DIRECTION_DOWN;
            return TRUE;
        }
        if (starts_with_word((const gchar*)text, "up")) {
            *direction = SCAN_DIRECTION_UP;
            return TRUE;
        }
    }
    return FALSE;
}

static gboolean
meta_frame_start(GwyContainer *meta, gdouble *frame_start)
{
    static const gchar *const keys[] = { "Frame start (s)", "Time since first kept frame (s)", NULL };

    return meta_quantity(meta, keys, "s", frame_start);
}

LocalscanTimingFound
localscan_channel_scan_timing(GwyContainer *data, gint id, ScanDirection fallback_direction,
                              ScanTiming *timing)
{
    GwyContainer *meta = channel_meta(data, id, FALSE);
    GwyDataField *field = NULL;
    LocalscanTimingFound found = 0;
    gchar key[32];
    gdouble line_time = LOCALSCAN_DEFAULT_LINE_TIME, frame_start = 0.0;
    ScanDirection direction = fallback_direction;
    gint xres = 0, yres = 0;

    g_snprintf(key, sizeof(key), "/%d/data", id);
    if (gwy_container_gis_object_by_name(data, key, &field) && GWY_IS_DATA_FIELD(field)) {
        xres = gwy_data_field_get_xres(field);
        yres = gwy_data_field_get_yres(field);
    }
    if (meta) {
        if (meta_line_time(meta, yres, &line_time))
            found |= LOCALSCAN_TIMING_LINE_TIME;
        if (meta_direction(meta, &direction))
            found |= LOCALSCAN_TIMING_DIRECTION;
        if (meta_frame_start(meta, &frame_start))
            found |= LOCALSCAN_TIMING_FRAME_START;
    }
    scan_timing_init(timing, xres, yres, frame_start, line_time, direction);
    return found;
}

gdouble
localscan_fill_value(GwyDataField *field, LocalscanFill fill)
{
    gint xres = gwy_data_field_get_xres(field), yres = gwy_data_field_get_yres(field);

    if (fill == LOCALSCAN_FILL_ZERO)
        return 0.0;
    if (fill == LOCALSCAN_FILL_MINIMUM)
        return gwy_data_field_get_min(field);
    if (fill == LOCALSCAN_FILL_MAXIMUM)
        return gwy_data_field_get_max(field);
    return paper_image_mean(gwy_data_field_get_data_const(field), xres, yres);
}

gboolean
localscan_table_to_field_pixels(const DriftTable *table, GwyDataField *field, gboolean whole_pixels,
                                gdouble *dx_px, gdouble *dy_px, GError **error)
{
    GwySIUnit *xyunit = gwy_data_field_get_si_unit_xy(field);
    gchar *unitstr;

    if (table->unit != DRIFT_UNIT_PX && !gwy_si_unit_equal_string(xyunit, "m")) {
        unitstr = gwy_si_unit_get_string(xyunit, GWY_SI_UNIT_FORMAT_PLAIN);
        g_set_error(error, LOCALSCAN_CHANNEL_ERROR, LOCALSCAN_CHANNEL_ERROR_UNITS,
                    "%s: the table is in %s but the image's lateral unit is '%s', not metres.",
                    table->source_name, drift_unit_name(table->unit), unitstr);
        g_free(unitstr);
        return FALSE;
    }
    return drift_table_to_pixels(table, gwy_data_field_get_yres(field),
                                 gwy_data_field_get_dx(field), gwy_data_field_get_dy(field),
                                 whole_pixels, dx_px, dy_px, error);
}

static void
paper_compensate_field(GwyDataField *field, const LocalscanApplied *applied, gdouble fill_value,
                       GwyDataField *result, GwyDataField *mask)
{
    gint n = applied->n_stripes, s;
    gint *dx = g_new(gint, n), *dy = g_new(gint, n);

    for (s = 0; s < n; s++) {
        dx[s] = (gint)floor(applied->dx_px[s] + 0.5);
        dy[s] = (gint)floor(applied->dy_px[s] + 0.5);
    }
    paper_compensate(gwy_data_field_get_data_const(field),
                     gwy_data_field_get_xres(field), gwy_data_field_get_yres(field),
                     n, dx, dy, fill_value,
                     gwy_data_field_get_data(result), gwy_data_field_get_data(mask));
    g_free(dx);
    g_free(dy);
}

static gboolean
continuous_compensate_field(GwyDataField *field, const DriftTable *table, const LocalscanOptions *options,
                            gdouble fill_value, GwyDataField *result, GwyDataField *mask, GError **error)
{
    gint xres = gwy_data_field_get_xres(field), yres = gwy_data_field_get_yres(field);
    ScanTiming timing;

    scan_timing_init(&timing, xres, yres, options->frame_start, options->line_time, options->direction);
    return continuous_compensate_table(gwy_data_field_get_data_const(field), xres, yres, table,
                                       gwy_data_field_get_dx(field), gwy_data_field_get_dy(field),
                                       &timing, options->interpolation, fill_value,
                                       gwy_data_field_get_data(result), gwy_data_field_get_data(mask),
                                       error);
}

static gint
count_filled(GwyDataField *mask)
{
    const gdouble *m = gwy_data_field_get_data_const(mask);
    gint i, n = gwy_data_field_get_xres(mask)*gwy_data_field_get_yres(mask), count = 0;

    for (i = 0; i < n; i++)
        count += (m[i] > 0.5);
    return count;
}

gboolean
localscan_compensate_field(GwyDataField *field, const DriftTable *table, const LocalscanOptions *options,
                           GwyDataField *result, GwyDataField *mask, LocalscanApplied *applied,
                           GError **error)
{
    gboolean paper = (options->mode == LOCALSCAN_MODE_PAPER);
    LocalscanApplied local;
    GwyDataField *filled;
    gdouble fill_value;
    gboolean ok = TRUE;

    local.n_stripes = table->n_stripes;
    local.dx_px = g_new0(gdouble, table->n_stripes);
    local.dy_px = g_new0(gdouble, table->n_stripes);
    local.n_filled = 0;
    if (!localscan_table_to_field_pixels(table, field, paper, local.dx_px, local.dy_px, error)) {
        localscan_applied_clear(&local);
        return FALSE;
    }

    /* Continuous compensation reads the table itself (exact columns, times);
     * the conversion above still validates it and gives the applied drift. */
    gwy_data_field_assign(result, field);
    filled = mask ? g_object_ref(mask) : gwy_data_field_new_alike(field, FALSE);
    gwy_data_field_assign(filled, field);
    gwy_si_unit_set_from_string(gwy_data_field_get_si_unit_z(filled), NULL);
    gwy_data_field_clear(filled);

    fill_value = localscan_fill_value(field, options->fill);
    if (paper)
        paper_compensate_field(field, &local, fill_value, result, filled);
    else
        ok = continuous_compensate_field(field, table, options, fill_value, result, filled, error);

    gwy_data_field_invalidate(result);
    gwy_data_field_invalidate(filled);
    local.n_filled = ok ? count_filled(filled) : 0;
    g_object_unref(filled);

    if (ok && applied)
        *applied = local;
    else
        localscan_applied_clear(&local);
    return ok;
}

void
localscan_applied_clear(LocalscanApplied *applied)
{
    g_free(applied->dx_px);
    g_free(applied->dy_px);
    applied->dx_px = applied->dy_px = NULL;
    applied->n_stripes = applied->n_filled = 0;
}

void
localscan_applied_to_physical(const LocalscanApplied *applied, GwyDataField *field,
                              gdouble *ypos, gdouble *dx, gdouble *dy)
{
    gint yres = gwy_data_field_get_yres(field), n = applied->n_stripes, s;
    gdouble xstep = gwy_data_field_get_dx(field), ystep = gwy_data_field_get_dy(field);
    gdouble yoff = gwy_data_field_get_yoffset(field);

    for (s = 0; s < n; s++) {
        ypos[s] = yoff + (stripe_centre_row(s, n, yres) + 0.5)*ystep;
        dx[s] = applied->dx_px[s]*xstep;
        dy[s] = applied->dy_px[s]*ystep;
    }
}

DriftTable*
localscan_table_round_px(const DriftTable *table)
{
    DriftTable *rounded;
    gint s;

    g_return_val_if_fail(table && table->unit == DRIFT_UNIT_PX, NULL);
    rounded = drift_table_copy(table);
    for (s = 0; s < rounded->n_stripes; s++) {
        DriftTableRow *row = rounded->rows + s;

        if (row->has_drift) {
            row->dx = floor(row->dx + 0.5);
            row->dy = floor(row->dy + 0.5);
        }
    }
    return rounded;
}

gint
localscan_table_stated_px(const DriftTable *table, GwyDataField *field,
                          gint *stripes, gdouble *dx_px, gdouble *dy_px, GError **error)
{
    gint n = table->n_stripes, s, count = 0;
    gdouble *filled_dx = g_new(gdouble, 2*n), *filled_dy = filled_dx + n;

    if (!localscan_table_to_field_pixels(table, field, FALSE, filled_dx, filled_dy, error)) {
        g_free(filled_dx);
        return -1;
    }
    for (s = 0; s < n; s++) {
        if (!table->rows[s].has_drift)
            continue;
        stripes[count] = s;
        if (!drift_table_get_extra(table, s, "dx_exact", dx_px + count))
            dx_px[count] = filled_dx[s];
        if (!drift_table_get_extra(table, s, "dy_exact", dy_px + count))
            dy_px[count] = filled_dy[s];
        count++;
    }
    g_free(filled_dx);
    return count;
}
