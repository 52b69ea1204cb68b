/*
 *  Benchmark of continuous-mode compensation against memcpy of the same
 *  image, in the same run, with the peak memory each kernel needs.
 *  bench-continuous [--size N] [--repetitions N] [--no-memory] [KERNEL]
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>
#include <sys/wait.h>
#ifdef __GLIBC__
#include <malloc.h>
#endif
#include <glib.h>
#include <libgwyddion/gwymath.h>
#include "continuous-compensate.h"
#include "stripe-geometry.h"

enum {
    N_STRIPES = 16,
    MAX_REPETITIONS = 1000,
};

typedef struct {
    gdouble best;
    gdouble median;
    gdouble cpu_best;     /* processor time: what the load leaves alone */
} Timing;

typedef struct {
    gint res;
    gint repetitions;
    gboolean memory;
} BenchOptions;

static Timing
summarise(gdouble *seconds, gdouble *cpu_seconds, gint n)
{
    Timing timing;

    gwy_math_sort(n, seconds);
    gwy_math_sort(n, cpu_seconds);
    timing.best = seconds[0];
    timing.median = seconds[n/2];
    timing.cpu_best = cpu_seconds[0];
    return timing;
}

/* Processor time of this process (s); wall time where there is none. */
static gdouble
cpu_time(void)
{
#if defined(CLOCK_PROCESS_CPUTIME_ID)
    struct timespec ts;

    if (clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts) == 0)
        return ts.tv_sec + 1e-9*ts.tv_nsec;
#endif
    return g_get_monotonic_time()/1e6;
}

static void
run_continuous(const BenchOptions *options, const gdouble *a,
               const DriftTable *table, const ScanTiming *timing,
               GwyInterpolationType interpolation,
               gdouble *result, gdouble *mask)
{
    GError *error = NULL;
    gint res = options->res;

    if (!continuous_compensate_table(a, res, res, table, 1.0, 1.0, timing,
                                     interpolation, 0.0, result, mask,
                                     &error)) {
        fprintf(stderr, "bench-continuous: %s\n", error->message);
        exit(EXIT_FAILURE);
    }
}

/* Timed runs of one kernel, each after a memcpy of the same image timed
 * too, so that both see the same machine load. */
static void
time_continuous(const BenchOptions *options, const gdouble *a,
                const DriftTable *table, const ScanTiming *timing,
                GwyInterpolationType interpolation,
                gdouble *result, gdouble *mask,
                Timing *kernel, Timing *baseline)
{
    gdouble seconds[MAX_REPETITIONS], copy_seconds[MAX_REPETITIONS];
    gdouble cpu[MAX_REPETITIONS], copy_cpu[MAX_REPETITIONS], cpu_start;
    gsize size = (gsize)options->res*options->res*sizeof(gdouble);
    gint64 start;
    gint i;

    for (i = 0; i < options->repetitions; i++) {
        start = g_get_monotonic_time();
        cpu_start = cpu_time();
        memcpy(result, a, size);
        copy_cpu[i] = cpu_time() - cpu_start;
        copy_seconds[i] = (g_get_monotonic_time() - start)/1e6;
        start = g_get_monotonic_time();
        cpu_start = cpu_time();
        run_continuous(options, a, table, timing, interpolation, result, mask);
        cpu[i] = cpu_time() - cpu_start;
        seconds[i] = (g_get_monotonic_time() - start)/1e6;
    }
    *kernel = summarise(seconds, cpu, options->repetitions);
    *baseline = summarise(copy_seconds, copy_cpu, options->repetitions);
}

/* A kB field of /proc/self/status, -1 if there is none. */
static glong
status_kib(const gchar *name)
{
    FILE *fh = fopen("/proc/self/status", "r");
    gsize len = strlen(name);
    gchar line[256];
    glong value = -1;

    if (!fh)
        return -1;
    while (fgets(line, sizeof(line), fh)) {
        if (strncmp(line, name, len) == 0 && line[len] == ':')
            value = atol(line + len + 1);
    }
    fclose(fh);
    return value;
}

/* Peak resident memory (kB) one call adds on top of the input and outputs
 * (all of them touched beforehand), -1 if the system cannot say.  Measured
 * in a child so that its malloc settings leave the timed runs alone: every
 * block of 64 KiB or more gets its own mapping, returned on free, so the
 * high-water mark sees each scratch buffer (glibc only; elsewhere
 * reused heap may hide some). */
