/*
 *  The rigid frame-to-frame correction peers use, as the baseline the
 *  series benchmark compares against: each frame registered against the
 *  previous one by whole-frame FFT phase correlation, the shifts summed,
 *  and every frame moved back by one constant sub-pixel shift.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_RIGID_BASELINE_H
#define LOCALSCAN_RIGID_BASELINE_H

#include <glib.h>
#include <libprocess/datafield.h>
#include "frame-series.h"

G_BEGIN_DECLS

/* The cumulative shift of every frame relative to frame 0, px (n_frames
 * entries each, frame 0 = 0): the content of frame 0 at (r, c) appears in
 * frame k at (r + dy[k], c + dx[k]). */
void      rigid_baseline_shifts   (const FrameSeries *series,
                                   gdouble *dx,
                                   gdouble *dy);

/* frame moved back by (dx, dy) into result (same size as frame):
 * result(r, c) = frame(r + dy, c + dx), B-spline interpolated; pixels with
 * no source get the frame's mean. */
void      rigid_baseline_correct  (GwyDataField *frame,
                                   gdouble dx,
                                   gdouble dy,
                                   GwyDataField *result);

/* The largest rectangle (col, row, width, height) every one of n frames of
 * xres x yres covers once moved back by its shift; FALSE when none. */
gboolean  rigid_baseline_crop     (const gdouble *dx,
                                   const gdouble *dy,
                                   gint n,
                                   gint xres,
                                   gint yres,
                                   gint *col,
                                   gint *row,
                                   gint *width,
                                   gint *height);

G_END_DECLS

#endif
