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
#include <libgwyddion/gwymath.h>
#include "drift-trajectory.h"
#include "quoted-input.h"
#include "median.h"
#include "stripe-geometry.h"
#include "localscan-intl.h"

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
 * ends).  Between close knots the divided differences are large, so the
 * penalty itself averages them instead of letting them set the slope.
 *
 * Why robustly, and how the penalty weight is chosen: a local scan that
 * found a neighbouring particle is off by several pixels, and a
 * least-squares fit spreads that over the neighbouring stripes (and into
 * the end slope, hence the local-scan velocity).  So the fit is iteratively
 * reweighted (Huber's weights, then Tukey's biweight on the residuals
 * standardised by their leverage, scale from the median absolute residual
 * but never below the 0.1 px a displayed centre is found to), and one or
 * two gross errors get weight 0.  The penalty weight is chosen per axis
 * together with the robust weights: generalised cross-validation on 16
 * noisy knots often picks a fit that follows the noise (its score degenerates
 * where the trace nears the number of knots), whose end slope is then off
 * by 0.05-0.1 px/s and moves the last half stripe by a pixel.  Instead the
 * noise variance is estimated by robust leave-one-out cross-validation and
 * the weight minimises a robust Mallows' C_p that prices each degree of
 * freedom at 1.4 times its expected cost.  Noisy data are smoothed as far
 * as their scatter asks for.  Exact data keep their values: constant
 * velocity (zero estimated noise) exactly, and curved drift sampled densely
 * enough, such as settling on 16 stripes, is interpolated, since there the
 * estimated noise is the smoothing's own bias (estimate_is_bias()).
 * Exact data too sparse or irregular for that check to tell from noise of
 * a hundredth of a pixel are smoothed like such noise.  In a
 * fit's loss a rejected measurement costs a fixed amount, so rejecting
 * good data never pays.  A genuine sudden change at the first or last
 * stripe cannot be told from a gross error there and is treated as one.
 */

/* The local scans advance nearly as fast as the stripes are imaged: their
 * drift then cancels from the measurements and cannot be estimated. */
#define LOCAL_VELOCITY_MIN_DENOMINATOR 0.1

/* The smallest scale of the robust weights, px: a local scan's displayed
 * centre is found to about 0.1 px, so a residual of a few tenths of a
 * pixel never marks a measurement as wrong, however well the others
 * agree (exact measurements keep weight 1). */
#define ROBUST_SCALE_MIN 0.1
/* Median absolute deviation to standard deviation, Gaussian noise. */
#define MAD_TO_SIGMA 1.4826
/* Huber's and Tukey's constants: 95 % efficiency on Gaussian noise. */
#define HUBER_K 1.345
#define TUKEY_C 4.685
#define ROBUST_CONVERGED 1e-6
/* Price of a degree of freedom relative to its expected cost (C_p's 1):
 * Kim and Gu's 1.4 keeps few noisy knots from being followed. */
#define COMPLEXITY_PRICE 1.4
/* Scores closer than this (px^2) are equal. */
#define SCORE_ROUNDING 1e-24
/* A noise estimate from robust cross-validation more than this many times
 * the one from differences is the smoother fits' bias, not noise, and the
 * knots are interpolated.  Measured on 16 stripes: with noise (0.01 or
 * 0.1 px, stripes a line apart or anywhere) the ratio is at most 13 in
 * 1800 fits, on exact settling at least 43 in 2000. */
#define NOISE_OVER_DIFFERENCES_MAX 20.0

/* When the noise variance of data that are not exact comes from a fit
 * leaving fewer than this fraction of the measurements as residual degrees
 * of freedom, it is estimated again from fits leaving at least that many.
 * Leave-one-out cross-validation cannot see noise between knots imaged
 * close together (each is predicted from its twin), so on 16 noisy knots
 * it sometimes prefers a near-interpolating fit, and a variance from the
 * one or two residual degrees of freedom left falls below a twentieth of
 * the truth about once in five draws (chi-squared, one degree of freedom):
 * C_p prices complexity at nothing and the trajectory follows the noise.
 * simscan --preset paper --seed 739936 (displayed centres 0.13 px off,
 * stripes 0 and 1 imaged 1.6 s apart): noise estimated at 0.022 px in x,
 * a fit of 14.9 degrees of freedom for 16 knots, a slope of -0.064 px/s
 * between the twins that the frame start's extrapolation carried to 1.45
 * px off and continuous mode 0.252 px RMS; with half the knots left to the
 * residuals the noise is estimated at 0.094 px, the fit is the quadratic
 * and continuous mode 0.148 px RMS (0.135 px with perfect local scans).
 * Over simscan seeds 1-1000 the two other results above 0.2 px went too
 * (seeds 752, 731: 0.229, 0.218 -> 0.162, 0.143 px; mean 0.1395 -> 0.1382
 * px).  Exact data keep the first estimate (noise_is_bias() of either):
 * there a smoother fit's residual is its bias, and smoothing exact
 * settling like noise of that size was up to 2.2 px off. */
#define NOISE_MIN_RESIDUAL_FRACTION 0.5

/* Below this many knots cross-validation's preference for interpolation
 * is not required to call the data exact; it only lowers the bar
 * (estimate_is_bias()): left out, a knot of a steep settling start with a
 * blank stripe beside it is predicted across three stripes by
 * interpolation worse than by a smoother fit, so exact data looked like
 * noise of 0.15 px and were smoothed 0.2 px off in the bend
 * (test-continuous-compensate, seed 81001636: 7 knots, blank stripes 2, 4
 * and 7; the differences' noise was 26 times below that). */