static glong
peak_memory_kib(const BenchOptions *options, const gdouble *a,
                const DriftTable *table, const ScanTiming *timing,
                GwyInterpolationType interpolation,
                gdouble *result, gdouble *mask)
{
    glong before, after, peak = -1;
    gint fds[2], status;
    FILE *clear_refs;
    pid_t pid;

    if (pipe(fds) != 0)
        return -1;
    fflush(stdout);
    pid = fork();
    if (pid == 0) {
        close(fds[0]);
#ifdef __GLIBC__
        mallopt(M_MMAP_THRESHOLD, 64*1024);
        mallopt(M_TRIM_THRESHOLD, 64*1024);
#endif
        /* A first call maps the code the child has not touched yet. */
        run_continuous(options, a, table, timing, interpolation,
                       result, mask);
#ifdef __GLIBC__
        /* Free heap left resident would hide new scratch. */
        malloc_trim(0);
#endif
        /* Writing 5 resets the high-water mark to the current size. */
        if ((clear_refs = fopen("/proc/self/clear_refs", "w"))) {
            if (fputs("5", clear_refs) < 0)
                peak = -2;
            if (fclose(clear_refs) != 0)
                peak = -2;
            before = status_kib("VmRSS");
            run_continuous(options, a, table, timing, interpolation,
                           result, mask);
            after = status_kib("VmHWM");
            if (peak != -2 && before >= 0 && after >= 0)
                peak = after - before;
        }
        if (write(fds[1], &peak, sizeof(peak)) != sizeof(peak))
            _exit(EXIT_FAILURE);
        _exit(EXIT_SUCCESS);
    }
    close(fds[1]);
    if (pid > 0) {
        if (read(fds[0], &peak, sizeof(peak)) != sizeof(peak) || peak < 0)
            peak = -1;
        waitpid(pid, &status, 0);
    }
    close(fds[0]);
    return peak;
}

static void
report(const gchar *name, Timing timing, Timing baseline, glong peak_kib)
{
    gchar memory[32];

    if (peak_kib >= 0)
        g_snprintf(memory, sizeof(memory), "%7.2f MiB", peak_kib/1024.0);
    else
        g_strlcpy(memory, "    n/a", sizeof(memory));
    printf("%-8s best %7.2f  median %7.2f ms | memcpy best %6.2f  median "
           "%6.2f ms | ratio best %5.2f  median %5.2f  cpu %5.2f | peak %s\n",
           name, 1e3*timing.best, 1e3*timing.median,
           1e3*baseline.best, 1e3*baseline.median,
           timing.best/baseline.best, timing.median/baseline.median,
           timing.cpu_best/baseline.cpu_best, memory);
}

/* The paper's situation at res lines: constant velocity plus settling,
 * 12 px in x and 7 px in y over the frame, every stripe measured with
 * sub-pixel exact values and local scans 0.1 s apart after the frame. */
static DriftTable*
make_table(const ScanTiming *timing, gint res)
{
    DriftTable *table = drift_table_new(N_STRIPES, DRIFT_UNIT_PX);
    gdouble frame = scan_timing_frame_end(timing), tau = 0.3*frame;
    gdouble ti, tl, px[2], py[2], t;
    gint s, k;

    for (s = 0; s < N_STRIPES; s++) {
        ti = scan_timing_rows_time(timing, stripe_first_row(s, N_STRIPES, res),
                                   stripe_end_row(s, N_STRIPES, res));
        tl = frame + 1.0 + 0.1*s;
        for (k = 0; k < 2; k++) {
            t = k ? tl : ti;
            px[k] = 8.0*t/frame + 4.0*(1.0 - exp(-t/tau));
            py[k] = -5.0*t/frame - 2.0*(1.0 - exp(-t/tau));
        }
        table->rows[s].has_drift = TRUE;
        table->rows[s].dx = floor(px[0] - px[1] + 0.5);
        table->rows[s].dy = floor(py[0] - py[1] + 0.5);
        drift_table_set_extra(table, s, "dx_exact", px[0] - px[1]);
        drift_table_set_extra(table, s, "dy_exact", py[0] - py[1]);
        drift_table_set_extra(table, s, "t_image", ti);
        drift_table_set_extra(table, s, "t_local", tl);
    }
    return table;
}

