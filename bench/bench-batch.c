/*
 *  End-to-end benchmark of gwy-localscan on a 4096 x 4096 channel: the
 *  whole command (load, compensate, save) against a memcpy of the channel's
 *  data, and its peak memory against the channel's size, in paper and
 *  continuous mode; and the dialog's work per change of a setting (the
 *  preview on its reduced copy, modules/core/preview-field.c) against the
 *  same memcpy; and the floor no such run can go below here: the tool's
 *  start-up and the file traffic of reading the input and writing the
 *  output.  All measured in one run.
 *  Run from the build folder (make bench): it runs ./tools/gwy-localscan
 *  with the module modules/.libs/localscan.so ($LOCALSCAN_MODULE wins) and
 *  HOME in a scratch folder.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <sys/wait.h>
#include <sys/resource.h>
#include <glib/gstdio.h>
#include <libgwyddion/gwyddion.h>
#include <libprocess/gwyprocess.h>
#include <libgwymodule/gwymodule-file.h>
#include <app/gwyapp.h>
#include "localscan-channel.h"
#include "localscan-params.h"
#include "preview-field.h"
#include "stripe-registration.h"

enum {
    RES = 4096,
    N_STRIPES = 16,
    MEMCPY_REPETITIONS = 7,
    RUN_REPETITIONS = 3,
    PREVIEW_REPETITIONS = 5,
};

#define TOOL "./tools/gwy-localscan"
#define MODULE "modules/.libs/localscan.so"

static gdouble
best_of(const gdouble *seconds, gint n)
{
    gdouble best = seconds[0];
    gint i;

    for (i = 1; i < n; i++)
        best = MIN(best, seconds[i]);
    return best;
}

static gdouble
time_memcpy(const gdouble *a, gdouble *b, gsize n)
{
    gdouble seconds[MEMCPY_REPETITIONS];
    gint64 start;
    gint i;

    for (i = 0; i < MEMCPY_REPETITIONS; i++) {
        start = g_get_monotonic_time();
        memcpy(b, a, n*sizeof(gdouble));
        seconds[i] = (g_get_monotonic_time() - start)/1e6;
    }
    return best_of(seconds, MEMCPY_REPETITIONS);
}

/* A rough surface and a slowly growing drift of fractional pixels, which
 * both modes accept (paper mode rounds the stored physical values). */
static GwyContainer*
make_input(gint res)
{
    GwyDataField *field = gwy_data_field_new(res, res, res*1e-9, res*1e-9, FALSE);
    GwyContainer *data = gwy_container_new();
    DriftTable *table = drift_table_new(N_STRIPES, DRIFT_UNIT_NM);
    GRand *rng = g_rand_new_with_seed(1);
    gdouble *d = gwy_data_field_get_data(field);
    gint i, s;

    for (i = 0; i < res*res; i++)
        d[i] = g_rand_double(rng)*1e-9;
    gwy_si_unit_set_from_string(gwy_data_field_get_si_unit_xy(field), "m");
    gwy_si_unit_set_from_string(gwy_data_field_get_si_unit_z(field), "m");
    gwy_container_set_object_by_name(data, "/0/data", field);
    gwy_container_set_const_string_by_name(data, "/0/data/title", (const guchar*)"Height");
    for (s = 0; s < N_STRIPES; s++) {
        table->rows[s].has_drift = TRUE;
        table->rows[s].dx = -0.37*s;
        table->rows[s].dy = 0.21*s;
    }
    localscan_channel_store_table(data, 0, table);
    drift_table_free(table);
    g_object_unref(field);
    g_rand_free(rng);
    return data;
}

/* Wall time, peak resident memory (bytes) and output size (bytes) of one
 * run of the tool. */
static gboolean
run_tool(const gchar *mode, const gchar *input, const gchar *output, gdouble *seconds,
         gsize *peak, gsize *output_bytes)
{
    GStatBuf st;
    gchar *argv[] = { TOOL, "-m", (gchar*)mode, "-o", (gchar*)output, (gchar*)input, NULL };
    struct rusage usage;
    gint64 start = g_get_monotonic_time();
    gint status;
    pid_t pid;

    if ((pid = fork()) == 0) {
        execv(TOOL, argv);
        _exit(127);
    }
    if (pid < 0 || wait4(pid, &status, 0, &usage) != pid)
        return FALSE;
    *seconds = (g_get_monotonic_time() - start)/1e6;
    *peak = (gsize)usage.ru_maxrss*1024;
    *output_bytes = (g_stat(output, &st) == 0) ? (gsize)st.st_size : 0;
    g_unlink(output);
    return WIFEXITED(status) && WEXITSTATUS(status) == 0;
}