#define CV_SIGHTED_KNOTS 10
/* Below CV_SIGHTED_KNOTS knots, the noise estimate from differences
 * (the larger of the two axes') this many times below the one from
 * cross-validation says the latter is bias.  The difference estimate fits
 * a quintic through the other knots, so with n knots its residuals hold
 * only n - DIFFERENCE_NEIGHBOURS independent numbers (one for seven
 * knots): on one axis it fell twenty times below the noise of noisy data
 * in about 2 % of fits, and noisy data were interpolated, while exact
 * settling stayed within twenty in 70-85 %.  The two axes' noise is alike
 * (a local scan finds both coordinates of one centre), and both estimates
 * are that low by chance far less often.  Per axis at twenty, a steep
 * exact settling start with blank stripes 2, 4 and 7 of 10 looked like
 * 0.09 px of noise (the differences 14.6 times lower) and was smoothed
 * 0.08-0.09 px off at its first knots (test-continuous-compensate seed
 * 71000482).  Over 600 draws of each of 10 stripes with 1-3 blank,
 * settling or constant velocity, exact or with 0.001-0.1 px noise, the
 * pooled rule at ten was nowhere worse in mean, 95th percentile or worst
 * trajectory error, and the worst of constant velocity with 0.1 px noise
 * and three blank stripes fell from 1.15 to 0.42 px; with settling along
 * x only, means and 95th percentiles stayed within 6 % either way (0.1 px
 * noise, one blank stripe: the worst 1.16 -> 0.46 px). */
#define FEW_KNOTS_NOISE_OVER_DIFFERENCES_MAX 10.0
/* ... and this many times below it where cross-validation on the axis
 * also preferred interpolation.  With few knots that preference alone
 * means little (60 % of fits of data with 0.01 px noise), but together
 * with differences four times below it is rare on noisy data and catches
 * exact settling about twice as often.  Seed 76000205 of
 * test-continuous-compensate had the differences 9.2 (x) and 4.8 (y)
 * times below and was smoothed to an interior RMS 0.106 of paper mode's;
 * the calibration is in docs/accuracy.md (trajectory, known limits). */
#define FEW_KNOTS_CV_NOISE_OVER_DIFFERENCES_MAX 4.0

enum {
    /* Third differences: quadratics go unpenalised. */
    PENALTY_ORDER = 3,
    /* Fewer knots leave too few residuals to tell noise from drift. */
    SMOOTHING_MIN_KNOTS = PENALTY_ORDER + 3,
    /* Penalty weights tried, log10: from interpolation to a quadratic. */
    SMOOTHING_LOG_MIN = -6,
    SMOOTHING_LOG_MAX = 10,
    SMOOTHING_STEPS_PER_DECADE = 4,
    /* Convex Huber steps first, so that Tukey's weights start near the
     * robust solution. */
    ROBUST_HUBER_ITERATIONS = 3,
    /* The noise estimate from differences fits quintics. */
    DIFFERENCE_NEIGHBOURS = 6,
    ROBUST_MAX_ITERATIONS = 30,
};

/* Penalised least squares over the knot values: minimise
 * sum_i w_i (y_i - f_i)^2 + lambda |D f|^2, D the scaled third divided
 * differences, w_i the measurements per knot times the knot's robustness
 * weight.  W + lambda D'D is a symmetric band matrix of half-width
 * PENALTY_ORDER, factored as L diag L'. */
typedef gdouble PenaltyBandRow[PENALTY_ORDER + 1];

typedef struct {
    gint n;
    const gdouble *t;          /* knot times */
    const gdouble *count;      /* measurements per knot */
    gdouble *robust;           /* robustness weight of each knot, 0 .. 1 */
    const gboolean *held;      /* knots left out of every fit (weight 0);
                                  NULL: none */
    gdouble *w;                /* count times robust */
    PenaltyBandRow *coeff;     /* D, row r at columns r .. r+PENALTY_ORDER */
    PenaltyBandRow *band;      /* D'D: band[i][k] = (D'D)_{i,i+k} */
    PenaltyBandRow *lower;     /* L: lower[i][k] = L_{i,i-k} */
    gdouble *pivot;            /* diag */
    PenaltyBandRow *inverse;   /* M^-1 within the band */
    gdouble *leverage;         /* diagonal of the influence matrix */
    gdouble *student;          /* standardised residuals */
    gdouble change;            /* largest change of a robustness weight */
    gdouble penalty_unit;      /* penalty weight of step 0 */
    gboolean cv_interpolates;  /* cross-validation prefers interpolation */
    gdouble noise_df;          /* residual degrees of freedom of the fit
                                  the noise variance came from */
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
    gint n_meas;
    gdouble *meas_weight;  /* robustness weight per measurement, given order */
    DriftMeasurement *meas; /* the measurements, given order */
    gint *meas_stripe;     /* stripe per measurement (from a table), or NULL */
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
smoother_init(Smoother *smoother, gint n, const gdouble *t,
              const gdouble *count)
{
    gint r, j, k, i;
    gdouble h = (t[n-1] - t[0])/(n - 1), scale = 1.0, prod;

    smoother->n = n;
    smoother->t = t;
    smoother->count = count;
    smoother->held = NULL;
    smoother->coeff = g_new0(PenaltyBandRow, n - PENALTY_ORDER);
    smoother->band = g_new0(PenaltyBandRow, n);
    smoother->lower = g_new0(PenaltyBandRow, n);
    smoother->inverse = g_new0(PenaltyBandRow, n);
    smoother->pivot = g_new(gdouble, 6*n);
    smoother->fit = smoother->pivot + n;
    smoother->robust = smoother->fit + n;
    smoother->w = smoother->robust + n;
    smoother->leverage = smoother->w + n;
    smoother->student = smoother->leverage + n;
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
    /* Knots a line apart make their divided differences, and so D'D,
     * thousands of times larger than even spacing does (where the largest
     * diagonal is 1 + 9 + 9 + 1); the penalty weights tried are scaled to
     * the largest, so that the heaviest stays a well-conditioned quadratic
     * fit instead of losing every digit to rounding. */
    prod = 0.0;
    for (i = 0; i < n; i++)
        prod = fmax(prod, smoother->band[i][0]);
    smoother->penalty_unit = (prod > 20.0 ? 20.0/prod : 1.0);
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

/* Leverages (the diagonal of the influence matrix (W + lambda D'D)^-1 W)
 * and their sum: the band of the inverse from the factors, backwards
 * (Takahashi's recurrence), O(n). */
static gdouble
smoother_leverages(Smoother *smoother)
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
        smoother->leverage[i] = smoother->w[i]*sum;
        trace += smoother->leverage[i];
    }
    return trace;
}

