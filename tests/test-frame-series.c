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
#include <stdio.h>
#include <glib/gstdio.h>
#include <check.h>
#include <libgwyddion/gwyddion.h>
#include <libgwymodule/gwymodule.h>
#include <app/gwyapp.h>
#include "frame-series-load.h"
#include "test-common.h"

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

/* The frames of one movie share a title but for a trailing number. */
START_TEST(test_title_base)
{
    static const gchar *const cases[][2] = {
        { "Height 12", "Height" }, { "HS-AFM sample_0 frame 3", "HS-AFM sample_0 frame" },
        { "Height", "Height" }, { "ZSensor2", "ZSensor2" }, { "12", "12" }, { "Height ", "Height " },
    };
    gchar *base;
    guint i;

    for (i = 0; i < G_N_ELEMENTS(cases); i++) {
        base = frame_series_title_base(cases[i][0]);
        ck_assert_str_eq(base, cases[i][1]);
        ck_assert(frame_series_title_matches(cases[i][0], base));
        g_free(base);
    }
    base = frame_series_title_base(NULL);
    ck_assert_str_eq(base, "");
    g_free(base);
    ck_assert(frame_series_title_matches("Height 7", "Height"));
    ck_assert(!frame_series_title_matches("Phase 7", "Height"));
    ck_assert(!frame_series_title_matches("Height (drift corrected)", "Height"));
}
END_TEST