static gboolean
bench_mode(const gchar *mode, const gchar *input, const gchar *output, gdouble memcpy_seconds,
           gsize *output_bytes)
{
    gdouble seconds[RUN_REPETITIONS];
    gsize peak = 0, channel = (gsize)RES*RES*sizeof(gdouble), one;
    gint i;

    for (i = 0; i < RUN_REPETITIONS; i++) {
        if (!run_tool(mode, input, output, seconds + i, &one, output_bytes)) {
            fprintf(stderr, "bench-batch: %s -m %s failed\n", TOOL, mode);
            return FALSE;
        }
        peak = MAX(peak, one);
    }
    printf("gwy-localscan -m %-10s end to end best %6.3f s = %5.1f x memcpy (target 15 x); "
           "peak RSS %6.0f MiB = %4.2f x the channel (target 3 x)\n",
           mode, best_of(seconds, RUN_REPETITIONS), best_of(seconds, RUN_REPETITIONS)/memcpy_seconds,
           peak/1048576.0, (gdouble)peak/channel);
    return TRUE;
}

/* Reading the input file and writing output_bytes to a new file, as fast
 * as the system does it (the file's own bytes, again and again, through
 * 1 MiB writes): what any tool that reads this input and writes this
 * output pays, whatever it computes. */
static gdouble
time_file_io(const gchar *input, gsize output_bytes, const gchar *scratch)
{
    gdouble seconds[RUN_REPETITIONS];
    gint i;

    for (i = 0; i < RUN_REPETITIONS; i++) {
        gint64 start = g_get_monotonic_time();
        gchar *contents = NULL;
        gsize length = 0, written = 0, chunk;
        FILE *fh;

        if (!g_file_get_contents(input, &contents, &length, NULL) || !length
            || !(fh = g_fopen(scratch, "wb")))
            return 0.0;
        while (written < output_bytes) {
            chunk = MIN(MIN(output_bytes - written, (gsize)1 << 20), length);
            if (fwrite(contents, 1, chunk, fh) != chunk)
                break;
            written += chunk;
        }
        fclose(fh);
        seconds[i] = (g_get_monotonic_time() - start)/1e6;
        g_unlink(scratch);
        g_free(contents);
    }
    return best_of(seconds, RUN_REPETITIONS);
}

/* What the end-to-end target cannot go below on this machine: the tool's
 * start-up (Gwyddion's module registry, loading and saving a 64 x 64
 * image) and the file traffic of the 4096 x 4096 run. */
static void
bench_floor(const gchar *dir, const gchar *input, const gchar *output, gsize output_bytes,
            gdouble memcpy_seconds)
{
    gchar *tiny = g_build_filename(dir, "tiny.gwy", NULL);
    GwyContainer *data = make_input(64);
    gdouble seconds[RUN_REPETITIONS], startup, io;
    gsize peak, bytes;
    gint i;

    if (!gwy_file_save(data, tiny, GWY_RUN_NONINTERACTIVE, NULL)) {
        fprintf(stderr, "bench-batch: cannot write %s\n", tiny);
        g_object_unref(data);
        g_free(tiny);
        return;
    }
    for (i = 0; i < RUN_REPETITIONS; i++) {
        if (!run_tool("paper", tiny, output, seconds + i, &peak, &bytes))
            seconds[i] = G_MAXDOUBLE;
    }
    startup = best_of(seconds, RUN_REPETITIONS);
    io = time_file_io(input, output_bytes, output);
    printf("floor of any such run here: start-up (64 x 64 run) %.3f s + reading the input and writing "
           "the %.0f MiB output %.3f s = %.3f s = %.1f x memcpy\n", startup, output_bytes/1048576.0, io,
           startup + io, (startup + io)/memcpy_seconds);
    g_unlink(tiny);
    g_object_unref(data);
    g_free(tiny);
}

/* A change of the stripe count with a reference: the dialog registers the
 * reduced copy against the reduced reference (made once per reference). */
static void
bench_preview_registration(GwyDataField *field, PreviewField *preview)
{
    GwyDataField *reference = gwy_data_field_duplicate(field);
    PreviewField *reduced_reference;
    DriftTable *table;
    GError *error = NULL;
    gdouble seconds[PREVIEW_REPETITIONS];
    gint64 start;
    gint i;

    reduced_reference = preview_field_new(reference, PREVIEW_FIELD_SIZE);
    for (i = 0; i < PREVIEW_REPETITIONS; i++) {
        start = g_get_monotonic_time();
        table = stripe_registration_table_for_fields(preview_field_source(preview),
                                                     preview_field_source(reduced_reference),
                                                     12 + 4*i, NULL, FALSE, NULL, &error);
        seconds[i] = (g_get_monotonic_time() - start)/1e6;
        if (table)
            drift_table_free(table);
        g_clear_error(&error);
    }
    printf("dialog, %d x %d, registration to a reference: per stripe-count change %.4f s "
           "(target 0.5 s)\n", RES, RES, best_of(seconds, PREVIEW_REPETITIONS));
    preview_field_free(reduced_reference);
    g_object_unref(reference);
}

