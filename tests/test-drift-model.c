/*
 *  Tests of the drift trajectories p(t) (docs/conventions.md).
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <stdlib.h>
#include <string.h>
#include <math.h>
#include <check.h>
#include <glib.h>
#include "drift-model.h"
#include "test-common.h"

#define N_TIMES 200
#define T_MAX 900.0

static guint32 test_seed;

static gdouble
uniform(GRand *rng, gdouble lo, gdouble hi)
{
    return g_rand_double_range(rng, lo, hi);
}

/* An x, y pair drawn in [-size, size), x first. */
static void
uniform_pair(GRand *rng, gdouble size, gdouble *pair)
{
    pair[0] = uniform(rng, -size, size);
    pair[1] = uniform(rng, -size, size);
}

/* Common part p0 + v t with random nm-scale p0 and nm/s-scale v. */
static void
random_linear_part(DriftModel *model, GRand *rng)
{
    uniform_pair(rng, 50e-9, model->p0);
    uniform_pair(rng, 0.5e-9, model->v);
}

/* The size of the terms that make up p(t), for a relative tolerance. */
static gdouble
magnitude(const DriftModel *m, gdouble t)
{
    return (fabs(m->p0[0]) + fabs(m->p0[1]) + (fabs(m->v[0]) + fabs(m->v[1]))*t
            + (fabs(m->u[0]) + fabs(m->u[1]))*m->tau
            + fabs(m->a[0]) + fabs(m->a[1])
            + fabs(m->step[0]) + fabs(m->step[1]));
}

static void
assert_eval_equals(const DriftModel *model, gdouble t,
                   gdouble ex, gdouble ey)
{
    gdouble px, py, tol = 1e-12*magnitude(model, fabs(t));

    drift_model_eval(model, t, &px, &py);
    ck_assert_msg(fabs(px - ex) <= tol && fabs(py - ey) <= tol,
                  "%s at t=%.17g: p=(%.17g, %.17g), formula (%.17g, %.17g)",
                  drift_model_type_name(model->type), t, px, py, ex, ey);
}

/* A model of the type with a random common part; each type's own
 * parameters are drawn after it. */
static void
random_base_model(DriftModel *m, DriftModelType type, GRand *rng)
{
    drift_model_init(m, type);
    random_linear_part(m, rng);
}

static void
random_none_model(DriftModel *m, GRand *rng)
{
    random_base_model(m, DRIFT_MODEL_NONE, rng);
}

static void
random_settling_model(DriftModel *m, GRand *rng)
{
    random_base_model(m, DRIFT_MODEL_SETTLING, rng);
    uniform_pair(rng, 3e-9, m->u);
    m->tau = uniform(rng, 10.0, 300.0);
}

static void
random_oscillation_model(DriftModel *m, GRand *rng)
{
    random_base_model(m, DRIFT_MODEL_OSCILLATION, rng);
    uniform_pair(rng, 5e-9, m->a);
    m->period = uniform(rng, 5.0, 200.0);
    m->phase = uniform(rng, -G_PI, G_PI);
}

static void
random_jump_model(DriftModel *m, GRand *rng)
{
    random_base_model(m, DRIFT_MODEL_JUMP, rng);
    uniform_pair(rng, 20e-9, m->step);
    m->t_jump = uniform(rng, 100.0, 800.0);
}

/* Frame-start creep on top of a constant velocity. */
static void
random_creep_model(DriftModel *m, GRand *rng)
{
    random_none_model(m, rng);
    uniform_pair(rng, 20e-9, m->creep);
    m->creep_tau = uniform(rng, 2.0, 30.0);
    m->creep_period = uniform(rng, 40.0, 200.0);
}

/* What each type adds to p0 + v t at t, by the formula of
 * docs/conventions.md. */
static void
added_none(G_GNUC_UNUSED const DriftModel *m, G_GNUC_UNUSED gdouble t,
           gdouble *dx, gdouble *dy)
{
    *dx = *dy = 0.0;
}

