/*
 *  The drift trajectory over scan time, built from per-stripe local-scan
 *  measurements.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <math.h>
#include <string.h>
#include <stdlib.h>
#include "drift-trajectory.h"
#include "stripe-geometry.h"

/*
 * Why a not-a-knot cubic spline through the per-stripe positions:
 * thermal drift is smooth, so a C2 interpolant with fourth-order accuracy
 * fits it far better than piecewise-linear or the C1 monotone cubic
 * (which is only third-order and flattens every local extremum, e.g. the
 * turning points of an oscillation).  A natural spline forces p'' = 0 at the
 * first and last stripe centres, and settling drift has its largest
 * curvature exactly at the start of the frame; the not-a-knot condition has
 * no such bias and reproduces any cubic (hence also constant velocity)
 * exactly.  Beyond the end knots the end cubic is followed for half an
 * interval, which covers the outer half of the first and last stripe (the
 * settling test: 0.19 px worst error at the top of the frame with a linear
 * continuation from the stripe centre, 0.03 px with this one), then the
 * trajectory continues linearly with the slope reached there, which keeps
 * extrapolation tame and is also the velocity assumed while the local scans
 * run after the frame.  The price is overshoot around a sudden jump, which
 * no smooth interpolant of stripe samples can resolve anyway.
 *
 * Why the knot values are smoothed first: a local scan's displacement
 * carries the error of the displayed centre found in the image (on
 * simscan's paper scenario 0.13 px RMS, against 0.01 px for the local scan
 * itself), and particles of neighbouring stripes may have been imaged only
 * a line apart, so a spline through the raw values turns that noise into
 * slopes of a pixel per line and overshoots of a pixel and more.  The
 * values are fitted by penalised least squares, the penalty being the
 * squared third divided differences (whose null space, quadratics, keeps
 * constant velocity and constant acceleration unbiased, also at the frame
 * ends), with the weight chosen per axis by generalised cross-validation:
 * noise-free smooth measurements keep their values (within 1e-3 px on the
 * settling test; on very few knots an exact cubic may lose a few per cent
 * of its range), noisy ones are averaged over as many stripes as their
 * scatter asks for.  A gross outlier (a local scan that found a
 * neighbouring particle) is not rejected: it is spread over its
 * neighbours, as the interpolating spline spreads it too.
 */

/* The local scans advance nearly as fast as the stripes are imaged: their
 * drift then cancels from the measurements and cannot be estimated. */
#define LOCAL_VELOCITY_MIN_DENOMINATOR 0.1

enum {
    /* Third differences: quadratics go unpenalised. */
    PENALTY_ORDER = 3,
    /* Fewer knots leave too few residuals to tell noise from drift. */
    SMOOTHING_MIN_KNOTS = PENALTY_ORDER + 3,
    /* Penalty weights tried, log10: from interpolation to a quadratic. */
    SMOOTHING_LOG_MIN = -6,
    SMOOTHING_LOG_MAX = 10,
    SMOOTHING_STEPS_PER_DECADE = 4,
};

/* Penalised least squares over the knot values: minimise
 * sum_i w_i (y_i - f_i)^2 + lambda |D f|^2, D the scaled third divided
 * differences.  W + lambda D'D is a symmetric band matrix of half-width
 * PENALTY_ORDER, factored as L diag L'. */
typedef gdouble PenaltyBandRow[PENALTY_ORDER + 1];

typedef struct {
    gint n;
    const gdouble *w;
    PenaltyBandRow *coeff;     /* D, row r at columns r .. r+PENALTY_ORDER */
    PenaltyBandRow *band;      /* D'D: band[i][k] = (D'D)_{i,i+k} */
    PenaltyBandRow *lower;     /* L: lower[i][k] = L_{i,i-k} */
    gdouble *pivot;            /* diag */
    PenaltyBandRow *inverse;   /* M^-1 within the band */
    gdouble *fit;
} Smoother;

