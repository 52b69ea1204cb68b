/*
 *  Tests of the drift fit's creep forms and guards: a constant acceleration
 *  or a logarithmic creep hidden in displacement measurements is found back,
 *  neither is ever selected as a drift model, non-finite fits are never
 *  fitted or chosen, measurements of frames overlapping in time are not
 *  used, and the shortest searched period follows the block time.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <stdlib.h>
#include <stdio.h>
#include <math.h>
#include <check.h>
#include "drift-fit.h"
#include "sim-random.h"
#include "test-common.h"

#define N_FRAMES 4
#define N_BLOCKS 16
#define FRAME_TIME 100.0
#define NOISE_NM 0.3

static guint32 base_seed;

typedef struct {
    DriftFitCreep creep;
    gdouble v[2];      /* nm/s */
    gdouble c[2];      /* b (nm/s^2) or c (nm/s) */
    gdouble t0;        /* s, logarithmic creep */
} HiddenCreep;

static void
creep_position(const HiddenCreep *h, gdouble t, gdouble *p)
{
    gint ax;

    for (ax = 0; ax < 2; ax++) {
        p[ax] = h->v[ax]*t;
        if (h->creep == DRIFT_FIT_CREEP_ACCELERATION)
            p[ax] += h->c[ax]*t*t;
        else
            p[ax] += h->c[ax]*h->t0*log1p(t/h->t0);
    }
}

/* Every later block against every earlier frame, as displacement-measure.c
 * ties blocks to times. */
static DriftMeasurement*
sample_creep(const HiddenCreep *h, guint32 seed, gint *n)
{
    DriftMeasurement *meas = g_new0(DriftMeasurement,
                                    N_FRAMES*N_FRAMES*N_BLOCKS);
    SimRandom rng;
    gint k, j, b, m = 0;

    sim_random_init(&rng, seed, 11);
    for (k = 1; k < N_FRAMES; k++) {
        for (j = 0; j < k; j++) {
            for (b = 0; b < N_BLOCKS; b++) {
                DriftMeasurement *d = meas + m++;
                gdouble pa[2], pb[2];

                d->t_a = FRAME_TIME*(k + (b + 0.5)/N_BLOCKS);
                d->t_b = FRAME_TIME*(j + (b + 0.5)/N_BLOCKS);
                creep_position(h, d->t_a, pa);
                creep_position(h, d->t_b, pb);
                d->dx = 1e-9*(pa[0] - pb[0]
                              + NOISE_NM*sim_random_gaussian(&rng));
                d->dy = 1e-9*(pa[1] - pb[1]
                              + NOISE_NM*sim_random_gaussian(&rng));
                d->weight = 1.0;
                d->group = b;
                d->frame_a = k;
                d->frame_b = j;
            }
        }
    }
    *n = m;
    return meas;
}

static void
draw_creep(SimRandom *rng, DriftFitCreep creep, HiddenCreep *h)
{
    gint ax;

    h->creep = creep;
    h->t0 = 20.0 + 40.0*sim_random_uniform(rng);
    for (ax = 0; ax < 2; ax++) {
        gdouble sign = (sim_random_uniform(rng) < 0.5) ? -1.0 : 1.0;

        h->v[ax] = 0.1*(2.0*sim_random_uniform(rng) - 1.0);
        /* Large enough to bend the trajectory by tens of nm over 400 s. */
        if (creep == DRIFT_FIT_CREEP_ACCELERATION)
            h->c[ax] = sign*(2e-4 + 3e-4*sim_random_uniform(rng));
        else
            h->c[ax] = sign*(0.5 + 0.5*sim_random_uniform(rng));
    }
}

START_TEST(test_acceleration_found)
{
    SimRandom rng;
    HiddenCreep h;
    DriftMeasurement *meas;
    DriftFit fit, none;
    DriftFitParameters p;
    gint n, ax;

    sim_random_init(&rng, base_seed, _i);
    draw_creep(&rng, DRIFT_FIT_CREEP_ACCELERATION, &h);
    meas = sample_creep(&h, base_seed + _i, &n);
    ck_assert(drift_fit_creep(meas, n, DRIFT_FIT_CREEP_ACCELERATION, NULL,
                              &fit));
    ck_assert_int_eq(fit.type, DRIFT_MODEL_NONE);
    ck_assert_int_eq(fit.creep, DRIFT_FIT_CREEP_ACCELERATION);
    drift_fit_parameters(&fit, &p);
    for (ax = 0; ax < 2; ax++) {
        ck_assert_msg(fabs(p.accel_nm_per_s2[ax] - 2.0*h.c[ax]) < 2e-5,
                      "case %d axis %d: acceleration %g, hidden %g nm/s^2",
                      _i, ax, p.accel_nm_per_s2[ax], 2.0*h.c[ax]);
        ck_assert_msg(fabs(p.velocity_nm_per_s[ax] - h.v[ax]) < 0.01,
                      "case %d axis %d: v %g, hidden %g nm/s", _i, ax,
                      p.velocity_nm_per_s[ax], h.v[ax]);
    }
    /* Held out, it predicts to the noise; constant velocity cannot. */
    ck_assert_msg(fit.cv_rms_nm < 1.3*NOISE_NM, "case %d: held-out %g nm",
                  _i, fit.cv_rms_nm);
    ck_assert(drift_fit_model(meas, n, DRIFT_MODEL_NONE, NULL, &none));
    ck_assert_msg(drift_fit_cross_validate(meas, n, DRIFT_MODEL_NONE, NULL)
                  > 3.0*fit.cv_rms_nm, "case %d: constant velocity predicts "
                  "as well", _i);
    g_free(meas);
}
END_TEST

