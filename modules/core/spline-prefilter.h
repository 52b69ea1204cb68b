/*
 *  The B-spline/o-MOMS coefficient prefilter: the tridiagonal system that
 *  turns data values into interpolation coefficients, along a row (one
 *  row, or eight side by side) and, one step per row, down the columns of
 *  whole rows.  Internal to the core.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_SPLINE_PREFILTER_H
#define LOCALSCAN_SPLINE_PREFILTER_H

#include <glib.h>

G_BEGIN_DECLS

/* Rows whose recursions spline_prefilter_batch() runs side by side: each
 * row's recursion is a serial chain, and eight chains keep the multiply-add
 * units busy while each waits for its previous step. */
enum { SPLINE_PREFILTER_BATCH = 8 };

/* The factored system (side, centre, side) for one length n, with the
 * mirror extension (border value repeated) of Gwyddion.  The same for
 * every row (or column) of that length, so factored once. */
typedef struct {
    gint n;
    gdouble side;       /* off-diagonal element of the filter */
    gdouble *factor;    /* elimination factors, n; factor[0] = 0 */
    gdouble *inv_diag;  /* inverse pivots, n */
} SplinePrefilter;

void     spline_prefilter_init           (SplinePrefilter *prefilter,
                                          gint n,
                                          gdouble centre,
                                          gdouble side);
void     spline_prefilter_clear          (SplinePrefilter *prefilter);
gint     spline_prefilter_warmup         (const SplinePrefilter *prefilter);

/* Along a row: data values to coefficients in place. */
void     spline_prefilter_row            (const SplinePrefilter *prefilter,
                                          gdouble *data);
/* Along SPLINE_PREFILTER_BATCH rows of src (src_stride apart) at once,
 * coefficients into rows (stride apart); lanes is scratch of
 * SPLINE_PREFILTER_BATCH*n doubles. */
void     spline_prefilter_batch          (const SplinePrefilter *prefilter,
                                          gdouble *lanes,
                                          const gdouble *src,
                                          gsize src_stride,
                                          gdouble *rows,
                                          gsize stride);

/* Down the columns, one whole row of n columns per step.  Forward
 * elimination: row -= q prev. */
void     spline_eliminate_row            (gdouble *restrict row,
                                          const gdouble *restrict prev,
                                          gdouble q,
                                          gint n);
/* Back substitution: row = (row - side below) inv. */
void     spline_substitute_row           (gdouble *restrict row,
                                          const gdouble *restrict below,
                                          gdouble side,
                                          gdouble inv,
                                          gint n);
/* The same kept in one buffer, row = (eliminated - side row) inv, for
 * steps whose results are not kept. */
void     spline_substitute_row_over      (gdouble *restrict row,
                                          const gdouble *restrict eliminated,
                                          gdouble side,
                                          gdouble inv,
                                          gint n);

G_END_DECLS

#endif