struct _DriftTrajectory {
    gint n;              /* knots */
    gdouble *t;          /* n strictly increasing knot times */
    gdouble *value[2];   /* D at the knots, x and y */
    gdouble *curv[2];    /* D'' at the knots */
    gdouble t_ref;
    gdouble v_local[2];
    gboolean is_zero;
};

GQuark
drift_trajectory_error_quark(void)
{
    return g_quark_from_static_string("drift-trajectory-error-quark");
}

/* Solves a tridiagonal system in place (Thomas algorithm): sub, diag, sup
 * are the three diagonals, rhs becomes the solution. */
static void
solve_tridiagonal(gint n, const gdouble *sub, gdouble *diag,
                  const gdouble *sup, gdouble *rhs)
{
    gint i;
    gdouble q;

    for (i = 1; i < n; i++) {
        q = sub[i]/diag[i-1];
        diag[i] -= q*sup[i-1];
        rhs[i] -= q*rhs[i-1];
    }
    rhs[n-1] /= diag[n-1];
    for (i = n-2; i >= 0; i--)
        rhs[i] = (rhs[i] - sup[i]*rhs[i+1])/diag[i];
}

/* Second derivatives of the not-a-knot cubic spline through (t, y).  The
 * end conditions eliminate curv[0] and curv[n-1], leaving a tridiagonal
 * system for the interior knots. */
static void
spline_not_a_knot_curvatures(gint n, const gdouble *t, const gdouble *y,
                             gdouble *curv)
{
    gdouble *h, *sub, *diag, *sup, *rhs;
    gint i, m;

    if (n <= 2) {
        for (i = 0; i < n; i++)
            curv[i] = 0.0;
        return;
    }
    h = g_new(gdouble, n-1);
    for (i = 0; i < n-1; i++)
        h[i] = t[i+1] - t[i];
    if (n == 3) {
        /* The not-a-knot spline through three points is their parabola. */
        gdouble c = 2.0*((y[2] - y[1])/h[1] - (y[1] - y[0])/h[0])/(h[0] + h[1]);
        curv[0] = curv[1] = curv[2] = c;
        g_free(h);
        return;
    }

    m = n - 2;
    sub = g_new0(gdouble, 4*m);
    diag = sub + m;
    sup = diag + m;
    rhs = sup + m;
    for (i = 1; i <= m; i++) {
        sub[i-1] = h[i-1];
        diag[i-1] = 2.0*(h[i-1] + h[i]);
        sup[i-1] = h[i];
        rhs[i-1] = 6.0*((y[i+1] - y[i])/h[i] - (y[i] - y[i-1])/h[i-1]);
    }
    /* curv[0] = ((h0 + h1) curv[1] - h0 curv[2])/h1 folded into row 1. */
    diag[0] = (h[0] + h[1])*(h[0] + 2.0*h[1])/h[1];
    sup[0] = (h[1]*h[1] - h[0]*h[0])/h[1];
    /* The same at the far end. */
    sub[m-1] = (h[n-3]*h[n-3] - h[n-2]*h[n-2])/h[n-3];
    diag[m-1] = (h[n-3] + h[n-2])*(2.0*h[n-3] + h[n-2])/h[n-3];
    solve_tridiagonal(m, sub, diag, sup, rhs);

    for (i = 1; i <= m; i++)
        curv[i] = rhs[i-1];
    curv[0] = ((h[0] + h[1])*curv[1] - h[0]*curv[2])/h[1];
    curv[n-1] = ((h[n-3] + h[n-2])*curv[n-2] - h[n-2]*curv[n-3])/h[n-3];
    g_free(sub);
    g_free(h);
}

/* Index i of the knot interval [t[i], t[i+1]] holding t, clamped. */
static gint
find_interval(const DriftTrajectory *trajectory, gdouble t)
{
    gint lo = 0, hi = trajectory->n - 1, mid;

    while (hi - lo > 1) {
        mid = (lo + hi)/2;
        if (trajectory->t[mid] <= t)
            lo = mid;
        else
            hi = mid;
    }
    return lo;
}