START_TEST(test_log_creep_found)
{
    SimRandom rng;
    HiddenCreep h;
    DriftMeasurement *meas;
    DriftFit fit;
    DriftFitParameters p;
    gint n, ax;

    sim_random_init(&rng, base_seed, 100 + _i);
    draw_creep(&rng, DRIFT_FIT_CREEP_LOGARITHMIC, &h);
    meas = sample_creep(&h, base_seed + 100 + _i, &n);
    ck_assert(drift_fit_creep(meas, n, DRIFT_FIT_CREEP_LOGARITHMIC, NULL,
                              &fit));
    drift_fit_parameters(&fit, &p);
    ck_assert_msg(fabs(p.tau_s/h.t0 - 1.0) < 0.25, "case %d: t0 %g, hidden "
                  "%g s", _i, p.tau_s, h.t0);
    for (ax = 0; ax < 2; ax++)
        ck_assert_msg(fabs(p.u_nm_per_s[ax] - h.c[ax]) < 0.15*fabs(h.c[ax]),
                      "case %d axis %d: c %g, hidden %g nm/s", _i, ax,
                      p.u_nm_per_s[ax], h.c[ax]);
    ck_assert_msg(fit.cv_rms_nm < 1.3*NOISE_NM, "case %d: held-out %g nm",
                  _i, fit.cv_rms_nm);
    g_free(meas);
}
END_TEST

START_TEST(test_creep_never_selected)
{
    SimRandom rng;
    HiddenCreep h;
    DriftMeasurement *meas;
    DriftFit fits[8];
    gint n, i, n_types;

    sim_random_init(&rng, base_seed, 200);
    draw_creep(&rng, DRIFT_FIT_CREEP_ACCELERATION, &h);
    meas = sample_creep(&h, base_seed + 200, &n);
    i = drift_fit_select(meas, n, NULL, fits);
    drift_fit_candidates(&n_types);
    ck_assert_int_ge(i, 0);
    for (i = 0; i < n_types; i++)
        ck_assert_int_eq(fits[i].creep, DRIFT_FIT_CREEP_NONE);
    g_free(meas);
}
END_TEST

/* Times so large that their squares overflow: every sum is infinite, so no
 * model may come out fitted, let alone chosen (a clamped NaN residual once
 * gave settling a BIC of -2193). */
START_TEST(test_non_finite_never_fitted)
{
    HiddenCreep h = { DRIFT_FIT_CREEP_ACCELERATION, { 0.1, 0.0 },
                      { 0.0, 0.0 }, 1.0 };
    DriftMeasurement *meas;
    DriftFit fits[8], fit;
    gint n, i, n_types;

    meas = sample_creep(&h, 1, &n);
    for (i = 0; i < n; i++) {
        meas[i].t_a *= 1e300;
        meas[i].t_b *= 1e300;
    }
    drift_fit_candidates(&n_types);
    ck_assert_int_eq(drift_fit_select(meas, n, NULL, fits), -1);
    for (i = 0; i < n_types; i++)
        ck_assert_msg(!fits[i].ok, "%s fitted",
                      drift_model_type_name(fits[i].type));
    ck_assert(!drift_fit_model(meas, n, DRIFT_MODEL_SETTLING, NULL, &fit));
    ck_assert(isnan(fit.bic));
    ck_assert(!drift_fit_creep(meas, n, DRIFT_FIT_CREEP_LOGARITHMIC, NULL,
                               &fit));
    ck_assert(isnan(drift_fit_cross_validate(meas, n, DRIFT_MODEL_NONE,
                                             NULL)));
    g_free(meas);
}
END_TEST

/* A measurement whose later frame was scanned no later than the earlier
 * one (overlapping frames) says nothing about drift and is not used. */
START_TEST(test_overlapping_frames_unused)
{
    HiddenCreep h = { DRIFT_FIT_CREEP_ACCELERATION, { 0.1, -0.05 },
                      { 0.0, 0.0 }, 1.0 };
    DriftMeasurement *meas;
    DriftFit fit;
    DriftFitParameters p;
    gint n, i, bad = 0;

    meas = sample_creep(&h, 2, &n);
    for (i = 0; i < n; i += 5) {
        meas[i].t_a = meas[i].t_b;
        meas[i].dx = 1e-6;
        bad++;
    }
    ck_assert(drift_fit_model(meas, n, DRIFT_MODEL_NONE, NULL, &fit));
    ck_assert_int_eq(fit.n_used, 2*(n - bad));
    drift_fit_parameters(&fit, &p);
    ck_assert_msg(fabs(p.velocity_nm_per_s[0] - 0.1) < 0.005,
                  "v_x %g nm/s", p.velocity_nm_per_s[0]);
    g_free(meas);
}
END_TEST

START_TEST(test_min_period)
{
    /* Three blocks of 486/16 lines of 0.43 s. */
    ck_assert(fabs(drift_fit_min_period(0.43, 486, 16) - 3.0*0.43*486/16)
              < 1e-12);
    ck_assert(fabs(drift_fit_min_period(2.0, 128, 0) - 3.0*2.0*128) < 1e-12);
}
END_TEST

static Suite*
drift_fit_creep_suite(void)
{
    TCase *tc;
    Suite *s = test_suite_new("drift-fit-creep", "creep", &tc);

    tcase_add_loop_test(tc, test_acceleration_found, 0, 10);
    tcase_add_loop_test(tc, test_log_creep_found, 0, 10);
    tcase_add_test(tc, test_creep_never_selected);
    tcase_add_test(tc, test_non_finite_never_fitted);
    tcase_add_test(tc, test_overlapping_frames_unused);
    tcase_add_test(tc, test_min_period);
    tcase_set_timeout(tc, 60);
    return s;
}

int
main(void)
{
    base_seed = test_seed_from_env("test-drift-fit-creep");
    return test_run_suite(drift_fit_creep_suite());
}