/* Standardises the residuals of the current fit to the noise of one
 * measurement (a residual's variance is sigma^2 (1 - leverage)/count) into
 * smoother->student and returns their robust scale: the median absolute
 * standardised residual as a standard deviation, but never below
 * ROBUST_SCALE_MIN. */
static gdouble
smoother_standardise(Smoother *smoother, const gdouble *y)
{
    gint n = smoother->n, i;
    gdouble *u = smoother->student, *sorted, scale;

    for (i = 0; i < n; i++) {
        u[i] = fabs(y[i] - smoother->fit[i])*sqrt(smoother->count[i]
                                                  /fmax(1.0 - smoother->leverage[i],
                                                        1e-12));
    }
    sorted = g_memdup2(u, n*sizeof(gdouble));
    scale = MAD_TO_SIGMA*median_in_place(sorted, n);
    g_free(sorted);
    return fmax(scale, ROBUST_SCALE_MIN);
}

/* New robustness weights from the standardised residuals of the current
 * fit: Huber's while !redescending, then Tukey's biweight, which gives a
 * gross error weight 0.  Returns the scale; smoother->change becomes the
 * largest change of a weight. */
static gdouble
smoother_reweight(Smoother *smoother, const gdouble *y, gboolean redescending)
{
    gint n = smoother->n, i;
    gdouble scale = smoother_standardise(smoother, y), a, weight;

    smoother->change = 0.0;
    for (i = 0; i < n; i++) {
        a = smoother->student[i]/scale;
        if (redescending)
            weight = (a < TUKEY_C ? (1.0 - a*a/(TUKEY_C*TUKEY_C))
                                    *(1.0 - a*a/(TUKEY_C*TUKEY_C)) : 0.0);
        else
            weight = (a <= HUBER_K ? 1.0 : HUBER_K/a);
        if (smoother->held && smoother->held[i])
            weight = 0.0;
        smoother->change = fmax(smoother->change,
                                fabs(weight - smoother->robust[i]));
        smoother->robust[i] = weight;
        smoother->w[i] = smoother->count[i]*weight;
    }
    return scale;
}

/* The fit for one penalty weight. */
static gdouble
smoother_fit_weighted(Smoother *smoother, const gdouble *y, gdouble lambda)
{
    smoother_factor(smoother, lambda);
    smoother_solve(smoother, y);
    return smoother_leverages(smoother);
}

/* Tukey's loss, scaled to u^2 for small u: a gross error costs c^2/3
 * however far off it is. */
static gdouble
tukey_loss(gdouble u)
{
    gdouble v = fmin(u*u/(TUKEY_C*TUKEY_C), 1.0);

    return TUKEY_C*TUKEY_C/3.0*(1.0 - (1.0 - v)*(1.0 - v)*(1.0 - v));
}

/* The robust fit for one penalty weight: iteratively reweighted least
 * squares from equal weights.  Returns the trace of the influence matrix;
 * *loss becomes the sum of scale^2 tukey_loss(e_i/scale) over every
 * measurement, e_i its residual (a measurement given weight 0 still costs
 * c^2/3 scale^2, so rejecting good data never pays, and a gross error costs
 * the same at every penalty weight that rejects it).  With scale <= 0 the
 * loss uses the robust scale of the fit itself. */
static gdouble
smoother_fit_robust(Smoother *smoother, const gdouble *y, gdouble lambda,
                    gdouble scale, gdouble *loss)
{
    gint n = smoother->n, i, iter;
    gdouble trace, e;

    for (i = 0; i < n; i++) {
        smoother->robust[i] = (smoother->held && smoother->held[i]) ? 0.0 : 1.0;
        smoother->w[i] = smoother->count[i]*smoother->robust[i];
    }
    for (iter = 0; iter < ROBUST_MAX_ITERATIONS; iter++) {
        smoother_fit_weighted(smoother, y, lambda);
        smoother_reweight(smoother, y, iter >= ROBUST_HUBER_ITERATIONS);
        if (smoother->change < ROBUST_CONVERGED
            && iter >= ROBUST_HUBER_ITERATIONS)
            break;
    }
    trace = smoother_fit_weighted(smoother, y, lambda);
    if (scale <= 0.0)
        scale = smoother_standardise(smoother, y);
    *loss = 0.0;
    for (i = 0; i < n; i++) {
        e = (y[i] - smoother->fit[i])*sqrt(smoother->count[i]);
        *loss += scale*scale*tukey_loss(e/scale);
    }
    return trace;
}

