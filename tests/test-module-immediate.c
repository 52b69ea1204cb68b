/*
 *  Tests of the Gwyddion process function localscan_drift run the way batch
 *  callers and pygwy run it: headless, GWY_RUN_IMMEDIATE, parameters from
 *  the settings.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <check.h>
#include <glib.h>
#include <glib/gstdio.h>
#include <libgwyddion/gwyddion.h>
#include <libprocess/gwyprocess.h>
#include <libgwydgets/gwydgets.h>
#include <libgwymodule/gwymodule.h>
#include <app/gwyapp.h>
#include "paper-compensate.h"
#include "continuous-compensate.h"
#include "localscan-channel.h"
#include "localscan-params.h"
#include "compensation-marker.h"
#include "scan-timing-meta.h"
#include "registration-frames.h"
#include "simscan-file-case.h"
#include "test-common.h"
#include "worked-example.h"

#define TITLE "Height"
#define RESULT_TITLE "Height (local-scan compensated)"

static guint32 test_seed;

typedef struct {
    gint source;
    const gchar *table_file;
    gint mode;
    gint fill;
    gboolean add_mask;
    gboolean plot_drift;
    gint interpolation;
    gint direction;
    gint reference_channel;
    gint stripes;
} ModuleSettings;

static const ModuleSettings default_settings = {
    LOCALSCAN_DEFAULT_SOURCE, "", LOCALSCAN_DEFAULT_MODE, LOCALSCAN_DEFAULT_FILL,
    LOCALSCAN_DEFAULT_ADD_MASK, LOCALSCAN_DEFAULT_PLOT_DRIFT, LOCALSCAN_DEFAULT_INTERPOLATION,
    LOCALSCAN_DEFAULT_DIRECTION, LOCALSCAN_REFERENCE_CHANNEL_NONE, LOCALSCAN_STRIPES_DEFAULT,
};

static void
set_string(GwyContainer *container, const gchar *key, const gchar *text)
{
    gwy_container_set_const_string_by_name(container, key, (const guchar*)text);
}

/* The keys and values the command-line tool sets too. */
static void
set_module_settings(const ModuleSettings *ms)
{
    GwyContainer *settings = gwy_app_settings_get();

    gwy_container_set_int32_by_name(settings, LOCALSCAN_SETTINGS_KEY(SOURCE), ms->source);
    set_string(settings, LOCALSCAN_SETTINGS_KEY(TABLE_FILE), ms->table_file);
    gwy_container_set_int32_by_name(settings, LOCALSCAN_SETTINGS_KEY(MODE), ms->mode);
    gwy_container_set_int32_by_name(settings, LOCALSCAN_SETTINGS_KEY(FILL), ms->fill);
    gwy_container_set_boolean_by_name(settings, LOCALSCAN_SETTINGS_KEY(ADD_MASK), ms->add_mask);
    gwy_container_set_boolean_by_name(settings, LOCALSCAN_SETTINGS_KEY(PLOT_DRIFT), ms->plot_drift);
    gwy_container_set_int32_by_name(settings, LOCALSCAN_SETTINGS_KEY(INTERPOLATION), ms->interpolation);
    gwy_container_set_int32_by_name(settings, LOCALSCAN_SETTINGS_KEY(DIRECTION), ms->direction);
    gwy_container_set_int32_by_name(settings, LOCALSCAN_SETTINGS_KEY(REFERENCE_CHANNEL), ms->reference_channel);
    gwy_container_set_int32_by_name(settings, LOCALSCAN_SETTINGS_KEY(STRIPES), ms->stripes);
}

/* Pixel k*k blocks: image (xres*k) x (yres*k). */
static GwyDataField*
make_field(const gdouble *values, gint xres, gint yres, gint k, gdouble xstep, gdouble ystep,
           const gchar *xyunit)
{
    GwyDataField *field = gwy_data_field_new(xres*k, yres*k, xres*k*xstep, yres*k*ystep, FALSE);
    gdouble *d = gwy_data_field_get_data(field);
    gint r, c;

    for (r = 0; r < yres*k; r++) {
        for (c = 0; c < xres*k; c++)
            d[r*xres*k + c] = values[(r/k)*xres + c/k];
    }
    gwy_si_unit_set_from_string(gwy_data_field_get_si_unit_xy(field), xyunit);
    gwy_si_unit_set_from_string(gwy_data_field_get_si_unit_z(field), "m");
    return field;
}

static GwyDataField*
make_worked_example(gint k, gdouble xstep, gdouble ystep, const gchar *xyunit)
{
    return make_field(worked_a, WORKED_XRES, WORKED_YRES, k, xstep, ystep, xyunit);
}

static GwyContainer*
make_container(GwyDataField *field, const gchar *table_text)
{
    GwyContainer *data = gwy_container_new();

    gwy_container_set_object(data, gwy_app_get_data_key_for_id(0), field);
    set_string(data, "/0/data/title", TITLE);
    set_string(data, "/0/base/palette", "Gray");
    if (table_text)
        localscan_channel_store_table_text(data, 0, table_text);
    gwy_app_data_browser_add(data);
    gwy_app_data_browser_select_data_field(data, 0);
    return data;
}

static void
drop_container(GwyContainer *data)
{
    gwy_app_data_browser_remove(data);
    g_object_unref(data);
}

static gint
count_ids(gint *ids)
{
    gint n = 0;

    while (ids[n] != -1)
        n++;
    g_free(ids);
    return n;
}

/* Runs the function; returns the id of the one new channel, or -1 when
 * none was made.  What it printed on stderr goes to *message. */
static gint
run_module(GwyContainer *data, gchar **message)
{
    gint before = count_ids(gwy_app_data_browser_get_data_ids(data)), after, saved_fd, fd;
    gchar *tmpname = NULL, *text = NULL;

    fflush(stderr);
    fd = g_file_open_tmp("localscan-stderr-XXXXXX", &tmpname, NULL);
    ck_assert_int_ge(fd, 0);
    saved_fd = dup(STDERR_FILENO);
    dup2(fd, STDERR_FILENO);
    gwy_process_func_run(LOCALSCAN_FUNCTION_NAME, data, GWY_RUN_IMMEDIATE);
    fflush(stderr);
    dup2(saved_fd, STDERR_FILENO);
    close(saved_fd);
    close(fd);
    g_file_get_contents(tmpname, &text, NULL, NULL);
    g_unlink(tmpname);
    g_free(tmpname);
    if (message)
        *message = text;
    else
        g_free(text);

    after = count_ids(gwy_app_data_browser_get_data_ids(data));
    ck_assert_int_le(after, before + 1);
    return after > before ? before : -1;
}

static GwyDataField*
get_field(GwyContainer *data, GQuark key)
{
    GwyDataField *field = NULL;

    ck_assert(gwy_container_gis_object(data, key, &field));
    ck_assert(GWY_IS_DATA_FIELD(field));
    return field;
}

static void
assert_field_values(GwyDataField *field, const gdouble *expected, gint xres, gint yres, gint k)
{
    const gdouble *d = gwy_data_field_get_data_const(field);
    gint r, c;

    ck_assert_int_eq(gwy_data_field_get_xres(field), xres*k);
    ck_assert_int_eq(gwy_data_field_get_yres(field), yres*k);
    for (r = 0; r < yres*k; r++) {
        for (c = 0; c < xres*k; c++) {
            ck_assert_msg(d[r*xres*k + c] == expected[(r/k)*xres + c/k],
                          "pixel (%d,%d) is %g, expected %g", r, c, d[r*xres*k + c],
                          expected[(r/k)*xres + c/k]);
        }
    }
}

static void
assert_same_field_bits(GwyDataField *got, GwyDataField *expected)
{
    gint n = gwy_data_field_get_xres(expected)*gwy_data_field_get_yres(expected);

    ck_assert_int_eq(gwy_data_field_get_xres(got), gwy_data_field_get_xres(expected));
    ck_assert_int_eq(gwy_data_field_get_yres(got), gwy_data_field_get_yres(expected));
    ck_assert(memcmp(gwy_data_field_get_data_const(got), gwy_data_field_get_data_const(expected),
                     n*sizeof(gdouble)) == 0);
}

/* Continuous compensation's vector loops round differently with the
 * buffers' alignment (2e-14 of the range seen): equal to far below what any
 * wrong timing, direction or table moves (a good fraction of the range). */
static void
assert_same_field_values(GwyDataField *got, GwyDataField *expected)
{
    gint n = gwy_data_field_get_xres(expected)*gwy_data_field_get_yres(expected), i;
    const gdouble *g = gwy_data_field_get_data_const(got), *e = gwy_data_field_get_data_const(expected);
    gdouble range = gwy_data_field_get_max(expected) - gwy_data_field_get_min(expected), worst = 0.0;

    ck_assert_int_eq(gwy_data_field_get_xres(got), gwy_data_field_get_xres(expected));
    ck_assert_int_eq(gwy_data_field_get_yres(got), gwy_data_field_get_yres(expected));
    for (i = 0; i < n; i++)
        worst = fmax(worst, fabs(g[i] - e[i]));
    ck_assert_msg(worst <= 1e-9*range, "values differ by up to %g of the range", worst/range);
}

/* Geometry and lateral unit like the field; dimensionless values. */
static void
assert_mask_geometry(GwyDataField *mask, GwyDataField *field)
{
    ck_assert(!gwy_data_field_check_compatibility(mask, field,
                                                  GWY_DATA_COMPATIBILITY_RES | GWY_DATA_COMPATIBILITY_REAL
                                                  | GWY_DATA_COMPATIBILITY_LATERAL));
    ck_assert(gwy_si_unit_equal_string(gwy_data_field_get_si_unit_z(mask), NULL));
}

static const gchar*
get_string(GwyContainer *data, const gchar *key)
{
    const guchar *s = NULL;

    if (!gwy_container_gis_string_by_name(data, key, &s))
        return NULL;
    return (const gchar*)s;
}

/* The worked example, pixels scaled k times, drift in px or nm (x and y
 * pixel sizes differ, so a mix-up of the two would show). */