static gboolean
parse_options(gint *argc, gchar ***argv, BenchOptions *options)
{
    gboolean no_memory = FALSE;
    GOptionEntry entries[] = {
        { "size", 0, 0, G_OPTION_ARG_INT, &options->res,
          "Image size in pixels (default 4096)", "N", },
        { "repetitions", 0, 0, G_OPTION_ARG_INT, &options->repetitions,
          "Timed runs per kernel (default 5)", "N", },
        { "no-memory", 0, 0, G_OPTION_ARG_NONE, &no_memory,
          "Skip the peak-memory run (e.g. under valgrind)", NULL, },
        { NULL, 0, 0, 0, NULL, NULL, NULL, },
    };
    GOptionContext *context;
    GError *error = NULL;
    gboolean ok;

    options->res = 4096;
    options->repetitions = 5;
    context = g_option_context_new("[KERNEL] - time continuous compensation "
                                   "(kernels whose name contains KERNEL)");
    g_option_context_add_main_entries(context, entries, NULL);
    ok = g_option_context_parse(context, argc, argv, &error);
    g_option_context_free(context);
    if (!ok) {
        fprintf(stderr, "bench-continuous: %s\n", error->message);
        g_clear_error(&error);
        return FALSE;
    }
    if (options->res < 16 || options->res > 32768
        || options->repetitions < 1
        || options->repetitions > MAX_REPETITIONS) {
        fprintf(stderr, "bench-continuous: size must be 16-32768 and "
                "repetitions 1-%d\n", MAX_REPETITIONS);
        return FALSE;
    }
    options->memory = !no_memory;
    return TRUE;
}

int
main(int argc, char **argv)
{
    static const struct {
        GwyInterpolationType type;
        const gchar *name;
    } kernels[] = {
        { GWY_INTERPOLATION_ROUND,   "round", },
        { GWY_INTERPOLATION_LINEAR,  "linear", },
        { GWY_INTERPOLATION_KEY,     "Keys", },
        { GWY_INTERPOLATION_SCHAUM,  "Schaum", },
        { GWY_INTERPOLATION_NNA,     "NNA", },
        { GWY_INTERPOLATION_BSPLINE, "B-spline", },
        { GWY_INTERPOLATION_OMOMS,   "o-MOMS", },
    };
    BenchOptions options;
    gdouble *a, *result, *mask;
    ScanTiming timing;
    DriftTable *table;
    Timing baseline, t;
    guint32 state = 12345;
    glong peak;
    gsize size, k;
    guint i;

    if (!parse_options(&argc, &argv, &options))
        return EXIT_FAILURE;
    size = (gsize)options.res*options.res;
    a = g_new(gdouble, size);
    result = g_new(gdouble, size);
    mask = g_new(gdouble, size);
    for (k = 0; k < size; k++) {
        state = state*1664525u + 1013904223u;
        a[k] = state/4294967296.0;
    }
    /* Touch every page of the outputs so that no run pays for faulting. */
    memset(result, 0, size*sizeof(gdouble));
    memset(mask, 0, size*sizeof(gdouble));
    scan_timing_init(&timing, options.res, options.res, 0.0,
                     300.0/256.0*4096.0/options.res, SCAN_DIRECTION_DOWN);
    table = make_table(&timing, options.res);

    printf("%d x %d image, %d stripes, best and median of %d runs, each "
           "after a memcpy of the image (timed: the ratio's baseline; cpu: "
           "ratio of the best processor times); peak memory beyond input "
           "and outputs (%.0f MiB each)\n",
           options.res, options.res, N_STRIPES, options.repetitions,
           size*sizeof(gdouble)/1048576.0);
    for (i = 0; i < G_N_ELEMENTS(kernels); i++) {
        if (argc > 1 && !strstr(kernels[i].name, argv[1]))
            continue;
        time_continuous(&options, a, table, &timing, kernels[i].type,
                        result, mask, &t, &baseline);
        peak = (options.memory
                ? peak_memory_kib(&options, a, table, &timing,
                                  kernels[i].type, result, mask)
                : -1);
        report(kernels[i].name, t, baseline, peak);
    }

    drift_table_free(table);
    g_free(mask);
    g_free(result);
    g_free(a);
    return EXIT_SUCCESS;
}