/* What the dialog does when a setting changes: compensate the reduced
 * copy it previews (the copy is made once, when the dialog opens). */
static void
bench_preview(GwyContainer *data, gdouble memcpy_seconds)
{
    GwyDataField *field = gwy_container_get_object_by_name(data, "/0/data");
    LocalscanOptions options = {
        LOCALSCAN_MODE_CONTINUOUS, LOCALSCAN_FILL_MEAN, LOCALSCAN_DEFAULT_INTERPOLATION,
        1.0, SCAN_DIRECTION_DOWN, 0.0,
    };
    DriftTable *table = localscan_channel_stored_table(data, 0, NULL);
    gdouble seconds[PREVIEW_REPETITIONS], copy_seconds, full;
    PreviewField *preview;
    GError *error = NULL;
    gint64 start;
    gint i;

    start = g_get_monotonic_time();
    preview = preview_field_new(field, PREVIEW_FIELD_SIZE);
    copy_seconds = (g_get_monotonic_time() - start)/1e6;
    for (i = 0; i < PREVIEW_REPETITIONS; i++) {
        options.mode = (i % 2 ? LOCALSCAN_MODE_PAPER : LOCALSCAN_MODE_CONTINUOUS);
        start = g_get_monotonic_time();
        if (!preview_field_compensate(preview, table, FALSE, &options, NULL, &error)) {
            fprintf(stderr, "bench-batch: preview: %s\n", error->message);
            g_clear_error(&error);
        }
        seconds[i] = (g_get_monotonic_time() - start)/1e6;
    }
    full = best_of(seconds, PREVIEW_REPETITIONS);
    printf("dialog, %d x %d: reduced copy (%d x %d) made once in %.3f s; per setting change "
           "%.4f s = %.2f x memcpy (target 0.5 s)\n",
           RES, RES, preview_field_xres(preview), preview_field_yres(preview), copy_seconds,
           full, full/memcpy_seconds);
    bench_preview_registration(field, preview);
    preview_field_free(preview);
    drift_table_free(table);
}

int
main(void)
{
    gsize n = (gsize)RES*RES;
    gdouble *a = g_new(gdouble, n), *b = g_new(gdouble, n), memcpy_seconds;
    gsize output_bytes = 0;
    gchar *dir, *input, *output, *home;
    GwyContainer *data;
    GError *error = NULL;
    gboolean ok;

    if (!(dir = g_dir_make_tmp("bench-batch-XXXXXX", &error))) {
        fprintf(stderr, "bench-batch: %s\n", error->message);
        return EXIT_FAILURE;
    }
    home = g_build_filename(dir, "home", NULL);
    g_mkdir(home, 0700);
    g_setenv("HOME", home, TRUE);
    if (!g_getenv("LOCALSCAN_MODULE"))
        g_setenv("LOCALSCAN_MODULE", MODULE, TRUE);
    gwy_app_init_nongui("enable-threads", FALSE, NULL);
    input = g_build_filename(dir, "in.gwy", NULL);
    output = g_build_filename(dir, "out.gwy", NULL);
    data = make_input(RES);
    ok = gwy_file_save(data, input, GWY_RUN_NONINTERACTIVE, &error);
    if (ok) {
        memset(a, 1, n*sizeof(gdouble));
        memset(b, 0, n*sizeof(gdouble));
        memcpy_seconds = time_memcpy(a, b, n);
        printf("memcpy of the %d x %d channel (%.0f MiB): best %.4f s\n",
               RES, RES, n*sizeof(gdouble)/1048576.0, memcpy_seconds);
        ok = (bench_mode("paper", input, output, memcpy_seconds, &output_bytes)
              && bench_mode("continuous", input, output, memcpy_seconds, &output_bytes));
        if (ok)
            bench_floor(dir, input, output, output_bytes, memcpy_seconds);
        bench_preview(data, memcpy_seconds);
    }
    else
        fprintf(stderr, "bench-batch: cannot write %s: %s\n", input, error->message);
    g_unlink(input);
    g_rmdir(home);
    g_rmdir(dir);
    g_object_unref(data);
    g_free(a);
    g_free(b);
    g_free(input);
    g_free(output);
    g_free(home);
    g_free(dir);
    return ok ? EXIT_SUCCESS : EXIT_FAILURE;
}
