/*
 *  Local-scan compensation of one channel (a GwyDataField in a container).
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <string.h>
#include <stdlib.h>
#include <math.h>
#include <libgwyddion/gwymacros.h>
#include <libgwyddion/gwysiunit.h>
#include <libprocess/stats.h>
#include <libprocess/arithmetic.h>
#include "localscan-channel.h"
#include "paper-compensate.h"
#include "continuous-compensate.h"
#include "drift-trajectory.h"
#include "stripe-geometry.h"
#include "scan-timing-meta.h"
#include "missing-data.h"
#include "localscan-intl.h"

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
        return g_strdup_printf(_("%s, channel %d drift table"), filename, id);
    return g_strdup_printf(_("channel %d drift table"), id);
}

GwyContainer*
localscan_channel_meta(GwyContainer *data, gint id, gboolean create)
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
localscan_channel_meta_string(GwyContainer *data, gint id, const gchar *key)
{
    GwyContainer *meta = localscan_channel_meta(data, id, FALSE);
    const guchar *text = NULL;

    if (meta && gwy_container_gis_string_by_name(meta, key, &text))
        return (const gchar*)text;
    return NULL;
}

const gchar*
localscan_channel_stored_table_text(GwyContainer *data, gint id)
{
    return localscan_channel_meta_string(data, id, DRIFT_TABLE_META_KEY);
}

DriftTable*
localscan_channel_stored_table(GwyContainer *data, gint id, GError **error)
{
    return localscan_channel_stored_table_of_file(data, id, NULL, error);
}

DriftTable*
localscan_channel_stored_table_of_file(GwyContainer *data, gint id, const gchar *filename,
                                       GError **error)
{
    const gchar *text = localscan_channel_stored_table_text(data, id);
    DriftTable *table = NULL;
    gchar *label;

    if (text) {
        label = localscan_channel_table_label(filename, id);
        table = drift_table_parse(text, -1, label, error);
        g_free(label);
    }
    else if (filename) {
        g_set_error(error, LOCALSCAN_CHANNEL_ERROR, LOCALSCAN_CHANNEL_ERROR_NO_TABLE,
                    _("%s: channel %d has no stored drift table (metadata item '%s')"),
                    filename, id, DRIFT_TABLE_META_KEY);
    }
    else {
        g_set_error(error, LOCALSCAN_CHANNEL_ERROR, LOCALSCAN_CHANNEL_ERROR_NO_TABLE,
                    _("Channel %d has no stored drift table (metadata item '%s')."),
                    id, DRIFT_TABLE_META_KEY);
    }
    return table;
}

/* Both sizes, "160 x 160 px, 320.0 x 320.0 nm", for messages. */
static gchar*
format_field_size(GwyDataField *field)
{
    GwySIValueFormat *vf = gwy_data_field_get_value_format_xy(field, GWY_SI_UNIT_FORMAT_PLAIN,
                                                              NULL);
    gchar *text;

    text = g_strdup_printf("%d x %d px, %.*f x %.*f%s%s",
                           gwy_data_field_get_xres(field), gwy_data_field_get_yres(field),
                           vf->precision, gwy_data_field_get_xreal(field)/vf->magnitude,
                           vf->precision, gwy_data_field_get_yreal(field)/vf->magnitude,
                           *vf->units ? " " : "", vf->units);
    gwy_si_unit_value_format_free(vf);
    return text;
}

static gboolean
reference_same_scan(GwyDataField *image, GwyDataField *reference)
{
    return !gwy_data_field_check_compatibility(image, reference,
                                               GWY_DATA_COMPATIBILITY_RES
                                               | GWY_DATA_COMPATIBILITY_REAL
                                               | GWY_DATA_COMPATIBILITY_LATERAL);
}

/* A channel of another quantity (the phase for a height image) shows the
 * sample with another contrast, inverted or changed where materials
 * differ: its features match the image's in places only, which the
 * stripes' scores do not always reveal. */
static gboolean
reference_same_quantity(GwyDataField *image, GwyDataField *reference)
{
    return !gwy_data_field_check_compatibility(image, reference, GWY_DATA_COMPATIBILITY_VALUE);
}