static void
check_worked_example(gint k, gboolean nm_table)
{
    const gdouble xstep = 2e-9, ystep = 5e-9;
    GwyDataField *field = make_worked_example(k, xstep, ystep, "m"), *source_copy, *result, *mask;
    GwyContainer *data;
    GString *table = g_string_new(NULL);
    gint newid, s;
    static const gint dx[3] = { 1, -1, 0 }, dy[3] = { 1, 0, -1 };

    if (nm_table)
        g_string_append(table, "# units: nm\n");
    g_string_append(table, "stripe,dx,dy\n");
    for (s = 0; s < 3; s++) {
        if (nm_table)
            g_string_append_printf(table, "%d,%g,%g\n", s, k*dx[s]*xstep*1e9, k*dy[s]*ystep*1e9);
        else
            g_string_append_printf(table, "%d,%d,%d\n", s, k*dx[s], k*dy[s]);
    }
    data = make_container(field, table->str);
    source_copy = gwy_data_field_duplicate(field);
    set_module_settings(&default_settings);

    newid = run_module(data, NULL);
    ck_assert_int_eq(newid, 1);
    result = get_field(data, gwy_app_get_data_key_for_id(newid));
    assert_field_values(result, worked_c, 4, 6, k);
    mask = get_field(data, gwy_app_get_mask_key_for_id(newid));
    assert_field_values(mask, worked_mask, 4, 6, k);
    assert_mask_geometry(mask, field);
    ck_assert_str_eq(get_string(data, "/1/data/title"), RESULT_TITLE);
    ck_assert_str_eq(localscan_channel_stored_table_text(data, newid), table->str);
    assert_same_field_bits(get_field(data, gwy_app_get_data_key_for_id(0)), source_copy);

    g_object_unref(source_copy);
    g_object_unref(field);
    g_string_free(table, TRUE);
    drop_container(data);
}

START_TEST(test_worked_example_exact)
{
    check_worked_example(1, FALSE);
}
END_TEST

START_TEST(test_worked_example_scaled)
{
    check_worked_example(3, FALSE);
}
END_TEST

START_TEST(test_worked_example_nm_table)
{
    check_worked_example(3, TRUE);
}
END_TEST

/* The library itself agrees with the spec's numbers, so comparing the module
 * with paper_compensate() below compares it with the spec. */
START_TEST(test_paper_compensate_matches_spec)
{
    GwyDataField *field = make_worked_example(1, 1.0, 1.0, "m");
    static const gint dx[3] = { 1, -1, 0 }, dy[3] = { 1, 0, -1 };
    gdouble result[24], mask[24];
    gdouble d = paper_image_mean(gwy_data_field_get_data_const(field), 4, 6);
    gint i;

    ck_assert(d == 12.5);
    paper_compensate(gwy_data_field_get_data_const(field), 4, 6, 3, dx, dy, d, result, mask);
    for (i = 0; i < 24; i++) {
        ck_assert(result[i] == worked_c[i]);
        ck_assert(mask[i] == worked_mask[i]);
    }
    g_object_unref(field);
}
END_TEST

/* Independent of the library's stripe_drift_fill_missing(). */
static void
fill_missing_nearest(gint n, const gboolean *has, gint *dx, gint *dy)
{
    gint s, dist, t;

    for (s = 0; s < n; s++) {
        if (has[s])
            continue;
        for (dist = 1; dist < n; dist++) {
            t = (s - dist >= 0 && has[s - dist]) ? s - dist : ((s + dist < n && has[s + dist]) ? s + dist : -1);
            if (t >= 0) {
                dx[s] = dx[t];
                dy[s] = dy[t];
                break;
            }
        }
    }
}

START_TEST(test_random_table_matches_paper_compensate)
{
    GRand *rng = g_rand_new_with_seed(test_seed + 7919*_i);
    gint xres = g_rand_int_range(rng, 8, 61), yres = g_rand_int_range(rng, 4, 49);
    gint n = g_rand_int_range(rng, 1, yres + 1), s, i, newid, anchor = g_rand_int_range(rng, 0, n);
    GwyDataField *field = gwy_data_field_new(xres, yres, 1e-6, 2e-6, FALSE), *expected, *expected_mask;
    GwyContainer *data;
    GString *table = g_string_new("stripe,dx,dy,score\n");
    gboolean *has = g_new(gboolean, n);
    gint *dx = g_new0(gint, n), *dy = g_new0(gint, n);
    gdouble *d = gwy_data_field_get_data(field);

    for (i = 0; i < xres*yres; i++)
        d[i] = g_rand_double_range(rng, -1e-8, 1e-8);
    gwy_si_unit_set_from_string(gwy_data_field_get_si_unit_xy(field), "m");
    for (s = 0; s < n; s++) {
        has[s] = (s == anchor || g_rand_double(rng) < 0.7);
        if (has[s]) {
            dx[s] = g_rand_int_range(rng, -6, 7);
            dy[s] = g_rand_int_range(rng, -6, 7);
            g_string_append_printf(table, "%d,%d,%d,0.5\n", s, dx[s], dy[s]);
        }
        else
            g_string_append_printf(table, "%d,,,\n", s);
    }
    fill_missing_nearest(n, has, dx, dy);

    expected = gwy_data_field_new_alike(field, FALSE);
    expected_mask = gwy_data_field_new_alike(field, FALSE);
    paper_compensate(d, xres, yres, n, dx, dy, paper_image_mean(d, xres, yres),
                     gwy_data_field_get_data(expected), gwy_data_field_get_data(expected_mask));

    data = make_container(field, table->str);
    set_module_settings(&default_settings);
    newid = run_module(data, NULL);
    ck_assert_msg(newid == 1, "seed %u, %dx%d, %d stripes: no new channel", test_seed, xres, yres, n);
    assert_same_field_bits(get_field(data, gwy_app_get_data_key_for_id(newid)), expected);
    if (gwy_data_field_get_max(expected_mask) > 0.0)
        assert_same_field_bits(get_field(data, gwy_app_get_mask_key_for_id(newid)), expected_mask);
    else
        ck_assert(!gwy_container_contains(data, gwy_app_get_mask_key_for_id(newid)));

    g_free(has);
    g_free(dx);
    g_free(dy);
    g_string_free(table, TRUE);
    g_object_unref(expected);
    g_object_unref(expected_mask);
    g_object_unref(field);
    drop_container(data);
    g_rand_free(rng);
}
END_TEST

START_TEST(test_result_channel_items)
{
    GwyDataField *field = make_worked_example(1, 1e-9, 1e-9, "m");
    GwyContainer *data = make_container(field, worked_table), *meta = gwy_container_new();
    GwyStringList *log = NULL;
    const gchar *last;
    gint newid;

    set_string(meta, "Scan rate", "2 Hz");
    gwy_container_set_object_by_name(data, "/0/meta", meta);
    g_object_unref(meta);
    localscan_channel_store_table_text(data, 0, worked_table);
    set_module_settings(&default_settings);

    newid = run_module(data, NULL);
    ck_assert_int_eq(newid, 1);
    ck_assert_str_eq(get_string(data, "/1/base/palette"), "Gray");
    ck_assert(gwy_container_gis_object_by_name(data, "/1/meta", &meta));
    ck_assert_str_eq(get_string(meta, "Scan rate"), "2 Hz");
    ck_assert(gwy_container_gis_object_by_name(data, "/1/data/log", &log));
    ck_assert_int_ge(gwy_string_list_get_length(log), 1);
    last = gwy_string_list_get(log, gwy_string_list_get_length(log) - 1);
    ck_assert_msg(strstr(last, LOCALSCAN_FUNCTION_NAME) != NULL, "log entry '%s'", last);
    /* Nothing was added to the source channel. */
    ck_assert(!gwy_container_contains(data, gwy_app_get_mask_key_for_id(0)));
    ck_assert(!gwy_container_contains_by_name(data, "/0/data/log"));
    ck_assert_int_eq(count_ids(gwy_app_data_browser_get_graph_ids(data)), 0);

    g_object_unref(field);
    drop_container(data);
}
END_TEST

START_TEST(test_csv_file_source)
{
    GwyDataField *field = make_worked_example(2, 1e-9, 1e-9, "m");
    GwyContainer *data = make_container(field, NULL);
    ModuleSettings ms = default_settings;
    gchar *filename = g_build_filename(g_get_home_dir(), "worked-k2.csv", NULL);
    gint newid;

    ck_assert(g_file_set_contents(filename, "# the worked example, pixels doubled\n"
                                  "stripe,dx,dy\n0,2,2\n1,-2,0\n2,0,-2\n", -1, NULL));
    ms.source = LOCALSCAN_SOURCE_FILE;
    ms.table_file = filename;
    set_module_settings(&ms);
    newid = run_module(data, NULL);
    ck_assert_int_eq(newid, 1);
    assert_field_values(get_field(data, gwy_app_get_data_key_for_id(newid)), worked_c, 4, 6, 2);
    assert_field_values(get_field(data, gwy_app_get_mask_key_for_id(newid)), worked_mask, 4, 6, 2);
    ck_assert_str_eq(localscan_channel_stored_table_text(data, 1), "stripe,dx,dy\n0,2,2\n1,-2,0\n2,0,-2\n");

    g_unlink(filename);
    g_free(filename);
    g_object_unref(field);
    drop_container(data);
}
END_TEST

/* Repeat last on the result: the result carries the table it was made
 * with, and must not be compensated again unless forced. */
START_TEST(test_result_not_compensated_twice)
{
    GwyDataField *field = make_worked_example(2, 1e-9, 1e-9, "m");
    GwyContainer *data = make_container(field, NULL);
    ModuleSettings ms = default_settings;
    gchar *message = NULL;
    gint newid, again;

    ms.source = LOCALSCAN_SOURCE_STORED;
    localscan_channel_store_table_text(data, 0, "stripe,dx,dy\n0,2,2\n1,-2,0\n2,0,-2\n");
    set_module_settings(&ms);
    newid = run_module(data, NULL);
    ck_assert_int_eq(newid, 1);
    ck_assert(compensation_marker_get(data, newid));
    ck_assert(!compensation_marker_get(data, 0));

    gwy_app_data_browser_select_data_field(data, newid);
    again = run_module(data, &message);
    printf("test-module-immediate: Repeat last on the result says: %s", message);
    ck_assert_int_eq(again, -1);
    ck_assert_msg(strstr(message, "already local-scan compensated") && !strchr(message, '\n')[1],
                  "not one line about the double correction: %s", message);
    g_free(message);

    gwy_container_set_boolean_by_name(gwy_app_settings_get(), LOCALSCAN_SETTINGS_KEY(FORCE), TRUE);
    again = run_module(data, NULL);
    gwy_container_set_boolean_by_name(gwy_app_settings_get(), LOCALSCAN_SETTINGS_KEY(FORCE), FALSE);
    ck_assert_int_eq(again, 2);

    g_object_unref(field);
    drop_container(data);
}
END_TEST