static void
added_settling(const DriftModel *m, gdouble t, gdouble *dx, gdouble *dy)
{
    gdouble f = m->tau*(1.0 - exp(-t/m->tau));

    *dx = m->u[0]*f;
    *dy = m->u[1]*f;
}

static void
added_oscillation(const DriftModel *m, gdouble t, gdouble *dx, gdouble *dy)
{
    gdouble s = sin(2.0*G_PI*t/m->period + m->phase);

    *dx = m->a[0]*s;
    *dy = m->a[1]*s;
}

static void
added_jump(const DriftModel *m, gdouble t, gdouble *dx, gdouble *dy)
{
    *dx = (t >= m->t_jump)*m->step[0];
    *dy = (t >= m->t_jump)*m->step[1];
}

/* The lag decays from each fly-back and restarts at the next. */
static void
added_creep(const DriftModel *m, gdouble t, gdouble *dx, gdouble *dy)
{
    gdouble f = exp(-(t - m->creep_period*floor(t/m->creep_period))
                    /m->creep_tau);

    *dx = m->creep[0]*f;
    *dy = m->creep[1]*f;
}

typedef struct {
    guint seed_offset;
    void (*random_model)(DriftModel *m, GRand *rng);
    void (*added)(const DriftModel *m, gdouble t, gdouble *dx, gdouble *dy);
} FormulaCase;

static const FormulaCase formula_cases[] = {
    { 0, random_none_model, added_none },
    { 1, random_settling_model, added_settling },
    { 2, random_oscillation_model, added_oscillation },
    { 3, random_jump_model, added_jump },
    { 5, random_creep_model, added_creep },
};

/* p(t) of a random model at random times against its formula. */
START_TEST(test_formula)
{
    const FormulaCase *fc = formula_cases + _i;
    GRand *rng = g_rand_new_with_seed(test_seed + fc->seed_offset);
    DriftModel m;
    gdouble t, dx, dy;
    gint k;

    fc->random_model(&m, rng);
    for (k = 0; k < N_TIMES; k++) {
        t = uniform(rng, 0.0, T_MAX);
        fc->added(&m, t, &dx, &dy);
        assert_eval_equals(&m, t, m.p0[0] + m.v[0]*t + dx,
                           m.p0[1] + m.v[1]*t + dy);
    }
    drift_model_clear(&m);
    g_rand_free(rng);
}
END_TEST

/* The step belongs to t >= t_jump, exactly at the boundary (the model of
 * the jump's formula case). */
START_TEST(test_jump_boundary)
{
    GRand *rng = g_rand_new_with_seed(test_seed + 3);
    DriftModel m;
    gdouble t, before;

    random_jump_model(&m, rng);
    t = m.t_jump;
    assert_eval_equals(&m, t, m.p0[0] + m.v[0]*t + m.step[0],
                       m.p0[1] + m.v[1]*t + m.step[1]);
    before = nextafter(t, -G_MAXDOUBLE);
    assert_eval_equals(&m, before, m.p0[0] + m.v[0]*before,
                       m.p0[1] + m.v[1]*before);
    drift_model_clear(&m);
    g_rand_free(rng);
}
END_TEST

/* The size of the terms that make up p'(t): |v|, |u| and the oscillation's
 * velocity amplitude |a| 2 pi/period. */
static gdouble
velocity_magnitude(const DriftModel *m)
{
    gdouble scale = (fabs(m->v[0]) + fabs(m->v[1])
                     + fabs(m->u[0]) + fabs(m->u[1]));

    if (m->type == DRIFT_MODEL_OSCILLATION)
        scale += (fabs(m->a[0]) + fabs(m->a[1]))*2.0*G_PI/m->period;
    return scale;
}

