/*
 *  A flexible drift trajectory: piecewise linear between knots, its
 *  curvature penalised, the penalty chosen by held-out error.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <string.h>
#include <math.h>
#include "smooth-trajectory.h"

/* The penalty weights tried, relative to the data's: 10^-4 .. 10^6 in
 * half decades. */
#define LAMBDA_FIRST -4.0
#define LAMBDA_STEPS 21
#define LAMBDA_STEP 0.5

/* The penalty chosen is the largest whose held-out mean square error is
 * within this factor of the least's (about 5 % in RMS). */
#define SMOOTHEST_TIE 1.1

/* A measurement touches at most this many knot values: three points of
 * its span on each side, two knots each. */
#define ROW_MAX 12

typedef struct {
    gint n_knots;
    const gdouble *t;
} Knots;

/* The knots and weights p(t) is made of (linear between knots, the end
 * segments continued), at most 2; the unknowns are the knots from 1 on. */
static gint
knot_weights(const Knots *k, gdouble t, gint *index, gdouble *w)
{
    gint lo = 0, hi = k->n_knots - 1, mid;
    gdouble u;

    while (hi - lo > 1) {
        mid = (lo + hi)/2;
        if (k->t[mid] <= t)
            lo = mid;
        else
            hi = mid;
    }
    u = (t - k->t[lo])/(k->t[hi] - k->t[lo]);
    index[0] = lo;
    index[1] = hi;
    w[0] = 1.0 - u;
    w[1] = u;
    return 2;
}

/* The row of a measurement: p at t_a minus p at t_b, each the mean over
 * its span by Simpson's rule. */
static gint
measurement_row(const Knots *k, const DriftMeasurement *m, gint *index,
                gdouble *w)
{
    static const gdouble simpson[3] = { 1.0/6.0, 4.0/6.0, 1.0/6.0 };
    gdouble h = (m->span > 0.0 && isfinite(m->span)) ? 0.5*m->span : 0.0;
    gint side, j, n = 0, q, got;
    gint idx[2];
    gdouble ww[2];

    for (side = 0; side < 2; side++) {
        gdouble t = side ? m->t_b : m->t_a, sign = side ? -1.0 : 1.0;

        for (j = 0; j < 3; j++) {
            got = knot_weights(k, t + (j - 1)*h, idx, ww);
            for (q = 0; q < got; q++) {
                index[n] = idx[q];
                w[n++] = sign*simpson[j]*ww[q];
            }
        }
    }
    return n;
}

/* Adds w a a^T and w a d to the normal equations (unknowns: knots 1 ..). */
static void
accumulate(gdouble *normal, gdouble *rhs[2], gint m, const gint *index,
           const gdouble *a, gint n, gdouble weight, const gdouble *d)
{
    gint i, j, ax;

    for (i = 0; i < n; i++) {
        if (!index[i])
            continue;
        for (j = 0; j < n; j++) {
            if (index[j])
                normal[(index[i] - 1)*m + index[j] - 1] += weight*a[i]*a[j];
        }
        for (ax = 0; ax < 2; ax++)
            rhs[ax][index[i] - 1] += weight*a[i]*d[ax];
    }
}

/* The curvature penalty R (m x m): the second differences of p over the
 * knots, each weighted like the integral of p'' squared. */
static void
curvature_penalty(const Knots *k, gdouble *penalty, gint m)
{
    gint j, a, b;

    memset(penalty, 0, (gsize)m*m*sizeof(gdouble));
    for (j = 1; j + 1 < k->n_knots; j++) {
        gdouble d0 = k->t[j] - k->t[j-1], d1 = k->t[j+1] - k->t[j];
        gdouble omega = 2.0/(d0 + d1), c[3];
        gint idx[3] = { j-1, j, j+1 };

        c[0] = 1.0/d0;
        c[1] = -1.0/d0 - 1.0/d1;
        c[2] = 1.0/d1;
        for (a = 0; a < 3; a++) {
            for (b = 0; b < 3; b++) {
                if (idx[a] && idx[b])
                    penalty[(idx[a] - 1)*m + idx[b] - 1] += omega*c[a]*c[b];
            }
        }
    }
}

