/*
 *  Local Scan Series Drift run by Gwyddion's process-function path
 *  (GWY_RUN_IMMEDIATE, as pygwy and batch callers run it) on a simulated
 *  series whose channels are the frames: a corrected channel per frame
 *  (what the core makes of the frames, titled after its source), the
 *  trajectory graph, the settings' timing where the file gives none, and
 *  the error of a channel with no partner.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <string.h>
#include <math.h>
#include <check.h>
#include <libgwyddion/gwyddion.h>
#include <libprocess/gwyprocess.h>
#include <libgwydgets/gwydgets.h>
#include <libgwymodule/gwymodule.h>
#include <app/gwyapp.h>
#include "localscan-channel.h"
#include "series-process.h"
#include "hidden-effect-cases.h"
#include "series-cases.h"
#include "test-common.h"

static guint32 base_seed;

/* The frames of a series case as channels 0 .. 4 of one container, titled
 * "Height k", with no timing: the settings give it. */
static GwyContainer*
series_container(gint i, DriftModel *model, FrameSeries **series)
{
    SeriesCaseOptions options = { FALSE, -1 };
    GwyContainer *data = gwy_container_new();
    gchar key[32], title[32];
    gint k;

    hidden_case_draw(base_seed, i, model);
    *series = series_case_scan(base_seed, i, model, &options, NULL);
    for (k = 0; k < (*series)->n_frames; k++) {
        g_snprintf(key, sizeof(key), "/%d/data", k);
        gwy_container_set_object_by_name(data, key, (*series)->frames[k].field);
        g_snprintf(key, sizeof(key), "/%d/data/title", k);
        g_snprintf(title, sizeof(title), "Height %d", k);
        gwy_container_set_const_string_by_name(data, key, (const guchar*)title);
    }
    gwy_app_data_browser_add(data);
    gwy_app_data_browser_select_data_field(data, 0);
    return data;
}

static void
set_timing_settings(gdouble line_time, gdouble interval)
{
    GwyContainer *settings = gwy_app_settings_get();

    gwy_container_set_double_by_name(settings, "/module/localscan_series/line_time",
                                     line_time);
    gwy_container_set_double_by_name(settings, "/module/localscan_series/frame_interval",
                                     interval);
    gwy_container_set_boolean_by_name(settings, "/module/localscan_series/add_graph",
                                      TRUE);
    gwy_container_set_boolean_by_name(settings, "/module/localscan_series/crop",
                                      FALSE);
}

START_TEST(test_series_immediate)
{
    DriftModel model;
    FrameSeries *series;
    GwyContainer *data;
    SeriesCorrection correction;
    gint k, n_before, n_after, *ids;
    gchar key[40];
    const guchar *title;
    GError *error = NULL;

    /* The series cases' frames: 128 lines of 0.5 s, back to back. */
    set_timing_settings(0.5, 0.0);
    data = series_container(_i, &model, &series);
    ids = gwy_app_data_browser_get_data_ids(data);
    for (n_before = 0; ids[n_before] >= 0; n_before++)
        ;
    g_free(ids);
    gwy_process_func_run(LOCALSCAN_SERIES_FUNCTION_NAME, data, GWY_RUN_IMMEDIATE);
    error = localscan_run_error_take(data);
    ck_assert_msg(!error, "the run failed: %s", error ? error->message : "");
    ids = gwy_app_data_browser_get_data_ids(data);
    for (n_after = 0; ids[n_after] >= 0; n_after++)
        ;
    g_free(ids);
    ck_assert_int_eq(n_after, n_before + SERIES_CASE_FRAMES);
    ck_assert(gwy_container_contains_by_name(data, "/0/graph/graph/1"));

    /* Each new channel is what the core makes of its frame with the timing
     * the settings gave. */
    ck_assert(series_correction_compute(series, NULL, NULL, &correction, NULL));
    for (k = 0; k < SERIES_CASE_FRAMES; k++) {
        GwyDataField *mine, *fixed = gwy_data_field_new_alike(series->frames[k].field, FALSE);
        GwyDataField *mask = gwy_data_field_new_alike(fixed, FALSE);
        gchar *expected = g_strdup_printf("Height %d (drift corrected)", k);

        ck_assert(series_correction_correct_frame(&correction, series, k,
                                                  GWY_INTERPOLATION_BSPLINE,
                                                  fixed, mask, NULL));
        g_snprintf(key, sizeof(key), "/%d/data/title", n_before + k);
        ck_assert(gwy_container_gis_string_by_name(data, key, &title));
        ck_assert_str_eq((const gchar*)title, expected);
        g_snprintf(key, sizeof(key), "/%d/data", n_before + k);
        mine = gwy_container_get_object_by_name(data, key);
        gwy_data_field_subtract_fields(fixed, fixed, mine);
        ck_assert_msg(gwy_data_field_get_max(fixed) < 1e-15
                      && gwy_data_field_get_min(fixed) > -1e-15,
                      "frame %d differs from the core's correction", k);
        g_object_unref(fixed);
        g_object_unref(mask);
        g_free(expected);
    }
    printf("case %d (%s): %d corrected channels and the graph\n", _i,
           drift_model_type_name(model.type), SERIES_CASE_FRAMES);
    series_correction_clear(&correction);
    frame_series_free(series);
    drift_model_clear(&model);
    gwy_app_data_browser_remove(data);
    g_object_unref(data);
}
END_TEST