/* Central differences of p against drift_model_velocity.  Their error is
 * h^2/6 |p'''|: for the oscillation (2 pi h/period)^2/6 of its velocity
 * amplitude, below 3e-7 of it for periods of 5 s and more, and for settling
 * (h/tau)^2/6 of |u|; rounding adds far less.  So the bound is 1e-6 of the
 * size of the velocity's terms, not of the velocity itself, which passes
 * through zero whenever the oscillation cancels v. */
static void
assert_velocity_matches_differences(const DriftModel *m, gdouble t)
{
    gdouble h = 1e-3, xa, ya, xb, yb, vx, vy, fdx, fdy, scale;

    drift_model_eval(m, t + h, &xa, &ya);
    drift_model_eval(m, t - h, &xb, &yb);
    drift_model_velocity(m, t, &vx, &vy);
    fdx = (xa - xb)/(2.0*h);
    fdy = (ya - yb)/(2.0*h);
    scale = velocity_magnitude(m);
    ck_assert_msg(fabs(fdx - vx) <= 1e-6*scale && fabs(fdy - vy) <= 1e-6*scale,
                  "%s at t=%g: velocity (%g, %g), differences (%g, %g)",
                  drift_model_type_name(m->type), t, vx, vy, fdx, fdy);
}

START_TEST(test_settling_velocity)
{
    GRand *rng = g_rand_new_with_seed(test_seed + 4);
    DriftModel m;
    gdouble t, vx, vy, ex, ey;
    gint k;

    random_settling_model(&m, rng);
    for (k = 0; k < N_TIMES; k++) {
        t = uniform(rng, 1.0, T_MAX);
        drift_model_velocity(&m, t, &vx, &vy);
        ex = m.v[0] + m.u[0]*exp(-t/m.tau);
        ey = m.v[1] + m.u[1]*exp(-t/m.tau);
        ck_assert_msg(fabs(vx - ex) <= 1e-12*(fabs(m.v[0]) + fabs(m.u[0]))
                      && fabs(vy - ey) <= 1e-12*(fabs(m.v[1]) + fabs(m.u[1])),
                      "settling velocity at t=%g: (%g, %g), formula (%g, %g)",
                      t, vx, vy, ex, ey);
        assert_velocity_matches_differences(&m, t);
    }
    /* The excess velocity has decayed to 1/e at t = tau. */
    drift_model_velocity(&m, m.tau, &vx, &vy);
    ck_assert(fabs((vx - m.v[0]) - m.u[0]/G_E) <= 1e-12*fabs(m.u[0]));
    drift_model_clear(&m);
    g_rand_free(rng);
}
END_TEST

START_TEST(test_oscillation_velocity)
{
    GRand *rng = g_rand_new_with_seed(test_seed + 5);
    DriftModel m;
    gint k;

    random_oscillation_model(&m, rng);
    for (k = 0; k < N_TIMES; k++)
        assert_velocity_matches_differences(&m, uniform(rng, 1.0, T_MAX));
    drift_model_clear(&m);
    g_rand_free(rng);
}
END_TEST

static void
random_walk_model(DriftModel *m, guint32 seed)
{
    drift_model_init(m, DRIFT_MODEL_RANDOM_WALK);
    m->p0[0] = 3e-9;
    m->v[0] = DRIFT_MODEL_PAPER_VX;
    m->v[1] = DRIFT_MODEL_PAPER_VY;
    m->walk_sigma = 0.01e-9;
    m->walk_dt = 0.5;
    m->walk_seed = seed;
    drift_model_prepare(m, T_MAX);
}