gboolean
localscan_reference_fits(GwyDataField *image, GwyDataField *reference)
{
    return reference_same_scan(image, reference) && reference_same_quantity(image, reference);
}

static gchar*
value_unit_text(GwyDataField *field)
{
    gchar *unit = gwy_si_unit_get_string(gwy_data_field_get_si_unit_z(field), GWY_SI_UNIT_FORMAT_PLAIN);

    if (*unit)
        return unit;
    g_free(unit);
    return g_strdup(_("no unit"));
}

gboolean
localscan_reference_check(GwyDataField *image, const gchar *image_name,
                          GwyDataField *reference, const gchar *reference_name,
                          gint n_stripes, GError **error)
{
    gint yres = gwy_data_field_get_yres(image);
    gchar *size, *refsize;

    if (!reference_same_scan(image, reference)) {
        size = format_field_size(image);
        refsize = format_field_size(reference);
        g_set_error(error, LOCALSCAN_CHANNEL_ERROR, LOCALSCAN_CHANNEL_ERROR_REFERENCE,
                    _("the reference %s (%s) is not a scan of the size of the image %s (%s)"),
                    reference_name, refsize, image_name, size);
        g_free(refsize);
        g_free(size);
        return FALSE;
    }
    if (!reference_same_quantity(image, reference)) {
        size = value_unit_text(image);
        refsize = value_unit_text(reference);
        g_set_error(error, LOCALSCAN_CHANNEL_ERROR, LOCALSCAN_CHANNEL_ERROR_REFERENCE,
                    _("the reference %s holds values in %s, the image %s in %s: register against a "
                      "channel of the same quantity"),
                    reference_name, refsize, image_name, size);
        g_free(refsize);
        g_free(size);
        return FALSE;
    }
    if (n_stripes > yres) {
        g_set_error(error, LOCALSCAN_CHANNEL_ERROR, LOCALSCAN_CHANNEL_ERROR_STRIPES,
                    _("%d stripes do not fit the %d rows of the image %s"),
                    n_stripes, yres, image_name);
        return FALSE;
    }
    /* A stripe of one row registers nothing (its match needs rows to
     * interpolate between), and thousands of them took minutes to fail:
     * 4096 stripes of a 4096 x 4096 image 183 s. */
    if (n_stripes > yres/2) {
        g_set_error(error, LOCALSCAN_CHANNEL_ERROR, LOCALSCAN_CHANNEL_ERROR_STRIPES,
                    _("%d stripes of the %d rows of the image %s leave stripes of one row, which "
                      "cannot be registered: give at most %d"),
                    n_stripes, yres, image_name, yres/2);
        return FALSE;
    }
    return TRUE;
}

void
localscan_channel_store_table_text(GwyContainer *data, gint id, const gchar *text)
{
    gwy_container_set_string_by_name(localscan_channel_meta(data, id, TRUE), DRIFT_TABLE_META_KEY,
                                     (const guchar*)g_strdup(text));
}

void
localscan_channel_store_table(GwyContainer *data, gint id, const DriftTable *table)
{
    gwy_container_set_string_by_name(localscan_channel_meta(data, id, TRUE), DRIFT_TABLE_META_KEY,
                                     (const guchar*)drift_table_to_string(table));
}

LocalscanTimingFound
localscan_channel_scan_timing(GwyContainer *data, gint id, ScanDirection fallback_direction,
                              ScanTiming *timing)
{
    return localscan_channel_scan_timing_fallback(data, id, LOCALSCAN_DEFAULT_LINE_TIME,
                                                  fallback_direction, 0.0, timing);
}