/* How far below the diagonal a (m x m) has nonzero values.  Knots are in
 * time order and a measurement ties the knots around its two moments, a
 * few frames apart: the normal equations of a long series are banded. */
static gint
lower_bandwidth(const gdouble *a, gint m)
{
    gint i, j, band = 0;

    for (i = 0; i < m; i++) {
        for (j = 0; j < i - band; j++) {
            if (a[i*m + j] != 0.0) {
                band = i - j;
                break;
            }
        }
    }
    return band;
}

/* Solves the symmetric positive definite (a, m x m, overwritten) x = b for
 * both right-hand sides by Cholesky; FALSE when a is not positive definite.
 * The factor keeps a's band, so only the band is computed: what lies
 * outside it would sum exact zeros (a 1200-knot trajectory cost seconds
 * per solve, and the penalty's choice solves a hundred times). */
static gboolean
solve_spd(gdouble *a, gint m, gdouble *rhs[2], gdouble *x[2])
{
    gint i, j, l, ax, band = lower_bandwidth(a, m);
    gdouble s;

    for (j = 0; j < m; j++) {
        s = a[j*m + j];
        for (l = MAX(0, j - band); l < j; l++)
            s -= a[j*m + l]*a[j*m + l];
        if (!(s > 0.0))
            return FALSE;
        a[j*m + j] = sqrt(s);
        for (i = j+1; i < MIN(m, j + band + 1); i++) {
            s = a[i*m + j];
            for (l = MAX(0, i - band); l < j; l++)
                s -= a[i*m + l]*a[j*m + l];
            a[i*m + j] = s/a[j*m + j];
        }
    }
    for (ax = 0; ax < 2; ax++) {
        for (i = 0; i < m; i++) {
            s = rhs[ax][i];
            for (l = MAX(0, i - band); l < i; l++)
                s -= a[i*m + l]*x[ax][l];
            x[ax][i] = s/a[i*m + i];
        }
        for (i = m-1; i >= 0; i--) {
            s = x[ax][i];
            for (l = i+1; l < MIN(m, i + band + 1); l++)
                s -= a[l*m + i]*x[ax][l];
            x[ax][i] = s/a[i*m + i];
        }
    }
    return TRUE;
}

static gboolean
usable(const DriftMeasurement *m)
{
    return (m->weight > 0.0 && isfinite(m->weight) && isfinite(m->dx)
            && isfinite(m->dy) && isfinite(m->t_a) && isfinite(m->t_b));
}

/* The normal equations of the measurements of fold f (f < 0: all). */
static gint
normal_equations(const Knots *k, const DriftMeasurement *meas, gint n,
                 gint folds, gint f, gdouble *normal, gdouble *rhs[2])
{
    gint m = k->n_knots - 1, i, len, index[ROW_MAX], count = 0;
    gdouble a[ROW_MAX], d[2];

    memset(normal, 0, (gsize)m*m*sizeof(gdouble));
    memset(rhs[0], 0, m*sizeof(gdouble));
    memset(rhs[1], 0, m*sizeof(gdouble));
    for (i = 0; i < n; i++) {
        if (!usable(meas + i)
            || (f >= 0 && ((meas[i].group % folds + folds) % folds) != f))
            continue;
        len = measurement_row(k, meas + i, index, a);
        d[0] = 1e9*meas[i].dx;
        d[1] = 1e9*meas[i].dy;
        accumulate(normal, rhs, m, index, a, len, meas[i].weight, d);
        count++;
    }
    return count;
}

/* p at the knots (nm) for normal equations with the penalty added. */
static gboolean
solve_penalised(const gdouble *normal, const gdouble *penalty, gdouble lambda,
                gint m, gdouble *rhs[2], gdouble *x[2], gdouble *work)
{
    gint i;

    for (i = 0; i < m*m; i++)
        work[i] = normal[i] + lambda*penalty[i];
    return solve_spd(work, m, rhs, x);
}

static void
predict_nm(const Knots *k, const gdouble *x[2], const DriftMeasurement *m,
           gdouble *p)
{
    gint index[ROW_MAX], len, i, ax;
    gdouble a[ROW_MAX];

    len = measurement_row(k, m, index, a);
    for (ax = 0; ax < 2; ax++) {
        p[ax] = 0.0;
        for (i = 0; i < len; i++) {
            if (index[i])
                p[ax] += a[i]*x[ax][index[i] - 1];
        }
    }
}

