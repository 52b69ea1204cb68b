/*
 *  When each pixel of a raster scan is measured (docs/conventions.md).
 *  Shared by the simulator, continuous compensation and fitting.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_SCAN_TIMING_H
#define LOCALSCAN_SCAN_TIMING_H

#include <glib.h>

G_BEGIN_DECLS

typedef enum {
    SCAN_DIRECTION_DOWN = 0,   /* row 0 first */
    SCAN_DIRECTION_UP   = 1,   /* row yres-1 first */
} ScanDirection;

typedef struct {
    gint xres;
    gint yres;
    gdouble frame_start;       /* s, t = 0 is the start of the first frame */
    gdouble line_time;         /* s per line, trace and retrace together */
    ScanDirection direction;
} ScanTiming;

/* "down" or "up", as the files and reports the tools write name it. */
const gchar* scan_direction_name(ScanDirection direction);

void     scan_timing_init        (ScanTiming *timing, gint xres, gint yres,
                                  gdouble frame_start, gdouble line_time,
                                  ScanDirection direction);
/* Start of the line that images row (fractional rows interpolate linearly). */
gdouble  scan_timing_row_start   (const ScanTiming *timing, gdouble row);
/* Moment the trace passes the centre of pixel (row, col): the trace takes the
 * first half of the line time, left to right, so col c is reached at
 * row_start + (c + 0.5) * line_time / (2 xres). */
gdouble  scan_timing_pixel_time  (const ScanTiming *timing, gdouble row, gdouble col);
/* Centre time of a block of rows [first, end): mean of its pixels' times. */
gdouble  scan_timing_rows_time   (const ScanTiming *timing, gint first, gint end);
gdouble  scan_timing_frame_end   (const ScanTiming *timing);
/* Inverse of scan_timing_row_start within the frame (fractional row). */
gdouble  scan_timing_row_at_time (const ScanTiming *timing, gdouble t);

G_END_DECLS

#endif