/* The result of compensating field with the stored table as the module
 * was told to (paper mode, image mean), for comparison. */
static GwyDataField*
expected_compensation(GwyDataField *field, const gchar *table_text, LocalscanFill fill,
                      GwyInterpolationType interpolation, GwyDataField **filled)
{
    DriftTable *table = drift_table_parse(table_text, -1, "test", NULL);
    LocalscanOptions options = { LOCALSCAN_MODE_PAPER, fill, interpolation, 1.0,
                                 SCAN_DIRECTION_DOWN, 0.0 };
    GwyDataField *result = gwy_data_field_new_alike(field, FALSE);

    *filled = gwy_data_field_new_alike(field, FALSE);
    ck_assert(localscan_compensate_field(field, table, &options, result, *filled, NULL, NULL));
    drift_table_free(table);
    return result;
}

static gint
channel_titled(GwyContainer *data, const gchar *title)
{
    gint *ids = gwy_app_data_browser_get_data_ids(data), i, found = -1;
    gchar key[40];

    for (i = 0; ids[i] >= 0; i++) {
        g_snprintf(key, sizeof(key), "/%d/data/title", ids[i]);
        if (!g_strcmp0(get_string(data, key), title))
            found = ids[i];
    }
    g_free(ids);
    return found;
}

/* "All channels of the scan": the Height's drift moves the Amplitude of
 * the same scan and the Height's mask too; a channel of another size is
 * left alone. */
START_TEST(test_all_channels)
{
    static const gchar table_text[] = "stripe,dx,dy\n0,2,2\n1,-2,0\n2,0,-2\n";
    GwyDataField *height = make_worked_example(2, 1e-9, 1e-9, "m");
    GwyContainer *data = make_container(height, table_text);
    GwyDataField *amplitude = gwy_data_field_duplicate(height), *other, *own_mask;
    GwyDataField *want, *filled, *want_mask, *mask_filled;
    ModuleSettings ms = default_settings;
    gint amp_id, height_id, i, before;

    gwy_data_field_multiply(amplitude, -3.0);
    gwy_data_field_add(amplitude, 7.0);
    gwy_container_set_object(data, gwy_app_get_data_key_for_id(1), amplitude);
    set_string(data, "/1/data/title", "Amplitude");
    other = gwy_data_field_new(5, 5, 5e-9, 5e-9, TRUE);
    gwy_container_set_object(data, gwy_app_get_data_key_for_id(2), other);
    set_string(data, "/2/data/title", "Other size");
    own_mask = gwy_data_field_new_alike(height, TRUE);
    for (i = 0; i < 6; i++)
        gwy_data_field_set_val(own_mask, i, 3, 1.0);
    gwy_container_set_object(data, gwy_app_get_mask_key_for_id(0), own_mask);
    gwy_app_data_browser_select_data_field(data, 0);
    before = count_ids(gwy_app_data_browser_get_data_ids(data));

    ms.source = LOCALSCAN_SOURCE_STORED;
    set_module_settings(&ms);
    gwy_container_set_boolean_by_name(gwy_app_settings_get(), LOCALSCAN_SETTINGS_KEY(ALL_CHANNELS), TRUE);
    gwy_process_func_run(LOCALSCAN_FUNCTION_NAME, data, GWY_RUN_IMMEDIATE);
    gwy_container_set_boolean_by_name(gwy_app_settings_get(), LOCALSCAN_SETTINGS_KEY(ALL_CHANNELS), FALSE);
    ck_assert_int_eq(count_ids(gwy_app_data_browser_get_data_ids(data)), before + 2);

    amp_id = channel_titled(data, "Amplitude" LOCALSCAN_TITLE_SUFFIX);
    ck_assert_int_ge(amp_id, 0);
    want = expected_compensation(amplitude, table_text, LOCALSCAN_FILL_MEAN,
                                 LOCALSCAN_DEFAULT_INTERPOLATION, &filled);
    assert_same_field_bits(get_field(data, gwy_app_get_data_key_for_id(amp_id)), want);
    assert_same_field_bits(get_field(data, gwy_app_get_mask_key_for_id(amp_id)), filled);
    ck_assert(compensation_marker_get(data, amp_id));
    ck_assert_int_lt(channel_titled(data, "Other size" LOCALSCAN_TITLE_SUFFIX), 0);
    g_object_unref(want);
    g_object_unref(filled);

    /* The Height's mask: its own mask moved by the same drift, joined
     * with the filled pixels. */
    height_id = channel_titled(data, TITLE LOCALSCAN_TITLE_SUFFIX);
    ck_assert_int_ge(height_id, 0);
    want_mask = expected_compensation(own_mask, table_text, LOCALSCAN_FILL_ZERO,
                                      GWY_INTERPOLATION_ROUND, &mask_filled);
    g_object_unref(mask_filled);
    want = expected_compensation(height, table_text, LOCALSCAN_FILL_MEAN,
                                 LOCALSCAN_DEFAULT_INTERPOLATION, &filled);
    gwy_data_field_max_of_fields(want_mask, want_mask, filled);
    ck_assert(gwy_data_field_get_max(want_mask) > 0.5);
    assert_same_field_bits(get_field(data, gwy_app_get_mask_key_for_id(height_id)), want_mask);
    assert_same_field_bits(get_field(data, gwy_app_get_data_key_for_id(height_id)), want);

    g_object_unref(want);
    g_object_unref(filled);
    g_object_unref(want_mask);
    g_object_unref(own_mask);
    g_object_unref(other);
    g_object_unref(amplitude);
    g_object_unref(height);
    drop_container(data);
}
END_TEST

START_TEST(test_fill_values)
{
    static const gint fills[3] = { LOCALSCAN_FILL_ZERO, LOCALSCAN_FILL_MINIMUM, LOCALSCAN_FILL_MAXIMUM };
    static const gdouble values[3] = { 0.0, 1.0, 24.0 };
    GwyDataField *field = make_worked_example(1, 1e-9, 1e-9, "m");
    ModuleSettings ms = default_settings;
    gdouble expected[24];
    GwyContainer *data;
    gint i, f;

    for (f = 0; f < 3; f++) {
        for (i = 0; i < 24; i++)
            expected[i] = worked_mask[i] ? values[f] : worked_c[i];
        data = make_container(field, worked_table);
        ms.fill = fills[f];
        set_module_settings(&ms);
        ck_assert_int_eq(run_module(data, NULL), 1);
        assert_field_values(get_field(data, gwy_app_get_data_key_for_id(1)), expected, 4, 6, 1);
        drop_container(data);
    }
    g_object_unref(field);
}
END_TEST

START_TEST(test_mask_only_when_wanted)
{
    GwyDataField *field = make_worked_example(1, 1e-9, 1e-9, "m");
    ModuleSettings ms = default_settings;
    GwyContainer *data;

    data = make_container(field, worked_table);
    ms.add_mask = FALSE;
    set_module_settings(&ms);
    ck_assert_int_eq(run_module(data, NULL), 1);
    ck_assert(!gwy_container_contains(data, gwy_app_get_mask_key_for_id(1)));
    drop_container(data);

    /* Zero drift fills nothing: no empty mask either. */
    data = make_container(field, "stripe,dx,dy\n0,0,0\n");
    set_module_settings(&default_settings);
    ck_assert_int_eq(run_module(data, NULL), 1);
    ck_assert(!gwy_container_contains(data, gwy_app_get_mask_key_for_id(1)));
    assert_same_field_bits(get_field(data, gwy_app_get_data_key_for_id(1)), field);
    drop_container(data);
    g_object_unref(field);
}
END_TEST

START_TEST(test_drift_graph)
{
    const gdouble xstep = 2e-9, ystep = 5e-9, yoff = 1e-6;
    GwyDataField *field = make_worked_example(3, xstep, ystep, "m");
    ModuleSettings ms = default_settings;
    static const gdouble centre_row[3] = { 2.5, 8.5, 14.5 };
    static const gint dx[3] = { 3, -3, 0 }, dy[3] = { 3, 0, -3 };
    GwyGraphCurveModel *gcmodel;
    GwyGraphModel *gmodel;
    GwySIUnit *unit;
    GwyContainer *data;
    const gdouble *x, *y;
    gchar *description;
    gint *ids, c, s;

    gwy_data_field_set_yoffset(field, yoff);
    data = make_container(field, "stripe,dx,dy\n0,3,3\n1,-3,0\n2,0,-3\n");
    ms.plot_drift = TRUE;
    set_module_settings(&ms);
    ck_assert_int_eq(run_module(data, NULL), 1);

    ids = gwy_app_data_browser_get_graph_ids(data);
    ck_assert_int_ne(ids[0], -1);
    ck_assert_int_eq(ids[1], -1);
    ck_assert(gwy_container_gis_object(data, gwy_app_get_graph_key_for_id(ids[0]), &gmodel));
    g_free(ids);
    ck_assert_int_eq(gwy_graph_model_get_n_curves(gmodel), 2);
    g_object_get(gmodel, "si-unit-x", &unit, NULL);
    ck_assert(gwy_si_unit_equal_string(unit, "m"));
    g_object_unref(unit);
    g_object_get(gmodel, "si-unit-y", &unit, NULL);
    ck_assert(gwy_si_unit_equal_string(unit, "m"));
    g_object_unref(unit);
    for (c = 0; c < 2; c++) {
        gcmodel = gwy_graph_model_get_curve(gmodel, c);
        g_object_get(gcmodel, "description", &description, NULL);
        ck_assert_str_eq(description, c ? "dy" : "dx");
        g_free(description);
        ck_assert_int_eq(gwy_graph_curve_model_get_ndata(gcmodel), 3);
        x = gwy_graph_curve_model_get_xdata(gcmodel);
        y = gwy_graph_curve_model_get_ydata(gcmodel);
        for (s = 0; s < 3; s++) {
            ck_assert_double_eq_tol(x[s], yoff + (centre_row[s] + 0.5)*ystep, 1e-18);
            ck_assert_double_eq_tol(y[s], c ? dy[s]*ystep : dx[s]*xstep, 1e-18);
        }
    }
    g_object_unref(field);
    drop_container(data);
}
END_TEST