/* Value and derivative of the spline of one axis on interval i. */
static void
spline_eval_interval(const DriftTrajectory *trajectory, gint axis, gint i,
                     gdouble t, gdouble *value, gdouble *slope)
{
    const gdouble *y = trajectory->value[axis], *c = trajectory->curv[axis];
    gdouble h = trajectory->t[i+1] - trajectory->t[i];
    gdouble a = (trajectory->t[i+1] - t)/h, b = (t - trajectory->t[i])/h;

    /* Written from y[i] so that a constant trajectory is exactly
     * constant (whole-pixel shifts must stay whole). */
    *value = (y[i] + b*(y[i+1] - y[i])
              + ((a*a*a - a)*c[i] + (b*b*b - b)*c[i+1])*h*h/6.0);
    *slope = ((y[i+1] - y[i])/h
              + ((1.0 - 3.0*a*a)*c[i] + (3.0*b*b - 1.0)*c[i+1])*h/6.0);
}

/* Where the linear continuation starts: half the end interval beyond each
 * end knot (on the frame edge for evenly cut stripes measured at their
 * centres). */
static gdouble
continuation_start(const gdouble *t, gint n, gboolean at_end)
{
    if (at_end)
        return t[n-1] + 0.5*(t[n-1] - t[n-2]);
    return t[0] - 0.5*(t[1] - t[0]);
}

static void
spline_eval(const DriftTrajectory *trajectory, gint axis, gdouble t,
            gdouble *value, gdouble *slope)
{
    const gdouble *knots = trajectory->t;
    gint n = trajectory->n;
    gdouble tlin;

    if (n == 1) {
        *value = trajectory->value[axis][0];
        *slope = 0.0;
        return;
    }
    if (t < knots[0]) {
        tlin = continuation_start(knots, n, FALSE);
        spline_eval_interval(trajectory, axis, 0, MAX(t, tlin), value, slope);
        if (t < tlin)
            *value += (t - tlin)*(*slope);
        return;
    }
    if (t > knots[n-1]) {
        tlin = continuation_start(knots, n, TRUE);
        spline_eval_interval(trajectory, axis, n-2, MIN(t, tlin),
                             value, slope);
        if (t > tlin)
            *value += (t - tlin)*(*slope);
        return;
    }
    spline_eval_interval(trajectory, axis, find_interval(trajectory, t), t,
                         value, slope);
}

/* D: third divided differences scaled by 6 h^3 (h the mean knot spacing),
 * so that on evenly spaced knots a row is (-1, 3, -3, 1). */
static void
smoother_init(Smoother *smoother, gint n, const gdouble *t, const gdouble *w)
{
    gint r, j, k, i;
    gdouble h = (t[n-1] - t[0])/(n - 1), scale = 1.0, prod;

    smoother->n = n;
    smoother->w = w;
    smoother->coeff = g_new0(PenaltyBandRow, n - PENALTY_ORDER);
    smoother->band = g_new0(PenaltyBandRow, n);
    smoother->lower = g_new0(PenaltyBandRow, n);
    smoother->inverse = g_new0(PenaltyBandRow, n);
    smoother->pivot = g_new(gdouble, 2*n);
    smoother->fit = smoother->pivot + n;
    for (k = 1; k <= PENALTY_ORDER; k++)
        scale *= k*h;
    for (r = 0; r < n - PENALTY_ORDER; r++) {
        for (j = 0; j <= PENALTY_ORDER; j++) {
            prod = 1.0;
            for (k = 0; k <= PENALTY_ORDER; k++) {
                if (k != j)
                    prod *= t[r+j] - t[r+k];
            }
            smoother->coeff[r][j] = scale/prod;
        }
        for (j = 0; j <= PENALTY_ORDER; j++) {
            i = r + j;
            for (k = 0; j + k <= PENALTY_ORDER; k++)
                smoother->band[i][k] += smoother->coeff[r][j]*smoother->coeff[r][j+k];
        }
    }
}

static void
smoother_clear(Smoother *smoother)
{
    g_free(smoother->coeff);
    g_free(smoother->band);
    g_free(smoother->lower);
    g_free(smoother->inverse);
    g_free(smoother->pivot);
}