/* Weighted RMS (nm) of the measurements of fold f (f < 0: all). */
static gdouble
residual_rms(const Knots *k, const gdouble *x[2], const DriftMeasurement *meas,
             gint n, gint folds, gint f, gdouble *wsum_out)
{
    gdouble sum = 0.0, wsum = 0.0, p[2], rx, ry;
    gint i;

    for (i = 0; i < n; i++) {
        if (!usable(meas + i)
            || (f >= 0 && ((meas[i].group % folds + folds) % folds) != f))
            continue;
        predict_nm(k, x, meas + i, p);
        rx = 1e9*meas[i].dx - p[0];
        ry = 1e9*meas[i].dy - p[1];
        sum += meas[i].weight*(rx*rx + ry*ry);
        wsum += meas[i].weight;
    }
    if (wsum_out)
        *wsum_out = wsum;
    return wsum > 0.0 ? sqrt(sum/wsum) : NAN;
}

static gdouble
trace(const gdouble *a, gint m)
{
    gdouble s = 0.0;
    gint i;

    for (i = 0; i < m; i++)
        s += a[i*m + i];
    return s;
}

/* The held-out error of each penalty weight; the best one's index. */
static gint
choose_lambda(const Knots *k, const DriftMeasurement *meas, gint n,
              gint folds, const gdouble *normal, const gdouble *penalty,
              gdouble scale, gdouble *best_cv)
{
    gint m = k->n_knots - 1, f, l, best = -1;
    gsize mm = (gsize)m*m;
    gdouble *fold_normal = g_new(gdouble, mm), *train = g_new(gdouble, mm);
    gdouble *work = g_new(gdouble, mm), *buf = g_new(gdouble, 6*m);
    gdouble *rhs_all[2] = { buf, buf + m }, *rhs[2] = { buf + 2*m, buf + 3*m };
    gdouble *x[2] = { buf + 4*m, buf + 5*m };
    gdouble *sum = g_new0(gdouble, 2*LAMBDA_STEPS), *wsum = sum + LAMBDA_STEPS;
    gdouble *frhs[2], w, r;
    gint i;

    frhs[0] = g_new(gdouble, 2*m);
    frhs[1] = frhs[0] + m;
    normal_equations(k, meas, n, folds, -1, train, rhs_all);
    for (f = 0; f < folds; f++) {
        if (!normal_equations(k, meas, n, folds, f, fold_normal, frhs))
            continue;
        for (i = 0; i < (gint)mm; i++)
            train[i] = normal[i] - fold_normal[i];
        for (i = 0; i < m; i++) {
            rhs[0][i] = rhs_all[0][i] - frhs[0][i];
            rhs[1][i] = rhs_all[1][i] - frhs[1][i];
        }
        for (l = 0; l < LAMBDA_STEPS; l++) {
            gdouble lambda = scale*pow(10.0, LAMBDA_FIRST + LAMBDA_STEP*l);

            if (!solve_penalised(train, penalty, lambda, m, rhs, x, work))
                continue;
            r = residual_rms(k, (const gdouble**)x, meas, n, folds, f, &w);
            if (isfinite(r)) {
                sum[l] += r*r*w;
                wsum[l] += w;
            }
        }
    }
    for (l = 0; l < LAMBDA_STEPS; l++) {
        if (wsum[l] > 0.0
            && (best < 0 || sum[l]/wsum[l] < sum[best]/wsum[best]))
            best = l;
    }
    /* The smoothest weight that predicts nearly as well: differences
     * between frames leave a shape repeated in every frame unseen, and a
     * rougher trajectory than the data ask for fills it with noise. */
    for (l = LAMBDA_STEPS - 1; best >= 0 && l > best; l--) {
        if (wsum[l] > 0.0 && sum[l]/wsum[l] <= SMOOTHEST_TIE*sum[best]/wsum[best]) {
            best = l;
            break;
        }
    }
    *best_cv = best >= 0 ? sqrt(sum[best]/wsum[best]) : NAN;
    g_free(fold_normal);
    g_free(train);
    g_free(work);
    g_free(buf);
    g_free(frhs[0]);
    g_free(sum);
    return best;
}

