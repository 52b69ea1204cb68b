/*
 *  Benchmark of paper-mode compensation against memcpy of the same image.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <glib.h>
#include <libgwyddion/gwymath.h>
#include "paper-compensate.h"

enum {
    RES = 4096,
    N_STRIPES = 16,
    REPETITIONS = 9,
};

typedef struct {
    gdouble best;
    gdouble median;
} Timing;

static Timing
summarise(gdouble *seconds)
{
    Timing timing;

    gwy_math_sort(REPETITIONS, seconds);
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
time_paper(const gdouble *a, const gint *dx, const gint *dy, gdouble d,
           gdouble *result, gdouble *mask)
{
    gdouble seconds[REPETITIONS];
    gint64 start;
    gint i;

    for (i = 0; i < REPETITIONS; i++) {
        start = g_get_monotonic_time();
        paper_compensate(a, RES, RES, N_STRIPES, dx, dy, d, result, mask);
        seconds[i] = (g_get_monotonic_time() - start)/1e6;
    }
    return summarise(seconds);
}

static void
report(const gchar *name, Timing timing, Timing baseline)
{
    printf("%-40s best %7.2f ms  median %7.2f ms  ratio to memcpy: "
           "best %5.2f  median %5.2f\n",
           name, 1e3*timing.best, 1e3*timing.median,
           timing.best/baseline.best, timing.median/baseline.median);
}

/* The paper's Figure 6 table (dx = -s for 1-based s, dy 0..-3 per group of
 * four) scaled from 256 to RES pixels. */
static void
figure6_table(gint *dx, gint *dy)
{
    gint s, scale = RES/256;

    for (s = 0; s < N_STRIPES; s++) {
        dx[s] = -(s + 1)*scale;
        dy[s] = -(s/4)*scale;
    }
}

/* Shifts of several stripes up to most of the image, alternating in sign. */
static void
large_table(gint *dx, gint *dy)
{
    gint s;

    for (s = 0; s < N_STRIPES; s++) {
        dx[s] = (s % 2 ? 1 : -1)*(RES/8)*(1 + s % 7);
        dy[s] = (s % 3 - 1)*(RES/N_STRIPES)*(1 + s % 5);
    }
}

int
main(void)
{
    gsize size = (gsize)RES*RES;
    gdouble *a, *result, *mask, d, checksum = 0.0;
    gint dx[N_STRIPES], dy[N_STRIPES];
    static const struct {
        const gchar *name;
        void (*fill)(gint *dx, gint *dy);
    } tables[] = {
        { "Figure 6 scaled", figure6_table },
        { "large shifts", large_table },
    };
    Timing baseline, timing;
    gint64 start;
    gsize i;
    guint t, with_mask;

    a = g_new(gdouble, size);
    result = g_new(gdouble, size);
    mask = g_new(gdouble, size);
    for (i = 0; i < size; i++)
        a[i] = (gdouble)(i % 1000003)*1e-3;
    /* Touch every output page first so no timing includes page faults. */
    memset(result, 0, size*sizeof(gdouble));
    memset(mask, 0, size*sizeof(gdouble));

    printf("paper mode on %dx%d doubles, %d stripes, %d repetitions each\n",
           RES, RES, N_STRIPES, REPETITIONS);
    start = g_get_monotonic_time();
    d = paper_image_mean(a, RES, RES);
    printf("%-40s %7.2f ms (once)\n", "paper_image_mean",
           (g_get_monotonic_time() - start)/1e3);

    baseline = time_memcpy(a, result);
    report("memcpy (baseline)", baseline, baseline);

    for (t = 0; t < G_N_ELEMENTS(tables); t++) {
        tables[t].fill(dx, dy);
        for (with_mask = 0; with_mask < 2; with_mask++) {
            gchar *name = g_strdup_printf("paper, %s, %s", tables[t].name,
                                          with_mask ? "with mask" : "no mask");

            timing = time_paper(a, dx, dy, d, result, with_mask ? mask : NULL);
            report(name, timing, baseline);
            checksum += (with_mask ? mask[t ? size - 1 : 0]
                         : result[size/(2 + t)]);
            g_free(name);
        }
    }

    /* Printed so the compiler cannot drop the work. */
    printf("(checksum %g; target: paper mode without mask within 3x of "
           "memcpy)\n", checksum);
    g_free(a);
    g_free(result);
    g_free(mask);
    return EXIT_SUCCESS;
}
