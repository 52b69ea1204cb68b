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
#include "scan-timing.h"

G_BEGIN_DECLS

/* Compensates image a (yres rows of xres) continuously: the drift trajectory
 * is built from the table (times from its t_image/t_local columns when
 * present, else each stripe's centre line and the end of the frame), every
 * pixel is moved back by the drift at the moment it was scanned, with
 * sub-pixel interpolation.  Pixels with no source get fill_value and 1.0 in
 * mask (may be NULL).  The table's exact dx_exact/dy_exact columns are used in
 * preference to the rounded dx/dy when present. */
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

G_END_DECLS

#endif
