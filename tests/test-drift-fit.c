/*
 *  Tests of the drift-model fit: known trajectories sampled as
 *  displacement measurements at known times must give their parameters back,
 *  and constant drift must never be taken for an effect.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <string.h>
#include <stdlib.h>
#include <math.h>
#include <check.h>
#include "drift-fit.h"
#include "sim-random.h"
#include "test-common.h"

/* Three frames of 16 blocks, 100 s each, every later block measured against
 * every earlier frame, the way displacement-measure.c ties blocks to times. */
#define N_FRAMES 3
#define N_BLOCKS 16
#define FRAME_TIME 100.0

static guint32 test_seed;

static DriftMeasurement*
sample_frames(const DriftModel *model, gint n_frames, gdouble noise_nm,
              guint32 seed, gint *n)
{
    DriftMeasurement *meas = g_new0(DriftMeasurement,
                                    n_frames*n_frames*N_BLOCKS);
    SimRandom rng;
    gint k, j, b, m = 0;

    sim_random_init(&rng, seed, 7);
    for (k = 1; k < n_frames; k++) {
        for (j = 0; j < k; j++) {
            for (b = 0; b < N_BLOCKS; b++) {
                DriftMeasurement *d = meas + m++;
                gdouble ax, ay, bx, by;

                d->t_a = FRAME_TIME*(k + (b + 0.5)/N_BLOCKS);
                d->t_b = FRAME_TIME*(j + (b + 0.5)/N_BLOCKS);
                drift_model_eval(model, d->t_a, &ax, &ay);
                drift_model_eval(model, d->t_b, &bx, &by);
                d->dx = ax - bx + 1e-9*noise_nm*sim_random_gaussian(&rng);
                d->dy = ay - by + 1e-9*noise_nm*sim_random_gaussian(&rng);
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

static DriftMeasurement*
sample_model(const DriftModel *model, gdouble noise_nm, guint32 seed, gint *n)
{
    return sample_frames(model, N_FRAMES, noise_nm, seed, n);
}

static const DriftFit*
select_model(const DriftMeasurement *meas, gint n, DriftFit *fits)
{
    gint i = drift_fit_select(meas, n, NULL, fits);

    ck_assert_int_ge(i, 0);
    return fits + i;
}

/* The fit chosen for the model sampled with noise_nm from seed; its
 * parameters in p. */
static DriftFit
fit_sampled_model(const DriftModel *model, gdouble noise_nm, guint32 seed,
                  DriftFitParameters *p)
{
    DriftFit fits[8], fit;
    DriftMeasurement *meas;
    gint n;

    meas = sample_model(model, noise_nm, seed, &n);
    fit = *select_model(meas, n, fits);
    drift_fit_parameters(&fit, p);
    g_free(meas);
    return fit;
}

START_TEST(test_constant_velocity)
{
    DriftModel model;
    DriftFitParameters p;
    DriftFit fit;
    gint seed;

    for (seed = 1; seed <= 20; seed++) {
        drift_model_init(&model, DRIFT_MODEL_NONE);
        model.v[0] = 0.08e-9;
        model.v[1] = -0.03e-9;
        fit = fit_sampled_model(&model, 0.5, seed, &p);
        ck_assert_msg(fit.type == DRIFT_MODEL_NONE,
                      "seed %d: constant drift taken for %s", seed,
                      drift_model_type_name(fit.type));
        ck_assert_msg(fabs(p.velocity_nm_per_s[0] - 0.08) < 0.005
                      && fabs(p.velocity_nm_per_s[1] + 0.03) < 0.005,
                      "v = %g, %g nm/s", p.velocity_nm_per_s[0],
                      p.velocity_nm_per_s[1]);
    }
}
END_TEST

START_TEST(test_settling)
{
    DriftModel model;
    DriftFitParameters p;
    DriftFit fit;

    drift_model_init(&model, DRIFT_MODEL_SETTLING);
    model.v[0] = 0.02e-9;
    model.u[0] = 0.5e-9;
    model.u[1] = -0.3e-9;
    model.tau = 60.0;
    fit = fit_sampled_model(&model, 0.3, 3, &p);
    ck_assert_str_eq(drift_model_type_name(fit.type), "settling");
    ck_assert_msg(fabs(p.tau_s/60.0 - 1.0) < 0.15, "tau %g s", p.tau_s);
    ck_assert_msg(fabs(p.u_nm_per_s[0] - 0.5) < 0.08
                  && fabs(p.u_nm_per_s[1] + 0.3) < 0.08,
                  "u = %g, %g", p.u_nm_per_s[0], p.u_nm_per_s[1]);
}
END_TEST

START_TEST(test_oscillation)
{
    DriftModel model;
    DriftFitParameters p;
    DriftFit fit;

    drift_model_init(&model, DRIFT_MODEL_OSCILLATION);
    model.v[1] = 0.05e-9;
    model.a[0] = 3e-9;
    model.a[1] = 1.5e-9;
    model.period = 37.0;
    model.phase = 0.7;
    fit = fit_sampled_model(&model, 0.3, 5, &p);
    ck_assert_str_eq(drift_model_type_name(fit.type), "oscillation");
    ck_assert_msg(fabs(p.period_s - 37.0) < 0.5, "period %g s", p.period_s);
    /* The sign of the amplitude goes with the phase (a, phi) ~ (-a, phi+pi). */
    ck_assert_msg(fabs(fabs(p.amplitude_nm[0]) - 3.0) < 0.3
                  && fabs(fabs(p.amplitude_nm[1]) - 1.5) < 0.3
                  && p.amplitude_nm[0]*p.amplitude_nm[1] > 0.0,
                  "a = %g, %g nm", p.amplitude_nm[0], p.amplitude_nm[1]);
}
END_TEST

START_TEST(test_jump)
{
    DriftModel model;
    DriftFitParameters p;
    DriftFit fit;

    drift_model_init(&model, DRIFT_MODEL_JUMP);
    model.v[0] = -0.04e-9;
    model.step[0] = 4e-9;
    model.step[1] = -2e-9;
    model.t_jump = 142.0;
    fit = fit_sampled_model(&model, 0.3, 9, &p);
    ck_assert_str_eq(drift_model_type_name(fit.type), "jump");
    /* Blocks are 6.25 s apart: the step is placed between two of them. */
    ck_assert_msg(fabs(p.t_s - 142.0) < 6.25, "t_s %g s", p.t_s);
    ck_assert_msg(fabs(p.step_nm[0] - 4.0) < 0.3
                  && fabs(p.step_nm[1] + 2.0) < 0.3,
                  "step %g, %g nm", p.step_nm[0], p.step_nm[1]);
}
END_TEST

/* Half a cycle of a slow oscillation over the series is a bend, not an
 * observed oscillation: the period search stops at 1.5 cycles over the
 * measured time span, and the effect named is not "oscillation". */
START_TEST(test_unobservable_period_not_named)
{
    DriftModel model;
    DriftFit fits[8];
    DriftMeasurement *meas;
    const DriftFit *fit;
    gdouble shortest, longest, span;
    gint n, i, n_types;
    const DriftModelType *types = drift_fit_candidates(&n_types);

    drift_model_init(&model, DRIFT_MODEL_OSCILLATION);
    model.v[0] = 0.02e-9;
    model.a[0] = 6e-9;
    model.a[1] = -4e-9;
    model.period = 600.0;
    model.phase = 0.3;
    meas = sample_model(&model, 0.3, 13, &n);
    /* Block centres from 1/32 to 3 - 1/32 frames. */
    span = FRAME_TIME*(N_FRAMES - 1.0/N_BLOCKS);
    ck_assert(drift_fit_observable_periods(meas, n, NULL, &shortest, &longest));
    ck_assert_msg(fabs(longest - span/1.5) < 1e-6, "longest period %g s, expected %g s",
                  longest, span/1.5);
    fit = select_model(meas, n, fits);
    ck_assert_msg(fit->type != DRIFT_MODEL_OSCILLATION,
                  "a 600 s period over %g s named oscillation", span);
    for (i = 0; i < n_types; i++) {
        if (types[i] == DRIFT_MODEL_OSCILLATION)
            ck_assert_msg(fits[i].nonlinear <= longest*(1.0 + 1e-9), "period %g s searched beyond %g s",
                          fits[i].nonlinear, longest);
    }
    g_free(meas);
}
END_TEST

/* Frames scanned in 1 s bursts 10 s apart: periods shorter than twice the
 * 9 s gaps alias, and 1.5 cycles of a longer one do not fit into 21 s, so
 * no oscillation is fitted at all. */
START_TEST(test_aliased_periods_not_fitted)
{
    DriftMeasurement meas[3*16];
    DriftFit fits[8];
    gdouble shortest, longest;
    gint i, k, j, m = 0, n_types;
    const DriftModelType *types = drift_fit_candidates(&n_types);
    SimRandom rng;

    /* Every field set: those not named below (the span) are 0. */
    memset(meas, 0, sizeof(meas));
    sim_random_init(&rng, 17, 1);
    for (k = 1; k < 3; k++) {
        for (j = 0; j < k; j++) {
            for (i = 0; i < 16; i++) {
                DriftMeasurement *d = meas + m++;

                d->t_a = 10.0*k + i/16.0;
                d->t_b = 10.0*j + i/16.0;
                d->dx = 1e-9*(0.3*(d->t_a - d->t_b) + 0.2*sim_random_gaussian(&rng));
                d->dy = 1e-9*(0.2*sim_random_gaussian(&rng));
                d->weight = 1.0;
                d->group = i;
                d->frame_a = k;
                d->frame_b = j;
            }
        }
    }
    ck_assert(!drift_fit_observable_periods(meas, m, NULL, &shortest, &longest));
    ck_assert_msg(shortest >= 18.0 && longest < 14.0, "observable %g..%g s", shortest, longest);
    ck_assert_int_ge(drift_fit_select(meas, m, NULL, fits), 0);
    for (i = 0; i < n_types; i++) {
        if (types[i] == DRIFT_MODEL_OSCILLATION)
            ck_assert(!fits[i].ok);
        if (types[i] == DRIFT_MODEL_NONE)
            ck_assert(fits[i].ok);
    }
}
END_TEST

START_TEST(test_outlier_dropped)
{
    DriftModel model;
    DriftFit fits[8];
    DriftFitParameters p;
    DriftMeasurement *meas;
    const DriftFit *fit;
    gint n;

    drift_model_init(&model, DRIFT_MODEL_NONE);
    model.v[0] = 0.1e-9;
    meas = sample_model(&model, 0.3, 11, &n);
    /* A registration that locked onto the wrong peak. */
    meas[5].dx += 40e-9;
    meas[20].dy -= 25e-9;
    fit = select_model(meas, n, fits);
    drift_fit_parameters(fit, &p);
    ck_assert_str_eq(drift_model_type_name(fit->type), "none");
    ck_assert_msg(fabs(p.velocity_nm_per_s[0] - 0.1) < 0.005,
                  "v %g nm/s", p.velocity_nm_per_s[0]);
    ck_assert_msg(fit->rms_nm < 0.5, "rms %g nm", fit->rms_nm);
    g_free(meas);
}
END_TEST

/* A fast settling (time constant 15-30 s, blocks of 6.25 s; 3-6 px of
 * travel at 7.8 nm/px) over five frames (160 blocks, as a short series
 * measures them) with failed registrations among the blocks (2-5 % of
 * them, 20-80 nm off in any direction).  Fitted to everything, the
 * failures make another model the best (a settling's time constant at
 * the end of its range, a constant acceleration instead), and cut against
 * that model the good blocks of the first seconds went as outliers with
 * the failures: the settling fitted to the rest read its travel short
 * (test-series-correction seed 370000064).  The trajectory over the first
 * frame must come back within 0.3 px RMS (0.2 px typically; the first
 * 3 s, before the first block's time, are extrapolated).  Without the
 * second cut 3 of seeds 1-20 fail; with it seeds 1-400 pass.  More
 * failures still defeat the cut at times (docs/series.md, step 3):
 * over three frames' 48 blocks with 3-8 % (seeds 240, 342, 430001456: the settling
 * 5-11 px wrong or not named), and over five frames with 3-8 % (seed
 * 470000944: cut against a jump, the settling's first blocks went and
 * constant drift was chosen). */
START_TEST(test_fast_settling_beside_failures)
{
    GRand *rng = test_rand_salted(test_seed, 300 + _i);
    DriftModel model;
    DriftFit fits[8];
    DriftMeasurement *meas;
    const DriftFit *fit;
    gdouble travel, angle, t, x, y, x0, y0, fx, fy, fx0, fy0, sum = 0.0;
    gdouble px = 1e-6/128.0, rms, fail;
    gint n, i, count = 0;

    drift_model_init(&model, DRIFT_MODEL_SETTLING);
    model.tau = g_rand_double_range(rng, 15.0, 30.0);
    travel = px*g_rand_double_range(rng, 3.0, 6.0);
    angle = g_rand_double_range(rng, 0.0, 2.0*G_PI);
    model.u[0] = travel/model.tau*cos(angle);
    model.u[1] = travel/model.tau*sin(angle);
    model.v[0] = g_rand_double_range(rng, -0.05e-9, 0.05e-9);
    model.v[1] = g_rand_double_range(rng, -0.05e-9, 0.05e-9);
    meas = sample_frames(&model, 5, 0.3, g_rand_int(rng), &n);
    fail = g_rand_double_range(rng, 0.02, 0.05);
    for (i = 0; i < n; i++) {
        if (g_rand_double(rng) < fail) {
            angle = g_rand_double_range(rng, 0.0, 2.0*G_PI);
            meas[i].dx += 1e-9*g_rand_double_range(rng, 20.0, 80.0)*cos(angle);
            meas[i].dy += 1e-9*g_rand_double_range(rng, 20.0, 80.0)*sin(angle);
        }
    }
    fit = select_model(meas, n, fits);
    ck_assert_msg(fit->type == DRIFT_MODEL_SETTLING,
                  "seed %u case %d: settling (tau %.1f s) taken for %s",
                  test_seed, _i, model.tau, drift_model_type_name(fit->type));
    drift_model_eval(&model, 0.0, &x0, &y0);
    drift_fit_eval(fit, 0.0, &fx0, &fy0);
    for (t = 0.5; t < FRAME_TIME; t += 1.0) {
        drift_model_eval(&model, t, &x, &y);
        drift_fit_eval(fit, t, &fx, &fy);
        x = (fx - fx0) - (x - x0);
        y = (fy - fy0) - (y - y0);
        sum += x*x + y*y;
        count++;
    }
    rms = sqrt(sum/count)/px;
    ck_assert_msg(rms <= 0.3, "seed %u case %d: tau %.1f s, fitted %.1f s: "
                  "trajectory over the first frame %.3f px RMS", test_seed,
                  _i, model.tau, fit->nonlinear, rms);
    g_free(meas);
    g_rand_free(rng);
}
END_TEST

/* A steady drift over three frames in which the content of one block
 * registers falsely, the same 3-8 px off, in every pair that holds it
 * (two similar particles, say).  A model with more freedom bends through
 * those three measurements and, as the best, was what the outliers were
 * cut against: none was cut, and the constant drift chosen kept them,
 * its velocity pulled 25 % short (test-series-command.sh seed 440001096).
 * The velocity must come back within 2 %. */
START_TEST(test_consistent_false_match)
{
    GRand *rng = test_rand_salted(test_seed, 400 + _i);
    DriftModel model;
    DriftFit fits[8];
    DriftFitParameters p;
    DriftMeasurement *meas;
    const DriftFit *fit;
    gdouble px = 1e-6/128.0, speed, angle, ex, ey, e;
    gint n, i, b;

    drift_model_init(&model, DRIFT_MODEL_NONE);
    speed = g_rand_double_range(rng, 0.1e-9, 0.3e-9);
    angle = g_rand_double_range(rng, 0.0, 2.0*G_PI);
    model.v[0] = speed*cos(angle);
    model.v[1] = speed*sin(angle);
    meas = sample_model(&model, 0.3, g_rand_int(rng), &n);
    b = g_rand_int_range(rng, 0, N_BLOCKS);
    e = px*g_rand_double_range(rng, 3.0, 8.0);
    angle = g_rand_double_range(rng, 0.0, 2.0*G_PI);
    ex = e*cos(angle);
    ey = e*sin(angle);
    for (i = 0; i < n; i++) {
        if (meas[i].group == b) {
            meas[i].dx += ex;
            meas[i].dy += ey;
        }
    }
    fit = select_model(meas, n, fits);
    drift_fit_parameters(fit, &p);
    ck_assert_msg(hypot(p.velocity_nm_per_s[0] - 1e9*model.v[0],
                        p.velocity_nm_per_s[1] - 1e9*model.v[1])
                  <= 0.02*1e9*speed,
                  "seed %u case %d: velocity (%.4f, %.4f) nm/s, drawn "
                  "(%.4f, %.4f) (%s chosen)", test_seed, _i,
                  p.velocity_nm_per_s[0], p.velocity_nm_per_s[1],
                  1e9*model.v[0], 1e9*model.v[1],
                  drift_model_type_name(fit->type));
    g_free(meas);
    g_rand_free(rng);
}
END_TEST

/* One pair of frames with a frame's time between them (a featureless
 * middle frame flagged, say): every block spans a jump placed between the
 * two frames, so such a jump is the velocity again, its step read from
 * the few percent by which the blocks' baselines differ.  A step of 168 nm
 * in 64 nm frames was fitted there (test-series-correction seed 19386928).
 * The jump is neither searched nor refitted there; within a frame, where
 * it splits the blocks, it still is.  Velocity and noise drawn at random. */
START_TEST(test_jump_between_one_pairs_frames)
{
    GRand *rng = test_rand_salted(test_seed, 500 + _i);
    gdouble speed = g_rand_double_range(rng, 0.02e-9, 0.2e-9),
            angle = g_rand_double_range(rng, 0.0, 2.0*G_PI), gap;
    DriftMeasurement *meas = g_new0(DriftMeasurement, N_BLOCKS);
    SimRandom noise;
    DriftModel model;
    DriftFit fit, refit;
    gint b;

    drift_model_init(&model, DRIFT_MODEL_NONE);
    model.v[0] = speed*cos(angle);
    model.v[1] = speed*sin(angle);
    sim_random_init(&noise, g_rand_int(rng), 3);
    for (b = 0; b < N_BLOCKS; b++) {
        DriftMeasurement *d = meas + b;

        d->t_a = FRAME_TIME*(2 + (b + 0.5)/N_BLOCKS) + g_rand_double_range(rng, -1.0, 1.0);
        d->t_b = FRAME_TIME*(b + 0.5)/N_BLOCKS + g_rand_double_range(rng, -1.0, 1.0);
        d->dx = model.v[0]*(d->t_a - d->t_b) + 0.05e-9*sim_random_gaussian(&noise);
        d->dy = model.v[1]*(d->t_a - d->t_b) + 0.05e-9*sim_random_gaussian(&noise);
        d->weight = 1.0;
        d->group = b;
        d->frame_a = 2;
        d->frame_b = 0;
    }
    ck_assert(drift_fit_model(meas, N_BLOCKS, DRIFT_MODEL_JUMP, NULL, &fit));
    ck_assert_msg(fit.nonlinear < FRAME_TIME || fit.nonlinear > 2.0*FRAME_TIME,
                  "seed %u: a jump fitted at %g s, between the frames", test_seed, fit.nonlinear);
    for (gap = 1.1*FRAME_TIME; gap < 2.0*FRAME_TIME; gap += 0.2*FRAME_TIME) {
        refit = fit;
        ck_assert_msg(!drift_fit_refit_at(meas, N_BLOCKS, gap, &refit),
                      "seed %u: refitted at %g s: step (%g, %g) nm", test_seed, gap,
                      refit.coef[0][1], refit.coef[1][1]);
        /* Refused, the fit is left as it was. */
        ck_assert(refit.nonlinear == fit.nonlinear
                  && memcmp(refit.coef, fit.coef, sizeof(fit.coef)) == 0);
    }
    /* Within frame 2, the step is as small as the noise allows. */
    ck_assert(drift_fit_refit_at(meas, N_BLOCKS, 2.5*FRAME_TIME, &refit));
    ck_assert_msg(hypot(refit.coef[0][1], refit.coef[1][1]) < 0.2,
                  "seed %u: a step of (%g, %g) nm within frame 2", test_seed,
                  refit.coef[0][1], refit.coef[1][1]);
    g_free(meas);
    g_rand_free(rng);
}
END_TEST

START_TEST(test_model_roundtrip)
{
    DriftModel model, back;
    DriftFit fits[8];
    DriftMeasurement *meas;
    gdouble t, x0, y0, x1, y1, mx0, my0, mx1, my1;
    gint n, i;

    drift_model_init(&model, DRIFT_MODEL_OSCILLATION);
    model.v[0] = 0.05e-9;
    model.a[0] = 2e-9;
    model.a[1] = -1e-9;
    model.period = 53.0;
    model.phase = 2.0;
    meas = sample_model(&model, 0.0, 1, &n);
    i = drift_fit_select(meas, n, NULL, fits);
    drift_fit_to_model(fits + i, &back);
    /* Differences of the trajectory agree (p0 is not observable). */
    for (t = 10.0; t < 300.0; t += 17.0) {
        drift_model_eval(&model, t, &x1, &y1);
        drift_model_eval(&model, 5.0, &x0, &y0);
        drift_model_eval(&back, t, &mx1, &my1);
        drift_model_eval(&back, 5.0, &mx0, &my0);
        ck_assert_msg(fabs((x1 - x0) - (mx1 - mx0)) < 0.05e-9
                      && fabs((y1 - y0) - (my1 - my0)) < 0.05e-9,
                      "t = %g: model and fit differ", t);
    }
    drift_model_clear(&back);
    g_free(meas);
}
END_TEST

static Suite*
drift_fit_suite(void)
{
    TCase *tc;
    Suite *s = test_suite_new("drift-fit", "fit", &tc);

    tcase_add_test(tc, test_constant_velocity);
    tcase_add_test(tc, test_settling);
    tcase_add_test(tc, test_oscillation);
    tcase_add_test(tc, test_jump);
    tcase_add_test(tc, test_unobservable_period_not_named);
    tcase_add_test(tc, test_aliased_periods_not_fitted);
    tcase_add_test(tc, test_outlier_dropped);
    tcase_add_loop_test(tc, test_fast_settling_beside_failures, 0, 12);
    tcase_add_loop_test(tc, test_consistent_false_match, 0, 12);
    tcase_add_loop_test(tc, test_jump_between_one_pairs_frames, 0, 8);
    tcase_add_test(tc, test_model_roundtrip);
    return s;
}

int
main(void)
{
    test_seed = test_seed_from_env("test-drift-fit");
    return test_run_suite(drift_fit_suite());
}