static gint
count_channels(GwyContainer *data)
{
    gint *ids = gwy_app_data_browser_get_data_ids(data), n;

    for (n = 0; ids[n] >= 0; n++)
        ;
    g_free(ids);
    return n;
}

/* The frames are the channels scanned like the current one: a channel of
 * the same size but another title (a simulator's drift-free truth, a
 * Phase beside a Height) is not one, nor is a channel a correction made.
 * Run a second time, the correction took its own results for frames too
 * (14 frames of 7, "(drift corrected) (drift corrected)"); run on a
 * corrected channel, it is refused. */
START_TEST(test_series_frames_chosen)
{
    DriftModel model;
    FrameSeries *series;
    GwyContainer *data, *meta;
    GwyDataField *other;
    gint n_before, n_first;
    gchar key[40];
    GError *error;

    set_timing_settings(0.5, 0.0);
    data = series_container(0, &model, &series);
    /* Another channel of frame 0's scan: the same lines, other values. */
    other = gwy_data_field_duplicate(series->frames[0].field);
    gwy_data_field_multiply(other, -1.0);
    g_snprintf(key, sizeof(key), "/%d/data", SERIES_CASE_FRAMES);
    gwy_container_set_object_by_name(data, key, other);
    g_snprintf(key, sizeof(key), "/%d/data/title", SERIES_CASE_FRAMES);
    gwy_container_set_const_string_by_name(data, key, (const guchar*)"Phase");
    /* An instrument's own item of that name is no correction's marker. */
    meta = gwy_container_new();
    gwy_container_set_const_string_by_name(meta, "Drift correction", (const guchar*)"closed loop");
    gwy_container_set_object_by_name(data, "/1/meta", meta);
    g_object_unref(meta);
    n_before = count_channels(data);
    gwy_process_func_run(LOCALSCAN_SERIES_FUNCTION_NAME, data, GWY_RUN_IMMEDIATE);
    error = localscan_run_error_take(data);
    ck_assert_msg(!error, "the run failed: %s", error ? error->message : "");
    n_first = count_channels(data);
    ck_assert_int_eq(n_first, n_before + SERIES_CASE_FRAMES);

    gwy_app_data_browser_select_data_field(data, 0);
    gwy_process_func_run(LOCALSCAN_SERIES_FUNCTION_NAME, data, GWY_RUN_IMMEDIATE);
    error = localscan_run_error_take(data);
    ck_assert_msg(!error, "the second run failed: %s", error ? error->message : "");
    ck_assert_int_eq(count_channels(data), n_first + SERIES_CASE_FRAMES);

    gwy_app_data_browser_select_data_field(data, n_before);
    gwy_process_func_run(LOCALSCAN_SERIES_FUNCTION_NAME, data, GWY_RUN_IMMEDIATE);
    error = localscan_run_error_take(data);
    ck_assert(error != NULL);
    printf("corrected channel: %s\n", error->message);
    ck_assert(strstr(error->message, "result of a drift correction") != NULL);
    ck_assert_int_eq(count_channels(data), n_first + SERIES_CASE_FRAMES);
    g_error_free(error);
    g_object_unref(other);
    frame_series_free(series);
    drift_model_clear(&model);
    gwy_app_data_browser_remove(data);
    g_object_unref(data);
}
END_TEST

/* One channel is no series: nothing added, the reason kept for the caller. */
START_TEST(test_series_lone_channel)
{
    GwyContainer *data = gwy_container_new();
    GwyDataField *field = gwy_data_field_new(64, 64, 64e-9, 64e-9, TRUE);
    GError *error;
    gint *ids, n;

    gwy_container_set_object_by_name(data, "/0/data", field);
    gwy_app_data_browser_add(data);
    gwy_app_data_browser_select_data_field(data, 0);
    gwy_process_func_run(LOCALSCAN_SERIES_FUNCTION_NAME, data, GWY_RUN_IMMEDIATE);
    error = localscan_run_error_take(data);
    ck_assert(error != NULL);
    printf("lone channel: %s\n", error->message);
    ck_assert(strstr(error->message, "at least two") != NULL);
    ids = gwy_app_data_browser_get_data_ids(data);
    for (n = 0; ids[n] >= 0; n++)
        ;
    ck_assert_int_eq(n, 1);
    g_free(ids);
    g_error_free(error);
    gwy_app_data_browser_remove(data);
    g_object_unref(field);
    g_object_unref(data);
}
END_TEST

int
main(void)
{
    const gchar *path = g_getenv("LOCALSCAN_MODULE");
    GError *error = NULL;
    TCase *tc;
    Suite *s = test_suite_new("series-module", "immediate", &tc);

    base_seed = test_seed_from_env("test-series-module");
    if (!path) {
        printf("test-series-module: SKIPPED: LOCALSCAN_MODULE is not set\n");
        return TEST_EXIT_SKIP;
    }
    gwy_app_init_nongui("enable-threads", FALSE, NULL);
    if (!gwy_module_register_module(path, &error)) {
        printf("test-series-module: cannot load %s: %s\n", path, error->message);
        return 1;
    }
    tcase_add_loop_test(tc, test_series_immediate, 0, 2);
    tcase_add_test(tc, test_series_frames_chosen);
    tcase_add_test(tc, test_series_lone_channel);
    tcase_set_timeout(tc, 120);
    return test_run_suite(s);
}
