/*
 *  Tests of the registration of large frames at half resolution: when it
 *  bins, how it bins, and that the binned registration measures as the
 *  table needs it (px of the frames as given, jumps kept, search bounds
 *  honoured).
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <check.h>
#include <fftw3.h>
#include "registration-binning.h"
#include "stripe-registration.h"
#include "registration-frames.h"
#include "median.h"
#include "test-common.h"

static guint32 test_seed;

/* A lattice of the given period (px) of amplitude amp added to data:
 * along x, or, with both, an egg-crate along x and y (a pattern along y
 * alone is no texture: each line carries a constant, as the lines'
 * offsets, which conditioning removes). */
static void
add_lattice(gdouble *data, gint xres, gint yres, gdouble period, gdouble amp, gboolean both, gdouble phase)
{
    gdouble q = 2.0*G_PI/period;
    gint r, c;

    for (r = 0; r < yres; r++) {
        for (c = 0; c < xres; c++)
            data[r*xres + c] += amp*cos(q*c + phase)*(both ? 2.0*cos(q*r + phase) : 1.0);
    }
}

START_TEST(test_bin_frame)
{
    GRand *rng = test_rand_salted(test_seed, 1);
    enum { XRES = 7, YRES = 5 };
    gdouble data[XRES*YRES], *binned;
    gint r, c, k;

    for (k = 0; k < XRES*YRES; k++)
        data[k] = g_rand_double_range(rng, -1e3, 1e3);
    data[1*XRES + 2] = NAN;
    data[4*XRES + 0] = INFINITY;   /* in the row binning leaves out */
    data[2*XRES + 5] = -INFINITY;
    binned = registration_bin_frame(data, XRES, YRES, 2);
    for (r = 0; r < YRES/2; r++) {
        for (c = 0; c < XRES/2; c++) {
            gdouble expected = 0.25*(data[2*r*XRES + 2*c] + data[2*r*XRES + 2*c + 1]
                                     + data[(2*r + 1)*XRES + 2*c] + data[(2*r + 1)*XRES + 2*c + 1]);

            if ((r == 0 && c == 1) || (r == 1 && c == 2))
                ck_assert_msg(isnan(binned[r*(XRES/2) + c]), "block (%d, %d) with a missing pixel is %g",
                              r, c, binned[r*(XRES/2) + c]);
            else
                ck_assert_msg(fabs(binned[r*(XRES/2) + c] - expected) <= 1e-12*fabs(expected) + 1e-12,
                              "block (%d, %d): %.15g, expected %.15g", r, c, binned[r*(XRES/2) + c], expected);
        }
    }
    g_free(binned);
    /* Values near the largest double: no overflow into a missing block. */
    for (k = 0; k < XRES*YRES; k++)
        data[k] = G_MAXDOUBLE*g_rand_double_range(rng, 0.9, 1.0);
    binned = registration_bin_frame(data, XRES, YRES, 2);
    for (k = 0; k < (XRES/2)*(YRES/2); k++)
        ck_assert_msg(isfinite(binned[k]) && binned[k] > 0.8*G_MAXDOUBLE, "block %d: %g", k, binned[k]);
    g_free(binned);
    g_rand_free(rng);
}
END_TEST

/* A fine lattice (period 2.5-4.5 px) is fine texture along the axes it
 * varies along; particles of 2-5 px sigma, plane, line offsets, bow and
 * 1/f noise are not. */
START_TEST(test_fine_texture_share)
{
    GRand *rng = test_rand_salted(test_seed, 2);
    FramePairSpec spec;
    FramePair *pair;
    gdouble period = g_rand_double_range(rng, 2.5, 4.5), share_x, share_y;
    gint res = 512;

    frame_pair_spec_init(&spec);
    spec.xres = spec.yres = res;
    pair = frame_pair_generate(&spec, test_seed);
    frame_pair_add_raw_artefacts(pair, 3.0, test_seed + 1);
    share_x = registration_fine_texture_share(pair->image, res, res, TRUE);
    share_y = registration_fine_texture_share(pair->image, res, res, FALSE);
    printf("particles with raw artefacts: fine share %.4f along x, %.4f along y\n", share_x, share_y);
    ck_assert_msg(share_x < 0.05 && share_y < 0.05, "fine share of a particle frame %g, %g (seed %u)",
                  share_x, share_y, test_seed);

    add_lattice(pair->image, res, res, period, 0.5, TRUE, g_rand_double_range(rng, 0.0, 2.0*G_PI));
    share_x = registration_fine_texture_share(pair->image, res, res, TRUE);
    share_y = registration_fine_texture_share(pair->image, res, res, FALSE);
    printf("with a lattice of %.2f px: fine share %.4f along x, %.4f along y\n", period, share_x, share_y);
    ck_assert_msg(share_x > 0.25 && share_y > 0.25, "lattice of %.2f px: fine share %g, %g (seed %u)",
                  period, share_x, share_y, test_seed);
    frame_pair_free(pair);
    g_rand_free(rng);
}
END_TEST

