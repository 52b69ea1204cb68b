/*
 *  A smooth surface on a regular grid (cubic B-spline).
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <string.h>
#include <math.h>
#include <libprocess/interpolation.h>
#include "spline-grid.h"

/* Node coordinates beyond this are reduced by whole periods before they
 * are made indices (far below G_MAXINT, far above any real image). */
#define SPLINE_GRID_INDEX_BOUND 1e8

SplineGrid*
spline_grid_new(gint nx, gint ny, gdouble x0, gdouble y0,
                gdouble dx, gdouble dy, SplineGridBoundary boundary)
{
    SplineGrid *grid = g_new(SplineGrid, 1);

    grid->nx = nx;
    grid->ny = ny;
    grid->x0 = x0;
    grid->y0 = y0;
    grid->dx = dx;
    grid->dy = dy;
    grid->boundary = boundary;
    grid->coeff = g_new(gdouble, (gsize)nx*ny);
    return grid;
}

/* Gwyddion's B-spline coefficients assume the half-sample mirror boundary,
 * which is what spline_grid_eval applies to a mirror grid. */
SplineGrid*
spline_grid_new_interpolating(const gdouble *values, gint nx, gint ny,
                              gdouble x0, gdouble y0, gdouble dx, gdouble dy)
{
    SplineGrid *grid = spline_grid_new(nx, ny, x0, y0, dx, dy,
                                       SPLINE_GRID_MIRROR);

    memcpy(grid->coeff, values, (gsize)nx*ny*sizeof(gdouble));
    gwy_interpolation_resolve_coeffs_2d(nx, ny, nx, grid->coeff,
                                        GWY_INTERPOLATION_BSPLINE);
    return grid;
}

void
spline_grid_free(SplineGrid *grid)
{
    if (!grid)
        return;
    g_free(grid->coeff);
    g_free(grid);
}

static inline gint
boundary_index(gint i, gint n, SplineGridBoundary boundary)
{
    if (boundary == SPLINE_GRID_PERIODIC) {
        i %= n;
        return i < 0 ? i + n : i;
    }
    /* Mirror, repeated for points far outside a tiny grid. */
    i %= 2*n;
    if (i < 0)
        i += 2*n;
    return i < n ? i : 2*n - 1 - i;
}

static inline void
bspline_weights(gdouble t, gdouble *w)
{
    gdouble s = 1.0 - t, t2 = t*t, t3 = t2*t;

    w[0] = s*s*s/6.0;
    w[1] = (3.0*t3 - 6.0*t2 + 4.0)/6.0;
    w[2] = (-3.0*t3 + 3.0*t2 + 3.0*t + 1.0)/6.0;
    w[3] = t3/6.0;
}

/* Both boundaries repeat: a periodic grid every n nodes, a mirrored one
 * every 2n.  A coordinate far outside (a sample drifted by metres, a
 * position of 1e12 nodes) is brought back by whole periods before it
 * becomes an index, so the index always fits a gint; fmod() is exact, and
 * coordinates within the bound are used as they are. */
static inline gdouble
within_index_range(gdouble u, gint n, SplineGridBoundary boundary)
{
    gdouble period = (boundary == SPLINE_GRID_PERIODIC ? 1.0 : 2.0)*n;

    if (fabs(u) < SPLINE_GRID_INDEX_BOUND)
        return u;
    if (!isfinite(u))
        return 0.0;
    return fmod(u, period);
}

gdouble
spline_grid_eval(const SplineGrid *grid, gdouble x, gdouble y)
{
    gdouble u = within_index_range((x - grid->x0)/grid->dx, grid->nx, grid->boundary);
    gdouble v = within_index_range((y - grid->y0)/grid->dy, grid->ny, grid->boundary);
    gdouble fu = floor(u), fv = floor(v), wx[4], wy[4], z = 0.0, zrow;
    gint i = (gint)fv, j = (gint)fu, k, l, cols[4];
    const gdouble *row;

    bspline_weights(u - fu, wx);
    bspline_weights(v - fv, wy);
    for (l = 0; l < 4; l++)
        cols[l] = boundary_index(j - 1 + l, grid->nx, grid->boundary);
    for (k = 0; k < 4; k++) {
        row = grid->coeff + (gsize)grid->nx*boundary_index(i - 1 + k, grid->ny,
                                                           grid->boundary);
        zrow = (wx[0]*row[cols[0]] + wx[1]*row[cols[1]]
                + wx[2]*row[cols[2]] + wx[3]*row[cols[3]]);
        z += wy[k]*zrow;
    }
    return z;
}