LocalscanTimingFound
localscan_channel_scan_timing_fallback(GwyContainer *data, gint id,
                                       gdouble fallback_line_time,
                                       ScanDirection fallback_direction,
                                       gdouble fallback_frame_start,
                                       ScanTiming *timing)
{
    ScanMetaTiming meta;
    ScanMetaFound meta_found;
    LocalscanTimingFound found = 0;
    GwyDataField *field = NULL;
    gchar key[32];
    gint xres = 0, yres = 0;

    g_snprintf(key, sizeof(key), "/%d/data", id);
    if (gwy_container_gis_object_by_name(data, key, &field) && GWY_IS_DATA_FIELD(field)) {
        xres = gwy_data_field_get_xres(field);
        yres = gwy_data_field_get_yres(field);
    }
    meta.line_time = fallback_line_time;
    meta.direction = fallback_direction;
    meta.frame_start = fallback_frame_start;
    meta_found = scan_timing_meta_read_channel(data, id, &meta);
    if (meta_found & SCAN_META_LINE_TIME)
        found |= LOCALSCAN_TIMING_LINE_TIME;
    if (meta_found & SCAN_META_DIRECTION)
        found |= LOCALSCAN_TIMING_DIRECTION;
    /* A date is no clock a table's t_image, t_local are written in. */
    if ((meta_found & SCAN_META_FRAME_START) && !meta.wall_clock)
        found |= LOCALSCAN_TIMING_FRAME_START;
    else
        meta.frame_start = fallback_frame_start;
    scan_timing_init(timing, xres, yres, meta.frame_start, meta.line_time, meta.direction);
    return found;
}

void
localscan_channel_drop_source_meta(GwyContainer *data, gint id)
{
    static const gchar *const source_only[] = { LOCALSCAN_META_SIMULATED_PARTICLES, };
    GwyContainer *meta = localscan_channel_meta(data, id, FALSE);
    guint i;

    for (i = 0; meta && i < G_N_ELEMENTS(source_only); i++)
        gwy_container_remove_by_name(meta, source_only[i]);
}

gdouble
localscan_fill_value(GwyDataField *field, LocalscanFill fill)
{
    gint xres = gwy_data_field_get_xres(field), yres = gwy_data_field_get_yres(field);

    const gdouble *a = gwy_data_field_get_data_const(field);
    gdouble min, max;

    if (fill == LOCALSCAN_FILL_ZERO)
        return 0.0;
    if (fill == LOCALSCAN_FILL_MEAN)
        return paper_image_mean(a, xres, yres);
    /* Of the pixels present (docs/missing-data.md). */
    missing_data_finite_range(a, (gsize)xres*yres, &min, &max);
    return (fill == LOCALSCAN_FILL_MINIMUM) ? min : max;
}

gboolean
localscan_table_to_field_pixels(const DriftTable *table, GwyDataField *field, gboolean whole_pixels,
                                gdouble *dx_px, gdouble *dy_px, GError **error)
{
    GwySIUnit *xyunit = gwy_data_field_get_si_unit_xy(field);
    gdouble xstep = gwy_data_field_get_dx(field), ystep = gwy_data_field_get_dy(field);
    gchar *unitstr;

    /* Gwyddion mends a zero or negative size when it loads a file, not a NaN
     * or infinite one. */
    if (!(isfinite(xstep) && xstep > 0.0 && isfinite(ystep) && ystep > 0.0)) {
        g_set_error(error, LOCALSCAN_CHANNEL_ERROR, LOCALSCAN_CHANNEL_ERROR_UNITS,
                    _("the image's pixel size (%g x %g) is not a positive number"), xstep, ystep);
        return FALSE;
    }
    if (table->unit != DRIFT_UNIT_PX && !gwy_si_unit_equal_string(xyunit, "m")) {
        unitstr = gwy_si_unit_get_string(xyunit, GWY_SI_UNIT_FORMAT_PLAIN);
        g_set_error(error, LOCALSCAN_CHANNEL_ERROR, LOCALSCAN_CHANNEL_ERROR_UNITS,
                    _("%s: the table is in %s but the image's lateral unit is '%s', not metres."),
                    table->source_name, drift_unit_name(table->unit), unitstr);
        g_free(unitstr);
        return FALSE;
    }
    return drift_table_to_pixels(table, gwy_data_field_get_yres(field), xstep, ystep,
                                 whole_pixels, dx_px, dy_px, error);
}

static void
paper_compensate_field(GwyDataField *field, const LocalscanApplied *applied, gdouble fill_value,
                       GwyDataField *result, GwyDataField *mask)
{
    gint n = applied->n_stripes, s;
    gint *dx = g_new(gint, n), *dy = g_new(gint, n);

    for (s = 0; s < n; s++) {
        dx[s] = (gint)drift_px_round(applied->dx_px[s]);
        dy[s] = (gint)drift_px_round(applied->dy_px[s]);
    }
    paper_compensate(gwy_data_field_get_data_const(field),
                     gwy_data_field_get_xres(field), gwy_data_field_get_yres(field),
                     n, dx, dy, fill_value,
                     gwy_data_field_get_data(result), gwy_data_field_get_data(mask));
    g_free(dx);
    g_free(dy);
}

