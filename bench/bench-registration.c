/*
 *  Benchmark of the stripe registration on 1024 x 1024 images, N = 16,
 *  against Gwyddion's own drift estimate on the same image in the same run.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <fftw3.h>
#include "stripe-registration.h"
#include "registration-frames.h"
#include "gwyddion-drift-baseline.h"

enum {
    RES = 1024,
    STRIPES = 16,
    REPEATS = 3,
};

static gdouble
time_ours(const FramePair *pair, gdouble max_shift, gdouble *rms)
{
    StripeShift shifts[STRIPES];
    gdouble tx[STRIPES], ty[STRIPES], best = G_MAXDOUBLE, sum = 0.0;
    StripeRegistrationOptions options;
    GError *error = NULL;
    gint i, s;

    for (i = 0; i < REPEATS; i++) {
        gint64 start = g_get_monotonic_time();

        stripe_registration_options_init(&options);
        options.search_x = options.search_y = max_shift;
        if (!stripe_registration_measure(pair->image, pair->reference, RES, RES, STRIPES, &options, shifts, &error))
            g_error("registration failed: %s", error->message);
        best = MIN(best, (g_get_monotonic_time() - start)/1e6);
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
    gdouble gwy, ours, ours_limited, rms, rms_limited;

    if (!gwyddion_drift_init())
        return 1;
    frame_pair_spec_init(&spec);
    spec.xres = spec.yres = RES;
    pair = frame_pair_generate(&spec, 2026);

    gwy = time_gwyddion(pair);
    ours = time_ours(pair, 0.0, &rms);
    ours_limited = time_ours(pair, 32.0, &rms_limited);
    printf("registration of %dx%d, N = %d (best of %d runs, one thread)\n", RES, RES, STRIPES, REPEATS);
    printf("  Gwyddion drift (x only, range 12):      %8.3f s/image  1.00\n", gwy);
    printf("  ours, search +-%d px (default):        %8.3f s/image  %.2f x Gwyddion  (rms error %.3f px)\n",
           RES/4, ours, ours/gwy, rms);
    printf("  ours, search +-32 px:                   %8.3f s/image  %.2f x Gwyddion  (rms error %.3f px)\n",
           ours_limited, ours_limited/gwy, rms_limited);
    frame_pair_free(pair);
    gwyddion_drift_finish();
    fftw_cleanup();
    return 0;
}
