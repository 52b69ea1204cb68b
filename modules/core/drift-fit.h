/*
 *  Fitting drift trajectories (drift-model.h) to displacement measurements
 *  between frames, and choosing between the models without rewarding extra
 *  parameters for free.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_DRIFT_FIT_H
#define LOCALSCAN_DRIFT_FIT_H

#include <glib.h>
#include "drift-model.h"
#include "drift-measurement.h"

G_BEGIN_DECLS

/* DriftMeasurement (drift-measurement.h): (dx, dy) = p(t_a) - p(t_b) in
 * metres.  A measurement with t_a not later than t_b (frames overlapping in
 * time) is not used. */

/* Slow-creep forms fitted beside the drift models so that a study can
 * compare them on measured data (docs/validation-study.c).  They are no
 * simulator drift models, so drift_fit_select never names them. */
typedef enum {
    DRIFT_FIT_CREEP_NONE = 0,      /* not a creep form: a drift model */
    DRIFT_FIT_CREEP_ACCELERATION,  /* p = v t + b t^2 */
    DRIFT_FIT_CREEP_LOGARITHMIC,   /* p = v t + c t0 log(1 + t/t0), t0
                                      searched like settling's tau */
} DriftFitCreep;

/* A fitted trajectory: p(t) = sum_j coef[axis][j] basis_j(t; nonlinear),
 * with basis_0(t) = t (the constant velocity) and p(0) = 0. */
typedef struct {
    DriftModelType type;
    gboolean ok;
    gint n_basis;          /* basis functions per axis */
    gdouble coef[2][4];    /* nm and s based: nm/s for the velocity */
    gdouble nonlinear;     /* tau, period or t_jump (s); 0 for none */
    gdouble range[2];      /* the interval the nonlinear parameter was
                              searched in (s) */
    gint at_limit;         /* the best grid value was the lowest (-1) or the
                              highest (+1) of that range, else 0 */
    gint n_params;         /* free parameters counted by the criterion */
    gint n_used;           /* scalar measurements used (2 per measurement) */
    gdouble rms_nm;        /* weighted RMS residual of the fit */
    gdouble cv_rms_nm;     /* cross-validated RMS prediction error, NaN if
                              not computed */
    gdouble bic;           /* Bayesian information criterion (lower better) */
    DriftFitCreep creep;   /* a creep form (type is then NONE), else NONE */
} DriftFit;

typedef struct {
    gint n_folds;           /* cross-validation folds over groups (default 5;
                               below 2: no cross-validation, the choice by
                               the criterion and the explained residual
                               alone, several times faster) */
    gdouble bic_margin;     /* an effect must beat "none" by this (default 20) */
    gdouble cv_gain;        /* and predict held-out groups better by this
                               fraction (default 0.1): registration errors
                               are correlated and hundreds of periods or
                               jump times are tried, so the BIC alone is
                               too lenient */
    gdouble min_explained;  /* and explain, beyond constant drift, this many
                               times its own residual RMS (default 1.5) */
    gdouble outlier_sigmas; /* residuals beyond this many robust sigmas are
                               dropped before the final fits (default 5) */
    gdouble outlier_floor_nm; /* and beyond this (the RMS of the two axes):
                               a gross outlier is a failed registration,
                               off by a good part of a pixel (default 0: no
                               floor; fit_report_options_for_series() sets a
                               quarter of the series' pixel where it is 0) */
    gdouble min_period;     /* s, shortest period/tau searched; <= 0: from the
                               measurement times */
    gboolean no_jump_at_frame_gap; /* unused, reserved */
    gdouble min_cycles;     /* an oscillation must show this many cycles
                               over the measured time span (default 1.5) */
} DriftFitOptions;

void           drift_fit_options_init (DriftFitOptions *options);

/* The shortest period or time constant worth searching (s, for
 * DriftFitOptions.min_period) when frames of `lines` lines of line_time s
 * are registered in n_blocks blocks of lines: a block averages the drift
 * over its lines, so periods and time constants shorter than a few blocks
 * cannot be told from registration error. */
gdouble        drift_fit_min_period   (gdouble line_time,
                                       gint lines,
                                       gint n_blocks);

/* The model types drift_fit_select tries, in order; n gets their count. */
const DriftModelType* drift_fit_candidates(gint *n);

/* Fits one model type to n measurements (weighted least squares, the
 * nonlinear parameter by a grid search refined by golden section).  FALSE
 * (fit->ok FALSE) when there are too few usable measurements or the fit is
 * not finite (times so large that their squares overflow, say); such a fit
 * is never selected. */
gboolean       drift_fit_model        (const DriftMeasurement *meas,
                                       gint n,
                                       DriftModelType type,
                                       const DriftFitOptions *options,
                                       DriftFit *fit);

