/*
 *  A flexible drift trajectory for drift no model of drift-model.h
 *  explains (a random walk, creep of no simple form): p(t) piecewise linear
 *  between knots, fitted to displacement measurements (drift-measurement.h)
 *  with a penalty on its curvature whose weight is chosen by held-out
 *  error (docs/series.md).
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_SMOOTH_TRAJECTORY_H
#define LOCALSCAN_SMOOTH_TRAJECTORY_H

#include <glib.h>
#include "drift-measurement.h"

G_BEGIN_DECLS

typedef struct {
    gint n_knots;
    gdouble *t;            /* knot times, s, ascending */
    gdouble *p[2];         /* the spline s at the knots, m; s at the first
                              knot is 0, p(t) = s(t) - s(0) */
    gdouble lambda;        /* the curvature penalty chosen (relative) */
    gdouble rms_nm;        /* weighted RMS residual of the fit */
    gdouble cv_rms_nm;     /* held-out RMS prediction error */
    gint n_used;           /* measurements used */
} SmoothTrajectory;

/* Fits the spline at the knots (n_knots times, ascending, where the
 * measurements are, at most SMOOTH_TRAJECTORY_MAX_KNOTS) to the
 * measurements (metres; weight 0: unused; each averaged over its span),
 * the penalty weight chosen among a range by n_folds-fold cross-validation
 * over the measurements' groups.  Differences fix the spline up to a
 * constant, so s is 0 at the first knot and p(t) = s(t) - s(0), s(0)
 * continued from the first knots: a knot at t = 0, where nothing is
 * measured, would leave the whole trajectory's level to the penalty.
 * NULL when fewer measurements than knots are usable or the system is
 * singular. */
SmoothTrajectory* smooth_trajectory_fit  (const DriftMeasurement *meas,
                                          gint n,
                                          const gdouble *knots,
                                          gint n_knots,
                                          gint n_folds);

#define SMOOTH_TRAJECTORY_MAX_KNOTS 1200

/* p(t) = s(t) - s(0), metres: linear between knots, the end segments
 * continued. */
void              smooth_trajectory_eval (const SmoothTrajectory *trajectory,
                                          gdouble t,
                                          gdouble *px,
                                          gdouble *py);

/* Predicted p(t_a) - p(t_b) of a measurement (averaged over its span). */
void              smooth_trajectory_predict(const SmoothTrajectory *trajectory,
                                            const DriftMeasurement *m,
                                            gdouble *dx,
                                            gdouble *dy);

void              smooth_trajectory_free (SmoothTrajectory *trajectory);

G_END_DECLS

#endif