/* Continuous mode passes the table, the pixel sizes, the line time from the
 * metadata (2 Hz: 0.5 s; it matters because the table gives absolute stripe
 * times), the direction and the interpolation through unchanged: the result
 * is continuous_compensate_table()'s (to its rounding). */
START_TEST(test_continuous_mode_passes_timing)
{
    static const gint directions[2] = { SCAN_DIRECTION_DOWN, SCAN_DIRECTION_UP };
    static const gchar table_text[] = "stripe,dx,dy,t_image\n0,0,0,1.5\n1,1.5,-0.5,4.5\n2,3,-1,7.5\n"
                                      "3,4.5,-1.5,10.5\n";
    GRand *rng = g_rand_new_with_seed(test_seed);
    GwyDataField *field = gwy_data_field_new(32, 24, 32e-9, 48e-9, FALSE), *expected, *expected_mask;
    GwyContainer *data, *meta;
    ModuleSettings ms = default_settings;
    DriftTable *table = drift_table_parse(table_text, -1, "test", NULL);
    gdouble *d = gwy_data_field_get_data(field);
    ScanTiming timing;
    gint i, k;

    ck_assert(table);
    for (i = 0; i < 32*24; i++)
        d[i] = g_rand_double_range(rng, 0.0, 1e-9);
    gwy_si_unit_set_from_string(gwy_data_field_get_si_unit_xy(field), "m");
    expected = gwy_data_field_new_alike(field, FALSE);
    expected_mask = gwy_data_field_new_alike(field, FALSE);
    for (k = 0; k < 2; k++) {
        scan_timing_init(&timing, 32, 24, 0.0, 0.5, directions[k]);
        ck_assert(continuous_compensate_table(d, 32, 24, table, 1e-9, 2e-9, &timing, GWY_INTERPOLATION_OMOMS,
                                              paper_image_mean(d, 32, 24),
                                              gwy_data_field_get_data(expected),
                                              gwy_data_field_get_data(expected_mask), NULL));
        data = make_container(field, table_text);
        meta = gwy_container_new();
        set_string(meta, "Scan rate", "2 Hz");
        gwy_container_set_object_by_name(data, "/0/meta", meta);
        g_object_unref(meta);
        localscan_channel_store_table_text(data, 0, table_text);
        ms.mode = LOCALSCAN_MODE_CONTINUOUS;
        ms.interpolation = GWY_INTERPOLATION_OMOMS;
        ms.direction = directions[k];
        set_module_settings(&ms);
        ck_assert_int_eq(run_module(data, NULL), 1);
        assert_same_field_values(get_field(data, gwy_app_get_data_key_for_id(1)), expected);
        if (gwy_data_field_get_max(expected_mask) > 0.0)
            assert_same_field_bits(get_field(data, gwy_app_get_mask_key_for_id(1)), expected_mask);
        ck_assert_str_eq(get_string(data, "/1/data/title"), RESULT_TITLE);
        drop_container(data);
    }
    drift_table_free(table);
    g_object_unref(expected);
    g_object_unref(expected_mask);
    g_object_unref(field);
    g_rand_free(rng);
}
END_TEST

/* Each bad source: no new channel, the source untouched, one line on stderr
 * that names the problem. */
static void
check_refused(GwyDataField *field, const gchar *stored_table, const ModuleSettings *ms,
              const gchar *expected_part)
{
    GwyContainer *data = make_container(field, stored_table);
    GwyDataField *source_copy = gwy_data_field_duplicate(field);
    gchar *message = NULL, *newline;

    set_module_settings(ms);
    ck_assert_int_eq(run_module(data, &message), -1);
    ck_assert_msg(g_str_has_prefix(message, LOCALSCAN_FUNCTION_NAME ": "), "message '%s'", message);
    ck_assert_msg(strstr(message, expected_part) != NULL, "message '%s' lacks '%s'", message, expected_part);
    newline = strchr(message, '\n');
    ck_assert_msg(newline && newline[1] == '\0', "message '%s' is not one line", message);
    assert_same_field_bits(get_field(data, gwy_app_get_data_key_for_id(0)), source_copy);
    ck_assert(!gwy_container_contains(data, gwy_app_get_mask_key_for_id(0)));
    ck_assert_int_eq(count_ids(gwy_app_data_browser_get_graph_ids(data)), 0);
    g_free(message);
    g_object_unref(source_copy);
    drop_container(data);
}

START_TEST(test_bad_sources_refused)
{
    GwyDataField *field = make_worked_example(1, 1e-9, 1e-9, "m");
    GwyDataField *pixel_field = make_worked_example(1, 1.0, 1.0, "");
    ModuleSettings ms = default_settings;
    gchar *missing = g_build_filename(g_get_home_dir(), "no-such-table.csv", NULL);

    ms.plot_drift = TRUE;
    check_refused(field, NULL, &ms, "Channel 0 has no stored drift table");
    check_refused(field, "stripe,dx,dy\n0,abc,1\n", &ms, "channel 0 drift table:2");
    check_refused(field, "stripe,dx,dy\n0,0.5,0\n", &ms, "channel 0 drift table:2");
    check_refused(field, "stripe,dx,dy\n0,0,0\n1,0,0\n2,0,0\n3,0,0\n4,0,0\n5,0,0\n6,0,0\n", &ms,
                  "channel 0 drift table:8");
    check_refused(pixel_field, "# units: nm\nstripe,dx,dy\n0,1,1\n", &ms, "metres");

    ms.source = LOCALSCAN_SOURCE_FILE;
    ms.table_file = missing;
    check_refused(field, worked_table, &ms, "no-such-table.csv");
    ms.table_file = "";
    check_refused(field, worked_table, &ms, "file");

    ms.source = LOCALSCAN_SOURCE_REFERENCE;
    check_refused(field, worked_table, &ms, "No reference image is chosen");

    g_free(missing);
    g_object_unref(pixel_field);
    g_object_unref(field);
}
END_TEST

/* The timing of channel 0 of a 4 x 6 image with the given metadata items
 * (key, value pairs, NULL-terminated; no metadata at all when NULL). */
static LocalscanTimingFound
timing_with_meta(const gchar *const *items, ScanDirection fallback, ScanTiming *timing)
{
    GwyDataField *field = make_worked_example(1, 1.0, 1.0, "m");
    GwyContainer *data = gwy_container_new(), *meta = gwy_container_new();
    LocalscanTimingFound found;
    gint i;

    gwy_container_set_object_by_name(data, "/0/data", field);
    if (items)
        gwy_container_set_object_by_name(data, "/0/meta", meta);
    for (i = 0; items && items[i]; i += 2)
        set_string(meta, items[i], items[i+1]);
    found = localscan_channel_scan_timing(data, 0, fallback, timing);
    ck_assert_int_eq(timing->xres, 4);
    ck_assert_int_eq(timing->yres, 6);
    g_object_unref(meta);
    g_object_unref(data);
    g_object_unref(field);
    return found;
}

/* Every key simscan and the measured files' importers give (simscan, Bruker
 * Nanoscope, Anasys nanoIR, Asylum, HS-AFM movies), and what the timing is
 * without them. */