START_TEST(test_binning_factor)
{
    GRand *rng = test_rand_salted(test_seed, 3);
    FramePairSpec spec;
    FramePair *pair;
    gint res = REGISTRATION_BINNING_MIN_SIDE;
    gdouble period = g_rand_double_range(rng, 2.5, 4.5);

    frame_pair_spec_init(&spec);
    spec.xres = spec.yres = res;
    pair = frame_pair_generate(&spec, test_seed);
    frame_pair_add_raw_artefacts(pair, 3.0, test_seed + 1);
    ck_assert_int_eq(registration_binning_factor(pair->image, pair->reference, res, res, 16), 2);
    /* Each binned stripe keeps 8 rows at the least. */
    ck_assert_int_eq(registration_binning_factor(pair->image, pair->reference, res, res, res/16), 2);
    ck_assert_int_eq(registration_binning_factor(pair->image, pair->reference, res, res, res/16 + 1), 1);
    /* Smaller frames are registered as they are. */
    ck_assert_int_eq(registration_binning_factor(pair->image, pair->reference, res - 1, res - 1, 16), 1);
    /* A fine lattice in one frame only keeps both at full resolution. */
    add_lattice(pair->reference, res, res, period, 0.5, TRUE, 0.0);
    ck_assert_msg(registration_binning_factor(pair->image, pair->reference, res, res, 16) == 1,
                  "a reference with a lattice of %.2f px was binned (seed %u)", period, test_seed);
    frame_pair_free(pair);
    g_rand_free(rng);
}
END_TEST

/* Errors (px) of the accepted stripes against the truth; returns how many
 * were accepted. */
static gint
stripe_errors(const FramePair *pair, const StripeShift *shifts, gint n, gdouble *rms, gdouble *worst)
{
    gdouble *tx = g_new(gdouble, n), *ty = g_new(gdouble, n), sum = 0.0, e;
    gint s, accepted = 0;

    frame_pair_stripe_truth(pair, n, tx, ty);
    *worst = 0.0;
    for (s = 0; s < n; s++) {
        if (!shifts[s].accepted)
            continue;
        e = hypot(shifts[s].dx - tx[s], shifts[s].dy - ty[s]);
        sum += e*e;
        *worst = MAX(*worst, e);
        accepted++;
    }
    *rms = accepted ? sqrt(sum/accepted) : 0.0;
    g_free(tx);
    g_free(ty);
    return accepted;
}

/* A raw pair large enough to be binned, with a smooth random drift: the
 * shifts come in px of the frames as given, as precise as the table
 * needs. */
START_TEST(test_binned_registration_accuracy)
{
    enum { N = 16 };
    FramePairSpec spec;
    FramePair *pair;
    StripeShift shifts[N];
    GError *error = NULL;
    gdouble rms, worst;
    gint res = REGISTRATION_BINNING_MIN_SIDE, accepted, s;

    frame_pair_spec_init(&spec);
    spec.xres = spec.yres = res;
    pair = frame_pair_generate(&spec, test_seed);
    frame_pair_add_raw_artefacts(pair, 3.0, test_seed + 1);
    ck_assert_int_eq(registration_binning_factor(pair->image, pair->reference, res, res, N), 2);
    ck_assert_msg(stripe_registration_measure(pair->image, pair->reference, res, res, N, NULL, shifts, &error),
                  "registration failed: %s", error ? error->message : "?");
    accepted = stripe_errors(pair, shifts, N, &rms, &worst);
    printf("binned %dx%d, N = %d: %d accepted, rms %.4f px, worst %.4f px\n", res, res, N, accepted, rms, worst);
    ck_assert_msg(accepted == N, "%d of %d stripes accepted (seed %u)", accepted, N, test_seed);
    ck_assert_msg(rms <= 0.05 && worst <= 0.15, "rms %g px, worst %g px (seed %u)", rms, worst, test_seed);
    /* The uncertainty, in px of the frames given, covers the error; the
     * row each shift is that of lies in its stripe's rows as given (in
     * binned rows it would lie in the stripe's first half). */
    for (s = 0; s < N; s++) {
        ck_assert_msg(shifts[s].sigma > 0.0 && shifts[s].sigma < 0.5, "stripe %d sigma %g", s, shifts[s].sigma);
        ck_assert_msg(shifts[s].row >= s*res/N - 0.5 && shifts[s].row <= (s + 1)*res/N - 0.5
                      && fabs(shifts[s].row - ((s + 0.5)*res/N - 0.5)) <= 0.25*res/N,
                      "stripe %d (rows %d-%d): row %g (seed %u)", s, s*res/N, (s + 1)*res/N - 1,
                      shifts[s].row, test_seed);
    }
    /* Binned, and its sigma in px of the frames given: a column less, the
     * same pair is registered at full resolution, whose sigma is about
     * half (a binned pixel is two; 1 if nothing was binned, 0.5 if the
     * sigma stayed in binned px). */
    {
        gdouble *image = g_new(gdouble, (res - 1)*res), *reference = g_new(gdouble, (res - 1)*res);
        gdouble binned[N], full[N], ratio;
        StripeShift whole[N];
        gint r;

        for (r = 0; r < res; r++) {
            memcpy(image + r*(res - 1), pair->image + r*res, (res - 1)*sizeof(gdouble));
            memcpy(reference + r*(res - 1), pair->reference + r*res, (res - 1)*sizeof(gdouble));
        }
        ck_assert_int_eq(registration_binning_factor(image, reference, res - 1, res, N), 1);
        ck_assert(stripe_registration_measure(image, reference, res - 1, res, N, NULL, whole, &error));
        for (s = 0; s < N; s++) {
            binned[s] = shifts[s].sigma;
            full[s] = whole[s].sigma;
        }
        ratio = median_in_place(binned, N)/median_in_place(full, N);
        printf("binned sigma %.2f times the full resolution's\n", ratio);
        ck_assert_msg(ratio > 1.3 && ratio < 4.0, "binned sigma %g times the full resolution's (seed %u)",
                      ratio, test_seed);
        g_free(image);
        g_free(reference);
    }
    frame_pair_free(pair);
}
END_TEST

