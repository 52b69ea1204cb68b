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
 * exactly.  Outside the first and last stripe centre (half a stripe at each
 * end of the frame) the trajectory continues linearly with the end slope,
 * which keeps extrapolation tame.  The price is overshoot around a sudden
 * jump, which no smooth interpolant of stripe samples can resolve anyway.
 */

/* The local scans advance nearly as fast as the stripes are imaged: their
 * drift then cancels from the measurements and cannot be estimated. */
#define LOCAL_VELOCITY_MIN_DENOMINATOR 0.1

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

static void
spline_eval(const DriftTrajectory *trajectory, gint axis, gdouble t,
            gdouble *value, gdouble *slope)
{
    gint n = trajectory->n, i;
    gdouble tend;

    if (n == 1) {
        *value = trajectory->value[axis][0];
        *slope = 0.0;
        return;
    }
    /* Linear continuation beyond the end knots with the end slopes. */
    if (t < trajectory->t[0] || t > trajectory->t[n-1]) {
        i = (t < trajectory->t[0]) ? 0 : n-2;
        tend = (t < trajectory->t[0]) ? trajectory->t[0] : trajectory->t[n-1];
        spline_eval_interval(trajectory, axis, i, tend, value, slope);
        *value += (t - tend)*(*slope);
        return;
    }
    i = find_interval(trajectory, t);
    spline_eval_interval(trajectory, axis, i, t, value, slope);
}

static gint
compare_by_image_time(gconstpointer pa, gconstpointer pb)
{
    const DriftMeasurement *a = pa, *b = pb;

    if (a->t_image < b->t_image)
        return -1;
    return a->t_image > b->t_image;
}

/* Least-squares slope of y against t over n points; 0 when t has no
 * spread.  Sums are taken relative to the first point, so that constant y
 * gives exactly zero. */
static gdouble
least_squares_slope(const gdouble *t, const gdouble *y, gint n)
{
    gdouble tm = 0.0, ym = 0.0, stt = 0.0, sty = 0.0;
    gint i;

    for (i = 0; i < n; i++) {
        tm += t[i] - t[0];
        ym += y[i] - y[0];
    }
    tm /= n;
    ym /= n;
    for (i = 0; i < n; i++) {
        stt += (t[i] - t[0] - tm)*(t[i] - t[0] - tm);
        sty += (t[i] - t[0] - tm)*(y[i] - y[0] - ym);
    }
    return stt > 0.0 ? sty/stt : 0.0;
}

/* The positions at the image times are p(t_image) - p(t_ref)
 * = m + p(t_local) - p(t_ref), so the drift during the local scans is
 * needed.  It is taken as a constant velocity v estimated from the last half
 * of the frame (the part closest in time to the local scans): the slope of
 * m + v tau against t_image, tau = t_local - t_ref, must be v itself, which
 * is linear in v. */
static void
estimate_local_velocity(const DriftMeasurement *sorted, gint n, gdouble t_ref,
                        gdouble *v_local)
{
    gint first = n - MAX(2, (n + 1)/2), k, i;
    gdouble *t, *y, *tau;
    gdouble tau_slope, m_slope;

    v_local[0] = v_local[1] = 0.0;
    if (n < 2)
        return;
    k = n - first;
    t = g_new(gdouble, 3*k);
    y = t + k;
    tau = y + k;
    for (i = 0; i < k; i++) {
        t[i] = sorted[first + i].t_image;
        tau[i] = sorted[first + i].t_local - t_ref;
    }
    tau_slope = least_squares_slope(t, tau, k);
    if (1.0 - tau_slope >= LOCAL_VELOCITY_MIN_DENOMINATOR) {
        for (i = 0; i < k; i++)
            y[i] = sorted[first + i].dx;
        m_slope = least_squares_slope(t, y, k);
        v_local[0] = m_slope/(1.0 - tau_slope);
        for (i = 0; i < k; i++)
            y[i] = sorted[first + i].dy;
        m_slope = least_squares_slope(t, y, k);
        v_local[1] = m_slope/(1.0 - tau_slope);
    }
    g_free(t);
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

DriftTrajectory*
drift_trajectory_new(const DriftMeasurement *meas, gint n, GError **error)
{
    DriftTrajectory *trajectory;
    DriftMeasurement *sorted;
    gdouble pos[2];
    gint i, k, count, axis;

    if (!check_measurements(meas, n, error))
        return NULL;

    sorted = g_memdup2(meas, n*sizeof(DriftMeasurement));
    qsort(sorted, n, sizeof(DriftMeasurement), compare_by_image_time);
    trajectory = g_new0(DriftTrajectory, 1);
    trajectory->t_ref = sorted[0].t_local;
    for (i = 1; i < n; i++)
        trajectory->t_ref = MIN(trajectory->t_ref, sorted[i].t_local);
    estimate_local_velocity(sorted, n, trajectory->t_ref, trajectory->v_local);

    trajectory->t = g_new(gdouble, 5*n);
    trajectory->value[0] = trajectory->t + n;
    trajectory->value[1] = trajectory->value[0] + n;
    trajectory->curv[0] = trajectory->value[1] + n;
    trajectory->curv[1] = trajectory->curv[0] + n;
    /* Measurements at the same image time are averaged into one knot. */
    for (i = 0; i < n; i = k) {
        pos[0] = pos[1] = 0.0;
        for (k = i; k < n && sorted[k].t_image == sorted[i].t_image; k++) {
            pos[0] += (sorted[k].dx
                       + trajectory->v_local[0]*(sorted[k].t_local
                                                 - trajectory->t_ref));
            pos[1] += (sorted[k].dy
                       + trajectory->v_local[1]*(sorted[k].t_local
                                                 - trajectory->t_ref));
        }
        count = trajectory->n++;
        trajectory->t[count] = sorted[i].t_image;
        trajectory->value[0][count] = pos[0]/(k - i);
        trajectory->value[1][count] = pos[1]/(k - i);
    }
    g_free(sorted);

    trajectory->is_zero = TRUE;
    for (axis = 0; axis < 2; axis++) {
        for (i = 0; i < trajectory->n; i++) {
            if (trajectory->value[axis][i] != 0.0)
                trajectory->is_zero = FALSE;
        }
        spline_not_a_knot_curvatures(trajectory->n, trajectory->t,
                                     trajectory->value[axis],
                                     trajectory->curv[axis]);
    }
    return trajectory;
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
 * absent; FALSE when present but not finite. */
static gboolean
extra_or_default(const DriftTable *table, gint s, const gchar *name,
                 gdouble fallback, gdouble *value, GError **error)
{
    if (!drift_table_get_extra(table, s, name, value)) {
        *value = fallback;
        return TRUE;
    }
    if (isfinite(*value))
        return TRUE;
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
