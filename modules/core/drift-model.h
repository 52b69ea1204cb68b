/*
 *  Drift trajectories p(t) of docs/conventions.md.  A feature
 *  truly at X appears in the image at X + p(t), t the moment its pixel was
 *  scanned; t = 0 is the start of the first frame.  Metres and seconds.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_DRIFT_MODEL_H
#define LOCALSCAN_DRIFT_MODEL_H

#include <glib.h>

G_BEGIN_DECLS

typedef enum {
    DRIFT_MODEL_NONE = 0,      /* p = p0 + v t (the paper's assumption) */
    DRIFT_MODEL_SETTLING,      /* p' = v + u exp(-t/tau) */
    DRIFT_MODEL_OSCILLATION,   /* p = p0 + v t + a sin(2 pi t/period + phase) */
    DRIFT_MODEL_JUMP,          /* p = p0 + v t + step [t >= t_jump] */
    DRIFT_MODEL_RANDOM_WALK,   /* p' = v + w(t), w a seeded random walk */
    DRIFT_MODEL_ACCELERATION,  /* p = p0 + v t + accel t^2/2 */
    DRIFT_MODEL_NTYPES
} DriftModelType;

typedef struct {
    DriftModelType type;
    gdouble p0[2];         /* m */
    gdouble v[2];          /* m/s */
    gdouble u[2];          /* settling: initial excess velocity, m/s */
    gdouble tau;           /* settling: s */
    gdouble a[2];          /* oscillation amplitude, m */
    gdouble period;        /* s */
    gdouble phase;         /* rad */
    gdouble step[2];       /* jump, m */
    gdouble t_jump;        /* s */
    gdouble accel[2];      /* constant acceleration, m/s^2 */
    gdouble walk_sigma;    /* random walk: velocity diffusion, m/s per sqrt(s) */
    gdouble walk_dt;       /* random walk: time step of the path, s */
    guint32 walk_seed;
    /* Frame-start creep, added to any type: after each fly-back of the slow
     * axis (every creep_period s from t = 0) the scanner lags by creep and
     * the lag decays with creep_tau.  creep_period 0: none. */
    gdouble creep[2];      /* m, the lag right after a fly-back */
    gdouble creep_tau;     /* s */
    gdouble creep_period;  /* s, the frame period; 0 = no creep */
    /* private: the random walk's precomputed path */
    gdouble walk_t_end;
    gint walk_n;
    gdouble *walk_p;       /* 2*walk_n positions of the walk part */
} DriftModel;

/* The paper's measured drift velocity, m/s (about 300 s per 256-line image). */
#define DRIFT_MODEL_PAPER_VX 0.08e-9
#define DRIFT_MODEL_PAPER_VY 0.02e-9

/* Sets every field to the model with no drift at all (p0, v, u, a, step,
 * walk_sigma, creep and creep_period zero; tau, period, walk_dt, creep_tau
 * 1 s so the formulas stay finite). */
void          drift_model_init       (DriftModel *model, DriftModelType type);
/* Deep copy (the random walk's path included); dest need not be initialised,
 * and must be cleared afterwards. */
void          drift_model_copy       (DriftModel *dest, const DriftModel *src);
/* Random walk only: precomputes the path over [0, t_end] (replacing any
 * earlier one).  The walk's velocity w starts at 0 and is constant over each
 * step of walk_dt, taking independent N(0, walk_sigma^2 walk_dt) increments
 * per axis, so p is its exact integral (piecewise linear).  Before t = 0 the
 * walk part is 0; after t_end it continues with its last velocity.  Without
 * a path (not prepared) the walk part is 0.  The path holds at most 4M
 * nodes: a walk_dt finer than t_end/4e6 is coarsened to that (g_warning;
 * the diffusion walk_sigma keeps its meaning).  Others: no-op. */
void          drift_model_prepare    (DriftModel *model, gdouble t_end);
void          drift_model_clear      (DriftModel *model);
void          drift_model_eval       (const DriftModel *model, gdouble t,
                                      gdouble *px, gdouble *py);
/* Velocity p'(t), m/s. */
void          drift_model_velocity   (const DriftModel *model, gdouble t,
                                      gdouble *vx, gdouble *vy);
const gchar*  drift_model_type_name  (DriftModelType type);  /* "none", "settling", ... */
gboolean      drift_model_type_from_name(const gchar *name, DriftModelType *type);

G_END_DECLS

#endif