/* A jump between two stripes appears in full in the binned registration,
 * and a search bound (px of the frames given) is kept. */
START_TEST(test_binned_jump_and_search)
{
    enum { N = 16 };
    GRand *rng = test_rand_salted(test_seed, 4);
    FramePairSpec spec;
    FramePair *pair;
    StripeShift shifts[N];
    StripeRegistrationOptions options;
    GError *error = NULL;
    gdouble rms, worst, jump, shift, tx[N], ty[N];
    gint res = REGISTRATION_BINNING_MIN_SIDE, s, boundary = g_rand_int_range(rng, 4, N - 4);

    frame_pair_spec_init(&spec);
    spec.xres = spec.yres = res;
    spec.drift = FALSE;
    shift = g_rand_double_range(rng, 24.0, 32.0);
    spec.shift_x = shift;
    spec.shift_y = g_rand_double_range(rng, -4.0, 4.0);
    spec.velocity_x = g_rand_double_range(rng, -0.004, 0.004);
    spec.velocity_y = g_rand_double_range(rng, -0.004, 0.004);
    jump = g_rand_double_range(rng, 3.0, 10.0)*(g_rand_boolean(rng) ? 1.0 : -1.0);
    spec.jump_row = boundary*res/N;
    spec.jump_x = jump*0.6;
    spec.jump_y = jump*0.8;
    pair = frame_pair_generate(&spec, test_seed);
    ck_assert_int_eq(registration_binning_factor(pair->image, pair->reference, res, res, N), 2);
    ck_assert(stripe_registration_measure(pair->image, pair->reference, res, res, N, NULL, shifts, &error));
    ck_assert_msg(stripe_errors(pair, shifts, N, &rms, &worst) == N, "a stripe not accepted (seed %u)",
                  test_seed);
    printf("binned jump of %.2f px at stripe %d: rms %.4f px, worst %.4f px\n", jump, boundary, rms, worst);
    ck_assert_msg(worst <= 0.15, "worst stripe %g px off (seed %u)", worst, test_seed);
    /* The step between the stripes either side: the jump and the drift
     * over a stripe's rows. */
    frame_pair_stripe_truth(pair, N, tx, ty);
    ck_assert_msg(hypot(shifts[boundary].dx - shifts[boundary-1].dx - (tx[boundary] - tx[boundary-1]),
                        shifts[boundary].dy - shifts[boundary-1].dy - (ty[boundary] - ty[boundary-1])) < 0.15,
                  "the step of (%g, %g) px (a jump of %.2f px) reads (%g, %g) (seed %u)",
                  tx[boundary] - tx[boundary-1], ty[boundary] - ty[boundary-1], jump,
                  shifts[boundary].dx - shifts[boundary-1].dx, shifts[boundary].dy - shifts[boundary-1].dy,
                  test_seed);

    /* Searched within fewer px than the shift, nothing is given at it. */
    stripe_registration_options_init(&options);
    options.search_x = options.search_y = shift - 10.0;
    ck_assert(stripe_registration_measure(pair->image, pair->reference, res, res, N, &options, shifts, &error));
    for (s = 0; s < N; s++)
        ck_assert_msg(!shifts[s].accepted || fabs(shifts[s].dx) <= shift - 10.0 + 0.5,
                      "stripe %d given dx %g beyond the search of %g px (seed %u)",
                      s, shifts[s].dx, shift - 10.0, test_seed);
    frame_pair_free(pair);
    g_rand_free(rng);
}
END_TEST

static Suite*
binning_suite(void)
{
    TCase *tc;
    Suite *suite = test_suite_new("registration-binning", "binning", &tc);

    tcase_set_timeout(tc, 120);
    tcase_add_test(tc, test_bin_frame);
    tcase_add_test(tc, test_fine_texture_share);
    tcase_add_test(tc, test_binning_factor);
    tcase_add_test(tc, test_binned_registration_accuracy);
    tcase_add_test(tc, test_binned_jump_and_search);
    return suite;
}

int
main(void)
{
    gint status;

    test_seed = test_seed_from_env("test-registration-binning");
    status = test_run_suite(binning_suite());
    fftw_cleanup();
    return status;
}
