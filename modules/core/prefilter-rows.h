/*
 *  The B-spline/o-MOMS prefilter along y of the x-corrected rows, made in
 *  blocks of rows through a ring instead of a full-size image.  Internal
 *  to the core.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_PREFILTER_ROWS_H
#define LOCALSCAN_PREFILTER_ROWS_H

#include <glib.h>
#include <libprocess/gwyprocessenums.h>
#include "row-resample.h"
#include "spline-prefilter.h"

G_BEGIN_DECLS

/* Coefficient rows made per back substitution along y.  Each block pays a
 * warm-up of spline_prefilter_warmup() steps (32 for B-spline, 39 for
 * o-MOMS) on a scratch row, and the ring holds the block, its warm-up and
 * a few rows more.  64 keeps the warm-up at or below about half the
 * block's own work while the ring stays near a hundred rows (0.8 MiB at
 * 1024 columns), so the rows an output row combines are still in cache. */
enum { PREFILTER_ROWS_BLOCK = 64 };

/* Rows from the block being made on hold the forward elimination, rows
 * before it coefficients.  The back substitution of a block starts warmup
 * rows below it from the elimination alone (as if the coefficient below
 * were zero); the error that makes shrinks by side/pivot per row, to below
 * 2^-60 of itself at the block, so no full-size image of eliminated rows
 * is needed. */
typedef struct {
    RowResampler *resampler;
    SplinePrefilter prefilter;
    gint warmup;
    gint ring_rows;
    gdouble *rows;
    gdouble *scratch;        /* the warm-up's coefficient row */
    const gdouble *below;    /* coefficients below the next row made */
    gint next_source;        /* first row not yet x-corrected and eliminated */
} PrefilterRows;

void     prefilter_rows_init         (PrefilterRows *prefilter_rows,
                                      RowResampler *resampler,
                                      GwyInterpolationType interpolation);
void     prefilter_rows_clear        (PrefilterRows *prefilter_rows);
/* Prepares the back substitution of the block of rows ending before end,
 * made from end-1 up by prefilter_rows_make(). */
void     prefilter_rows_begin_block  (PrefilterRows *prefilter_rows,
                                      gint end);
/* Coefficient row i, the row above the one made last. */
void     prefilter_rows_make         (PrefilterRows *prefilter_rows,
                                      gint i);

/* Coefficient row i, which must be alive in the ring. */
static inline const gdouble*
prefilter_rows_get(const PrefilterRows *prefilter_rows, gint i)
{
    return (prefilter_rows->rows
            + ((i % prefilter_rows->ring_rows)
               *(gsize)prefilter_rows->resampler->xres));
}

G_END_DECLS

#endif
