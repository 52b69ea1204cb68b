/*
 *  The peers' methods on the cases of `simscan benchmark`, writing results
 *  `simscan score` reads (docs/benchmark.md):
 *  - rigid: each frame shifted as a whole by FFT phase correlation against
 *    the one before, shifts accumulated (rigid-baseline.h), as unDrift-like
 *    tools and most users do; the trajectory is the frame's shift on every
 *    line, the corrected frames are the shifted frames;
 *  - gwyddion-drift: Gwyddion's own Compensate Drift run on every frame
 *    (its line-by-line x drift within the frame, gwyddion-drift-baseline.h)
 *    on top of the rigid shifts, as a Gwyddion user would combine them;
 *    trajectory only.
 *  Frames are loaded by the product's own loader; missing pixels are
 *  filled with the frame's mean and every frame is plane-levelled first,
 *  as a user prepares frames for these tools.
 *
 *    bench/benchmark-baselines CASES_DIR RESULTS_DIR
 *
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <stdio.h>
#include <string.h>
#include <math.h>
#include <glib/gstdio.h>
#include <json-glib/json-glib.h>
#include <libgwyddion/gwyddion.h>
#include <libprocess/gwyprocess.h>
#include <app/gwyapp.h>
#include "frame-series.h"
#include "frame-series-load.h"
#include "missing-data.h"
#include "paper-compensate.h"
#include "output-files.h"
#include "trajectory-csv.h"
#include "gwy-stream-save.h"
#include "rigid-baseline.h"
#include "gwyddion-drift-baseline.h"

static gchar**
case_names(const gchar *cases_dir)
{
    gchar *path = g_build_filename(cases_dir, "benchmark.json", NULL);
    JsonParser *parser = json_parser_new();
    gchar **names = NULL;
    JsonArray *a;
    guint i;

    if (json_parser_load_from_file(parser, path, NULL)
        && JSON_NODE_HOLDS_OBJECT(json_parser_get_root(parser))) {
        a = json_object_get_array_member(json_node_get_object(json_parser_get_root(parser)),
                                         "cases");
        names = g_new0(gchar*, json_array_get_length(a) + 1);
        for (i = 0; i < json_array_get_length(a); i++)
            names[i] = g_strdup(json_array_get_string_element(a, i));
    }
    g_object_unref(parser);
    g_free(path);
    return names;
}

static FrameSeries*
load_case(const gchar *case_dir)
{
    GPtrArray *files = g_ptr_array_new_with_free_func(g_free);
    FrameSeriesOptions options;
    FrameSeries *series;
    GError *error = NULL;
    gchar *path;
    gint k;

    for (k = 0; ; k++) {
        gchar *name = g_strdup_printf("frame-%03d.gwy", k);

        path = g_build_filename(case_dir, name, NULL);
        g_free(name);
        if (!g_file_test(path, G_FILE_TEST_IS_REGULAR)) {
            g_free(path);
            break;
        }
        g_ptr_array_add(files, path);
    }
    frame_series_options_init(&options);
    series = frame_series_load((gchar**)files->pdata, files->len, &options,
                               &error);
    if (!series) {
        fprintf(stderr, "benchmark-baselines: %s: %s\n", case_dir,
                error->message);
        g_clear_error(&error);
    }
    g_ptr_array_free(files, TRUE);
    return series;
}

/* What a user hands a rigid tool: no missing pixels, no plane. */
static void
prepare_frames(FrameSeries *series)
{
    gdouble a, bx, by, *d;
    gint k, xres, yres;

    for (k = 0; k < series->n_frames; k++) {
        GwyDataField *field = series->frames[k].field;

        xres = gwy_data_field_get_xres(field);
        yres = gwy_data_field_get_yres(field);
        d = gwy_data_field_get_data(field);
        if (missing_data_count(d, (gsize)xres*yres)) {
            gdouble *filled = missing_data_filled_copy(d, (gsize)xres*yres,
                                                       paper_image_mean(d, xres, yres));

            memcpy(d, filled, (gsize)xres*yres*sizeof(gdouble));
            g_free(filled);
        }
        gwy_data_field_invalidate(field);
        gwy_data_field_fit_plane(field, &a, &bx, &by);
        gwy_data_field_plane_level(field, a, bx, by);
    }
}

static gboolean
write_text(const gchar *dir, const gchar *name, GString *text)
{
    gchar *path = g_build_filename(dir, name, NULL);
    GError *error = NULL;
    gboolean ok = output_files_write_one(path, (const guchar*)text->str,
                                         text->len, &error);

    if (!ok) {
        fprintf(stderr, "benchmark-baselines: %s\n", error->message);
        g_clear_error(&error);
    }
    g_free(path);
    return ok;
}


/* The trajectory of per-frame shifts plus, when row_dx is given, each
 * frame's own line-by-line x drift (frame k's rows at row_dx + k*yres). */
static GString*
trajectory_text(const FrameSeries *series, const gdouble *dx,
                const gdouble *dy, const gdouble *row_dx)
{
    GString *text = g_string_new(NULL);
    gint k, r, yres;
    gdouble t, own, first = 0.0;

    trajectory_csv_begin(text, "drift trajectory",
                         frame_series_dx(series), frame_series_dy(series));
    for (k = 0; k < series->n_frames; k++) {
        const ScanTiming *timing = &series->frames[k].timing;

        yres = timing->yres;
        for (r = 0; r < yres; r++) {
            t = scan_timing_rows_time(timing, r, r+1);
            own = row_dx ? row_dx[k*yres + r] : 0.0;
            if (k == 0 && r == 0)
                first = own;
            trajectory_csv_line(text, k, r, t, dx[k] + own - first, dy[k], 4);
        }
    }
    return text;
}

