/*
 *  The drift trajectory over scan time, built from per-stripe local-scan
 *  measurements (docs/conventions.md).
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_DRIFT_TRAJECTORY_H
#define LOCALSCAN_DRIFT_TRAJECTORY_H

#include <glib.h>
#include "drift-table.h"
#include "scan-timing.h"
#include "drift-measurement.h"

G_BEGIN_DECLS

#define DRIFT_TRAJECTORY_ERROR drift_trajectory_error_quark()

typedef enum {
    DRIFT_TRAJECTORY_ERROR_EMPTY,     /* no stripe was measured */
    DRIFT_TRAJECTORY_ERROR_VALUE,     /* NaN/inf time or drift */
    DRIFT_TRAJECTORY_ERROR_TIMING,    /* timing unusable or not the image's */
} DriftTrajectoryError;

/* A local-scan measurement (drift-measurement.h), in px: the particle
 * imaged at t_a (in the big frame) is found by the local scan at t_b
 * displaced by (dx, dy), so (dx, dy) = p(t_a) - p(t_b).  weight and group
 * are not used here. */

typedef struct _DriftTrajectory DriftTrajectory;

GQuark            drift_trajectory_error_quark  (void);

/* Builds the displacement D(t) = p(t) - p(t_ref), t_ref the earliest t_b
 * of the measurements, from n measurements in any order.  With six or more
 * distinct image times the measured values are smoothed first, robustly
 * (penalised least squares on third differences, iteratively reweighted
 * with Tukey's biweight, penalty weight by a robust C_p), so measurement
 * noise is averaged over instead of interpolated and a gross error (a
 * local scan that found the wrong particle) gets weight 0 instead of
 * moving its neighbours; exact measurements of smooth drift keep their
 * values to far below 0.01 px. */
DriftTrajectory*  drift_trajectory_new          (const DriftMeasurement *meas,
                                                 gint n,
                                                 GError **error);
/* The same without smoothing: the spline passes through every
 * measurement. */
DriftTrajectory*  drift_trajectory_new_interpolating
                                                (const DriftMeasurement *meas,
                                                 gint n,
                                                 GError **error);

/* Measurements of a table for an image of timing->yres rows: stripes with a
 * blank dx, dy are left out (no nearest-stripe filling); dx_exact, dy_exact
 * (px) are preferred to dx, dy (table unit, converted with the pixel sizes);
 * t_image defaults to the centre time of the stripe's pixels, t_local to the
 * end of the frame.  Returns the number of measurements written into meas
 * (room for table->n_stripes), or -1 with error set. */
gint              drift_trajectory_measurements_from_table
                                                (const DriftTable *table,
                                                 gdouble x_pixel_size,
                                                 gdouble y_pixel_size,
                                                 const ScanTiming *timing,
                                                 DriftMeasurement *meas,
                                                 GError **error);

/* drift_trajectory_measurements_from_table() then drift_trajectory_new(). */
DriftTrajectory*  drift_trajectory_new_from_table
                                                (const DriftTable *table,
                                                 gdouble x_pixel_size,
                                                 gdouble y_pixel_size,
                                                 const ScanTiming *timing,
                                                 GError **error);

void              drift_trajectory_free         (DriftTrajectory *trajectory);

/* D(t) in px: a feature truly at X (as it was at t_ref) appears at
 * X + D(t) in a pixel scanned at t. */
void              drift_trajectory_eval         (const DriftTrajectory *trajectory,
                                                 gdouble t,
                                                 gdouble *dx,
                                                 gdouble *dy);
/* dD/dt in px/s. */
void              drift_trajectory_velocity     (const DriftTrajectory *trajectory,
                                                 gdouble t,
                                                 gdouble *vx,
                                                 gdouble *vy);
/* The moment the compensated image shows: the earliest local scan. */
gdouble           drift_trajectory_reference_time(const DriftTrajectory *trajectory);
/* The drift velocity assumed while the local scans ran (px/s). */
void              drift_trajectory_local_velocity(const DriftTrajectory *trajectory,
                                                  gdouble *vx,
                                                  gdouble *vy);
/* TRUE when D(t) is zero at every t. */
gboolean          drift_trajectory_is_zero      (const DriftTrajectory *trajectory);

/* A measurement whose weight is below this is reported as down-weighted. */
#define DRIFT_TRAJECTORY_DOWNWEIGHTED 0.5

/* The measurements the trajectory was built from: for
 * drift_trajectory_new() and _interpolating() those given, in their order;
 * for drift_trajectory_new_from_table() the measured stripes in order. */
gint              drift_trajectory_n_measurements(const DriftTrajectory *trajectory);
/* Weight 0 .. 1 the robust fit gave measurement i: 1 for a measurement
 * consistent with the others, 0 for a gross error that was ignored (always
 * 1 without smoothing).  The smaller of the x and y weights. */
gdouble           drift_trajectory_measurement_weight(const DriftTrajectory *trajectory,
                                                      gint i);
/* How far measurement i lies from the trajectory, px: |(dx, dy) -
 * (D(t_a) - v (t_b - t_ref))|, v the drift during the local scans the
 * trajectory estimated (0 where it cannot be told). */
gdouble           drift_trajectory_measurement_residual(const DriftTrajectory *trajectory,
                                                        gint i);
/* The stripe of measurement i for a trajectory from a table, else i. */
gint              drift_trajectory_measurement_stripe(const DriftTrajectory *trajectory,
                                                      gint i);
/* Measurements with weight below DRIFT_TRAJECTORY_DOWNWEIGHTED. */
gint              drift_trajectory_n_downweighted(const DriftTrajectory *trajectory);

G_END_DECLS

#endif