/* Factors W + lambda D'D = L diag L'. */
static void
smoother_factor(Smoother *smoother, gdouble lambda)
{
    PenaltyBandRow *lower = smoother->lower;
    gdouble *pivot = smoother->pivot, sum;
    gint n = smoother->n, i, j, k, m;

    for (j = 0; j < n; j++) {
        sum = smoother->w[j] + lambda*smoother->band[j][0];
        for (k = 1; k <= PENALTY_ORDER && j - k >= 0; k++)
            sum -= lower[j][k]*lower[j][k]*pivot[j-k];
        pivot[j] = sum;
        for (i = j + 1; i <= MIN(n - 1, j + PENALTY_ORDER); i++) {
            sum = lambda*smoother->band[j][i-j];
            for (m = 1; j - m >= 0 && i - (j - m) <= PENALTY_ORDER; m++)
                sum -= lower[i][i-j+m]*lower[j][m]*pivot[j-m];
            lower[i][i-j] = sum/pivot[j];
        }
    }
}

/* fit = (W + lambda D'D)^-1 W y with the current factors. */
static void
smoother_solve(Smoother *smoother, const gdouble *y)
{
    PenaltyBandRow *lower = smoother->lower;
    gdouble *f = smoother->fit;
    gint n = smoother->n, i, k;

    for (i = 0; i < n; i++) {
        f[i] = smoother->w[i]*y[i];
        for (k = 1; k <= PENALTY_ORDER && i - k >= 0; k++)
            f[i] -= lower[i][k]*f[i-k];
    }
    for (i = n - 1; i >= 0; i--) {
        f[i] /= smoother->pivot[i];
        for (k = 1; k <= PENALTY_ORDER && i + k < n; k++)
            f[i] -= lower[i+k][k]*f[i+k];
    }
}

/* Trace of the influence matrix (W + lambda D'D)^-1 W: the band of the
 * inverse from the factors, backwards (Takahashi's recurrence), O(n). */
static gdouble
smoother_trace(Smoother *smoother)
{
    PenaltyBandRow *lower = smoother->lower;
    PenaltyBandRow *inv = smoother->inverse;
    gdouble trace = 0.0, sum;
    gint n = smoother->n, i, j, k, last;

    for (i = n - 1; i >= 0; i--) {
        last = MIN(n - 1, i + PENALTY_ORDER);
        for (j = last; j > i; j--) {
            sum = 0.0;
            for (k = i + 1; k <= last; k++)
                sum -= lower[k][k-i]*(k <= j ? inv[k][j-k] : inv[j][k-j]);
            inv[i][j-i] = sum;
        }
        sum = 1.0/smoother->pivot[i];
        for (k = i + 1; k <= last; k++)
            sum -= lower[k][k-i]*inv[i][k-i];
        inv[i][0] = sum;
        trace += smoother->w[i]*sum;
    }
    return trace;
}

/* Sets smoother->fit to the penalised least-squares fit of y with the
 * weight that minimises the generalised cross-validation score
 * n RSS/(n - trace)^2.  Constant values are fitted exactly. */
static void
smoother_fit(Smoother *smoother, const gdouble *y)
{
    gint n = smoother->n, i, step;
    gdouble best_score = G_MAXDOUBLE, best_lambda = 0.0, lambda, rss;
    gdouble wsum = 0.0, trace, score, e;
    gboolean constant = TRUE;

    for (i = 1; i < n; i++)
        constant = constant && (y[i] == y[0]);
    if (constant) {
        memcpy(smoother->fit, y, n*sizeof(gdouble));
        return;
    }
    for (i = 0; i < n; i++)
        wsum += smoother->w[i];
    for (step = SMOOTHING_LOG_MIN*SMOOTHING_STEPS_PER_DECADE;
         step <= SMOOTHING_LOG_MAX*SMOOTHING_STEPS_PER_DECADE; step++) {
        lambda = pow(10.0, step/(gdouble)SMOOTHING_STEPS_PER_DECADE);
        smoother_factor(smoother, lambda);
        smoother_solve(smoother, y);
        trace = smoother_trace(smoother);
        rss = 0.0;
        for (i = 0; i < n; i++) {
            e = y[i] - smoother->fit[i];
            rss += smoother->w[i]*e*e;
        }
        score = wsum*rss/((wsum - trace)*(wsum - trace));
        if (score < best_score) {
            best_score = score;
            best_lambda = lambda;
        }
    }
    smoother_factor(smoother, best_lambda);
    smoother_solve(smoother, y);
}

