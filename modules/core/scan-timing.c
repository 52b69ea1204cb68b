/*
 *  When each pixel of a raster scan is measured.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include "scan-timing.h"

const gchar*
scan_direction_name(ScanDirection direction)
{
    return direction == SCAN_DIRECTION_UP ? "up" : "down";
}

void
scan_timing_init(ScanTiming *timing, gint xres, gint yres,
                 gdouble frame_start, gdouble line_time,
                 ScanDirection direction)
{
    timing->xres = xres;
    timing->yres = yres;
    timing->frame_start = frame_start;
    timing->line_time = line_time;
    timing->direction = direction;
}

/* Lines in the order they are scanned: row for a downward scan, mirrored for
 * an upward one. */
static gdouble
scan_order_of_row(const ScanTiming *timing, gdouble row)
{
    if (timing->direction == SCAN_DIRECTION_UP)
        return (timing->yres - 1) - row;
    return row;
}

gdouble
scan_timing_row_start(const ScanTiming *timing, gdouble row)
{
    return timing->frame_start + scan_order_of_row(timing, row)*timing->line_time;
}

gdouble
scan_timing_pixel_time(const ScanTiming *timing, gdouble row, gdouble col)
{
    return (scan_timing_row_start(timing, row)
            + (col + 0.5)*timing->line_time/(2.0*timing->xres));
}

/* Pixel times are linear in the column, so a block's mean time is the mean
 * of its rows' middle-pixel times. */
gdouble
scan_timing_rows_time(const ScanTiming *timing, gint first, gint end)
{
    gdouble mid_row = 0.5*(first + end - 1);

    return scan_timing_pixel_time(timing, mid_row, 0.5*(timing->xres - 1));
}

gdouble
scan_timing_frame_end(const ScanTiming *timing)
{
    return timing->frame_start + timing->yres*timing->line_time;
}

gdouble
scan_timing_row_at_time(const ScanTiming *timing, gdouble t)
{
    gdouble order = (t - timing->frame_start)/timing->line_time;

    if (timing->direction == SCAN_DIRECTION_UP)
        return (timing->yres - 1) - order;
    return order;
}