START_TEST(test_scan_timing_from_metadata)
{
    static const gchar *const simscan[] = { "Line time (s)", "1.5", "Slow scan", "up",
                                            "Frame start (s)", "12.25", "Seed", "3", NULL };
    static const gchar *const simscan_zero[] = { "Line time (s)", "1.171875", "Slow scan", "down",
                                                 "Frame start (s)", "0", NULL };
    static const gchar *const nanoscope[] = { "Scan Rate", "2.32515", "Frame direction", "Down",
                                              "Capture direction", "Up", NULL };
    static const gchar *const nanoscope_up[] = { "Scan Rate", "2.32515", "Frame direction", "Up", NULL };
    static const gchar *const anasys[] = { "ScanRate", "0.5 Hz", "ScanAngle", "-90 deg", NULL };
    static const gchar *const nanoscope_relative[] = { "Scan Rate", "2.32515", "Relative frame time", "209.88",
                                                       NULL };
    static const gchar *const nanoscope_date[] = { "Scan Rate", "2.32515", "Date", "04:06:25 PM Thu Sep 26 2019",
                                                   NULL };
    static const gchar *const anasys_stamp[] = { "ScanRate", "0.5 Hz", "TimeStamp", "2021-03-04T10:20:30Z", NULL };
    static const gchar *const asylum[] = { "ScanRate", "1.0016", "FastMapScanRate", "0.23461", NULL };
    static const gchar *const hsafm[] = { "Frame time (s)", "0.413", "Time since first kept frame (s)", "6.189",
                                          NULL };
    static const gchar *const units[] = { "Line time", "500 ms", "Scan Rate", "2.5 kHz", NULL };
    static const gchar *const rate_units[] = { "Line time", "fast", "Scan rate", "2.5 kHz", NULL };
    static const gchar *const bad[] = { "Line time", "-1 s", "Scan rate", "2 m", "Frame time (s)", "inf",
                                        "Slow scan", "sideways", "Frame start (s)", "soon", NULL };
    ScanTiming t;

    ck_assert_int_eq(timing_with_meta(NULL, SCAN_DIRECTION_UP, &t), 0);
    ck_assert(t.line_time == LOCALSCAN_DEFAULT_LINE_TIME && t.direction == SCAN_DIRECTION_UP);
    ck_assert(t.frame_start == 0.0);

    ck_assert_int_eq(timing_with_meta(simscan, SCAN_DIRECTION_DOWN, &t),
                     LOCALSCAN_TIMING_LINE_TIME | LOCALSCAN_TIMING_DIRECTION | LOCALSCAN_TIMING_FRAME_START);
    ck_assert(t.line_time == 1.5 && t.direction == SCAN_DIRECTION_UP && t.frame_start == 12.25);
    ck_assert_int_eq(timing_with_meta(simscan_zero, SCAN_DIRECTION_UP, &t),
                     LOCALSCAN_TIMING_LINE_TIME | LOCALSCAN_TIMING_DIRECTION | LOCALSCAN_TIMING_FRAME_START);
    ck_assert(t.line_time == 1.171875 && t.direction == SCAN_DIRECTION_DOWN && t.frame_start == 0.0);

    ck_assert_int_eq(timing_with_meta(nanoscope, SCAN_DIRECTION_UP, &t),
                     LOCALSCAN_TIMING_LINE_TIME | LOCALSCAN_TIMING_DIRECTION);
    ck_assert_double_eq_tol(t.line_time, 1.0/2.32515, 1e-15);
    ck_assert(t.direction == SCAN_DIRECTION_DOWN && t.frame_start == 0.0);
    timing_with_meta(nanoscope_up, SCAN_DIRECTION_DOWN, &t);
    ck_assert(t.direction == SCAN_DIRECTION_UP);

    ck_assert_int_eq(timing_with_meta(anasys, SCAN_DIRECTION_DOWN, &t), LOCALSCAN_TIMING_LINE_TIME);
    ck_assert_double_eq_tol(t.line_time, 2.0, 1e-15);
    ck_assert_int_eq(timing_with_meta(asylum, SCAN_DIRECTION_DOWN, &t), LOCALSCAN_TIMING_LINE_TIME);
    ck_assert_double_eq_tol(t.line_time, 1.0/1.0016, 1e-15);
    ck_assert_int_eq(timing_with_meta(hsafm, SCAN_DIRECTION_DOWN, &t),
                     LOCALSCAN_TIMING_LINE_TIME | LOCALSCAN_TIMING_FRAME_START);
    ck_assert_double_eq_tol(t.line_time, 0.413/6, 1e-15);
    ck_assert_double_eq_tol(t.frame_start, 6.189, 1e-15);

    ck_assert_int_eq(timing_with_meta(nanoscope_relative, SCAN_DIRECTION_DOWN, &t),
                     LOCALSCAN_TIMING_LINE_TIME | LOCALSCAN_TIMING_FRAME_START);
    ck_assert(t.frame_start == 209.88);
    ck_assert_int_eq(timing_with_meta(nanoscope_date, SCAN_DIRECTION_DOWN, &t), LOCALSCAN_TIMING_LINE_TIME);
    ck_assert(t.frame_start == 0.0);
    ck_assert_int_eq(timing_with_meta(anasys_stamp, SCAN_DIRECTION_DOWN, &t), LOCALSCAN_TIMING_LINE_TIME);
    ck_assert(t.frame_start == 0.0);

    timing_with_meta(units, SCAN_DIRECTION_DOWN, &t);
    ck_assert_double_eq_tol(t.line_time, 0.5, 1e-15);
    timing_with_meta(rate_units, SCAN_DIRECTION_DOWN, &t);
    ck_assert_double_eq_tol(t.line_time, 1.0/2500.0, 1e-15);
    ck_assert_int_eq(timing_with_meta(bad, SCAN_DIRECTION_DOWN, &t), 0);
    ck_assert(t.line_time == LOCALSCAN_DEFAULT_LINE_TIME && t.direction == SCAN_DIRECTION_DOWN);
    ck_assert(t.frame_start == 0.0);
}
END_TEST

/* The core reader gives the dates themselves, for simscan fit's series:
 * Nanoscope's as a start, Anasys's as the end of the frame. */
START_TEST(test_scan_timing_meta_dates)
{
    GwyContainer *meta = gwy_container_new();
    ScanMetaTiming mt;

    set_string(meta, "Date", "04:06:25 PM Thu Sep 26 2019");
    gwy_clear(&mt, 1);
    ck_assert_int_eq(scan_timing_meta_read(meta, 6, &mt), SCAN_META_FRAME_START);
    ck_assert(mt.frame_start == 1569513985.0 && mt.wall_clock && !mt.start_is_end);
    set_string(meta, "TimeStamp", "2021-03-04T10:20:30.25Z");
    ck_assert_int_eq(scan_timing_meta_read(meta, 6, &mt), SCAN_META_FRAME_START);
    ck_assert(mt.frame_start == 1614853230.25 && mt.wall_clock && mt.start_is_end);
    set_string(meta, "Date", "04:06:25 PM Thu Sxp 26 2019");
    set_string(meta, "TimeStamp", "yesterday");
    ck_assert_int_eq(scan_timing_meta_read(meta, 6, &mt), 0);
    set_string(meta, "Frame time (s)", "0.6");
    ck_assert_int_eq(scan_timing_meta_read(meta, 6, &mt), SCAN_META_LINE_TIME);
    ck_assert_double_eq_tol(mt.line_time, 0.1, 1e-15);
    g_object_unref(meta);
}
END_TEST

/* The new channel carries the source's metadata except what describes the
 * source's content: simscan's particle positions in the drifting image. */
START_TEST(test_source_content_meta_dropped)
{
    GwyDataField *field = make_worked_example(1, 1.0, 1.0, "m");
    GwyContainer *data = make_container(field, worked_table), *meta;
    const guchar *text;
    gint id;

    ck_assert(gwy_container_gis_object_by_name(data, "/0/meta", &meta));
    set_string(meta, "Simulated particles (px)", "x,y,x_shown,y_shown\n1.0,2.0,1.5,2.5\n");
    set_string(meta, "Line time (s)", "0.5");
    set_module_settings(&default_settings);
    id = run_module(data, NULL);
    ck_assert_int_ge(id, 1);
    ck_assert(gwy_container_gis_object_by_name(data, "/1/meta", &meta));
    ck_assert(!gwy_container_contains_by_name(meta, "Simulated particles (px)"));
    ck_assert(gwy_container_gis_string_by_name(meta, "Line time (s)", &text));
    ck_assert_str_eq((const gchar*)text, "0.5");
    ck_assert(gwy_container_gis_object_by_name(data, "/0/meta", &meta));
    ck_assert(gwy_container_contains_by_name(meta, "Simulated particles (px)"));
    drop_container(data);
    g_object_unref(field);
}
END_TEST

/************************************************************************
 * Drift from registration to a reference channel
 ************************************************************************/

#define REF_SIZE 256
#define REF_STRIPES 16
#define REF_STEP 4e-9
/* Interior compared with the reference: away from the edges, where drift
 * (up to ~10 px) brings in content the reference does not have. */
#define REF_MARGIN 16
#define REF_NOISE 0.01
#define REF_MIN_DRIFT 3.0

/* Channel 0 the drift-free scan of a seeded random surface, channel 1 the
 * drifting scan of it (the image, selected), as one file holds them. */
static GwyContainer*
make_reference_container(const FramePair *pair)
{
    GwyContainer *data = gwy_container_new();
    const gdouble *values[2] = { pair->reference, pair->image };
    static const gchar *titles[2] = { "Reference", TITLE };
    gchar key[32];
    gint i;

    for (i = 0; i < 2; i++) {
        GwyDataField *field = make_field(values[i], pair->xres, pair->yres, 1, REF_STEP, REF_STEP, "m");

        gwy_container_set_object(data, gwy_app_get_data_key_for_id(i), field);
        g_object_unref(field);
        g_snprintf(key, sizeof(key), "/%d/data/title", i);
        set_string(data, key, titles[i]);
    }
    gwy_app_data_browser_add(data);
    gwy_app_data_browser_select_data_field(data, 1);
    return data;
}

static gdouble
rms_stripe_drift(const FramePair *pair)
{
    gdouble tx[REF_STRIPES], ty[REF_STRIPES], sum = 0.0;
    gint s;

    frame_pair_stripe_truth(pair, REF_STRIPES, tx, ty);
    for (s = 0; s < REF_STRIPES; s++)
        sum += tx[s]*tx[s] + ty[s]*ty[s];
    return sqrt(sum/REF_STRIPES);
}

/* Low noise (0.01 against particle heights ~1) so that the match with the
 * reference is limited by the alignment, not by the noise; a drift whose
 * stripes move less than REF_MIN_DRIFT px (rms) is too small to show an
 * improvement, so the next seed is taken. */
static FramePair*
make_reference_pair(void)
{
    FramePairSpec spec;
    FramePair *pair;
    guint32 k;

    frame_pair_spec_init(&spec);
    spec.xres = spec.yres = REF_SIZE;
    spec.noise = REF_NOISE;
    for (k = 0; k < 100; k++) {
        pair = frame_pair_generate(&spec, test_seed + k);
        if (rms_stripe_drift(pair) >= REF_MIN_DRIFT)
            break;
        frame_pair_free(pair);
        pair = NULL;
    }
    ck_assert(pair);
    printf("test-module-immediate: frame pair of seed %u + %u, rms stripe drift %.2f px\n",
           test_seed, k, rms_stripe_drift(pair));
    fflush(stdout);
    return pair;
}

static void
set_reference_settings(gint mode, gboolean plot_drift)
{
    ModuleSettings ms = default_settings;

    ms.source = LOCALSCAN_SOURCE_REFERENCE;
    ms.reference_channel = 0;
    ms.stripes = REF_STRIPES;
    ms.mode = mode;
    ms.plot_drift = plot_drift;
    /* Sub-pixel accuracy of the measured drift is judged with a sub-pixel
     * kernel; the default nearest pixel keeps heights instead. */
    ms.interpolation = GWY_INTERPOLATION_BSPLINE;
    set_module_settings(&ms);
}

/* RMS of (field - reference) over the interior pixels the mask (may be
 * NULL) leaves unfilled. */