static gint
compare_by_image_time(gconstpointer pa, gconstpointer pb)
{
    const DriftMeasurement *a = pa, *b = pb;

    if (a->t_image < b->t_image)
        return -1;
    return a->t_image > b->t_image;
}

/* Slope of the not-a-knot spline through (t, y) where its linear
 * continuation after the last knot starts. */
static gdouble
spline_end_slope(gint n, const gdouble *t, const gdouble *y)
{
    gdouble *curv, h, a, b, slope;

    if (n < 2)
        return 0.0;
    curv = g_new(gdouble, n);
    spline_not_a_knot_curvatures(n, t, y, curv);
    h = t[n-1] - t[n-2];
    a = (t[n-1] - continuation_start(t, n, TRUE))/h;
    b = 1.0 - a;
    slope = ((y[n-1] - y[n-2])/h
             + ((1.0 - 3.0*a*a)*curv[n-2] + (3.0*b*b - 1.0)*curv[n-1])*h/6.0);
    g_free(curv);
    return slope;
}

/* The positions at the image times are p(t_image) - p(t_ref)
 * = m + p(t_local) - p(t_ref), so the drift during the local scans is
 * needed.  The local scans come after the frame, where the trajectory
 * continues linearly with its end slope; so the local-scan velocity v is
 * the end slope of the spline through m + v tau, tau = t_local - t_ref,
 * which is linear in v: v = m'/(1 - tau').  When the local scans advance
 * nearly as fast as the stripes were imaged, their drift cancels from the
 * measurements, cannot be estimated, and is taken as zero. */
static void
estimate_local_velocity(DriftTrajectory *trajectory, const gdouble *tau)
{
    gint n = trajectory->n, axis;
    gdouble tau_slope = spline_end_slope(n, trajectory->t, tau);

    for (axis = 0; axis < 2; axis++) {
        trajectory->v_local[axis] = 0.0;
        if (1.0 - tau_slope >= LOCAL_VELOCITY_MIN_DENOMINATOR) {
            trajectory->v_local[axis]
                = (spline_end_slope(n, trajectory->t, trajectory->value[axis])
                   /(1.0 - tau_slope));
        }
    }
}

static gboolean
check_measurements(const DriftMeasurement *meas, gint n, GError **error)
{
    gint i;

    if (n < 1) {
        g_set_error(error, DRIFT_TRAJECTORY_ERROR, DRIFT_TRAJECTORY_ERROR_EMPTY,
                    "no stripe has a drift measurement");
        return FALSE;
    }
    for (i = 0; i < n; i++) {
        if (!isfinite(meas[i].t_image) || !isfinite(meas[i].t_local)
            || !isfinite(meas[i].dx) || !isfinite(meas[i].dy)) {
            g_set_error(error, DRIFT_TRAJECTORY_ERROR,
                        DRIFT_TRAJECTORY_ERROR_VALUE,
                        "drift measurement %d is not a finite number", i);
            return FALSE;
        }
    }
    return TRUE;
}

/* Smooths the knot values of both axes (weights: measurements per knot). */
static void
smooth_knots(DriftTrajectory *trajectory, const gdouble *weights)
{
    gint n = trajectory->n, axis;
    Smoother smoother;

    smoother_init(&smoother, n, trajectory->t, weights);
    for (axis = 0; axis < 2; axis++) {
        smoother_fit(&smoother, trajectory->value[axis]);
        memcpy(trajectory->value[axis], smoother.fit, n*sizeof(gdouble));
    }
    smoother_clear(&smoother);
}