SmoothTrajectory*
smooth_trajectory_fit(const DriftMeasurement *meas, gint n,
                      const gdouble *knots, gint n_knots, gint n_folds)
{
    Knots k = { n_knots, knots };
    gint m = n_knots - 1, used, best, i, ax;
    gsize mm = (gsize)MAX(m, 1)*MAX(m, 1);
    gdouble *normal, *penalty, *work, *buf, *rhs[2], *x[2], scale, cv;
    SmoothTrajectory *st = NULL;

    if (n_knots < 3 || n_knots > SMOOTH_TRAJECTORY_MAX_KNOTS)
        return NULL;
    for (i = 1; i < n_knots; i++) {
        if (!(knots[i] > knots[i-1]))
            return NULL;
    }
    normal = g_new(gdouble, mm);
    penalty = g_new(gdouble, mm);
    work = g_new(gdouble, mm);
    buf = g_new(gdouble, 4*m);
    rhs[0] = buf;
    rhs[1] = buf + m;
    x[0] = buf + 2*m;
    x[1] = buf + 3*m;
    used = normal_equations(&k, meas, n, 1, -1, normal, rhs);
    curvature_penalty(&k, penalty, m);
    /* The penalty in the data's own scale, so that the weights tried fit
     * any units and knot spacing. */
    scale = trace(normal, m)/MAX(trace(penalty, m), G_MINDOUBLE);
    if (used >= m && isfinite(scale) && scale > 0.0
        && (best = choose_lambda(&k, meas, n, MAX(n_folds, 2), normal, penalty,
                                 scale, &cv)) >= 0) {
        gdouble lambda = scale*pow(10.0, LAMBDA_FIRST + LAMBDA_STEP*best);

        if (solve_penalised(normal, penalty, lambda, m, rhs, x, work)) {
            st = g_new0(SmoothTrajectory, 1);
            st->n_knots = n_knots;
            st->t = g_memdup2(knots, n_knots*sizeof(gdouble));
            for (ax = 0; ax < 2; ax++) {
                st->p[ax] = g_new(gdouble, n_knots);
                st->p[ax][0] = 0.0;
                for (i = 1; i < n_knots; i++)
                    st->p[ax][i] = 1e-9*x[ax][i-1];
            }
            st->lambda = pow(10.0, LAMBDA_FIRST + LAMBDA_STEP*best);
            st->rms_nm = residual_rms(&k, (const gdouble**)x, meas, n, 1, -1,
                                      NULL);
            st->cv_rms_nm = cv;
            st->n_used = used;
        }
    }
    g_free(normal);
    g_free(penalty);
    g_free(work);
    g_free(buf);
    return st;
}

/* The spline itself, s(t); p(t) = s(t) - s(0). */
static void
spline_value(const SmoothTrajectory *st, gdouble t, gdouble *px, gdouble *py)
{
    Knots k = { st->n_knots, st->t };
    gint index[2];
    gdouble w[2];

    knot_weights(&k, t, index, w);
    *px = w[0]*st->p[0][index[0]] + w[1]*st->p[0][index[1]];
    *py = w[0]*st->p[1][index[0]] + w[1]*st->p[1][index[1]];
}

void
smooth_trajectory_eval(const SmoothTrajectory *st, gdouble t, gdouble *px,
                       gdouble *py)
{
    gdouble x0, y0;

    spline_value(st, t, px, py);
    spline_value(st, 0.0, &x0, &y0);
    *px -= x0;
    *py -= y0;
}

void
smooth_trajectory_predict(const SmoothTrajectory *st, const DriftMeasurement *m,
                          gdouble *dx, gdouble *dy)
{
    Knots k = { st->n_knots, st->t };
    gint index[ROW_MAX], len, i;
    gdouble a[ROW_MAX];

    len = measurement_row(&k, m, index, a);
    *dx = *dy = 0.0;
    for (i = 0; i < len; i++) {
        *dx += a[i]*st->p[0][index[i]];
        *dy += a[i]*st->p[1][index[i]];
    }
}

void
smooth_trajectory_free(SmoothTrajectory *st)
{
    if (!st)
        return;
    g_free(st->t);
    g_free(st->p[0]);
    g_free(st->p[1]);
    g_free(st);
}