START_TEST(test_random_walk_reproducible)
{
    GRand *rng = g_rand_new_with_seed(test_seed + 6);
    DriftModel a, b, c, copy;
    gdouble t, xa, ya, xb, yb, xc, yc, max_diff = 0.0;
    gint k;

    random_walk_model(&a, test_seed);
    random_walk_model(&b, test_seed);
    random_walk_model(&c, test_seed + 1);
    drift_model_copy(&copy, &a);
    drift_model_clear(&a);
    for (k = 0; k < N_TIMES; k++) {
        t = uniform(rng, 0.0, T_MAX);
        drift_model_eval(&copy, t, &xa, &ya);
        drift_model_eval(&b, t, &xb, &yb);
        drift_model_eval(&c, t, &xc, &yc);
        ck_assert(memcmp(&xa, &xb, sizeof(gdouble)) == 0);
        ck_assert(memcmp(&ya, &yb, sizeof(gdouble)) == 0);
        max_diff = MAX(max_diff, fabs(xa - xc) + fabs(ya - yc));
    }
    /* Over 900 s a walk of 0.01 nm/s/sqrt(s) wanders by nanometres. */
    ck_assert_msg(max_diff > 0.1e-9,
                  "another seed changed the walk by only %g m", max_diff);
    drift_model_clear(&copy);
    drift_model_clear(&b);
    drift_model_clear(&c);
    g_rand_free(rng);
}
END_TEST

/* p is the exact integral of the velocity: piecewise linear, continuous at
 * the nodes, starting at p0 and moving at v + w; the velocity increments
 * have variance walk_sigma^2 walk_dt. */
START_TEST(test_random_walk_integral)
{
    DriftModel m;
    gdouble t, x0, y0, x1, y1, vx, vy, wx_prev = 0.0, sum2 = 0.0;
    gdouble sigma2, h = 1e-6;
    gint k, n = 0;

    random_walk_model(&m, test_seed);
    drift_model_eval(&m, 0.0, &x0, &y0);
    ck_assert(fabs(x0 - m.p0[0]) <= 1e-24 && fabs(y0 - m.p0[1]) <= 1e-24);
    for (k = 0; (k + 1)*m.walk_dt <= T_MAX; k++) {
        t = (k + 0.5)*m.walk_dt;
        drift_model_eval(&m, k*m.walk_dt, &x0, &y0);
        drift_model_eval(&m, (k + 1)*m.walk_dt, &x1, &y1);
        drift_model_velocity(&m, t, &vx, &vy);
        ck_assert(fabs((x1 - x0)/m.walk_dt - vx) <= 1e-9*fabs(vx) + 1e-22);
        ck_assert(fabs((y1 - y0)/m.walk_dt - vy) <= 1e-9*fabs(vy) + 1e-22);
        /* Continuity across the node at (k + 1) walk_dt. */
        drift_model_eval(&m, (k + 1)*m.walk_dt - h, &x0, &y0);
        ck_assert(fabs(x1 - x0) <= 2.0*h*fabs(vx) + 1e-21);
        if (k > 0) {
            sum2 += (vx - m.v[0] - wx_prev)*(vx - m.v[0] - wx_prev);
            n++;
        }
        else
            ck_assert(fabs(vx - m.v[0]) <= 1e-24);
        wx_prev = vx - m.v[0];
    }
    sigma2 = m.walk_sigma*m.walk_sigma*m.walk_dt;
    ck_assert_msg(fabs(sum2/n/sigma2 - 1.0) < 0.2,
                  "velocity increment variance %g, expected %g",
                  sum2/n, sigma2);
    /* Without sigma the walk adds nothing. */
    drift_model_clear(&m);
    random_walk_model(&m, test_seed);
    m.walk_sigma = 0.0;
    drift_model_prepare(&m, T_MAX);
    assert_eval_equals(&m, 123.4, m.p0[0] + m.v[0]*123.4, m.p0[1] + m.v[1]*123.4);
    drift_model_clear(&m);
}
END_TEST

