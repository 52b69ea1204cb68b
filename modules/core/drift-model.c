/*
 *  Drift trajectories p(t) of docs/conventions.md.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <string.h>
#include <math.h>
#include "drift-model.h"
#include "sim-random.h"

/* 4M nodes, 64 MB of path; a finer walk_dt over a long time is coarsened. */
#define RANDOM_WALK_MAX_NODES 4194304

static const gchar *const drift_model_names[DRIFT_MODEL_NTYPES] = {
    "none", "settling", "oscillation", "jump", "random-walk", "acceleration",
};

void
drift_model_init(DriftModel *model, DriftModelType type)
{
    memset(model, 0, sizeof(DriftModel));
    model->type = type;
    model->tau = 1.0;
    model->period = 1.0;
    model->walk_dt = 1.0;
    model->creep_tau = 1.0;
}

void
drift_model_copy(DriftModel *dest, const DriftModel *src)
{
    *dest = *src;
    if (src->walk_p)
        dest->walk_p = g_memdup2(src->walk_p, 2*src->walk_n*sizeof(gdouble));
}

void
drift_model_clear(DriftModel *model)
{
    g_free(model->walk_p);
    model->walk_p = NULL;
    model->walk_n = 0;
    model->walk_t_end = 0.0;
}

/* Node k of the path is the walk's displacement at t = k walk_dt; the
 * velocity over step k is w_k, so the displacement is its exact integral. */
void
drift_model_prepare(DriftModel *model, gdouble t_end)
{
    SimRandom rng;
    gdouble w[2] = { 0.0, 0.0 }, kick;
    gint k, n;

    if (model->type != DRIFT_MODEL_RANDOM_WALK)
        return;
    g_return_if_fail(model->walk_dt > 0.0);
    drift_model_clear(model);
    t_end = MAX(t_end, 0.0);
    if (t_end/model->walk_dt > RANDOM_WALK_MAX_NODES - 2) {
        g_warning("simscan: random walk step %g s over %g s needs too many "
                  "nodes; using %g s", model->walk_dt, t_end,
                  t_end/(RANDOM_WALK_MAX_NODES - 2));
        model->walk_dt = t_end/(RANDOM_WALK_MAX_NODES - 2);
    }
    n = (gint)ceil(t_end/model->walk_dt) + 2;
    model->walk_n = n;
    model->walk_t_end = t_end;
    model->walk_p = g_new(gdouble, 2*n);
    model->walk_p[0] = model->walk_p[1] = 0.0;
    sim_random_init(&rng, model->walk_seed, 0x77a1);
    kick = model->walk_sigma*sqrt(model->walk_dt);
    for (k = 1; k < n; k++) {
        model->walk_p[2*k] = model->walk_p[2*k - 2] + w[0]*model->walk_dt;
        model->walk_p[2*k + 1] = model->walk_p[2*k - 1] + w[1]*model->walk_dt;
        w[0] += kick*sim_random_gaussian(&rng);
        w[1] += kick*sim_random_gaussian(&rng);
    }
}

/* Walk velocity over the step holding t (the last step continues beyond the
 * path; nothing before t = 0). */
static gint
random_walk_step(const DriftModel *model, gdouble t)
{
    gint k;

    if (!model->walk_p || t < 0.0)
        return -1;
    k = (gint)floor(t/model->walk_dt);
    return MIN(k, model->walk_n - 2);
}

static void
random_walk_step_velocity(const DriftModel *model, gint k,
                          gdouble *wx, gdouble *wy)
{
    const gdouble *p = model->walk_p + 2*k;

    *wx = (p[2] - p[0])/model->walk_dt;
    *wy = (p[3] - p[1])/model->walk_dt;
}

static void
random_walk_eval(const DriftModel *model, gdouble t, gdouble *px, gdouble *py)
{
    gint k = random_walk_step(model, t);
    gdouble wx, wy, s;

    if (k < 0) {
        *px = *py = 0.0;
        return;
    }
    random_walk_step_velocity(model, k, &wx, &wy);
    s = t - k*model->walk_dt;
    *px = model->walk_p[2*k] + wx*s;
    *py = model->walk_p[2*k + 1] + wy*s;
}

/* The creep's decay factor at t and the time since its fly-back; 0 before
 * t = 0 and without creep. */
static gdouble
frame_creep_decay(const DriftModel *model, gdouble t)
{
    if (!(model->creep_period > 0.0) || t < 0.0)
        return 0.0;
    return exp(-fmod(t, model->creep_period)/model->creep_tau);
}

void
drift_model_eval(const DriftModel *model, gdouble t,
                 gdouble *px, gdouble *py)
{
    gdouble x = model->p0[0] + model->v[0]*t, y = model->p0[1] + model->v[1]*t;
    gdouble f, wx, wy;

    switch (model->type) {
        case DRIFT_MODEL_SETTLING:
        f = model->tau*(-expm1(-t/model->tau));
        x += model->u[0]*f;
        y += model->u[1]*f;
        break;

        case DRIFT_MODEL_OSCILLATION:
        f = sin(2.0*G_PI*t/model->period + model->phase);
        x += model->a[0]*f;
        y += model->a[1]*f;
        break;

        case DRIFT_MODEL_JUMP:
        if (t >= model->t_jump) {
            x += model->step[0];
            y += model->step[1];
        }
        break;

        case DRIFT_MODEL_RANDOM_WALK:
        random_walk_eval(model, t, &wx, &wy);
        x += wx;
        y += wy;
        break;

        case DRIFT_MODEL_ACCELERATION:
        x += 0.5*model->accel[0]*t*t;
        y += 0.5*model->accel[1]*t*t;
        break;

        default:
        break;
    }
    f = frame_creep_decay(model, t);
    *px = x + model->creep[0]*f;
    *py = y + model->creep[1]*f;
}

void
drift_model_velocity(const DriftModel *model, gdouble t,
                     gdouble *vx, gdouble *vy)
{
    gdouble x = model->v[0], y = model->v[1], f, wx, wy;
    gint k;

    switch (model->type) {
        case DRIFT_MODEL_SETTLING:
        f = exp(-t/model->tau);
        x += model->u[0]*f;
        y += model->u[1]*f;
        break;

        case DRIFT_MODEL_OSCILLATION:
        f = 2.0*G_PI/model->period;
        f *= cos(2.0*G_PI*t/model->period + model->phase);
        x += model->a[0]*f;
        y += model->a[1]*f;
        break;

        case DRIFT_MODEL_RANDOM_WALK:
        if ((k = random_walk_step(model, t)) >= 0) {
            random_walk_step_velocity(model, k, &wx, &wy);
            x += wx;
            y += wy;
        }
        break;

        case DRIFT_MODEL_ACCELERATION:
        x += model->accel[0]*t;
        y += model->accel[1]*t;
        break;

        default:
        /* The jump's step is a position discontinuity, not a velocity. */
        break;
    }
    f = -frame_creep_decay(model, t)/model->creep_tau;
    *vx = x + model->creep[0]*f;
    *vy = y + model->creep[1]*f;
}

const gchar*
drift_model_type_name(DriftModelType type)
{
    if ((guint)type >= DRIFT_MODEL_NTYPES)
        return NULL;
    return drift_model_names[type];
}

gboolean
drift_model_type_from_name(const gchar *name, DriftModelType *type)
{
    guint i;

    for (i = 0; i < DRIFT_MODEL_NTYPES; i++) {
        if (name && g_ascii_strcasecmp(name, drift_model_names[i]) == 0) {
            if (type)
                *type = (DriftModelType)i;
            return TRUE;
        }
    }
    return FALSE;
}
