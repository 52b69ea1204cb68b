/*
 *  Benchmark of continuous-mode compensation against memcpy of the same
 *  image, in the same run.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <glib.h>
#include "continuous-compensate.h"
#include "stripe-geometry.h"

enum {
    RES = 4096,
    N_STRIPES = 16,
    REPETITIONS = 5,
};

typedef struct {
    gdouble best;
    gdouble median;
} Timing;

static gint
compare_doubles(gconstpointer a, gconstpointer b)
{
    gdouble x = *(const gdouble*)a, y = *(const gdouble*)b;

    return (x > y) - (x < y);
}

static Timing
summarise(gdouble *seconds)
{
    Timing timing;

    qsort(seconds, REPETITIONS, sizeof(gdouble), compare_doubles);
    timing.best = seconds[0];
    timing.median = seconds[REPETITIONS/2];
    return timing;
}

static Timing
time_memcpy(const gdouble *a, gdouble *result)
{
    gdouble seconds[REPETITIONS];
    gint64 start;
    gint i;

    for (i = 0; i < REPETITIONS; i++) {
        start = g_get_monotonic_time();
        memcpy(result, a, (gsize)RES*RES*sizeof(gdouble));
        seconds[i] = (g_get_monotonic_time() - start)/1e6;
    }
    return summarise(seconds);
}

static Timing
time_continuous(const gdouble *a, const DriftTable *table,
                const ScanTiming *timing, GwyInterpolationType interpolation,
                gdouble *result, gdouble *mask)
{
    gdouble seconds[REPETITIONS];
    GError *error = NULL;
    gint64 start;
    gint i;

    for (i = 0; i < REPETITIONS; i++) {
        start = g_get_monotonic_time();
        if (!continuous_compensate_table(a, RES, RES, table, 1.0, 1.0, timing,
                                         interpolation, 0.0, result, mask,
                                         &error)) {
            fprintf(stderr, "bench-continuous: %s\n", error->message);
            exit(EXIT_FAILURE);
        }
        seconds[i] = (g_get_monotonic_time() - start)/1e6;
    }
    return summarise(seconds);
}

static void
report(const gchar *name, Timing timing, Timing baseline)
{
    printf("%-40s best %8.2f ms  median %8.2f ms  ratio to memcpy: "
           "best %5.2f  median %5.2f\n",
           name, 1e3*timing.best, 1e3*timing.median,
           timing.best/baseline.best, timing.median/baseline.median);
}

/* The paper's situation at 4096 lines: constant velocity plus settling,
 * 12 px in x and 7 px in y over the frame, every stripe measured with
 * sub-pixel exact values and local scans 0.1 s apart after the frame. */
static DriftTable*
make_table(const ScanTiming *timing)
{
    DriftTable *table = drift_table_new(N_STRIPES, DRIFT_UNIT_PX);
    gdouble frame = scan_timing_frame_end(timing), tau = 0.3*frame;
    gdouble ti, tl, px[2], py[2], t;
    gint s, k;

    for (s = 0; s < N_STRIPES; s++) {
        ti = scan_timing_rows_time(timing, stripe_first_row(s, N_STRIPES, RES),
                                   stripe_end_row(s, N_STRIPES, RES));
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

/* An optional argument picks the kernels whose name contains it (for
 * profiling one of them). */
int
main(int argc, char **argv)
{
    static const struct {
        GwyInterpolationType type;
        const gchar *name;
    } kernels[] = {
        { GWY_INTERPOLATION_LINEAR,  "continuous, linear", },
        { GWY_INTERPOLATION_KEY,     "continuous, Keys", },
        { GWY_INTERPOLATION_BSPLINE, "continuous, B-spline", },
    };
    gsize size = (gsize)RES*RES;
    gdouble *a = g_new(gdouble, size), *result = g_new(gdouble, size);
    gdouble *mask = g_new(gdouble, size);
    ScanTiming timing;
    DriftTable *table;
    Timing baseline, t;
    guint32 state = 12345;
    gsize k;
    guint i;

    for (k = 0; k < size; k++) {
        state = state*1664525u + 1013904223u;
        a[k] = state/4294967296.0;
    }
    /* Touch every page of the outputs so that no run pays for faulting. */
    memset(result, 0, size*sizeof(gdouble));
    memset(mask, 0, size*sizeof(gdouble));
    scan_timing_init(&timing, RES, RES, 0.0, 300.0/256.0, SCAN_DIRECTION_DOWN);
    table = make_table(&timing);

    printf("%d x %d image, %d stripes, best and median of %d runs\n",
           RES, RES, N_STRIPES, REPETITIONS);
    baseline = time_memcpy(a, result);
    report("memcpy (baseline)", baseline, baseline);
    for (i = 0; i < G_N_ELEMENTS(kernels); i++) {
        if (argc > 1 && !strstr(kernels[i].name, argv[1]))
            continue;
        t = time_continuous(a, table, &timing, kernels[i].type, result, mask);
        report(kernels[i].name, t, baseline);
    }

    drift_table_free(table);
    g_free(mask);
    g_free(result);
    g_free(a);
    return EXIT_SUCCESS;
}