static gboolean
continuous_compensate_field(GwyDataField *field, const DriftTable *table,
                            const LocalscanOptions *options, gdouble fill_value,
                            GwyDataField *result, GwyDataField *mask, GError **error)
{
    gint xres = gwy_data_field_get_xres(field), yres = gwy_data_field_get_yres(field);
    ScanTiming timing;

    scan_timing_init(&timing, xres, yres,
                     options->frame_start, options->line_time, options->direction);
    return continuous_compensate_table(gwy_data_field_get_data_const(field), xres, yres, table,
                                       gwy_data_field_get_dx(field), gwy_data_field_get_dy(field),
                                       &timing, options->interpolation, fill_value,
                                       gwy_data_field_get_data(result),
                                       gwy_data_field_get_data(mask),
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

/* dest gets field's pixels (its values unspecified), size and units. */
static void
take_geometry(GwyDataField *dest, GwyDataField *field)
{
    gint xres = gwy_data_field_get_xres(field), yres = gwy_data_field_get_yres(field);

    if (gwy_data_field_get_xres(dest) != xres || gwy_data_field_get_yres(dest) != yres)
        gwy_data_field_resample(dest, xres, yres, GWY_INTERPOLATION_NONE);
    gwy_data_field_set_xreal(dest, gwy_data_field_get_xreal(field));
    gwy_data_field_set_yreal(dest, gwy_data_field_get_yreal(field));
    gwy_data_field_set_xoffset(dest, gwy_data_field_get_xoffset(field));
    gwy_data_field_set_yoffset(dest, gwy_data_field_get_yoffset(field));
    gwy_si_unit_assign(gwy_data_field_get_si_unit_xy(dest), gwy_data_field_get_si_unit_xy(field));
    gwy_si_unit_assign(gwy_data_field_get_si_unit_z(dest), gwy_data_field_get_si_unit_z(field));
}

gboolean
localscan_compensate_check(GwyDataField *field, const DriftTable *table,
                           const LocalscanOptions *options, GError **error)
{
    gint xres = gwy_data_field_get_xres(field), yres = gwy_data_field_get_yres(field);
    gboolean paper = (options->mode == LOCALSCAN_MODE_PAPER);
    gdouble *dx = g_new(gdouble, 2*table->n_stripes), *dy = dx + table->n_stripes;
    ScanTiming timing;
    gboolean ok;

    ok = localscan_table_to_field_pixels(table, field, paper, dx, dy, error);
    g_free(dx);
    if (!ok || paper)
        return ok;
    scan_timing_init(&timing, xres, yres,
                     options->frame_start, options->line_time, options->direction);
    return continuous_compensate_check_table(xres, yres, table,
                                             gwy_data_field_get_dx(field),
                                             gwy_data_field_get_dy(field),
                                             &timing, options->interpolation, error);
}

gint
localscan_continuous_left_out(GwyDataField *field, const DriftTable *table,
                              const LocalscanOptions *options, gint *stripes,
                              gdouble *off_px, GError **error)
{
    DriftTrajectory *trajectory;
    ScanTiming timing;
    gdouble off;
    gint i, n = 0;

    if (options->mode == LOCALSCAN_MODE_PAPER)
        return 0;
    scan_timing_init(&timing, gwy_data_field_get_xres(field), gwy_data_field_get_yres(field),
                     options->frame_start, options->line_time, options->direction);
    trajectory = drift_trajectory_new_from_table(table, gwy_data_field_get_dx(field),
                                                 gwy_data_field_get_dy(field), &timing, error);
    if (!trajectory)
        return -1;
    for (i = 0; i < drift_trajectory_n_measurements(trajectory); i++) {
        if (drift_trajectory_measurement_weight(trajectory, i) >= DRIFT_TRAJECTORY_DOWNWEIGHTED
            || !((off = drift_trajectory_measurement_residual(trajectory, i))
                 > LOCALSCAN_LEFT_OUT_MIN_PX))
            continue;
        if (off_px)
            off_px[n] = off;
        stripes[n++] = drift_trajectory_measurement_stripe(trajectory, i);
    }
    drift_trajectory_free(trajectory);
    return n;
}

gboolean
localscan_compensate_field(GwyDataField *field, const DriftTable *table,
                           const LocalscanOptions *options,
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
    if (!missing_data_check(gwy_data_field_get_data_const(field), gwy_data_field_get_xres(field),
                            gwy_data_field_get_yres(field), _("the image"), error)
        || !localscan_table_to_field_pixels(table, field, paper, local.dx_px, local.dy_px,
                                            error)) {
        localscan_applied_clear(&local);
        return FALSE;
    }

    /* Continuous compensation reads the table itself (exact columns, times);
     * the conversion above still validates it and gives the applied drift.
     * Both compensations write every pixel of result and mask, so neither
     * is copied from the image nor cleared first. */
    take_geometry(result, field);
    filled = mask ? g_object_ref(mask) : gwy_data_field_new_alike(field, FALSE);
    take_geometry(filled, field);
    gwy_si_unit_set_from_string(gwy_data_field_get_si_unit_z(filled), NULL);

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

gdouble
localscan_stripe_centre_y(GwyDataField *field, gint stripe, gint n_stripes)
{
    return gwy_data_field_get_yoffset(field)
           + (stripe_centre_row(stripe, n_stripes, gwy_data_field_get_yres(field)) + 0.5)
             *gwy_data_field_get_dy(field);
}

void
localscan_applied_to_physical(const LocalscanApplied *applied, GwyDataField *field,
                              gdouble *ypos, gdouble *dx, gdouble *dy)
{
    gint n = applied->n_stripes, s;
    gdouble xstep = gwy_data_field_get_dx(field), ystep = gwy_data_field_get_dy(field);

    for (s = 0; s < n; s++) {
        ypos[s] = localscan_stripe_centre_y(field, s, n);
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
            row->dx = drift_px_round(row->dx);
            row->dy = drift_px_round(row->dy);
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

/* Adds the id of an item "/ID/data" holding a data field. */
static void
collect_channel_id(gpointer hkey, gpointer hvalue, gpointer user_data)
{
    const gchar *name = g_quark_to_string(GPOINTER_TO_UINT(hkey));
    GValue *value = (GValue*)hvalue;
    GArray *ids = (GArray*)user_data;
    gchar *end;
    glong id;
    gint value_id;

    if (name[0] != '/' || !g_ascii_isdigit(name[1]))
        return;
    id = strtol(name + 1, &end, 10);
    if (strcmp(end, "/data") != 0 || id > G_MAXINT
        || !G_VALUE_HOLDS_OBJECT(value)
        || !GWY_IS_DATA_FIELD(g_value_get_object(value)))
        return;
    value_id = (gint)id;
    g_array_append_val(ids, value_id);
}

static gint
compare_ids(gconstpointer a, gconstpointer b)
{
    gint ia = *(const gint*)a, ib = *(const gint*)b;

    return (ia > ib) - (ia < ib);
}

gint*
localscan_channel_ids(GwyContainer *data)
{
    GArray *ids = g_array_new(FALSE, FALSE, sizeof(gint));
    gint end = -1;

    gwy_container_foreach(data, NULL, collect_channel_id, ids);
    g_array_sort(ids, compare_ids);
    g_array_append_val(ids, end);
    return (gint*)g_array_free(ids, FALSE);
}

gint*
localscan_channel_ids_titled(GwyContainer *data, const gchar *title)
{
    gint *ids = localscan_channel_ids(data), i, n = 0;

    for (i = 0; ids[i] != -1; i++) {
        if (g_strcmp0(localscan_channel_title(data, ids[i]), title) == 0)
            ids[n++] = ids[i];
    }
    ids[n] = -1;
    return ids;
}

gchar*
localscan_channel_id_list(const gint *ids)
{
    GString *str = g_string_new(NULL);
    gint i;

    for (i = 0; ids[i] != -1; i++)
        g_string_append_printf(str, i ? ", %d" : "%d", ids[i]);
    return g_string_free(str, FALSE);
}

gpointer
localscan_channel_item(GwyContainer *data, gint id, const gchar *item)
{
    GObject *object = NULL;
    gchar *key = g_strdup_printf("/%d/%s", id, item);

    gwy_container_gis_object_by_name(data, key, &object);
    g_free(key);
    return object;
}

const gchar*
localscan_channel_title(GwyContainer *data, gint id)
{
    const guchar *title = NULL;
    gchar key[40];

    g_snprintf(key, sizeof(key), "/%d/data/title", id);
    gwy_container_gis_string_by_name(data, key, &title);
    return (const gchar*)title;
}

/* GObject data, not a container item: it must never reach a saved file. */
#define RUN_ERROR_DATA "localscan-run-error"

void
localscan_run_error_set(GwyContainer *data, const GError *error)
{
    g_object_set_data_full(G_OBJECT(data), RUN_ERROR_DATA, error ? g_error_copy(error) : NULL,
                           (GDestroyNotify)g_error_free);
}

GError*
localscan_run_error_take(GwyContainer *data)
{
    return g_object_steal_data(G_OBJECT(data), RUN_ERROR_DATA);
}

GwyDataField*
localscan_channel_mask(GwyContainer *data, gint id)
{
    GwyDataField *field = localscan_channel_item(data, id, "data");
    GObject *mask = localscan_channel_item(data, id, "mask");

    if (!GWY_IS_DATA_FIELD(field) || !GWY_IS_DATA_FIELD(mask)
        || gwy_data_field_check_compatibility(field, GWY_DATA_FIELD(mask), GWY_DATA_COMPATIBILITY_RES)
        || missing_data_count(gwy_data_field_get_data_const(GWY_DATA_FIELD(mask)),
                              (gsize)gwy_data_field_get_xres(field)*gwy_data_field_get_yres(field)))
        return NULL;
    return GWY_DATA_FIELD(mask);
}

gint*
localscan_channels_drop_misfit_masks(GwyContainer *data)
{
    gint *ids = localscan_channel_ids(data), i, n = 0;
    gchar key[32];

    for (i = 0; ids[i] != -1; i++) {
        g_snprintf(key, sizeof(key), "/%d/mask", ids[i]);
        if (gwy_container_contains_by_name(data, key) && !localscan_channel_mask(data, ids[i])) {
            gwy_container_remove_by_name(data, key);
            ids[n++] = ids[i];
        }
    }
    ids[n] = -1;
    return ids;
}

static gsize
fill_missing_of_channel(GwyContainer *data, gint id)
{
    GwyDataField *field = localscan_channel_item(data, id, "data");
    GwyDataField *mask = localscan_channel_mask(data, id);
    gchar *mask_key = g_strdup_printf("/%d/mask", id);
    gdouble *a, *m, fill;
    gsize i, n, filled = 0;

    if (field) {
        a = gwy_data_field_get_data(field);
        n = (gsize)gwy_data_field_get_xres(field)*gwy_data_field_get_yres(field);
        if (missing_data_count(a, n)) {
            /* The one test of a mask (localscan_channel_mask): anything
             * else stored there is replaced by a mask of the filled pixels. */
            if (!mask) {
                mask = gwy_data_field_new_alike(field, TRUE);
                gwy_si_unit_set_from_string(gwy_data_field_get_si_unit_z(mask), NULL);
                gwy_container_set_object_by_name(data, mask_key, mask);
                g_object_unref(mask);
            }
            fill = paper_image_mean(a, gwy_data_field_get_xres(field), gwy_data_field_get_yres(field));
            m = gwy_data_field_get_data(mask);
            for (i = 0; i < n; i++) {
                if (!isfinite(a[i])) {
                    a[i] = fill;
                    m[i] = 1.0;
                    filled++;
                }
            }
            gwy_data_field_invalidate(field);
            gwy_data_field_invalidate(mask);
            gwy_data_field_data_changed(field);
        }
    }
    g_free(mask_key);
    return filled;
}

gsize
localscan_channels_fill_missing(GwyContainer *data)
{
    gint *ids = localscan_channel_ids(data);
    gsize filled = 0;
    guint i;

    for (i = 0; ids[i] != -1; i++)
        filled += fill_missing_of_channel(data, ids[i]);
    g_free(ids);
    return filled;
}