static DriftTrajectory*
trajectory_new(const DriftMeasurement *meas, gint n, gboolean smooth,
               GError **error)
{
    DriftTrajectory *trajectory;
    DriftMeasurement *sorted;
    gdouble *tau, *weights;
    gdouble sum[3];
    gint i, k, j, axis;

    if (!check_measurements(meas, n, error))
        return NULL;

    sorted = g_memdup2(meas, n*sizeof(DriftMeasurement));
    qsort(sorted, n, sizeof(DriftMeasurement), compare_by_image_time);
    trajectory = g_new0(DriftTrajectory, 1);
    trajectory->t_ref = sorted[0].t_local;
    for (i = 1; i < n; i++)
        trajectory->t_ref = MIN(trajectory->t_ref, sorted[i].t_local);

    trajectory->t = g_new(gdouble, 5*n);
    trajectory->value[0] = trajectory->t + n;
    trajectory->value[1] = trajectory->value[0] + n;
    trajectory->curv[0] = trajectory->value[1] + n;
    trajectory->curv[1] = trajectory->curv[0] + n;
    tau = g_new(gdouble, 2*n);
    weights = tau + n;
    /* Measurements at the same image time are averaged into one knot. */
    for (i = 0; i < n; i = k) {
        sum[0] = sum[1] = sum[2] = 0.0;
        for (k = i; k < n && sorted[k].t_image == sorted[i].t_image; k++) {
            sum[0] += sorted[k].dx;
            sum[1] += sorted[k].dy;
            sum[2] += sorted[k].t_local - trajectory->t_ref;
        }
        j = trajectory->n++;
        trajectory->t[j] = sorted[i].t_image;
        trajectory->value[0][j] = sum[0]/(k - i);
        trajectory->value[1][j] = sum[1]/(k - i);
        tau[j] = sum[2]/(k - i);
        weights[j] = k - i;
    }
    g_free(sorted);

    if (smooth && trajectory->n >= SMOOTHING_MIN_KNOTS)
        smooth_knots(trajectory, weights);
    estimate_local_velocity(trajectory, tau);
    trajectory->is_zero = TRUE;
    for (axis = 0; axis < 2; axis++) {
        for (j = 0; j < trajectory->n; j++) {
            trajectory->value[axis][j] += trajectory->v_local[axis]*tau[j];
            if (trajectory->value[axis][j] != 0.0)
                trajectory->is_zero = FALSE;
        }
        spline_not_a_knot_curvatures(trajectory->n, trajectory->t,
                                     trajectory->value[axis],
                                     trajectory->curv[axis]);
    }
    g_free(tau);
    return trajectory;
}

DriftTrajectory*
drift_trajectory_new(const DriftMeasurement *meas, gint n, GError **error)
{
    return trajectory_new(meas, n, TRUE, error);
}

DriftTrajectory*
drift_trajectory_new_interpolating(const DriftMeasurement *meas, gint n,
                                   GError **error)
{
    return trajectory_new(meas, n, FALSE, error);
}

static gboolean
check_timing(const DriftTable *table, const ScanTiming *timing,
             GError **error)
{
    if (timing->xres < 1 || timing->yres < 1
        || !isfinite(timing->line_time) || timing->line_time <= 0.0
        || !isfinite(timing->frame_start)) {
        g_set_error(error, DRIFT_TRAJECTORY_ERROR,
                    DRIFT_TRAJECTORY_ERROR_TIMING,
                    "%s: scan timing is unusable (line time %g s, "
                    "%d x %d pixels)",
                    table->source_name ? table->source_name : "drift table",
                    timing->line_time, timing->xres, timing->yres);
        return FALSE;
    }
    return drift_table_check_image(table, timing->yres, error);
}

/* The value of an extra column, or fallback when the column is blank or
 * absent; FALSE when it holds anything but a finite number. */
static gboolean
extra_or_default(const DriftTable *table, gint s, const gchar *name,
                 gdouble fallback, gdouble *value, GError **error)
{
    gint j = drift_table_find_column(table, name);

    if (drift_table_get_extra(table, s, name, value) && isfinite(*value))
        return TRUE;
    if (j < 0 || !*table->extra_values[s*table->n_extra + j]) {
        *value = fallback;
        return TRUE;
    }
    g_set_error(error, DRIFT_TRAJECTORY_ERROR, DRIFT_TRAJECTORY_ERROR_VALUE,
                "%s:%d: %s is not a finite number",
                table->source_name ? table->source_name : "drift table",
                table->rows[s].line, name);
    return FALSE;
}