/* Refits fit (of a model with a nonlinear parameter) with that parameter
 * fixed at theta, to the measurements with weight > 0: when something
 * finer than the grid search places it (a jump located line by line).
 * FALSE, fit unchanged, when the model has no such parameter, the
 * solution is not finite, or theta is a jump time the measurements cannot
 * tell from the velocity (fewer than three of them on either side of the
 * split between those it lies within and the others). */
gboolean       drift_fit_refit_at     (const DriftMeasurement *meas,
                                       gint n,
                                       gdouble theta,
                                       DriftFit *fit);

/* The periods an oscillation can be observed with (s): at least
 * min_cycles cycles over the time span of the measurements, and no shorter
 * than twice the longest gap between measured times (shorter periods alias
 * across the gap), nor than min_period.  Only these are searched, and of
 * them only periods that do not cancel between the frames (whole cycles
 * per frame interval: such an oscillation repeats in every frame and no
 * frame series sees it).  FALSE (and no oscillation fitted) when the
 * interval is empty. */
gboolean       drift_fit_observable_periods(const DriftMeasurement *meas,
                                            gint n,
                                            const DriftFitOptions *options,
                                            gdouble *shortest,
                                            gdouble *longest);

/* Cross-validated RMS prediction error (nm): groups split into folds
 * (group modulo n_folds), each fold predicted by the model fitted to the
 * others, its nonlinear parameter searched again (an oscillation's over the
 * periods the whole series can show: a held-out fold's gaps would shut out
 * short periods); NaN when no fold could be fitted.  drift_fit_select
 * fills DriftFit.cv_rms_nm the same way over the measurements it kept. */
gdouble        drift_fit_cross_validate(const DriftMeasurement *meas,
                                        gint n,
                                        DriftModelType type,
                                        const DriftFitOptions *options);

/* Fits a creep form (not DRIFT_FIT_CREEP_NONE) like drift_fit_model and
 * fills fit->cv_rms_nm by the cross-validation of drift_fit_cross_validate.
 * fit->type is DRIFT_MODEL_NONE, fit->creep the form. */
gboolean       drift_fit_creep        (const DriftMeasurement *meas,
                                       gint n,
                                       DriftFitCreep creep,
                                       const DriftFitOptions *options,
                                       DriftFit *fit);

/* Fits every candidate (fits gets drift_fit_candidates' count of entries),
 * drops gross outliers (weights set to 0 in a private copy) and returns the
 * index into fits of the chosen model: the lowest BIC, but an effect only
 * when it beats "none" by bic_margin, predicts held-out groups better by
 * the fraction cv_gain and explains min_explained times its residual; an
 * oscillation only with a period inside the observable range, not at its
 * long end (drift_fit_observable_periods).  Returns -1 when nothing
 * could be fitted. */
gint           drift_fit_select       (const DriftMeasurement *meas,
                                       gint n,
                                       const DriftFitOptions *options,
                                       DriftFit *fits);

/* The same; kept (n entries, may be NULL) says which measurements survived
 * the outlier cut. */
gint           drift_fit_select_kept  (const DriftMeasurement *meas,
                                       gint n,
                                       const DriftFitOptions *options,
                                       DriftFit *fits,
                                       gboolean *kept);

/* p(t) of a fit, metres (p(0) = 0). */
void           drift_fit_eval         (const DriftFit *fit,
                                       gdouble t,
                                       gdouble *px,
                                       gdouble *py);
/* Predicted p(t_a) - p(t_b) of a measurement, metres, each averaged over
 * the measurement's span. */
void           drift_fit_predict      (const DriftFit *fit,
                                       const DriftMeasurement *m,
                                       gdouble *dx,
                                       gdouble *dy);
/* The fit as a simulator drift model (p0 = 0).  An oscillation fitted with
 * independent phases per axis gets the phase of its larger axis and the
 * other axis' signed projection on it.  A creep form has no simulator
 * model: it gives its constant velocity alone. */
void           drift_fit_to_model     (const DriftFit *fit,
                                       DriftModel *model);

/* The reported effect parameters, physical units: tau_s, u_nm_per_s[2]
 * (settling; logarithmic creep: t0 and c, its initial excess velocity);
 * period_s, amplitude_nm[2], phase_rad; t_s, step_nm[2]; accel_nm_per_s2[2]
 * (constant acceleration, 2 b).  Unused fields are NaN. */
typedef struct {
    gdouble velocity_nm_per_s[2];
    gdouble tau_s;
    gdouble u_nm_per_s[2];
    gdouble period_s;
    gdouble amplitude_nm[2];
    gdouble phase_rad;
    gdouble t_s;
    gdouble step_nm[2];
    gdouble accel_nm_per_s2[2];
} DriftFitParameters;

void           drift_fit_parameters   (const DriftFit *fit,
                                       DriftFitParameters *params);

G_END_DECLS

#endif