/* Pixels whose source lies outside the frame once shifted. */
static GwyDataField*
shift_mask(GwyDataField *frame, gdouble dx, gdouble dy)
{
    GwyDataField *mask = gwy_data_field_new_alike(frame, TRUE);
    gint xres = gwy_data_field_get_xres(frame);
    gint yres = gwy_data_field_get_yres(frame), r, c;
    gdouble *m = gwy_data_field_get_data(mask);

    for (r = 0; r < yres; r++) {
        for (c = 0; c < xres; c++) {
            if (c + dx < 0.0 || c + dx > xres - 1 || r + dy < 0.0
                || r + dy > yres - 1)
                m[r*xres + c] = 1.0;
        }
    }
    return mask;
}

static gboolean
write_rigid_frames(const FrameSeries *series, const gdouble *dx,
                   const gdouble *dy, const gchar *dir)
{
    GwyContainer *data = gwy_container_new();
    gchar *path = g_build_filename(dir, "corrected.gwy", NULL);
    GError *error = NULL;
    gboolean ok;
    gint k;

    for (k = 0; k < series->n_frames; k++) {
        GwyDataField *frame = series->frames[k].field;
        GwyDataField *fixed = gwy_data_field_new_alike(frame, FALSE);
        GwyDataField *mask = shift_mask(frame, dx[k], dy[k]);

        rigid_baseline_correct(frame, dx[k], dy[k], fixed);
        gwy_container_set_object(data, gwy_app_get_data_key_for_id(k), fixed);
        gwy_container_set_object(data, gwy_app_get_mask_key_for_id(k), mask);
        g_object_unref(fixed);
        g_object_unref(mask);
    }
    ok = gwy_stream_save(data, path, &error);
    if (!ok) {
        fprintf(stderr, "benchmark-baselines: %s\n", error->message);
        g_clear_error(&error);
    }
    g_object_unref(data);
    g_free(path);
    return ok;
}

static gchar*
method_dir(const gchar *results, const gchar *method, const gchar *name)
{
    gchar *dir = g_build_filename(results, method, name, NULL);

    g_mkdir_with_parents(dir, 0777);
    return dir;
}

static gboolean
run_gwyddion_drift(const FrameSeries *series, const gdouble *dx,
                   const gdouble *dy, const gchar *dir, gdouble *seconds)
{
    gint k, xres = series->frames[0].timing.xres;
    gint yres = series->frames[0].timing.yres;
    gdouble *row_dx = g_new(gdouble, series->n_frames*yres), s;
    gboolean ok = TRUE;
    GString *text;

    *seconds = 0.0;
    for (k = 0; k < series->n_frames && ok; k++) {
        ok = gwyddion_drift_estimate(gwy_data_field_get_data_const(series->frames[k].field),
                                     xres, yres, row_dx + k*yres, &s);
        *seconds += s;
    }
    if (ok) {
        text = trajectory_text(series, dx, dy, row_dx);
        ok = write_text(dir, "trajectory.csv", text);
        g_string_free(text, TRUE);
    }
    g_free(row_dx);
    return ok;
}

static gboolean
run_case(const gchar *cases_dir, const gchar *results, const gchar *name)
{
    gchar *case_dir = g_build_filename(cases_dir, name, NULL), *dir;
    FrameSeries *series = load_case(case_dir);
    gdouble *dx, *dy, seconds = 0.0;
    GTimer *timer;
    GString *text;
    gboolean ok;

    g_free(case_dir);
    if (!series)
        return FALSE;
    prepare_frames(series);
    dx = g_new(gdouble, 2*series->n_frames);
    dy = dx + series->n_frames;
    timer = g_timer_new();
    rigid_baseline_shifts(series, dx, dy);
    printf("%s: rigid %.3f s", name, g_timer_elapsed(timer, NULL));
    dir = method_dir(results, "rigid", name);
    text = trajectory_text(series, dx, dy, NULL);
    ok = write_text(dir, "trajectory.csv", text)
         && write_rigid_frames(series, dx, dy, dir);
    g_string_free(text, TRUE);
    g_free(dir);
    dir = method_dir(results, "gwyddion-drift", name);
    ok = ok && run_gwyddion_drift(series, dx, dy, dir, &seconds);
    printf(", gwyddion-drift %.3f s\n", seconds);
    g_free(dir);
    g_timer_destroy(timer);
    g_free(dx);
    frame_series_free(series);
    return ok;
}

int
main(int argc, char **argv)
{
    gchar **names;
    gboolean ok = TRUE;
    gint i;

    if (argc != 3) {
        fprintf(stderr, "usage: %s CASES_DIR RESULTS_DIR\n", argv[0]);
        return 2;
    }
    if (!gwyddion_drift_init())
        return 1;
    if (!(names = case_names(argv[1]))) {
        fprintf(stderr, "benchmark-baselines: %s: no benchmark.json\n",
                argv[1]);
        return 1;
    }
    for (i = 0; names[i]; i++)
        ok = run_case(argv[1], argv[2], names[i]) && ok;
    g_strfreev(names);
    gwyddion_drift_finish();
    return ok ? 0 : 1;
}