gint
drift_trajectory_measurements_from_table(const DriftTable *table,
                                         gdouble x_pixel_size,
                                         gdouble y_pixel_size,
                                         const ScanTiming *timing,
                                         DriftMeasurement *meas,
                                         GError **error)
{
    gint n = table->n_stripes, yres = timing->yres, s, count = 0;
    gdouble *dx_px, *dy_px;
    gdouble t_centre, t_end, dx_exact, dy_exact;
    gboolean ok = TRUE;

    if (!check_timing(table, timing, error))
        return -1;
    dx_px = g_new(gdouble, 2*n);
    dy_px = dx_px + n;
    /* Converts units; the nearest-stripe values it fills in are ignored
     * below, blank stripes are simply not measured here. */
    if (!drift_table_to_pixels(table, yres, x_pixel_size, y_pixel_size,
                               FALSE, dx_px, dy_px, error)) {
        g_free(dx_px);
        return -1;
    }
    t_end = scan_timing_frame_end(timing);
    for (s = 0; s < n && ok; s++) {
        if (!table->rows[s].has_drift)
            continue;
        t_centre = scan_timing_rows_time(timing,
                                         stripe_first_row(s, n, yres),
                                         stripe_end_row(s, n, yres));
        ok = (extra_or_default(table, s, "t_image", t_centre,
                               &meas[count].t_image, error)
              && extra_or_default(table, s, "t_local", t_end,
                                  &meas[count].t_local, error)
              && extra_or_default(table, s, "dx_exact", dx_px[s],
                                  &dx_exact, error)
              && extra_or_default(table, s, "dy_exact", dy_px[s],
                                  &dy_exact, error));
        meas[count].dx = dx_exact;
        meas[count].dy = dy_exact;
        count++;
    }
    g_free(dx_px);
    return ok ? count : -1;
}

DriftTrajectory*
drift_trajectory_new_from_table(const DriftTable *table,
                                gdouble x_pixel_size,
                                gdouble y_pixel_size,
                                const ScanTiming *timing,
                                GError **error)
{
    DriftMeasurement *meas;
    DriftTrajectory *trajectory = NULL;
    gint n;

    meas = g_new(DriftMeasurement, MAX(table->n_stripes, 1));
    n = drift_trajectory_measurements_from_table(table, x_pixel_size,
                                                 y_pixel_size, timing,
                                                 meas, error);
    if (n >= 0)
        trajectory = drift_trajectory_new(meas, n, error);
    g_free(meas);
    return trajectory;
}

void
drift_trajectory_free(DriftTrajectory *trajectory)
{
    if (!trajectory)
        return;
    g_free(trajectory->t);
    g_free(trajectory);
}

void
drift_trajectory_eval(const DriftTrajectory *trajectory, gdouble t,
                      gdouble *dx, gdouble *dy)
{
    gdouble slope;

    spline_eval(trajectory, 0, t, dx, &slope);
    spline_eval(trajectory, 1, t, dy, &slope);
}

void
drift_trajectory_velocity(const DriftTrajectory *trajectory, gdouble t,
                          gdouble *vx, gdouble *vy)
{
    gdouble value;

    spline_eval(trajectory, 0, t, &value, vx);
    spline_eval(trajectory, 1, t, &value, vy);
}

gdouble
drift_trajectory_reference_time(const DriftTrajectory *trajectory)
{
    return trajectory->t_ref;
}

void
drift_trajectory_local_velocity(const DriftTrajectory *trajectory,
                                gdouble *vx, gdouble *vy)
{
    *vx = trajectory->v_local[0];
    *vy = trajectory->v_local[1];
}

gboolean
drift_trajectory_is_zero(const DriftTrajectory *trajectory)
{
    return trajectory->is_zero;
}