static gdouble
interior_rms_difference(GwyDataField *field, const gdouble *reference, GwyDataField *mask)
{
    const gdouble *d = gwy_data_field_get_data_const(field);
    const gdouble *m = mask ? gwy_data_field_get_data_const(mask) : NULL;
    gdouble sum = 0.0, e;
    gint r, c, k, count = 0;

    for (r = REF_MARGIN; r < REF_SIZE - REF_MARGIN; r++) {
        for (c = REF_MARGIN; c < REF_SIZE - REF_MARGIN; c++) {
            k = r*REF_SIZE + c;
            if (m && m[k] > 0.5)
                continue;
            e = d[k] - reference[k];
            sum += e*e;
            count++;
        }
    }
    ck_assert_int_gt(count, (REF_SIZE - 2*REF_MARGIN)*(REF_SIZE - 2*REF_MARGIN)/2);
    return sqrt(sum/count);
}

/* Every accepted stripe's measured drift (dx_exact, dy_exact) within
 * 0.5 px of the truth (the stripe's mean drift); dx, dy are the exact
 * values rounded in paper mode and the exact values in continuous mode. */
static void
check_measured_table(const DriftTable *table, const FramePair *pair, gboolean paper)
{
    gdouble tx[REF_STRIPES], ty[REF_STRIPES], ex, ey, worst = 0.0;
    gint s, accepted = 0;

    ck_assert_int_eq(table->n_stripes, REF_STRIPES);
    ck_assert_int_eq(table->unit, DRIFT_UNIT_PX);
    frame_pair_stripe_truth(pair, REF_STRIPES, tx, ty);
    for (s = 0; s < REF_STRIPES; s++) {
        const DriftTableRow *row = table->rows + s;

        ck_assert(drift_table_get_extra(table, s, "score", NULL));
        if (!row->has_drift) {
            ck_assert(!drift_table_get_extra(table, s, "dx_exact", NULL));
            continue;
        }
        accepted++;
        ck_assert(drift_table_get_extra(table, s, "dx_exact", &ex));
        ck_assert(drift_table_get_extra(table, s, "dy_exact", &ey));
        ck_assert_msg(fabs(ex - tx[s]) <= 0.5 && fabs(ey - ty[s]) <= 0.5,
                      "stripe %d measured (%.3f, %.3f) px, truth (%.3f, %.3f) px (seed %u)",
                      s, ex, ey, tx[s], ty[s], test_seed);
        worst = MAX(worst, MAX(fabs(ex - tx[s]), fabs(ey - ty[s])));
        ck_assert(row->dx == (paper ? floor(ex + 0.5) : ex));
        ck_assert(row->dy == (paper ? floor(ey + 0.5) : ey));
    }
    printf("test-module-immediate: %s mode: %d of %d stripes registered, worst error %.3f px\n",
           paper ? "paper" : "continuous", accepted, REF_STRIPES, worst);
    fflush(stdout);
    ck_assert_msg(accepted >= REF_STRIPES*3/4, "only %d of %d stripes registered (seed %u)",
                  accepted, REF_STRIPES, test_seed);
}

/* The new channel, its stored table (the measured one), and how much better
 * it lines up with the reference than the drifting input does. */
static void
check_reference_run(gint mode, gdouble min_improvement)
{
    gboolean paper = (mode == LOCALSCAN_MODE_PAPER);
    FramePair *pair = make_reference_pair();
    GwyContainer *data = make_reference_container(pair);
    GwyDataField *image = get_field(data, gwy_app_get_data_key_for_id(1));
    GwyDataField *source_copy = gwy_data_field_duplicate(image), *result, *mask = NULL;
    DriftTable *table;
    GError *error = NULL;
    gdouble before, after;
    gchar *message = NULL;
    gint newid;

    set_reference_settings(mode, FALSE);
    newid = run_module(data, &message);
    ck_assert_msg(newid == 2, "no new channel; the module said: %s", message);
    ck_assert_str_eq(message, "");
    ck_assert_str_eq(get_string(data, "/2/data/title"), RESULT_TITLE);
    assert_same_field_bits(image, source_copy);

    table = localscan_channel_stored_table(data, newid, &error);
    ck_assert_msg(table, "%s", error ? error->message : "?");
    check_measured_table(table, pair, paper);

    result = get_field(data, gwy_app_get_data_key_for_id(newid));
    gwy_container_gis_object(data, gwy_app_get_mask_key_for_id(newid), &mask);
    before = interior_rms_difference(image, pair->reference, mask);
    after = interior_rms_difference(result, pair->reference, mask);
    printf("test-module-immediate: %s mode: interior rms difference from the reference %.4f before, "
           "%.4f after (%.1fx better, need %.0fx)\n",
           paper ? "paper" : "continuous", before, after, before/after, min_improvement);
    fflush(stdout);
    ck_assert_msg(after*min_improvement <= before,
                  "compensation improved the match only %.2fx (seed %u)", before/after, test_seed);

    drift_table_free(table);
    g_free(message);
    g_object_unref(source_copy);
    drop_container(data);
    frame_pair_free(pair);
}

/* Observed over seeds 1-25: paper mode 5.5-9x (whole-pixel rounding and
 * the drift within a stripe remain), continuous mode 13-19x (down to the
 * noise); without compensation the factor is 1. */
START_TEST(test_reference_paper_mode)
{
    check_reference_run(LOCALSCAN_MODE_PAPER, 4.0);
}
END_TEST

START_TEST(test_reference_continuous_mode)
{
    check_reference_run(LOCALSCAN_MODE_CONTINUOUS, 8.0);
}
END_TEST

/* The stripes whose content meets reference rows [r0, r0 + h) measured as
 * exactly as elsewhere: within 0.05 px (0.008-0.017 px over seeds 1-8;
 * with the mask ignored the filled patch pulls them 0.06-0.38 px off). */
static void
check_stripes_meeting_hole(const DriftTable *table, const FramePair *pair, gint r0, gint h)
{
    gdouble tx[REF_STRIPES], ty[REF_STRIPES], ex, ey, worst = 0.0;
    gint s, first, end, met = 0;

    frame_pair_stripe_truth(pair, REF_STRIPES, tx, ty);
    for (s = 0; s < REF_STRIPES; s++) {
        first = s*REF_SIZE/REF_STRIPES;
        end = (s + 1)*REF_SIZE/REF_STRIPES;
        if (!table->rows[s].has_drift || first - ty[s] - 2 >= r0 + h || end - ty[s] + 2 <= r0)
            continue;
        ck_assert(drift_table_get_extra(table, s, "dx_exact", &ex));
        ck_assert(drift_table_get_extra(table, s, "dy_exact", &ey));
        worst = MAX(worst, hypot(ex - tx[s], ey - ty[s]));
        met++;
    }
    printf("test-module-immediate: masked hole: %d stripes meeting it, worst %.3f px\n", met, worst);
    ck_assert_msg(worst <= 0.05, "a stripe meeting the masked hole %.3f px off (seed %u)", worst,
                  test_seed);
}

/* Gwyddion's importers fill the pixels a file lacks with the mean and mask
 * them: a hole of 25-40 px so given in the reference is left out of the
 * registration (the default masking): every stripe measured stays within
 * 0.5 px of the truth, those meeting the hole within 0.05 px. */
START_TEST(test_reference_masked_hole)
{
    FramePair *pair = make_reference_pair();
    GwyContainer *data = make_reference_container(pair);
    GwyDataField *reference = get_field(data, gwy_app_get_data_key_for_id(0));
    GwyDataField *mask = gwy_data_field_new_alike(reference, TRUE);
    GRand *rng = g_rand_new_with_seed(test_seed ^ 0x3a5eu);
    gint w = g_rand_int_range(rng, 25, 41), h = g_rand_int_range(rng, 25, 41), r0, c0, r, c;
    gdouble mean = gwy_data_field_get_avg(reference);
    DriftTable *table;
    GError *error = NULL;
    gchar *message = NULL;

    r0 = g_rand_int_range(rng, REF_MARGIN, REF_SIZE - REF_MARGIN - h);
    c0 = g_rand_int_range(rng, REF_MARGIN, REF_SIZE - REF_MARGIN - w);
    for (r = r0; r < r0 + h; r++) {
        for (c = c0; c < c0 + w; c++) {
            gwy_data_field_set_val(reference, c, r, mean);
            gwy_data_field_set_val(mask, c, r, 1.0);
        }
    }
    gwy_data_field_data_changed(reference);
    gwy_container_set_object(data, gwy_app_get_mask_key_for_id(0), mask);
    set_reference_settings(LOCALSCAN_MODE_PAPER, FALSE);
    ck_assert_int_eq(run_module(data, &message), 2);
    ck_assert_str_eq(message, "");
    table = localscan_channel_stored_table(data, 2, &error);
    ck_assert_msg(table, "%s", error ? error->message : "?");
    check_measured_table(table, pair, TRUE);
    check_stripes_meeting_hole(table, pair, r0, h);

    drift_table_free(table);
    g_free(message);
    g_object_unref(mask);
    g_rand_free(rng);
    drop_container(data);
    frame_pair_free(pair);
}
END_TEST

/* The drift graph and the log work for this source too; the log names the
 * reference through the settings it records. */
