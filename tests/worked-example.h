/*
 *  The worked example of paper mode (docs/paper-mode.md): a 4 x 6 image A
 *  of the values 1 .. 24, N = 3 stripes of two rows with drift
 *  (1, 1), (-1, 0), (0, -1) px, the compensated image C with the fill
 *  value 12.5 (the mean of A) and the mask of the filled pixels.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_WORKED_EXAMPLE_H
#define LOCALSCAN_WORKED_EXAMPLE_H

#include <glib.h>

enum {
    WORKED_XRES = 4,
    WORKED_YRES = 6,
    WORKED_STRIPES = 3,
};

#define WORKED_FILL 12.5

/* Pixel (row r, column c) of A is worked_a[r*WORKED_XRES + c]. */
static const gdouble worked_a[WORKED_XRES*WORKED_YRES] = {
     1,  2,  3,  4,
     5,  6,  7,  8,
     9, 10, 11, 12,
    13, 14, 15, 16,
    17, 18, 19, 20,
    21, 22, 23, 24,
};

static const gint worked_dx[WORKED_STRIPES] = { 1, -1, 0 };
static const gint worked_dy[WORKED_STRIPES] = { 1, 0, -1 };

/* The same drift as a table. */
static const gchar worked_table[] =
    "stripe,dx,dy\n"
    "0,1,1\n"
    "1,-1,0\n"
    "2,0,-1\n";

static const gdouble worked_c[WORKED_XRES*WORKED_YRES] = {
    6.0,  7.0,  8.0,  12.5,
    12.5, 9.0,  10.0, 11.0,
    12.5, 9.0,  10.0, 11.0,
    12.5, 13.0, 14.0, 15.0,
    12.5, 13.0, 14.0, 15.0,
    17.0, 18.0, 19.0, 20.0,
};

static const gdouble worked_mask[WORKED_XRES*WORKED_YRES] = {
    0, 0, 0, 1,
    1, 0, 0, 0,
    1, 0, 0, 0,
    1, 0, 0, 0,
    1, 0, 0, 0,
    0, 0, 0, 0,
};

#endif
