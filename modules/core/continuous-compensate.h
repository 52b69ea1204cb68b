/*
 *  Continuous (line-by-line, sub-pixel) compensation driven by a drift
 *  trajectory over scan time.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_CONTINUOUS_COMPENSATE_H
#define LOCALSCAN_CONTINUOUS_COMPENSATE_H

#include <glib.h>
#include <libprocess/gwyprocessenums.h>
#include "drift-table.h"
#include "drift-trajectory.h"
#include "scan-timing.h"

G_BEGIN_DECLS

#define CONTINUOUS_COMPENSATE_ERROR continuous_compensate_error_quark()

typedef enum {
    CONTINUOUS_COMPENSATE_ERROR_TIMING,        /* timing not of this image */
    CONTINUOUS_COMPENSATE_ERROR_INTERPOLATION, /* unsupported type */
    CONTINUOUS_COMPENSATE_ERROR_TOO_FAST,      /* drift folds the image over */
} ContinuousCompensateError;

GQuark   continuous_compensate_error_quark(void);

/* Compensates image a (yres rows of xres) continuously: the drift trajectory
 * is built from the table (times from its t_image/t_local columns when
 * present, else each stripe's centre line and the end of the frame), every
 * pixel is moved back by the drift at the moment it was scanned, with
 * sub-pixel interpolation.  Pixels with no source get fill_value and 1.0 in
 * mask (may be NULL), and so do those whose nearest source pixel is missing
 * (NaN or infinite; the kernel sees fill_value there, docs/missing-data.md).  The table's exact dx_exact/dy_exact columns are used in
 * preference to the rounded dx/dy when present.
 *
 * The result shows the sample as it was at the earliest local scan
 * (drift_trajectory_reference_time()).  timing must describe this image
 * (xres, yres); NULL means frame_start 0, line time 1 s, scanning down.
 * Blank stripes are left out of the trajectory (no nearest-stripe rule).
 * A pixel has a source when its source position lies within half a pixel
 * of the image's pixel centres in y, and in x within the nearest source
 * row; with whole-pixel drift this is exactly paper mode's rule.  result
 * and mask must not alias a.  Returns FALSE with error set (result and mask
 * untouched) on an unusable table, timing or interpolation type. */
gboolean continuous_compensate_table(const gdouble *a,
                                     gint xres,
                                     gint yres,
                                     const DriftTable *table,
                                     gdouble x_pixel_size,
                                     gdouble y_pixel_size,
                                     const ScanTiming *timing,
                                     GwyInterpolationType interpolation,
                                     gdouble fill_value,
                                     gdouble *result,
                                     gdouble *mask,
                                     GError **error);

/* Whether continuous_compensate_table() would accept the table, timing and
 * interpolation for an xres x yres image, with the same errors; builds the
 * trajectory and the resampling plan (work of the order of the rows), not
 * the image. */
gboolean continuous_compensate_check_table(gint xres,
                                           gint yres,
                                           const DriftTable *table,
                                           gdouble x_pixel_size,
                                           gdouble y_pixel_size,
                                           const ScanTiming *timing,
                                           GwyInterpolationType interpolation,
                                           GError **error);

/* The same with the trajectory given directly, D(t) in px (e.g. built
 * with drift_trajectory_new() from a drift model sampled densely). */
gboolean continuous_compensate_trajectory(const gdouble *a,
                                          gint xres,
                                          gint yres,
                                          const DriftTrajectory *trajectory,
                                          const ScanTiming *timing,
                                          GwyInterpolationType interpolation,
                                          gdouble fill_value,
                                          gdouble *result,
                                          gdouble *mask,
                                          GError **error);

G_END_DECLS

#endif