static gdouble
penalty_weight(const Smoother *smoother, gint step)
{
    return smoother->penalty_unit*pow(10.0,
                                      step/(gdouble)SMOOTHING_STEPS_PER_DECADE);
}

/* Robust leave-one-out cross-validation: the sum of
 * scale^2 tukey_loss(e_i/scale) over every measurement, e_i its residual
 * against the fit to all others (r_i/(1 - leverage_i) for a linear
 * smoother), scale the fit's robust scale. */
static gdouble
smoother_cross_validation(Smoother *smoother, const gdouble *y)
{
    gint n = smoother->n, i;
    gdouble scale = smoother_standardise(smoother, y), e, loss = 0.0;

    for (i = 0; i < n; i++) {
        e = ((y[i] - smoother->fit[i])*sqrt(smoother->count[i])
             /fmax(1.0 - smoother->leverage[i], 1e-12));
        loss += scale*scale*tukey_loss(e/scale);
    }
    return loss;
}

/* The noise variance of one measurement, from the fit preferred by robust
 * leave-one-out cross-validation (which, unlike generalised
 * cross-validation, sees that a near-interpolating fit of noisy knots
 * predicts each knot badly from the others): its robust loss per residual
 * degree of freedom.  A rejected gross error adds its fixed cost, so data
 * with gross errors are smoothed somewhat more.  Only fits leaving at least
 * min_df degrees of freedom to the residuals estimate noise (the one used
 * leaves smoother->noise_df); smoother->cv_interpolates says whether
 * cross-validation prefers one leaving less than one. */
static gdouble
smoother_noise_variance(Smoother *smoother, const gdouble *y, gdouble min_df)
{
    gint n = smoother->n, i, step;
    gdouble total = 0.0, best_score = G_MAXDOUBLE, variance = 0.0;
    gdouble best_any = G_MAXDOUBLE, trace, loss, score;

    for (i = 0; i < n; i++)
        total += smoother->count[i];
    for (step = SMOOTHING_LOG_MIN*SMOOTHING_STEPS_PER_DECADE;
         step <= SMOOTHING_LOG_MAX*SMOOTHING_STEPS_PER_DECADE; step++) {
        trace = smoother_fit_robust(smoother, y, penalty_weight(smoother, step), 0.0,
                                    &loss);
        score = smoother_cross_validation(smoother, y);
        if (score < best_any) {
            best_any = score;
            smoother->cv_interpolates = (total - trace < 1.0);
        }
        if (score < best_score && total - trace >= min_df) {
            best_score = score;
            variance = loss/(total - trace);
            smoother->noise_df = total - trace;
        }
    }
    return variance;
}

static gdouble difference_noise_scale(gint n, const gdouble *t,
                                      const gdouble *y);

/* Whether the noise variance estimated for y is the smoother fits' bias
 * rather than noise by the second sign estimate_is_bias() reads, alone:
 * the noise estimated from differences (of all knots, none yet rejected)
 * is far below it.  smoother_fit() asks it before it estimates the noise
 * again from smoother fits.  FALSE when there are too few knots to
 * tell. */
static gboolean
noise_is_bias(const Smoother *smoother, const gdouble *y, gdouble variance)
{
    gint n = smoother->n;

    return (n > DIFFERENCE_NEIGHBOURS
            && sqrt(variance) > (NOISE_OVER_DIFFERENCES_MAX
                                 *difference_noise_scale(n, smoother->t, y)));
}

/* Sets smoother->fit to the robust penalised least-squares fit of y whose
 * penalty weight minimises loss + 2 COMPLEXITY_PRICE sigma^2 trace
 * (Mallows' C_p with each degree of freedom priced above its expected
 * cost), sigma^2 the noise variance from robust cross-validation (again
 * from smoother fits when it came from a near-interpolating fit of data
 * that are not exact, NOISE_MIN_RESIDUAL_FRACTION).  Exact
 * data have sigma = 0 and keep their values; noisy data are not followed
 * into the near-interpolating fits where cross-validation alone is
 * erratic on a few knots.  Robustness and smoothing are chosen together:
 * a fit that follows a gross error also follows the noise and costs
 * degrees of freedom, a smoother one rejects the error at a fixed price.
 * Constant values are fitted exactly.  Returns the first estimate of
 * sigma^2, from which estimate_is_bias() judges exactness. */