START_TEST(test_reference_graph_and_log)
{
    FramePair *pair = make_reference_pair();
    GwyContainer *data = make_reference_container(pair);
    GwyGraphCurveModel *gcmodel;
    GwyGraphModel *gmodel;
    GwyStringList *log = NULL;
    DriftTable *table;
    gdouble dx_px[REF_STRIPES], dy_px[REF_STRIPES];
    const gdouble *y;
    const gchar *entry;
    gint *ids, s;

    set_reference_settings(LOCALSCAN_MODE_PAPER, TRUE);
    ck_assert_int_eq(run_module(data, NULL), 2);
    table = localscan_channel_stored_table(data, 2, NULL);
    ck_assert(table);
    ck_assert(drift_table_to_pixels(table, REF_SIZE, REF_STEP, REF_STEP, TRUE, dx_px, dy_px, NULL));

    ids = gwy_app_data_browser_get_graph_ids(data);
    ck_assert_int_ne(ids[0], -1);
    ck_assert(gwy_container_gis_object(data, gwy_app_get_graph_key_for_id(ids[0]), &gmodel));
    g_free(ids);
    ck_assert_int_eq(gwy_graph_model_get_n_curves(gmodel), 2);
    for (s = 0; s < 2; s++) {
        gcmodel = gwy_graph_model_get_curve(gmodel, s);
        ck_assert_int_eq(gwy_graph_curve_model_get_ndata(gcmodel), REF_STRIPES);
    }
    y = gwy_graph_curve_model_get_ydata(gwy_graph_model_get_curve(gmodel, 0));
    for (s = 0; s < REF_STRIPES; s++)
        ck_assert_double_eq_tol(y[s], dx_px[s]*REF_STEP, 1e-20);
    y = gwy_graph_curve_model_get_ydata(gwy_graph_model_get_curve(gmodel, 1));
    for (s = 0; s < REF_STRIPES; s++)
        ck_assert_double_eq_tol(y[s], dy_px[s]*REF_STEP, 1e-20);

    ck_assert(gwy_container_gis_object_by_name(data, "/2/data/log", &log));
    ck_assert_int_ge(gwy_string_list_get_length(log), 1);
    entry = gwy_string_list_get(log, gwy_string_list_get_length(log) - 1);
    printf("test-module-immediate: log entry: %s\n", entry);
    ck_assert_msg(g_str_has_prefix(entry, "proc::" LOCALSCAN_FUNCTION_NAME "("), "log entry %s", entry);
    /* Settings by name, the reference as "file — channel". */
    ck_assert_msg(strstr(entry, "source=reference"), "log entry %s", entry);
    ck_assert_msg(strstr(entry, " \342\200\224 Reference"), "log entry %s", entry);
    ck_assert_msg(strstr(entry, "mode=paper"), "log entry %s", entry);

    drift_table_free(table);
    drop_container(data);
    frame_pair_free(pair);
}
END_TEST

/* Each unusable reference: no new channel, one line naming the problem. */
static void
check_reference_refused(GwyContainer *data, gint reference_channel, gint stripes, const gchar *expected_part)
{
    ModuleSettings ms = default_settings;
    gchar *message = NULL;

    ms.source = LOCALSCAN_SOURCE_REFERENCE;
    ms.reference_channel = reference_channel;
    ms.stripes = stripes;
    set_module_settings(&ms);
    ck_assert_int_eq(run_module(data, &message), -1);
    ck_assert_msg(g_str_has_prefix(message, LOCALSCAN_FUNCTION_NAME ": ") && strstr(message, expected_part),
                  "message '%s' lacks '%s'", message, expected_part);
    ck_assert_msg(strchr(message, '\n') == message + strlen(message) - 1, "message '%s' is not one line", message);
    g_free(message);
}

START_TEST(test_reference_refused)
{
    FramePair *pair = make_reference_pair();
    GwyContainer *data = make_reference_container(pair);
    GwyDataField *narrow = gwy_data_field_new(128, 256, 128*REF_STEP, 256*REF_STEP, TRUE);
    GwyDataField *wider = gwy_data_field_new(256, 256, 512*REF_STEP, 256*REF_STEP, TRUE);

    gwy_si_unit_set_from_string(gwy_data_field_get_si_unit_xy(narrow), "m");
    gwy_si_unit_set_from_string(gwy_data_field_get_si_unit_xy(wider), "m");
    gwy_container_set_object(data, gwy_app_get_data_key_for_id(2), narrow);
    gwy_container_set_object(data, gwy_app_get_data_key_for_id(3), wider);
    check_reference_refused(data, -1, REF_STRIPES, "No reference image is chosen");
    check_reference_refused(data, 1, REF_STRIPES, "another channel than the image itself");
    check_reference_refused(data, 7, REF_STRIPES, "reference channel 7 does not exist");
    check_reference_refused(data, 2, REF_STRIPES, "reference channel 2 (128 x 256 px");
    check_reference_refused(data, 3, REF_STRIPES, "is not a scan of the size of the image channel 1 (256 x 256 px");
    check_reference_refused(data, 0, REF_SIZE + 1, "257 stripes do not fit the 256 rows of the image channel 1");
    ck_assert_int_eq(count_ids(gwy_app_data_browser_get_data_ids(data)), 4);

    g_object_unref(narrow);
    g_object_unref(wider);
    drop_container(data);
    frame_pair_free(pair);
}
END_TEST

/* A reference of white noise shares nothing with the image: registration
 * accepts no stripe and says so. */
START_TEST(test_reference_unrelated_refused)
{
    FramePair *pair = make_reference_pair();
    GwyContainer *data = make_reference_container(pair);
    GwyDataField *reference = get_field(data, gwy_app_get_data_key_for_id(0));
    GRand *rng = g_rand_new_with_seed(test_seed);
    gdouble *d = gwy_data_field_get_data(reference);
    gint i;

    for (i = 0; i < REF_SIZE*REF_SIZE; i++)
        d[i] = g_rand_double(rng);
    check_reference_refused(data, 0, REF_STRIPES, "No stripe of the image could be registered");
    ck_assert_int_eq(count_ids(gwy_app_data_browser_get_data_ids(data)), 2);
    g_rand_free(rng);
    drop_container(data);
    frame_pair_free(pair);
}
END_TEST

/* What the importers of the measured files put into metadata gives their
 * timing (shared/data/measured/MANIFEST.md: FastScan 2.325 Hz scanning
 * down, its "Relative frame time" the frame start, HS-AFM 0.413 s frames
 * 6.189 s apart, nanoIR 0.25-1 Hz, its TimeStamp a date and so not used,
 * Asylum). */
typedef struct {
    const gchar *file;
    gint id;
    LocalscanTimingFound found;
    gdouble line_time;
    ScanDirection direction;
    gdouble frame_start;
} MeasuredTiming;

static const MeasuredTiming measured_timings[] = {
    { "fastscan-series/09261606.001", 0,
      LOCALSCAN_TIMING_LINE_TIME | LOCALSCAN_TIMING_DIRECTION | LOCALSCAN_TIMING_FRAME_START,
      1.0/2.32515, SCAN_DIRECTION_DOWN, 7279.93 },
    { "hsafm-minicircles/hsafm_sample0_frames50-140.gwy", 1, LOCALSCAN_TIMING_LINE_TIME | LOCALSCAN_TIMING_FRAME_START,
      0.41263/256, SCAN_DIRECTION_UP, 6.189 },
    { "afmir-film/PEA_BDA_film.axz", 10, LOCALSCAN_TIMING_LINE_TIME, 4.0, SCAN_DIRECTION_UP, 0.0 },
    { "particles-film/PTO_110_Virgin0001.gwy", 0, LOCALSCAN_TIMING_LINE_TIME, 1.0/1.0016, SCAN_DIRECTION_UP, 0.0 },
};

START_TEST(test_measured_files_timing)
{
    const MeasuredTiming *mt = measured_timings + _i;
    gchar *path = g_build_filename(test_measured_dir(), mt->file, NULL);
    GwyContainer *data;
    ScanTiming t;

    data = gwy_file_load(path, GWY_RUN_NONINTERACTIVE, NULL);
    ck_assert_msg(data, "cannot load %s", path);
    ck_assert_int_eq(localscan_channel_scan_timing(data, mt->id, SCAN_DIRECTION_UP, &t), mt->found);
    printf("test-module-immediate: %s channel %d: line time %g s, slow scan %s, frame start %g s\n",
           mt->file, mt->id, t.line_time, t.direction == SCAN_DIRECTION_UP ? "up" : "down", t.frame_start);
    ck_assert_double_eq_tol(t.line_time, mt->line_time, 1e-12);
    ck_assert_int_eq(t.direction, mt->direction);
    ck_assert_double_eq_tol(t.frame_start, mt->frame_start, 1e-12);
    g_object_unref(data);
    g_free(path);
}
END_TEST

/* Measured file i's timing case, or SKIPPED when the file is absent. */
static void
add_measured_timing_test(TCase *tc, guint i)
{
    gchar *what = g_strdup_printf("%s timing", measured_timings[i].file);
    gchar *path = test_measured_file("test-module-immediate",
                                     measured_timings[i].file, what);

    if (path)
        tcase_add_loop_test(tc, test_measured_files_timing, i, i + 1);
    g_free(path);
    g_free(what);
}

/************************************************************************
 * Continuous mode on simscan's files: timing from their metadata
 ************************************************************************/

/* Seeds tried in order until enough had every local scan on its own
 * particle (a scan that measured a neighbour is the trajectory's problem,
 * not the timing's: continuous mode may then lose to paper mode). */
#define SIMSCAN_SEEDS_TRIED 12
#define SIMSCAN_SEEDS_JUDGED 3
#define GOOD_STRIPE_PX 0.5
/* On such seeds continuous mode's RMS against the truth is 0.64-0.76 of
 * paper mode's (seeds 1-24 of both cases); with the wrong timing (1 s per
 * line, scanning down) it was 2.0 of it scanning up. */
#define CONTINUOUS_VS_PAPER 0.85

static const LocalscanTimingFound all_timing = (LOCALSCAN_TIMING_LINE_TIME | LOCALSCAN_TIMING_DIRECTION
                                                | LOCALSCAN_TIMING_FRAME_START);

/* The file simscan wrote, loaded, in the data browser, channel 0 selected. */
static GwyContainer*
load_simscan_file(const SimscanFileCase *fcase, guint32 seed)
{
    gchar *dir = g_dir_make_tmp("localscan-simscan-XXXXXX", NULL), *path;
    GError *error = NULL;
    GwyContainer *data;

    ck_assert(dir);
    path = g_build_filename(dir, "simscan.gwy", NULL);
    ck_assert_msg(simscan_file_write(fcase, seed, path, &error), "%s", error ? error->message : "");
    data = gwy_file_load(path, GWY_RUN_NONINTERACTIVE, &error);
    ck_assert_msg(data, "cannot load simscan's file: %s", error ? error->message : "");
    g_unlink(path);
    g_rmdir(dir);
    g_free(path);
    g_free(dir);
    gwy_app_data_browser_add(data);
    gwy_app_data_browser_select_data_field(data, 0);
    return data;
}

/* The direction setting is the opposite of the file's: the metadata must
 * win. */
