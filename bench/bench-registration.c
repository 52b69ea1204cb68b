/*
 *  Benchmark of the stripe registration on 1024 x 1024 images, N = 16,
 *  against Gwyddion's own drift estimate on the same image in the same run
 *  (Gwyddion on one thread; ours on the cores it is given, its processor
 *  time printed beside), and on 4096 x 4096 (issue 9's targets: 0.1 x
 *  Gwyddion's time, 3 s on a 2-core machine).
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include <fftw3.h>
#include "stripe-registration.h"
#include "registration-frames.h"
#include "gwyddion-drift-baseline.h"

enum {
    RES = 1024,
    LARGE_RES = 4096,
    STRIPES = 16,
    REPEATS = 3,
};

/* Best wall-clock time of repeats registrations of the pair (res x res),
 * with the processor time of that run in cpu and the rms error against the
 * truth in rms. */
static gdouble
time_ours(const FramePair *pair, gint res, gint repeats, gdouble max_shift, gdouble *cpu, gdouble *rms)
{
    StripeShift shifts[STRIPES];
    gdouble tx[STRIPES], ty[STRIPES], best = G_MAXDOUBLE, sum = 0.0, seconds;
    StripeRegistrationOptions options;
    GError *error = NULL;
    gint i, s;

    for (i = 0; i < repeats; i++) {
        gint64 start = g_get_monotonic_time();
        clock_t cpu_start = clock();

        stripe_registration_options_init(&options);
        options.search_x = options.search_y = max_shift;
        if (!stripe_registration_measure(pair->image, pair->reference, res, res, STRIPES, &options, shifts,
                                         &error))
            g_error("registration failed: %s", error->message);
        seconds = (g_get_monotonic_time() - start)/1e6;
        if (seconds < best) {
            best = seconds;
            *cpu = (gdouble)(clock() - cpu_start)/CLOCKS_PER_SEC;
        }
    }
    frame_pair_stripe_truth(pair, STRIPES, tx, ty);
    for (s = 0; s < STRIPES; s++)
        sum += (shifts[s].dx - tx[s])*(shifts[s].dx - tx[s]) + (shifts[s].dy - ty[s])*(shifts[s].dy - ty[s]);
    *rms = sqrt(sum/STRIPES);
    return best;
}

static gdouble
time_gwyddion(const FramePair *pair)
{
    gdouble *drift = g_new(gdouble, RES), best = G_MAXDOUBLE, seconds;
    gint i;

    for (i = 0; i < REPEATS; i++) {
        if (!gwyddion_drift_estimate(pair->image, RES, RES, drift, &seconds))
            g_error("Gwyddion's drift function did not produce a drift graph");
        best = MIN(best, seconds);
    }
    g_free(drift);
    return best;
}

int
main(void)
{
    FramePairSpec spec;
    FramePair *pair;
    gdouble gwy, ours, ours_limited, large, rms, rms_limited, rms_large, cpu, cpu_limited, cpu_large;

    if (!gwyddion_drift_init())
        return 1;
    frame_pair_spec_init(&spec);
    spec.xres = spec.yres = RES;
    pair = frame_pair_generate(&spec, 2026);

    gwy = time_gwyddion(pair);
    ours = time_ours(pair, RES, REPEATS, 0.0, &cpu, &rms);
    ours_limited = time_ours(pair, RES, REPEATS, 32.0, &cpu_limited, &rms_limited);
    frame_pair_free(pair);
    printf("registration of %dx%d, N = %d (best of %d runs; Gwyddion on one thread, ours on %u cores, "
           "processor time in brackets)\n", RES, RES, STRIPES, REPEATS, g_get_num_processors());
    printf("  Gwyddion drift (x only, range 12):      %8.3f s/image  1.00\n", gwy);
    printf("  ours, whole-frame search (default):     %8.3f s/image  %.2f x Gwyddion (%.3f s)  "
           "(rms error %.3f px; target 0.1 x)\n", ours, ours/gwy, cpu, rms);
    printf("  ours, search +-32 px:                   %8.3f s/image  %.2f x Gwyddion (%.3f s)  "
           "(rms error %.3f px)\n", ours_limited, ours_limited/gwy, cpu_limited, rms_limited);

    spec.xres = spec.yres = LARGE_RES;
    pair = frame_pair_generate(&spec, 2026);
    large = time_ours(pair, LARGE_RES, 1, 0.0, &cpu_large, &rms_large);
    printf("registration of %dx%d, N = %d, whole-frame search: %.2f s (%.2f s of processor time), "
           "rms error %.3f px (target 3 s on 2 cores)\n", LARGE_RES, LARGE_RES, STRIPES, large, cpu_large,
           rms_large);
    frame_pair_free(pair);
    gwyddion_drift_finish();
    fftw_cleanup();
    return 0;
}