static gdouble
smoother_fit(Smoother *smoother, const gdouble *y)
{
    gint n = smoother->n, i, step, best_step = 0;
    gdouble best_score = G_MAXDOUBLE, variance, noise, scale, trace, loss, score;
    gboolean constant = TRUE;

    for (i = 1; i < n; i++)
        constant = constant && (y[i] == y[0]);
    if (constant) {
        memcpy(smoother->fit, y, n*sizeof(gdouble));
        for (i = 0; i < n; i++)
            smoother->robust[i] = 1.0;
        smoother->cv_interpolates = TRUE;
        return 0.0;
    }
    variance = noise = smoother_noise_variance(smoother, y, 1.0);
    if (smoother->noise_df < NOISE_MIN_RESIDUAL_FRACTION*n
        && !noise_is_bias(smoother, y, variance)) {
        noise = smoother_noise_variance(smoother, y,
                                        NOISE_MIN_RESIDUAL_FRACTION*n);
        if (noise_is_bias(smoother, y, noise))
            noise = variance;
    }
    scale = fmax(sqrt(noise), ROBUST_SCALE_MIN);
    for (step = SMOOTHING_LOG_MIN*SMOOTHING_STEPS_PER_DECADE;
         step <= SMOOTHING_LOG_MAX*SMOOTHING_STEPS_PER_DECADE; step++) {
        trace = smoother_fit_robust(smoother, y, penalty_weight(smoother, step), scale,
                                    &loss);
        score = loss + 2.0*COMPLEXITY_PRICE*noise*trace;
        /* Exact data score zero up to rounding at every weight: keep the
         * smallest, best conditioned one. */
        if (score < best_score - SCORE_ROUNDING) {
            best_score = score;
            best_step = step;
        }
    }
    smoother_fit_robust(smoother, y, penalty_weight(smoother, best_step), scale, &loss);
    return variance;
}

/* A noise estimate from differences (Gasser, Sroka and Jennen-Steinmetz's
 * pseudo-residuals, of higher order): each knot's residual from the
 * polynomial through its DIFFERENCE_NEIGHBOURS nearest others, divided by
 * the root of 1 + the sum of that polynomial's squared Lagrange weights,
 * so that noise keeps its variance at any knot spacing; their median
 * absolute value as a standard deviation.  A quintic follows drift smooth
 * enough to be sampled by the stripes to far below any noise, so on exact
 * data this is next to zero where the smoother fits' bias is not.  n must
 * exceed DIFFERENCE_NEIGHBOURS. */
static gdouble
difference_noise_scale(gint n, const gdouble *t, const gdouble *y)
{
    gdouble *errors = g_new(gdouble, n), predicted, norm, weight, scale;
    gint i, j, k, first;

    for (i = 0; i < n; i++) {
        first = CLAMP(i - DIFFERENCE_NEIGHBOURS/2, 0, n - 1 - DIFFERENCE_NEIGHBOURS);
        predicted = 0.0;
        norm = 1.0;
        for (j = first; j <= first + DIFFERENCE_NEIGHBOURS; j++) {
            if (j == i)
                continue;
            weight = 1.0;
            for (k = first; k <= first + DIFFERENCE_NEIGHBOURS; k++) {
                if (k != i && k != j)
                    weight *= (t[i] - t[k])/(t[j] - t[k]);
            }
            predicted += weight*y[j];
            norm += weight*weight;
        }
        errors[i] = fabs(y[i] - predicted)/sqrt(norm);
    }
    scale = MAD_TO_SIGMA*median_in_place(errors, n);
    g_free(errors);
    return scale;
}

/* The knots whose robustness weight (robust, the smaller of both axes')
 * is at least DRIFT_TRAJECTORY_DOWNWEIGHTED: their times and values of y
 * into kt and ky; returns how many. */
static gint
trusted_knots(gint n, const gdouble *t, const gdouble *y,
              const gdouble *robust, gdouble *kt, gdouble *ky)
{
    gint i, m = 0;

    for (i = 0; i < n; i++) {
        if (robust[i] >= DRIFT_TRAJECTORY_DOWNWEIGHTED) {
            kt[m] = t[i];
            ky[m++] = y[i];
        }
    }
    return m;
}

/* difference_noise_scale() of the trusted knots of y; NAN when there are
 * too few for it. */
static gdouble
trusted_difference_noise(gint n, const gdouble *t, const gdouble *y,
                         const gdouble *robust)
{
    gdouble *kt = g_new(gdouble, 2*n), scale = NAN;
    gint m = trusted_knots(n, t, y, robust, kt, kt + n);

    if (m > DIFFERENCE_NEIGHBOURS)
        scale = difference_noise_scale(m, kt, kt + n);
    g_free(kt);
    return scale;
}

/* Sets values to the interpolation of the trusted knots of y: those keep
 * their measured values, the others lie on the not-a-knot spline through
 * them. */
static void
interpolate_trusted(gint n, const gdouble *t, const gdouble *y,
                    const gdouble *robust, gdouble *values)
{
    DriftTrajectory spline;
    gdouble *kt = g_new(gdouble, 3*n), *ky = kt + n, *curv = ky + n, slope;
    gint i, m = trusted_knots(n, t, y, robust, kt, ky);

    spline_not_a_knot_curvatures(m, kt, ky, curv);
    memset(&spline, 0, sizeof(spline));
    spline.n = m;
    spline.t = kt;
    spline.value[0] = ky;
    spline.curv[0] = curv;
    for (i = 0; i < n; i++) {
        if (robust[i] >= DRIFT_TRAJECTORY_DOWNWEIGHTED)
            values[i] = y[i];
        else
            spline_eval(&spline, 0, t[i], values + i, &slope);
    }
    g_free(kt);
}

