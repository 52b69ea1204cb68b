/*
 *  A smooth surface on a regular grid: cubic B-spline coefficients with
 *  mirror (measured images) or periodic (synthetic substrate) extension.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef SIMSCAN_SPLINE_GRID_H
#define SIMSCAN_SPLINE_GRID_H

#include <glib.h>

G_BEGIN_DECLS

typedef enum {
    SPLINE_GRID_MIRROR,        /* half-sample mirror, as Gwyddion's coefficients */
    SPLINE_GRID_PERIODIC,
} SplineGridBoundary;

typedef struct {
    gint nx, ny;
    gdouble x0, y0;            /* position of node (0, 0) */
    gdouble dx, dy;            /* node spacing */
    SplineGridBoundary boundary;
    gdouble *coeff;            /* nx*ny B-spline coefficients, row by row */
} SplineGrid;

/* Coefficients uninitialised. */
SplineGrid*  spline_grid_new               (gint nx, gint ny,
                                            gdouble x0, gdouble y0,
                                            gdouble dx, gdouble dy,
                                            SplineGridBoundary boundary);
/* A mirror-extended grid that interpolates values at its nodes exactly. */
SplineGrid*  spline_grid_new_interpolating (const gdouble *values,
                                            gint nx, gint ny,
                                            gdouble x0, gdouble y0,
                                            gdouble dx, gdouble dy);
void         spline_grid_free              (SplineGrid *grid);
gdouble      spline_grid_eval              (const SplineGrid *grid,
                                            gdouble x, gdouble y);

G_END_DECLS

#endif