START_TEST(test_type_names)
{
    DriftModelType type, back;

    for (type = 0; type < DRIFT_MODEL_NTYPES; type++) {
        ck_assert(drift_model_type_from_name(drift_model_type_name(type), &back));
        ck_assert_int_eq(back, type);
    }
    ck_assert_str_eq(drift_model_type_name(DRIFT_MODEL_NONE), "none");
    ck_assert_str_eq(drift_model_type_name(DRIFT_MODEL_SETTLING), "settling");
    ck_assert_str_eq(drift_model_type_name(DRIFT_MODEL_OSCILLATION),
                     "oscillation");
    ck_assert_str_eq(drift_model_type_name(DRIFT_MODEL_JUMP), "jump");
    ck_assert(!drift_model_type_from_name("wobble", &back));
    ck_assert(!drift_model_type_from_name(NULL, &back));
    ck_assert(drift_model_type_name(DRIFT_MODEL_NTYPES) == NULL);
}
END_TEST

/* The creep's velocity is the derivative of p (a central difference away
 * from the fly-backs; the model and times of the creep's formula case), and
 * right after a fly-back the whole lag is back. */
START_TEST(test_frame_creep_velocity)
{
    GRand *rng = g_rand_new_with_seed(test_seed + 5);
    DriftModel m;
    gdouble t, vx, vy, x1, y1, x2, y2, h = 1e-4;
    gint k;

    random_creep_model(&m, rng);
    for (k = 0; k < N_TIMES; k++) {
        t = uniform(rng, 0.0, T_MAX);
        if (fmod(t, m.creep_period) < 2.0*h
            || fmod(t, m.creep_period) > m.creep_period - 2.0*h)
            continue;
        drift_model_velocity(&m, t, &vx, &vy);
        drift_model_eval(&m, t - h, &x1, &y1);
        drift_model_eval(&m, t + h, &x2, &y2);
        ck_assert_msg(fabs(vx - (x2 - x1)/(2.0*h)) < 1e-6*(fabs(vx) + 1e-9)
                      && fabs(vy - (y2 - y1)/(2.0*h)) < 1e-6*(fabs(vy) + 1e-9),
                      "creep velocity at t=%g: (%g, %g)", t, vx, vy);
    }
    t = 3.0*m.creep_period + 1e-6;
    drift_model_eval(&m, t, &x1, &y1);
    ck_assert_msg(fabs(x1 - m.p0[0] - t*m.v[0] - m.creep[0])
                  < 1e-6*fabs(m.creep[0]) + 1e-12*magnitude(&m, T_MAX),
                  "after the fly-back: %g, lag %g", x1 - m.p0[0] - t*m.v[0],
                  m.creep[0]);
    drift_model_clear(&m);
    g_rand_free(rng);
}
END_TEST

/* A freshly initialised model of any type has no drift at all. */
START_TEST(test_init_is_no_drift)
{
    DriftModel m;
    DriftModelType type;
    gdouble px, py;

    for (type = 0; type < DRIFT_MODEL_NTYPES; type++) {
        drift_model_init(&m, type);
        drift_model_prepare(&m, 100.0);
        drift_model_eval(&m, 37.5, &px, &py);
        ck_assert(px == 0.0 && py == 0.0);
        drift_model_velocity(&m, 37.5, &px, &py);
        ck_assert(px == 0.0 && py == 0.0);
        drift_model_clear(&m);
    }
}
END_TEST

static Suite*
drift_model_suite(void)
{
    TCase *tc;
    Suite *s = test_suite_new("drift-model", "core", &tc);

    tcase_add_loop_test(tc, test_formula, 0, G_N_ELEMENTS(formula_cases));
    tcase_add_test(tc, test_jump_boundary);
    tcase_add_test(tc, test_settling_velocity);
    tcase_add_test(tc, test_oscillation_velocity);
    tcase_add_test(tc, test_random_walk_reproducible);
    tcase_add_test(tc, test_random_walk_integral);
    tcase_add_test(tc, test_frame_creep_velocity);
    tcase_add_test(tc, test_type_names);
    tcase_add_test(tc, test_init_is_no_drift);
    return s;
}

int
main(void)
{
    test_seed = test_seed_from_env("test-drift-model");
    return test_run_suite(drift_model_suite());
}