static gint
compare_by_image_time(gconstpointer pa, gconstpointer pb, gpointer user_data)
{
    const DriftMeasurement *meas = user_data;
    const DriftMeasurement *a = meas + *(const gint*)pa;
    const DriftMeasurement *b = meas + *(const gint*)pb;

    if (a->t_a < b->t_a)
        return -1;
    return a->t_a > b->t_a;
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

/* The positions at the image times are p(t_a) - p(t_ref)
 * = m + p(t_b) - p(t_ref), so the drift during the local scans is
 * needed.  The local scans come after the frame, where the trajectory
 * continues linearly with its end slope; so the local-scan velocity v is
 * the end slope of the spline through m + v tau, tau = t_b - t_ref,
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
                    _("no stripe has a drift measurement"));
        return FALSE;
    }
    for (i = 0; i < n; i++) {
        if (!isfinite(meas[i].t_a) || !isfinite(meas[i].t_b)
            || !isfinite(meas[i].dx) || !isfinite(meas[i].dy)) {
            g_set_error(error, DRIFT_TRAJECTORY_ERROR,
                        DRIFT_TRAJECTORY_ERROR_VALUE,
                        _("drift measurement %d is not a finite number"), i);
            return FALSE;
        }
    }
    return TRUE;
}

/* Fits every axis's measured values (2 x n) into trajectory->value;
 * robust becomes each knot's robustness weight, the smaller of the two
 * axes'. */
static void
smooth_axes(DriftTrajectory *trajectory, Smoother *smoother, const gdouble *measured,
            gdouble *robust, gdouble *variance, gboolean *cv_interpolates)
{
    gint n = trajectory->n, axis, j;

    for (j = 0; j < n; j++)
        robust[j] = 1.0;
    for (axis = 0; axis < 2; axis++) {
        variance[axis] = smoother_fit(smoother, measured + axis*n);
        cv_interpolates[axis] = smoother->cv_interpolates;
        memcpy(trajectory->value[axis], smoother->fit, n*sizeof(gdouble));
        for (j = 0; j < n; j++)
            robust[j] = fmin(robust[j], smoother->robust[j]);
    }
}

/* A local scan that found a wrong particle is wrong on both axes, though
 * on one of them perhaps by little: two such scans side by side at the
 * frame's end, 5 and 11 px off in x but 0.5 and 0.9 px in y, outvoted the
 * good scan beside them on y, which the y fit rejected instead (three
 * knots at an end cannot tell a bend of the drift from two errors).  So
 * every knot rejected on either axis is left out of both, the rest fitted,
 * and a left-out knot taken back where it lies on that fit on both axes
 * (within the range Tukey's weights give any weight).  FALSE when none is
 * taken back (the first fit stands). */
static gboolean
readmit_knots(DriftTrajectory *trajectory, Smoother *smoother, const gdouble *measured,
              gboolean *held)
{
    gint n = trajectory->n, axis, j;
    gboolean *fits = g_new(gboolean, n), any = FALSE;
    gdouble scale;

    for (j = 0; j < n; j++)
        fits[j] = held[j];
    smoother->held = held;
    for (axis = 0; axis < 2; axis++) {
        smoother_fit(smoother, measured + axis*n);
        scale = smoother_standardise(smoother, measured + axis*n);
        for (j = 0; j < n; j++) {
            fits[j] = fits[j] && (fabs(measured[axis*n + j] - smoother->fit[j])*sqrt(smoother->count[j])
                                  < TUKEY_C*scale);
        }
    }
    for (j = 0; j < n; j++) {
        any = any || fits[j];
        held[j] = held[j] && !fits[j];
    }
    g_free(fits);
    return any;
}

/* Whether the noise estimate variance[axis] of the smoothed fit of that
 * axis is the bias of the smoother fits rather than noise, so that its
 * trusted knots are interpolated (interpolate_trusted()).
 *
 * Exact measurements of curved drift (settling) need this check: every
 * smoother fit has a bias there, which robust cross-validation takes for
 * noise (0.007-0.009 px on exact settling), and with sigma^2 estimated from
 * a fit of trace T that fit's C_p score, about
 * sigma^2 ((n - T) + 2 COMPLEXITY_PRICE T), is always below
 * interpolation's, 2 COMPLEXITY_PRICE n sigma^2: such data were smoothed,
 * which flattened the steep start and moved the extrapolated half stripe
 * at the frame edge by 0.03-0.04 px.  From CV_SIGHTED_KNOTS knots on,
 * two signs, each alone seen on noisy data about once in a thousand fits
 * (never both in the same), say that sigma is bias: cross-validation
 * preferred a fit too close to interpolation to estimate noise, and the
 * noise estimated from differences of the trusted knots is far below
 * sigma.  A local scan rejected on either axis found a wrong particle and
 * is left out on both: its other coordinate may be off by less than the
 * rejection threshold.  Counts per knot are not weighed in: several
 * measurements of one image time are rare and only make the knot's own
 * error smaller.
 *
 * Below CV_SIGHTED_KNOTS knots the differences decide, both axes count
 * (FEW_KNOTS_NOISE_OVER_DIFFERENCES_MAX), and cross-validation's
 * preference only lowers the bar (FEW_KNOTS_CV_NOISE_OVER_DIFFERENCES_MAX). */
static gboolean
estimate_is_bias(gint n, const gdouble *t, const gdouble *measured,
                 const gdouble *robust, const gdouble *variance,
                 const gboolean *cv_interpolates, gint axis)
{
    gdouble scale, bar;

    if (variance[axis] <= 0.0)
        return FALSE;
    if (n >= CV_SIGHTED_KNOTS) {
        scale = trusted_difference_noise(n, t, measured + axis*n, robust);
        return (cv_interpolates[axis] && !isnan(scale)
                && sqrt(variance[axis]) > NOISE_OVER_DIFFERENCES_MAX*scale);
    }
    /* The knots trusted are those of both axes: either scale is NAN only
     * when both are. */
    scale = fmax(trusted_difference_noise(n, t, measured, robust),
                 trusted_difference_noise(n, t, measured + n, robust));
    bar = (cv_interpolates[axis] ? FEW_KNOTS_CV_NOISE_OVER_DIFFERENCES_MAX
           : FEW_KNOTS_NOISE_OVER_DIFFERENCES_MAX);
    return !isnan(scale) && sqrt(variance[axis]) > bar*scale;
}

/* Smooths the knot values of both axes (count: measurements per knot),
 * or interpolates the trusted ones where the estimated noise is the
 * smoothing's bias (estimate_is_bias()); robust becomes each knot's
 * robustness weight, the smaller of the two axes'.  Knots rejected on one
 * axis get a second look (readmit_knots()). */
static void
smooth_knots(DriftTrajectory *trajectory, const gdouble *count,
             gdouble *robust)
{
    gint n = trajectory->n, axis, j;
    gdouble *measured = g_new(gdouble, 2*n), variance[2];
    gboolean cv_interpolates[2], *held = g_new(gboolean, n), any_held = FALSE;
    Smoother smoother;

    smoother_init(&smoother, n, trajectory->t, count);
    for (axis = 0; axis < 2; axis++)
        memcpy(measured + axis*n, trajectory->value[axis], n*sizeof(gdouble));
    smooth_axes(trajectory, &smoother, measured, robust, variance, cv_interpolates);
    for (j = 0; j < n; j++) {
        held[j] = (robust[j] < DRIFT_TRAJECTORY_DOWNWEIGHTED);
        any_held = any_held || held[j];
    }
    if (any_held && readmit_knots(trajectory, &smoother, measured, held))
        smooth_axes(trajectory, &smoother, measured, robust, variance, cv_interpolates);
    smoother_clear(&smoother);
    for (axis = 0; axis < 2; axis++) {
        if (estimate_is_bias(n, trajectory->t, measured, robust, variance,
                             cv_interpolates, axis))
            interpolate_trusted(n, trajectory->t, measured + axis*n, robust,
                                trajectory->value[axis]);
    }
    g_free(held);
    g_free(measured);
}

static DriftTrajectory*
trajectory_new(const DriftMeasurement *meas, gint n, gboolean smooth,
               GError **error)
{
    DriftTrajectory *trajectory;
    gdouble *tau, *count, *robust;
    gdouble sum[3];
    gint *order, *knot_of;
    gint i, k, j, axis;

    if (!check_measurements(meas, n, error))
        return NULL;

    order = g_new(gint, 2*n);
    knot_of = order + n;
    for (i = 0; i < n; i++)
        order[i] = i;
    g_qsort_with_data(order, n, sizeof(gint), compare_by_image_time,
                      (gpointer)meas);
    trajectory = g_new0(DriftTrajectory, 1);
    trajectory->t_ref = meas[0].t_b;
    for (i = 1; i < n; i++)
        trajectory->t_ref = MIN(trajectory->t_ref, meas[i].t_b);

    trajectory->t = g_new(gdouble, 5*n);
    trajectory->value[0] = trajectory->t + n;
    trajectory->value[1] = trajectory->value[0] + n;
    trajectory->curv[0] = trajectory->value[1] + n;
    trajectory->curv[1] = trajectory->curv[0] + n;
    trajectory->n_meas = n;
    trajectory->meas_weight = g_new(gdouble, n);
    trajectory->meas = g_memdup2(meas, n*sizeof(DriftMeasurement));
    tau = g_new(gdouble, 3*n);
    count = tau + n;
    robust = count + n;
    /* Measurements at the same image time are averaged into one knot. */
    for (i = 0; i < n; i = k) {
        const DriftMeasurement *first = meas + order[i];

        sum[0] = sum[1] = sum[2] = 0.0;
        j = trajectory->n++;
        for (k = i; k < n && meas[order[k]].t_a == first->t_a; k++) {
            sum[0] += meas[order[k]].dx;
            sum[1] += meas[order[k]].dy;
            sum[2] += meas[order[k]].t_b - trajectory->t_ref;
            knot_of[order[k]] = j;
        }
        trajectory->t[j] = first->t_a;
        trajectory->value[0][j] = sum[0]/(k - i);
        trajectory->value[1][j] = sum[1]/(k - i);
        tau[j] = sum[2]/(k - i);
        count[j] = k - i;
        robust[j] = 1.0;
    }

    if (smooth && trajectory->n >= SMOOTHING_MIN_KNOTS)
        smooth_knots(trajectory, count, robust);
    for (i = 0; i < n; i++)
        trajectory->meas_weight[i] = robust[knot_of[i]];
    g_free(order);
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
                    _("%s: scan timing is unusable (line time %g s, "
                    "%d x %d pixels)"),
                    table->source_name ? table->source_name : _("drift table"),
                    timing->line_time, timing->xres, timing->yres);
        return FALSE;
    }
    return drift_table_check_image(table, timing->yres, error);
}