START_TEST(test_hsafm_channels_as_frames)
{
    gchar *file = data_path("hsafm-minicircles/hsafm_sample0_frames50-140.gwy");
    FrameSeries *series;
    GError *error = NULL;

    FrameSeriesOptions options;
    guint i, notes;

    series = frame_series_load(&file, 1, NULL, &error);
    ck_assert_msg(series != NULL, "%s", error ? error->message : "");
    ck_assert_int_eq(series->n_frames, 7);
    ck_assert(fabs(series->frames[0].timing.line_time - 0.41263/256) < 1e-9);
    ck_assert(fabs(series->frames[1].timing.frame_start - 6.189) < 1e-9);
    ck_assert(fabs(series->frames[6].timing.frame_start - 37.135) < 0.01);
    /* The file gives the timing but not the direction: down, said. */
    ck_assert_int_eq(series->frames[3].timing.direction, SCAN_DIRECTION_DOWN);
    notes = series->notes->len;
    ck_assert_uint_ge(notes, 1);
    frame_series_free(series);
    /* The dialog's direction stands in where the metadata is silent, with
     * no note (it was ignored there: the frames stayed down). */
    frame_series_options_init(&options);
    options.fallback_direction = SCAN_DIRECTION_UP;
    series = frame_series_load(&file, 1, &options, &error);
    ck_assert_msg(series != NULL, "%s", error ? error->message : "");
    for (i = 0; i < 7; i++)
        ck_assert_int_eq(series->frames[i].timing.direction, SCAN_DIRECTION_UP);
    ck_assert(fabs(series->frames[1].timing.frame_start - 6.189) < 1e-9);
    ck_assert_uint_eq(series->notes->len, notes - 1);
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

/* A file whose frames carry no timing: the refusal tells the user what to
 * do in the words of the front end that asked (the dialog has no
 * --line-time). */
/* Channels 0 and 1 of data: two frames of 16 x 16 px alike but not
 * identical (identical ones are dropped), without metadata. */
static void
add_two_alike_frames(GwyContainer *data)
{
    gint k;

    for (k = 0; k < 2; k++) {
        GwyDataField *field = gwy_data_field_new(16, 16, 16e-9, 16e-9, TRUE);

        gwy_data_field_set_val(field, 3, 5, k*1e-9);
        gwy_container_set_object(data, gwy_app_get_data_key_for_id(k), field);
        g_object_unref(field);
    }
}

START_TEST(test_timing_hints_name_the_front_end)
{
    GwyContainer *data = gwy_container_new();
    gchar *name = g_strdup("frames.gwy");
    FrameSeriesOptions options;
    FrameSeries *series;
    GError *error = NULL;

    add_two_alike_frames(data);
    frame_series_options_init(&options);
    series = frame_series_from_files(&data, &name, 1, &options, &error);
    ck_assert(series == NULL);
    ck_assert_int_eq(error->code, FRAME_SERIES_ERROR_TIMING);
    ck_assert_msg(g_str_has_suffix(error->message, "the line time is not in the metadata; give --line-time"),
                  "%s", error->message);
    g_clear_error(&error);
    options.hints_for_dialog = TRUE;
    series = frame_series_from_files(&data, &name, 1, &options, &error);
    ck_assert(series == NULL);
    ck_assert_msg(g_str_has_suffix(error->message, "the line time is not in the metadata; set the line time"),
                  "%s", error->message);
    g_clear_error(&error);
    g_object_unref(data);
    g_free(name);
}
END_TEST

/* --frame-times gives a time to each frame as given: one channel of four
 * identical to an earlier one is dropped with its own time, and the
 * others keep theirs (the times were counted after the drop: 'gives 4
 * times for 3 frames'). */
START_TEST(test_frame_times_follow_dropped_duplicates)
{
    GwyContainer *data = gwy_container_new();
    gchar *name = g_strdup("frames.gwy");
    gdouble times[4] = { 0.0, 20.0, 40.0, 60.0 };
    static const gdouble kept[3] = { 0.0, 20.0, 60.0 };
    FrameSeriesOptions options;
    FrameSeries *series;
    GError *error = NULL;
    gint k;

    for (k = 0; k < 4; k++) {
        GwyDataField *field = gwy_data_field_new(16, 16, 16e-9, 16e-9, TRUE);

        /* Channel 2 the same as channel 0. */
        gwy_data_field_set_val(field, 3, 5, (k % 2 ? k : 0)*1e-9);
        gwy_container_set_object(data, gwy_app_get_data_key_for_id(k), field);
        g_object_unref(field);
    }
    frame_series_options_init(&options);
    options.line_time = 1.0;
    options.frame_times = times;
    options.n_frame_times = 4;
    series = frame_series_from_files(&data, &name, 1, &options, &error);
    ck_assert_msg(series != NULL, "%s", error ? error->message : "?");
    ck_assert_int_eq(series->n_frames, 3);
    for (k = 0; k < 3; k++)
        ck_assert_msg(series->frames[k].timing.frame_start == kept[k],
                      "frame %d starts at %g s, not %g s", k, series->frames[k].timing.frame_start, kept[k]);
    frame_series_free(series);
    options.n_frame_times = 3;
    series = frame_series_from_files(&data, &name, 1, &options, &error);
    ck_assert(series == NULL);
    ck_assert_str_eq(error->message, "--frame-times gives 3 times for 4 frames");
    g_clear_error(&error);
    g_object_unref(data);
    g_free(name);
}
END_TEST

/* A file of three 16-line frames whose metadata gives a line time of 1 ms
 * and these start times. */
static GwyContainer*
timed_frames(const gdouble *starts)
{
    GwyContainer *data = gwy_container_new();
    gchar value[40];
    gint k;

    for (k = 0; k < 3; k++) {
        GwyDataField *field = gwy_data_field_new(16, 16, 16e-9, 16e-9, TRUE);
        GwyContainer *meta = gwy_container_new();

        gwy_data_field_set_val(field, 3, 5, k*1e-9);
        gwy_container_set_object(data, gwy_app_get_data_key_for_id(k), field);
        gwy_container_set_const_string_by_name(meta, "Line time (s)", (const guchar*)"0.001");
        gwy_container_set_const_string_by_name(meta, "Slow scan", (const guchar*)"down");
        g_ascii_dtostr(value, sizeof(value), starts[k]);
        gwy_container_set_string_by_name(meta, "Frame start (s)", (const guchar*)g_strdup(value));
        gwy_container_set_object(data, gwy_app_get_data_meta_key_for_id(k), meta);
        g_object_unref(meta);
        g_object_unref(field);
    }
    return data;
}

/* A time lapse of 16 ms frames, 100 s apart, is one clock's (refused
 * before as 6000 frame times apart); frames stamped 0 s, 100 s and 1.7e9 s
 * (a relative time beside a date) are not, and are refused. */
START_TEST(test_one_clock)
{
    static const gdouble lapse[3] = { 0.0, 100.0, 200.0 }, mixed[3] = { 0.0, 100.0, 1.7e9 };
    GwyContainer *data = timed_frames(lapse);
    gchar *name = g_strdup("frames.gwy");
    FrameSeries *series;
    GError *error = NULL;

    series = frame_series_from_files(&data, &name, 1, NULL, &error);
    ck_assert_msg(series != NULL, "%s", error ? error->message : "?");
    ck_assert(series->frames[2].timing.frame_start == 200.0);
    frame_series_free(series);
    g_object_unref(data);
    data = timed_frames(mixed);
    series = frame_series_from_files(&data, &name, 1, NULL, &error);
    ck_assert(series == NULL);
    /* Untitled channels named by their ids. */
    ck_assert_msg(g_str_has_prefix(error->message, "frames.gwy channel 0 and frames.gwy channel 2 start")
                  && strstr(error->message, "cannot come from one clock"), "%s", error->message);
    g_clear_error(&error);
    g_object_unref(data);
    g_free(name);
}
END_TEST

/* --channels FIRST-LAST past the file's last channel: the frames there
 * are, and a note of the ids that do not exist; a range holding none of
 * them is refused naming the last channel there is. */
START_TEST(test_channel_range_beyond_the_file)
{
    static const gdouble starts[3] = { 0.0, 1.0, 2.0 };
    GwyContainer *data = timed_frames(starts);
    gchar *name = g_strdup("frames.gwy");
    FrameSeriesOptions options;
    FrameSeries *series;
    GError *error = NULL;
    gboolean noted = FALSE;
    guint i;

    frame_series_options_init(&options);
    options.first_id = 1;
    options.last_id = 9;
    series = frame_series_from_files(&data, &name, 1, &options, &error);
    ck_assert_msg(series != NULL, "%s", error ? error->message : "?");
    ck_assert_int_eq(series->n_frames, 2);
    for (i = 0; i < series->notes->len; i++)
        noted |= g_str_equal(g_ptr_array_index(series->notes, i),
                             "frames.gwy: channels 3-9 of the range 1-9 do not exist");
    ck_assert_msg(noted, "no note of channels 3-9");
    frame_series_free(series);
    options.first_id = 5;
    series = frame_series_from_files(&data, &name, 1, &options, &error);
    ck_assert(series == NULL);
    ck_assert_str_eq(error->message, "frames.gwy: no channel 5-9 (its last channel is 2)");
    g_clear_error(&error);
    g_object_unref(data);
    g_free(name);
}
END_TEST

/* Channels of one file taken as frames with nothing chosen, under titles
 * of different signals (Height and Amplitude in the same unit): loaded,
 * with a note naming the titles; a movie's "Height", "Height 1", ...
 * or untitled channels get none, nor does a choice by title or range. */
START_TEST(test_mixed_titles_noted)
{
    static const gdouble starts[3] = { 0.0, 1.0, 2.0 };
    static const gchar *const mixed[3] = { "Height", "Amplitude", "Height 2" };
    static const gchar *const movie[3] = { "Height", "Height 1", "Height 2" };
    GwyContainer *data = timed_frames(starts);
    gchar *name = g_strdup("frames.gwy");
    FrameSeriesOptions options;
    FrameSeries *series;
    GError *error = NULL;
    gint k;

    series = frame_series_from_files(&data, &name, 1, NULL, &error);
    ck_assert_msg(series != NULL, "%s", error ? error->message : "?");
    ck_assert(!test_strings_hold(series->notes, "different titles"));
    frame_series_free(series);
    for (k = 0; k < 3; k++)
        gwy_container_set_const_string(data, gwy_app_get_data_title_key_for_id(k),
                                       (const guchar*)mixed[k]);
    series = frame_series_from_files(&data, &name, 1, NULL, &error);
    ck_assert_msg(series != NULL, "%s", error ? error->message : "?");
    ck_assert_int_eq(series->n_frames, 3);
    ck_assert_msg(test_strings_hold(series->notes, "frames.gwy: the frames are channels of 2 different titles "
                        "('Height', 'Amplitude'), taken as one series in channel order"),
                  "no note of the mixed titles");
    frame_series_free(series);
    frame_series_options_init(&options);
    options.first_id = 0;
    options.last_id = 2;
    series = frame_series_from_files(&data, &name, 1, &options, &error);
    ck_assert_msg(series != NULL, "%s", error ? error->message : "?");
    ck_assert(!test_strings_hold(series->notes, "different titles"));
    frame_series_free(series);
    for (k = 0; k < 3; k++)
        gwy_container_set_const_string(data, gwy_app_get_data_title_key_for_id(k),
                                       (const guchar*)movie[k]);
    series = frame_series_from_files(&data, &name, 1, NULL, &error);
    ck_assert_msg(series != NULL, "%s", error ? error->message : "?");
    ck_assert(!test_strings_hold(series->notes, "different titles"));
    frame_series_free(series);
    g_object_unref(data);
    g_free(name);
}
END_TEST

/* Too few frames: the refusal says where the others went, channels of
 * another size passed over and bit-identical frames dropped. */
START_TEST(test_too_few_frames_said_why)
{
    static const gdouble starts[3] = { 0.0, 1.0, 2.0 };
    GwyContainer *data = timed_frames(starts);
    GwyDataField *other = gwy_data_field_new(32, 32, 32e-9, 32e-9, TRUE);
    gchar *name = g_strdup("frames.gwy");
    FrameSeries *series;
    GError *error = NULL;

    gwy_container_set_object(data, gwy_app_get_data_key_for_id(1), other);
    gwy_container_set_object(data, gwy_app_get_data_key_for_id(2), other);
    series = frame_series_from_files(&data, &name, 1, NULL, &error);
    ck_assert(series == NULL);
    ck_assert_str_eq(error->message, "frames.gwy: a series needs at least two distinct frames, "
                     "found 1; 2 channels were passed over (another size, pixel size or unit "
                     "than the first): choose the frames by title or id");
    g_clear_error(&error);
    g_object_unref(data);
    data = timed_frames(starts);
    gwy_container_set_object(data, gwy_app_get_data_key_for_id(1),
                             gwy_container_get_object(data, gwy_app_get_data_key_for_id(0)));
    gwy_container_set_object(data, gwy_app_get_data_key_for_id(2), other);
    series = frame_series_from_files(&data, &name, 1, NULL, &error);
    ck_assert(series == NULL);
    ck_assert_str_eq(error->message, "frames.gwy: a series needs at least two distinct frames, "
                     "found 1; 1 channel was passed over (another size, pixel size or unit "
                     "than the first); 1 frame was dropped as a duplicate: choose the frames "
                     "by title or id");
    g_clear_error(&error);
    g_object_unref(other);
    g_object_unref(data);
    g_free(name);
}
END_TEST

/* One file's channels that start at the same moment are signals of one
 * scan (a FastScan file's ZSensor, AmplitudeActual and Phase): refused as
 * such, where 'not in time order' said nothing of why; frames of separate
 * files stamped alike stay 'not in time order'. */
START_TEST(test_channels_of_one_scan_refused)
{
    static const gdouble together[3] = { 5.0, 5.0, 5.0 };
    GwyContainer *data = timed_frames(together), *datas[2];
    gchar *names[2] = { g_strdup("scan.gwy"), g_strdup("again.gwy") };
    FrameSeriesOptions options;
    FrameSeries *series;
    GError *error = NULL;

    series = frame_series_from_files(&data, names, 1, NULL, &error);
    ck_assert(series == NULL);
    ck_assert_msg(g_str_has_suffix(error->message, " were scanned at the same time: they are "
                                   "channels of one scan, not frames of a series; choose the "
                                   "frames by title or id"), "%s", error->message);
    g_clear_error(&error);
    frame_series_options_init(&options);
    options.channel_ids = (const gint[]){ 0 };
    options.n_channel_ids = 1;
    datas[0] = data;
    datas[1] = timed_frames(together);
    gwy_data_field_set_val(gwy_container_get_object(datas[1], gwy_app_get_data_key_for_id(0)),
                           1, 1, 1e-9);
    series = frame_series_from_files(datas, names, 2, &options, &error);
    ck_assert(series == NULL);
    ck_assert_msg(strstr(error->message, "frames must be in time order"), "%s", error->message);
    g_clear_error(&error);
    g_object_unref(datas[1]);
    g_object_unref(data);
    g_free(names[0]);
    g_free(names[1]);
}
END_TEST

/************************************************************************
 * simscan's own files: timing from simscan's metadata keys
 ************************************************************************/

#define SIMSCAN_PATH TEST_BUILDDIR "/simscan/simscan"
#define SIMSCAN_FRAMES 3
#define SIMSCAN_CROP 100
#define SIMSCAN_FRAME_PERIOD 200.0
/* Registration of whole-pixel shifts: within a few percent of the
 * velocity (one frame's shift is 1-3 px, 39 nm each). */
#define SIMSCAN_VELOCITY_TOLERANCE 0.05

static guint32 test_seed;

static gboolean
spawn(const gchar *const *argv, gchar **out, gchar **err)
{
    gint status = -1;

    ck_assert(g_spawn_sync(NULL, (gchar**)argv, NULL, G_SPAWN_DEFAULT, NULL, NULL, out, err, &status, NULL));
    return g_spawn_check_exit_status(status, NULL);
}

/* Frames k = 0, 1, ... of simscan's image, each cropped k*shift px further
 * on and started k*SIMSCAN_FRAME_PERIOD s later, with simscan's metadata
 * (line time, slow scan, frame start) and nothing else timing them. */
static void
write_simscan_frames(const gchar *dir, const gchar *simulated, const gint *shift, gchar **files)
{
    GwyContainer *data = gwy_file_load(simulated, GWY_RUN_NONINTERACTIVE, NULL), *frame, *meta;
    GwyDataField *field, *crop;
    gchar start[G_ASCII_DTOSTR_BUF_SIZE];
    gint k;

    ck_assert(data);
    field = gwy_container_get_object_by_name(data, "/0/data");
    for (k = 0; k < SIMSCAN_FRAMES; k++) {
        crop = gwy_data_field_area_extract(field, k*shift[0] + 8, k*shift[1] + 8, SIMSCAN_CROP, SIMSCAN_CROP);
        meta = gwy_container_duplicate(gwy_container_get_object_by_name(data, "/0/meta"));
        g_ascii_dtostr(start, sizeof(start), k*SIMSCAN_FRAME_PERIOD);
        gwy_container_set_const_string_by_name(meta, "Frame start (s)", (const guchar*)start);
        frame = gwy_container_new();
        gwy_container_set_object_by_name(frame, "/0/data", crop);
        gwy_container_set_object_by_name(frame, "/0/meta", meta);
        files[k] = g_strdup_printf("%s/frame%d.gwy", dir, k);
        ck_assert(gwy_file_save(frame, files[k], GWY_RUN_NONINTERACTIVE, NULL));
        g_object_unref(frame);
        g_object_unref(meta);
        g_object_unref(crop);
    }
    files[k] = NULL;
    g_object_unref(data);
}

/* simscan fit on frames simscan wrote needs no timing option: the velocity
 * it finds is the frames' hidden shift over their metadata frame starts. */
START_TEST(test_simscan_fit_reads_simscan_timing)
{
    guint32 seed = test_seed;
    GRand *rng = g_rand_new_with_seed(seed);
    gchar *dir = g_dir_make_tmp("test-frame-series-XXXXXX", NULL);
    gchar *simulated = g_build_filename(dir, "simulated.gwy", NULL), *seedarg = g_strdup_printf("%u", seed);
    gchar *files[SIMSCAN_FRAMES + 1], *out = NULL, *err = NULL, *v;
    const gchar *make[] = { SIMSCAN_PATH, "-q", "--xres", "128", "--yres", "128", "--seed", seedarg,
                            "-o", simulated, NULL };
    const gchar *fit[SIMSCAN_FRAMES + 3] = { SIMSCAN_PATH, "fit", };
    gint shift[2], k;
    gdouble vx, vy, want[2], dx;

    /* Crops start 8 px in and move right and down (up to 16 px). */
    shift[0] = g_rand_int_range(rng, 1, 4);
    shift[1] = g_rand_int_range(rng, 0, 3);
    printf("test-frame-series: simscan seed %u (LOCALSCAN_TEST_SEED), frames %d, %d px apart\n",
           seed, shift[0], shift[1]);
    ck_assert(dir);
    ck_assert_msg(spawn(make, &out, &err), "simscan failed: %s", err);
    g_free(out);
    g_free(err);
    write_simscan_frames(dir, simulated, shift, files);
    for (k = 0; k < SIMSCAN_FRAMES; k++)
        fit[k+2] = files[k];
    ck_assert_msg(spawn(fit, &out, &err), "simscan fit without timing options failed: %s", err);
    ck_assert_msg((v = strstr(out, "\"velocity_nm_per_s\"")), "no velocity in %s", out);
    ck_assert(sscanf(strchr(v, '[') + 1, "%lf , %lf", &vx, &vy) == 2);

    /* A feature at X shows at X - k*shift in crop k: drift -shift per frame. */
    dx = 5000.0/128;
    want[0] = -shift[0]*dx/SIMSCAN_FRAME_PERIOD;
    want[1] = -shift[1]*dx/SIMSCAN_FRAME_PERIOD;
    printf("test-frame-series: velocity %g, %g nm/s, hidden %g, %g nm/s\n", vx, vy, want[0], want[1]);
    ck_assert(fabs(vx - want[0]) <= SIMSCAN_VELOCITY_TOLERANCE*fabs(want[0]) + 0.005);
    ck_assert(fabs(vy - want[1]) <= SIMSCAN_VELOCITY_TOLERANCE*fabs(want[0]) + 0.005);

    for (k = 0; k < SIMSCAN_FRAMES; k++) {
        g_unlink(files[k]);
        g_free(files[k]);
    }
    g_unlink(simulated);
    g_rmdir(dir);
    g_free(out);
    g_free(err);
    g_free(seedarg);
    g_free(simulated);
    g_free(dir);
    g_rand_free(rng);
}
END_TEST

/* Two frames whose second has a line time (or a start) key with a value
 * no instrument gives: the refusal names the key and its value, cut
 * short and made valid UTF-8, instead of "not in the metadata". */
static void
check_unusable_meta(const gchar *key, const gchar *value, const gchar *usable,
                    const gchar *other_key, const gchar *other_value, const gchar *expected)
{
    GwyContainer *data = gwy_container_new();
    gchar *name = g_strdup("frames.gwy"), *wanted;
    FrameSeriesOptions options;
    FrameSeries *series;
    GError *error = NULL;
    gint k;

    add_two_alike_frames(data);
    for (k = 0; k < 2; k++) {
        GwyContainer *meta = gwy_container_new();
        gchar metakey[32];

        gwy_container_set_const_string_by_name(meta, other_key, (const guchar*)other_value);
        gwy_container_set_const_string_by_name(meta, key, (const guchar*)(k ? value : usable));
        g_snprintf(metakey, sizeof(metakey), "/%d/meta", k);
        gwy_container_set_object_by_name(data, metakey, meta);
        g_object_unref(meta);
    }
    frame_series_options_init(&options);
    series = frame_series_from_files(&data, &name, 1, &options, &error);
    ck_assert(series == NULL);
    ck_assert_int_eq(error->code, FRAME_SERIES_ERROR_TIMING);
    wanted = g_strdup_printf("frames.gwy channel 1: %s", expected);
    ck_assert_msg(g_str_equal(error->message, wanted), "'%s', expected '%s'", error->message, wanted);
    ck_assert(g_utf8_validate(error->message, -1, NULL));
    g_clear_error(&error);
    g_free(wanted);
    g_object_unref(data);
    g_free(name);
}

START_TEST(test_unusable_timing_named)
{
    /* A start may be any number (its clock's), a line time not. */
    static const gchar *const bad_line_times[] = { "nan", "-0.01", "1e300", "10 parsecs", "inf s" };
    static const gchar *const bad_starts[] = { "nan", "-inf", "10 parsecs", "12 o'clock" };
    GRand *rng = test_rand_salted(test_seed, 7);
    const gchar *bad = bad_line_times[g_rand_int_range(rng, 0, G_N_ELEMENTS(bad_line_times))];
    GString *junk = g_string_new(NULL);
    gchar *expected;
    gint i;

    expected = g_strdup_printf("the metadata gives no usable line time ('Line time (s)' is '%s'); "
                               "give --line-time", bad);
    check_unusable_meta("Line time (s)", bad, "0.01", "Frame start (s)", "0", expected);
    g_free(expected);
    bad = bad_starts[g_rand_int_range(rng, 0, G_N_ELEMENTS(bad_starts))];
    expected = g_strdup_printf("the metadata gives no usable start time of the frame ('Frame start (s)' is "
                               "'%s'); give --frame-times", bad);
    check_unusable_meta("Frame start (s)", bad, "0", "Line time (s)", "0.01", expected);
    g_free(expected);
    /* Bytes no UTF-8 text holds (0xf8-0xff), far more than a message
     * shows: 40 characters shown, each byte as U+FFFD. */
    for (i = 0; i < 300; i++)
        g_string_append_c(junk, (gchar)g_rand_int_range(rng, 0xf8, 0x100));
    check_unusable_meta("Line time (s)", junk->str, "0.01", "Frame start (s)", "0",
                        "the metadata gives no usable line time ('Line time (s)' is "
                        "'\xef\xbf\xbd\xef\xbf\xbd\xef\xbf\xbd\xef\xbf\xbd\xef\xbf\xbd"
                        "\xef\xbf\xbd\xef\xbf\xbd\xef\xbf\xbd\xef\xbf\xbd\xef\xbf\xbd"
                        "\xef\xbf\xbd\xef\xbf\xbd\xef\xbf\xbd\xef\xbf\xbd\xef\xbf\xbd"
                        "\xef\xbf\xbd\xef\xbf\xbd\xef\xbf\xbd\xef\xbf\xbd\xef\xbf\xbd"
                        "\xef\xbf\xbd\xef\xbf\xbd\xef\xbf\xbd\xef\xbf\xbd\xef\xbf\xbd"
                        "\xef\xbf\xbd\xef\xbf\xbd\xef\xbf\xbd\xef\xbf\xbd\xef\xbf\xbd"
                        "\xef\xbf\xbd\xef\xbf\xbd\xef\xbf\xbd\xef\xbf\xbd\xef\xbf\xbd"
                        "\xef\xbf\xbd\xef\xbf\xbd\xef\xbf\xbd\xef\xbf\xbd\xef\xbf\xbd...'); "
                        "give --line-time");
    g_string_free(junk, TRUE);
    g_rand_free(rng);
}
END_TEST

int
main(void)
{
    TCase *tc, *tc_simscan;
    Suite *s = test_suite_new("frame-series", "simscan", &tc_simscan);
    gchar *probe;

    test_seed = test_seed_from_env("test-frame-series");
    measured = test_measured_dir();
    probe = test_measured_file("test-frame-series",
                               "fastscan-series/09261606.001",
                               "the measured-file tests");
    gwy_app_init_nongui("enable-threads", FALSE, NULL);
    tcase_set_timeout(tc_simscan, 120);
    tcase_add_test(tc_simscan, test_simscan_fit_reads_simscan_timing);
    tcase_add_test(tc_simscan, test_title_base);
    tcase_add_test(tc_simscan, test_timing_hints_name_the_front_end);
    tcase_add_test(tc_simscan, test_unusable_timing_named);
    tcase_add_test(tc_simscan, test_frame_times_follow_dropped_duplicates);
    tcase_add_test(tc_simscan, test_one_clock);
    tcase_add_test(tc_simscan, test_channel_range_beyond_the_file);
    tcase_add_test(tc_simscan, test_mixed_titles_noted);
    tcase_add_test(tc_simscan, test_too_few_frames_said_why);
    tcase_add_test(tc_simscan, test_channels_of_one_scan_refused);
    if (probe) {
        tc = tcase_create("measured");
        tcase_add_test(tc, test_nanoscope_timing);
        tcase_add_test(tc, test_hsafm_channels_as_frames);
        tcase_add_test(tc, test_anasys_duplicates_dropped);
        tcase_add_test(tc, test_options_override_and_refusals);
        suite_add_tcase(s, tc);
    }
    g_free(probe);
    return test_run_suite(s);
}
