/*
 *  Tests of frame-series loading on the measured files: timing from each
 *  format's metadata, non-square pixels, channels as frames, duplicate
 *  frames dropped, clear refusals.  Skips when the measured data is absent.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <stdlib.h>
#include <string.h>
#include <math.h>
#include <check.h>
#include <libgwyddion/gwyddion.h>
#include <libgwymodule/gwymodule.h>
#include <app/gwyapp.h>
#include "frame-series.h"

static const gchar *measured;

static gchar*
data_path(const gchar *relative)
{
    return g_build_filename(measured, relative, NULL);
}

START_TEST(test_nanoscope_timing)
{
    gchar *files[3] = {
        data_path("fastscan-series/09261606.001"),
        data_path("fastscan-series/09261609.001"),
        data_path("fastscan-series/09261616.001"),
    };
    FrameSeriesOptions options;
    FrameSeries *series;
    GError *error = NULL;
    gint i;

    frame_series_options_init(&options);
    options.channel = "ZSensor";
    series = frame_series_load(files, 3, &options, &error);
    ck_assert_msg(series != NULL, "%s", error ? error->message : "");
    ck_assert_int_eq(series->n_frames, 3);
    ck_assert_int_eq(series->frames[0].timing.xres, 768);
    ck_assert_int_eq(series->frames[0].timing.yres, 486);
    ck_assert(fabs(frame_series_dx(series) - 0.1302e-9) < 0.001e-9);
    ck_assert(fabs(frame_series_dy(series) - 0.2058e-9) < 0.001e-9);
    /* Scan Rate 2.32515 Hz; Relative frame time 7279.93, 7489.81, 7908.97. */
    ck_assert(fabs(series->frames[0].timing.line_time - 1.0/2.32515) < 1e-6);
    ck_assert(fabs(series->frames[1].timing.frame_start - 209.88) < 1e-6);
    ck_assert(fabs(series->frames[2].timing.frame_start - 629.04) < 1e-6);
    for (i = 0; i < 3; i++) {
        ck_assert_int_eq(series->frames[i].timing.direction,
                         SCAN_DIRECTION_DOWN);
        ck_assert_int_eq(series->frames[i].direction_source,
                         FRAME_TIME_METADATA);
    }
    frame_series_free(series);
    for (i = 0; i < 3; i++)
        g_free(files[i]);
}
END_TEST

START_TEST(test_hsafm_channels_as_frames)
{
    gchar *file = data_path("hsafm-minicircles/hsafm_sample0_frames50-140.gwy");
    FrameSeries *series;
    GError *error = NULL;

    series = frame_series_load(&file, 1, NULL, &error);
    ck_assert_msg(series != NULL, "%s", error ? error->message : "");
    ck_assert_int_eq(series->n_frames, 7);
    ck_assert(fabs(series->frames[0].timing.line_time - 0.41263/256) < 1e-9);
    ck_assert(fabs(series->frames[1].timing.frame_start - 6.189) < 1e-9);
    ck_assert(fabs(series->frames[6].timing.frame_start - 37.135) < 0.01);
    frame_series_free(series);
    g_free(file);
}
END_TEST

START_TEST(test_anasys_duplicates_dropped)
{
    gchar *file = data_path("afmir-film/PEA_BDA_film.axz");
    FrameSeriesOptions options;
    FrameSeries *series;
    GError *error = NULL;
    static const gint kept[5] = { 9, 10, 11, 12, 16 };
    gint i;

    frame_series_options_init(&options);
    options.channel = "Height";
    options.first_id = 9;
    options.last_id = 17;
    series = frame_series_load(&file, 1, &options, &error);
    ck_assert_msg(series != NULL, "%s", error ? error->message : "");
    ck_assert_int_eq(series->n_frames, 5);
    for (i = 0; i < 5; i++)
        ck_assert_int_eq(series->frames[i].channel_id, kept[i]);
    /* ScanRate 0.25 Hz from Height 10 on; stamps 17:42:59 and 17:51:30
     * taken as frame ends, 128 lines of 4 s each. */
    ck_assert(fabs(series->frames[1].timing.line_time - 4.0) < 1e-9);
    ck_assert(fabs(series->frames[2].timing.frame_start
                   - series->frames[1].timing.frame_start - 511.41) < 0.01);
    ck_assert_int_ge(series->notes->len, 4);
    frame_series_free(series);
    g_free(file);
}
END_TEST

START_TEST(test_options_override_and_refusals)
{
    gchar *file = data_path("hsafm-minicircles/hsafm_extra_frames14-62.gwy");
    gchar *missing = data_path("no-such-file.gwy");
    gdouble times[3] = { 0.0, 10.0, 20.0 };
    FrameSeriesOptions options;
    FrameSeries *series;
    GError *error = NULL;

    frame_series_options_init(&options);
    options.frame_times = times;
    options.n_frame_times = 3;
    series = frame_series_load(&file, 1, &options, &error);
    ck_assert(series == NULL);
    ck_assert_str_eq(error->message, "--frame-times gives 3 times for 7 frames");
    g_clear_error(&error);

    options.frame_times = NULL;
    options.line_time = 0.01;
    options.direction = SCAN_DIRECTION_UP;
    series = frame_series_load(&file, 1, &options, &error);
    ck_assert(series != NULL);
    ck_assert(series->frames[3].timing.line_time == 0.01);
    ck_assert_int_eq(series->frames[3].timing.direction, SCAN_DIRECTION_UP);
    frame_series_free(series);

    series = frame_series_load(&missing, 1, NULL, &error);
    ck_assert(series == NULL);
    ck_assert(g_str_has_prefix(error->message, missing));
    g_clear_error(&error);

    options.channel = "No such channel";
    options.line_time = -1.0;
    series = frame_series_load(&file, 1, &options, &error);
    ck_assert(series == NULL);
    ck_assert_int_eq(error->code, FRAME_SERIES_ERROR_CHANNEL);
    g_clear_error(&error);
    g_free(file);
    g_free(missing);
}
END_TEST

int
main(void)
{
    Suite *s = suite_create("frame-series");
    TCase *tc = tcase_create("measured");
    gchar *probe;
    SRunner *sr;
    gint failed;

    measured = g_getenv("LOCALSCAN_MEASURED_DIR");
    if (!measured)
        measured = TEST_SRCDIR "/../shared/data/measured";
    probe = g_build_filename(measured, "fastscan-series", "09261606.001", NULL);
    if (!g_file_test(probe, G_FILE_TEST_EXISTS)) {
        printf("SKIPPED: measured data absent (%s)\n", measured);
        g_free(probe);
        return 77;
    }
    g_free(probe);
    gwy_app_init_nongui("enable-threads", FALSE, NULL);
    tcase_add_test(tc, test_nanoscope_timing);
    tcase_add_test(tc, test_hsafm_channels_as_frames);
    tcase_add_test(tc, test_anasys_duplicates_dropped);
    tcase_add_test(tc, test_options_override_and_refusals);
    suite_add_tcase(s, tc);
    sr = srunner_create(s);
    srunner_run_all(sr, CK_NORMAL);
    failed = srunner_ntests_failed(sr);
    srunner_free(sr);
    return failed ? EXIT_FAILURE : EXIT_SUCCESS;
}