static gint
run_simscan_mode_with(GwyContainer *data, const SimscanFileCase *fcase, gint mode,
                      gint interpolation)
{
    ModuleSettings ms = default_settings;

    ms.mode = mode;
    ms.interpolation = interpolation;
    ms.direction = (fcase->direction == SCAN_DIRECTION_UP ? SCAN_DIRECTION_DOWN : SCAN_DIRECTION_UP);
    set_module_settings(&ms);
    gwy_app_data_browser_select_data_field(data, 0);
    return run_module(data, NULL);
}

/* Continuous mode is judged against paper mode for its sub-pixel
 * positions, so with a sub-pixel kernel; the default nearest pixel keeps
 * heights instead (tests/test-height-keeping). */
#define SIMSCAN_KERNEL GWY_INTERPOLATION_BSPLINE

static gint
run_simscan_mode(GwyContainer *data, const SimscanFileCase *fcase, gint mode)
{
    return run_simscan_mode_with(data, fcase, mode, SIMSCAN_KERNEL);
}

/* The timing read from the file is what simscan was told, and continuous
 * mode compensates with exactly it (the result is the direct call's to its
 * rounding).  Returns the new channel, or -1 when
 * continuous compensation refuses the table (as it must then). */
static gint
check_simscan_timing(GwyContainer *data, const SimscanFileCase *fcase, guint32 seed)
{
    GwyDataField *field = get_field(data, gwy_app_get_data_key_for_id(0)), *expected;
    ScanTiming told, found;
    gint id;

    simscan_file_timing(fcase, field, &told);
    ck_assert_int_eq(localscan_channel_scan_timing(data, 0, !fcase->direction, &found), all_timing);
    ck_assert_msg(found.line_time == told.line_time && found.direction == told.direction
                  && found.frame_start == 0.0 && found.xres == told.xres && found.yres == told.yres,
                  "%s, seed %u: timing %g s, direction %d, frame start %g s read; simscan was told %g s, %d",
                  fcase->name, seed, found.line_time, found.direction, found.frame_start,
                  told.line_time, told.direction);
    expected = simscan_file_expected_continuous(data, &told, SIMSCAN_KERNEL);
    id = run_simscan_mode(data, fcase, LOCALSCAN_MODE_CONTINUOUS);
    if (!expected)
        ck_assert_int_eq(id, -1);
    else {
        ck_assert_int_ge(id, 0);
        assert_same_field_values(get_field(data, gwy_app_get_data_key_for_id(id)), expected);
        g_object_unref(expected);
    }
    return id;
}

static void
check_simscan_case(const SimscanFileCase *fcase)
{
    GwyContainer *data;
    DriftTable *table;
    gdouble worst, t_ref, rms_before, rms_paper, rms_continuous;
    gint judged = 0, continuous_id, paper_id;
    guint32 seed;

    for (seed = 1; seed <= SIMSCAN_SEEDS_TRIED && judged < SIMSCAN_SEEDS_JUDGED; seed++) {
        data = load_simscan_file(fcase, seed);
        table = localscan_channel_stored_table(data, 0, NULL);
        ck_assert(table);
        continuous_id = check_simscan_timing(data, fcase, seed);
        worst = simscan_file_worst_stripe_px(fcase, table, get_field(data, gwy_app_get_data_key_for_id(0)));
        if (worst > GOOD_STRIPE_PX || continuous_id < 0) {
            printf("test-module-immediate: %s, simscan seed %u: a local scan is %.2f px off, not judged\n",
                   fcase->name, seed, worst);
        }
        else {
            paper_id = run_simscan_mode(data, fcase, LOCALSCAN_MODE_PAPER);
            ck_assert_int_ge(paper_id, 0);
            t_ref = simscan_file_reference_time(table);
            rms_before = simscan_file_truth_rms(fcase, data, 0, t_ref);
            rms_paper = simscan_file_truth_rms(fcase, data, paper_id, t_ref);
            rms_continuous = simscan_file_truth_rms(fcase, data, continuous_id, t_ref);
            printf("test-module-immediate: %s, simscan seed %u: RMS against the truth at %.1f s: "
                   "before %.3f nm, paper %.3f nm, continuous %.3f nm (%.2f of paper)\n",
                   fcase->name, seed, t_ref, 1e9*rms_before, 1e9*rms_paper, 1e9*rms_continuous,
                   rms_continuous/rms_paper);
            ck_assert_msg(rms_continuous < CONTINUOUS_VS_PAPER*rms_paper,
                          "%s, simscan seed %u: continuous %g nm RMS, paper %g nm", fcase->name, seed,
                          1e9*rms_continuous, 1e9*rms_paper);
            judged++;
        }
        drift_table_free(table);
        drop_container(data);
    }
    ck_assert_msg(judged == SIMSCAN_SEEDS_JUDGED, "%s: only %d of simscan seeds 1-%d had every local scan "
                  "on its particle", fcase->name, judged, SIMSCAN_SEEDS_TRIED);
}

START_TEST(test_simscan_default_timing)
{
    check_simscan_case(&simscan_file_default);
}
END_TEST

START_TEST(test_simscan_up_timing)
{
    check_simscan_case(&simscan_file_up);
}
END_TEST

/* The same scan as a later frame: "Frame start (s)" and the table's
 * t_image, t_local all 1000 s later give the same image.  Not to the bit:
 * the trajectory's smoothing rounds differently at later times (3e-5 of
 * the range here); a frame start ignored moves 0.9 of it. */
START_TEST(test_simscan_frame_start)
{
    GwyContainer *data = load_simscan_file(&simscan_file_up, 2), *meta;
    DriftTable *table = localscan_channel_stored_table(data, 0, NULL);
    GwyDataField *first, *later;
    gdouble t, range, diff;
    gint s, id;

    /* A kernel continuous in the source position: the nearest pixel (the
     * default) flips wherever the shifted clock's rounding crosses half a
     * pixel, which says nothing about the timing. */
    ck_assert(table);
    id = run_simscan_mode_with(data, &simscan_file_up, LOCALSCAN_MODE_CONTINUOUS,
                               GWY_INTERPOLATION_BSPLINE);
    ck_assert_int_ge(id, 0);
    first = get_field(data, gwy_app_get_data_key_for_id(id));
    for (s = 0; s < table->n_stripes; s++) {
        if (drift_table_get_extra(table, s, "t_image", &t))
            drift_table_set_extra(table, s, "t_image", t + 1000.0);
        if (drift_table_get_extra(table, s, "t_local", &t))
            drift_table_set_extra(table, s, "t_local", t + 1000.0);
    }
    localscan_channel_store_table(data, 0, table);
    ck_assert(gwy_container_gis_object_by_name(data, "/0/meta", &meta));
    set_string(meta, "Frame start (s)", "1000");
    id = run_simscan_mode_with(data, &simscan_file_up, LOCALSCAN_MODE_CONTINUOUS,
                               GWY_INTERPOLATION_BSPLINE);
    ck_assert_int_ge(id, 0);
    later = gwy_data_field_duplicate(get_field(data, gwy_app_get_data_key_for_id(id)));
    range = gwy_data_field_get_max(first) - gwy_data_field_get_min(first);
    gwy_data_field_subtract_fields(later, later, first);
    diff = fmax(-gwy_data_field_get_min(later), gwy_data_field_get_max(later));
    printf("test-module-immediate: frame start 1000 s: largest difference %.3g of the range\n", diff/range);
    ck_assert_msg(diff <= 1e-3*range, "frame start 1000 s changes the result by %g of its range", diff/range);
    g_object_unref(later);
    drift_table_free(table);
    drop_container(data);
}
END_TEST


static gboolean
load_module(void)
{
    const gchar *path = g_getenv("LOCALSCAN_MODULE");
    GError *error = NULL;

    if (!path) {
        fprintf(stderr, "test-module-immediate: LOCALSCAN_MODULE is not set.\n");
        return FALSE;
    }
    gwy_app_init_nongui("enable-threads", FALSE, NULL);
    if (!gwy_module_register_module(path, &error)) {
        fprintf(stderr, "test-module-immediate: cannot load %s: %s\n", path, error->message);
        g_clear_error(&error);
        return FALSE;
    }
    return gwy_process_func_exists(LOCALSCAN_FUNCTION_NAME);
}

int
main(void)
{
    TCase *tc;
    Suite *suite = test_suite_new("module-immediate", "immediate", &tc);
    guint i;

    test_seed = test_seed_from_env("test-module-immediate");
    if (!load_module())
        return 1;

    tcase_add_test(tc, test_paper_compensate_matches_spec);
    tcase_add_test(tc, test_worked_example_exact);
    tcase_add_test(tc, test_worked_example_scaled);
    tcase_add_test(tc, test_worked_example_nm_table);
    tcase_add_loop_test(tc, test_random_table_matches_paper_compensate, 0, 8);
    tcase_add_test(tc, test_result_channel_items);
    tcase_add_test(tc, test_csv_file_source);
    tcase_add_test(tc, test_result_not_compensated_twice);
    tcase_add_test(tc, test_all_channels);
    tcase_add_test(tc, test_fill_values);
    tcase_add_test(tc, test_mask_only_when_wanted);
    tcase_add_test(tc, test_drift_graph);
    tcase_add_test(tc, test_continuous_mode_passes_timing);
    tcase_add_test(tc, test_bad_sources_refused);
    tcase_add_test(tc, test_scan_timing_from_metadata);
    tcase_add_test(tc, test_scan_timing_meta_dates);
    tcase_add_test(tc, test_source_content_meta_dropped);
    for (i = 0; i < G_N_ELEMENTS(measured_timings); i++)
        add_measured_timing_test(tc, i);
    tcase_add_test(tc, test_simscan_default_timing);
    tcase_add_test(tc, test_simscan_up_timing);
    tcase_add_test(tc, test_simscan_frame_start);
    tcase_add_test(tc, test_reference_paper_mode);
    tcase_add_test(tc, test_reference_continuous_mode);
    tcase_add_test(tc, test_reference_masked_hole);
    tcase_add_test(tc, test_reference_graph_and_log);
    tcase_add_test(tc, test_reference_refused);
    tcase_add_test(tc, test_reference_unrelated_refused);
    return test_run_suite(suite);
}
