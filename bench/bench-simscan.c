/*
 *  Benchmark of the simulator: a 1024 x 1024 drifting scan of the paper's
 *  sample and the 16 local scans after it (target: under 1 s in all).
 *  Figures are times and ratios against a plain pass over the image's
 *  pixels measured in the same run; nothing is asserted.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <stdio.h>
#include <stdlib.h>
#include <libprocess/stats.h>
#include "paper-compensate.h"
#include "simscan-config.h"
#include "simscan-run.h"

#define RES 1024
#define REPEAT 3

static gdouble
time_best(void (*func)(gpointer), gpointer data)
{
    gdouble best = G_MAXDOUBLE;
    gint i;

    for (i = 0; i < REPEAT; i++) {
        gint64 t0 = g_get_monotonic_time();

        func(data);
        best = MIN(best, (g_get_monotonic_time() - t0)*1e-6);
    }
    return best;
}

typedef struct {
    SimscanConfig config;
    SimscanScene *scene;
    SimscanMeasurement *m;
    gdouble sink;
} Bench;

static void
run_scene(gpointer data)
{
    Bench *b = data;

    simscan_scene_free(b->scene);
    b->scene = simscan_scene_new(&b->config, NULL, NULL);
}

static void
run_measure(gpointer data)
{
    Bench *b = data;

    simscan_measurement_free(b->m);
    b->m = simscan_measure(b->scene, 16, NULL);
}

/* The baseline: the mean of the image, one pass over its pixels. */
static void
run_mean(gpointer data)
{
    Bench *b = data;

    b->sink += paper_image_mean(gwy_data_field_get_data_const(b->scene->image),
                                RES, RES);
}

int
main(void)
{
    Bench b = { .scene = NULL, .m = NULL, .sink = 0.0 };
    gdouble t_mean, t_scene, t_measure;

    simscan_config_init(&b.config);
    b.config.xres = b.config.yres = RES;
    b.config.noise_rms = 0.2e-9;
    t_scene = time_best(run_scene, &b);
    t_measure = time_best(run_measure, &b);
    t_mean = time_best(run_mean, &b);
    if (!b.m) {
        fprintf(stderr, "bench-simscan: no stripe was measured\n");
        return EXIT_FAILURE;
    }
    printf("simscan %d x %d, paper sample (%u particles found), best of %d\n",
           RES, RES, b.scene->particles->len, REPEAT);
    printf("  baseline (one pass over the pixels): %9.4f s\n", t_mean);
    printf("  scan + truth + particle detection:   %9.4f s  (%.0f x baseline)\n",
           t_scene, t_scene/t_mean);
    printf("  16 local scans, table, compensation, errors:\n"
           "                                       %9.4f s  (%.0f x baseline, "
           "%d lines)\n", t_measure, t_measure/t_mean, b.m->lines);
    printf("  total:                               %9.4f s  (target < 1 s)\n",
           t_scene + t_measure);
    simscan_measurement_free(b.m);
    simscan_scene_free(b.scene);
    simscan_config_clear(&b.config);
    return (b.sink == 12345.0) ? EXIT_FAILURE : EXIT_SUCCESS;
}