/* Table times, s: a date in seconds since 1970 fits, 1e308 does not. */
#define DRIFT_TRAJECTORY_TIME_MAX 1e10

/* The value of an extra column, or fallback when the column is blank or
 * absent; FALSE when it holds anything but a finite number within
 * [-most, most] of the unit (s for a time, px for an exact drift). */
static gboolean
extra_or_default(const DriftTable *table, gint s, const gchar *name,
                 gdouble fallback, gdouble most, const gchar *unit,
                 gdouble *value, GError **error)
{
    gint j = drift_table_find_column(table, name);
    gchar *quoted;

    if (drift_table_get_extra(table, s, name, value) && isfinite(*value)) {
        /* Times beyond centuries are no clock's: 1e308 s would overflow the
         * trajectory's arithmetic into NaN; so would such a drift. */
        if (fabs(*value) <= most)
            return TRUE;
        g_set_error(error, DRIFT_TRAJECTORY_ERROR, DRIFT_TRAJECTORY_ERROR_VALUE,
                    _("%s:%d: %s = %g %s is out of range (from %g to %g %s)"),
                    table->source_name ? table->source_name : _("drift table"),
                    table->rows[s].line, name, *value, unit, -most, most, unit);
        return FALSE;
    }
    if (j < 0 || !*table->extra_values[s*table->n_extra + j]) {
        *value = fallback;
        return TRUE;
    }
    /* The text as written: 'abc' was said to be no finite number. */
    quoted = quoted_input_excerpt(table->extra_values[s*table->n_extra + j], -1);
    g_set_error(error, DRIFT_TRAJECTORY_ERROR, DRIFT_TRAJECTORY_ERROR_VALUE,
                _("%s:%d: %s = '%s' is not a finite number"),
                table->source_name ? table->source_name : _("drift table"),
                table->rows[s].line, name, quoted);
    g_free(quoted);
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
        ok = (extra_or_default(table, s, "t_image", t_centre, DRIFT_TRAJECTORY_TIME_MAX, "s",
                               &meas[count].t_a, error)
              && extra_or_default(table, s, "t_local", t_end, DRIFT_TRAJECTORY_TIME_MAX, "s",
                                  &meas[count].t_b, error)
              && extra_or_default(table, s, "dx_exact", dx_px[s], DRIFT_TABLE_MAX_PIXELS, "px",
                                  &dx_exact, error)
              && extra_or_default(table, s, "dy_exact", dy_px[s], DRIFT_TABLE_MAX_PIXELS, "px",
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
    gint n, s, i;

    meas = g_new0(DriftMeasurement, MAX(table->n_stripes, 1));
    n = drift_trajectory_measurements_from_table(table, x_pixel_size,
                                                 y_pixel_size, timing,
                                                 meas, error);
    if (n >= 0)
        trajectory = drift_trajectory_new(meas, n, error);
    if (trajectory) {
        /* The measurements are the measured stripes in order. */
        trajectory->meas_stripe = g_new(gint, MAX(n, 1));
        for (s = i = 0; s < table->n_stripes && i < n; s++) {
            if (table->rows[s].has_drift)
                trajectory->meas_stripe[i++] = s;
        }
    }
    g_free(meas);
    return trajectory;
}

void
drift_trajectory_free(DriftTrajectory *trajectory)
{
    if (!trajectory)
        return;
    g_free(trajectory->t);
    g_free(trajectory->meas_weight);
    g_free(trajectory->meas);
    g_free(trajectory->meas_stripe);
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

gint
drift_trajectory_n_measurements(const DriftTrajectory *trajectory)
{
    return trajectory->n_meas;
}

gdouble
drift_trajectory_measurement_weight(const DriftTrajectory *trajectory, gint i)
{
    g_return_val_if_fail(i >= 0 && i < trajectory->n_meas, 0.0);
    return trajectory->meas_weight[i];
}

gdouble
drift_trajectory_measurement_residual(const DriftTrajectory *trajectory, gint i)
{
    const DriftMeasurement *m;
    gdouble a[2], tau;

    g_return_val_if_fail(i >= 0 && i < trajectory->n_meas, NAN);
    m = trajectory->meas + i;
    /* What the trajectory was built to give: D(t_a) less the local scan's
     * own drift after t_ref (estimate_local_velocity).  Not D(t_a) - D(t_b):
     * the spline's extrapolation to t_b is no zero where every t_b is t_ref
     * (a registration's table, every t_local the frame's end), and every
     * stripe of a steady drift read 7.7 px off. */
    drift_trajectory_eval(trajectory, m->t_a, a, a + 1);
    tau = m->t_b - trajectory->t_ref;
    return hypot(m->dx - (a[0] - trajectory->v_local[0]*tau),
                 m->dy - (a[1] - trajectory->v_local[1]*tau));
}

gint
drift_trajectory_measurement_stripe(const DriftTrajectory *trajectory, gint i)
{
    g_return_val_if_fail(i >= 0 && i < trajectory->n_meas, -1);
    return trajectory->meas_stripe ? trajectory->meas_stripe[i] : i;
}

gint
drift_trajectory_n_downweighted(const DriftTrajectory *trajectory)
{
    gint i, count = 0;

    for (i = 0; i < trajectory->n_meas; i++)
        count += (trajectory->meas_weight[i] < DRIFT_TRAJECTORY_DOWNWEIGHTED);
    return count;
}
