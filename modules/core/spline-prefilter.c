/*
 *  The B-spline/o-MOMS coefficient prefilter along rows and down columns.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <math.h>
#include "spline-prefilter.h"
#include "vector-loops.h"

/* Factors the symmetric tridiagonal system (side, centre, side) with the
 * mirror extension, whose first and last pivots see centre + side. */
void
spline_prefilter_init(SplinePrefilter *prefilter, gint n, gdouble centre,
                      gdouble side)
{
    gdouble pivot, q;
    gint i;

    prefilter->n = n;
    prefilter->side = side;
    prefilter->factor = g_new(gdouble, 2*n);
    prefilter->inv_diag = prefilter->factor + n;
    prefilter->factor[0] = 0.0;
    if (n == 1) {
        prefilter->inv_diag[0] = 1.0/(centre + 2.0*side);
        return;
    }
    pivot = centre + side;
    prefilter->inv_diag[0] = 1.0/pivot;
    for (i = 1; i < n; i++) {
        q = side/pivot;
        pivot = (i == n-1 ? centre + side : centre) - q*side;
        prefilter->factor[i] = q;
        prefilter->inv_diag[i] = 1.0/pivot;
    }
}

void
spline_prefilter_clear(SplinePrefilter *prefilter)
{
    g_free(prefilter->factor);
    prefilter->factor = prefilter->inv_diag = NULL;
}

/* Steps over which an error in a back substitution's starting value
 * shrinks below 2^-60 of itself (each step multiplies it by side/pivot):
 * well below a double's rounding, 2^-53, so a substitution started that
 * far away from a guess agrees with the exact one to rounding.  32 steps
 * for B-spline, 39 for o-MOMS. */
gint
spline_prefilter_warmup(const SplinePrefilter *prefilter)
{
    gdouble decay = 0.0;
    gint i;

    for (i = 0; i < prefilter->n; i++)
        decay = MAX(decay, prefilter->side*prefilter->inv_diag[i]);
    if (decay <= 0.0)
        return 0;
    return (gint)ceil(-60.0*G_LN2/log(decay));
}

/* Data values to interpolation coefficients along one row, in place. */
void
spline_prefilter_row(const SplinePrefilter *prefilter, gdouble *data)
{
    const gdouble *factor = prefilter->factor, *inv_diag = prefilter->inv_diag;
    gdouble side = prefilter->side;
    gint n = prefilter->n, i;

    for (i = 1; i < n; i++)
        data[i] -= factor[i]*data[i-1];
    data[n-1] *= inv_diag[n-1];
    for (i = n-2; i >= 0; i--)
        data[i] = (data[i] - side*data[i+1])*inv_diag[i];
}

#if defined(__GNUC__)
/* Two doubles as one value, the SSE2 vector.  The running values of the x
 * prefilter's recursions stay in registers this way; in an array GCC keeps
 * them in memory, and every step of the chain waits for a store to be
 * forwarded to the next load (wider vectors are spilled the same way where
 * AVX is missing).  Aligned as a double: the buffers are. */
typedef gdouble Pair __attribute__((vector_size(2*sizeof(gdouble)),
                                    aligned(sizeof(gdouble))));

static inline Pair
pair_gather(const gdouble *p, gsize stride)
{
    Pair v = { p[0], p[stride] };

    return v;
}

static inline void
pair_scatter(gdouble *p, gsize stride, Pair v)
{
    p[0] = v[0];
    p[stride] = v[1];
}

/* Data values of SPLINE_PREFILTER_BATCH rows of src (src_stride apart) to
 * coefficients in rows (stride apart).  Each row's recursion is a serial
 * chain; the eight rows' chains run side by side in four Pairs, and lanes
 * keeps the forward pass (n groups of four Pairs) for the backward one.
 * rows should be padded (stride not a multiple of 4 KiB) so that writing
 * them across does not keep evicting the same cache set. */
static void VECTOR_CLONES
prefilter_batch_lanes(const SplinePrefilter *prefilter, Pair *restrict lanes,
                      const gdouble *restrict src, gsize src_stride,
                      gdouble *restrict rows, gsize stride)
{
    const gdouble *factor = prefilter->factor, *inv_diag = prefilter->inv_diag;
    gdouble side = prefilter->side, f, inv;
    gsize s = src_stride, t = stride;
    gint n = prefilter->n, i;
    Pair c0, c1, c2, c3, *lane;

    G_STATIC_ASSERT(SPLINE_PREFILTER_BATCH == 8);
    c0 = pair_gather(src, s);
    c1 = pair_gather(src + 2*s, s);
    c2 = pair_gather(src + 4*s, s);
    c3 = pair_gather(src + 6*s, s);
    lanes[0] = c0;
    lanes[1] = c1;
    lanes[2] = c2;
    lanes[3] = c3;
    for (i = 1; i < n; i++) {
        f = factor[i];
        c0 = pair_gather(src + i, s) - f*c0;
        c1 = pair_gather(src + 2*s + i, s) - f*c1;
        c2 = pair_gather(src + 4*s + i, s) - f*c2;
        c3 = pair_gather(src + 6*s + i, s) - f*c3;
        lane = lanes + 4*i;
        lane[0] = c0;
        lane[1] = c1;
        lane[2] = c2;
        lane[3] = c3;
    }
    inv = inv_diag[n-1];
    c0 *= inv;
    c1 *= inv;
    c2 *= inv;
    c3 *= inv;
    pair_scatter(rows + n-1, t, c0);
    pair_scatter(rows + 2*t + n-1, t, c1);
    pair_scatter(rows + 4*t + n-1, t, c2);
    pair_scatter(rows + 6*t + n-1, t, c3);
    /* (x - side c) inv as x inv - (side inv) c: the chain waits for one
     * multiply-add per step instead of two operations. */
    for (i = n-2; i >= 0; i--) {
        inv = inv_diag[i];
        f = side*inv;
        lane = lanes + 4*i;
        c0 = lane[0]*inv - f*c0;
        c1 = lane[1]*inv - f*c1;
        c2 = lane[2]*inv - f*c2;
        c3 = lane[3]*inv - f*c3;
        pair_scatter(rows + i, t, c0);
        pair_scatter(rows + 2*t + i, t, c1);
        pair_scatter(rows + 4*t + i, t, c2);
        pair_scatter(rows + 6*t + i, t, c3);
    }
}
#else
typedef gdouble Pair;

/* Data values of SPLINE_PREFILTER_BATCH rows of src (src_stride apart) to
 * coefficients in rows (stride apart).  Each row's recursion is a serial
 * chain; in lanes (n groups of SPLINE_PREFILTER_BATCH) the rows' values
 * at one column lie side by side, so the chains run together. */
static void
prefilter_batch_lanes(const SplinePrefilter *prefilter, Pair *restrict lanes,
                      const gdouble *restrict src, gsize src_stride,
                      gdouble *restrict rows, gsize stride)
{
    const gdouble *factor = prefilter->factor, *inv_diag = prefilter->inv_diag;
    gdouble side = prefilter->side, f, inv;
    gdouble *restrict lane;
    gint n = prefilter->n, i, k;

    for (k = 0; k < SPLINE_PREFILTER_BATCH; k++)
        lanes[k] = src[k*src_stride];
    for (i = 1; i < n; i++) {
        f = factor[i];
        lane = lanes + i*SPLINE_PREFILTER_BATCH;
        for (k = 0; k < SPLINE_PREFILTER_BATCH; k++)
            lane[k] = (src[k*src_stride + i]
                       - f*lane[k - SPLINE_PREFILTER_BATCH]);
    }
    lane = lanes + (n-1)*SPLINE_PREFILTER_BATCH;
    inv = inv_diag[n-1];
    for (k = 0; k < SPLINE_PREFILTER_BATCH; k++) {
        lane[k] *= inv;
        rows[k*stride + n-1] = lane[k];
    }
    for (i = n-2; i >= 0; i--) {
        inv = inv_diag[i];
        f = side*inv;
        lane = lanes + i*SPLINE_PREFILTER_BATCH;
        for (k = 0; k < SPLINE_PREFILTER_BATCH; k++) {
            lane[k] = lane[k]*inv - f*lane[k + SPLINE_PREFILTER_BATCH];
            rows[k*stride + i] = lane[k];
        }
    }
}
#endif

/* The lanes' vector type stays private to this file. */
void
spline_prefilter_batch(const SplinePrefilter *prefilter, gdouble *lanes,
                       const gdouble *src, gsize src_stride,
                       gdouble *rows, gsize stride)
{
    prefilter_batch_lanes(prefilter, (Pair*)lanes, src, src_stride,
                          rows, stride);
}

void VECTOR_CLONES
spline_eliminate_row(gdouble *restrict row, const gdouble *restrict prev,
                     gdouble q, gint n)
{
    gint c = 0, j;

    for (; c + ROW_CHUNK <= n; c += ROW_CHUNK) {
        for (j = 0; j < ROW_CHUNK; j++)
            row[c + j] -= q*prev[c + j];
    }
    for (; c < n; c++)
        row[c] -= q*prev[c];
}

void VECTOR_CLONES
spline_substitute_row(gdouble *restrict row, const gdouble *restrict below,
                      gdouble side, gdouble inv, gint n)
{
    gint c = 0, j;

    for (; c + ROW_CHUNK <= n; c += ROW_CHUNK) {
        for (j = 0; j < ROW_CHUNK; j++)
            row[c + j] = (row[c + j] - side*below[c + j])*inv;
    }
    for (; c < n; c++)
        row[c] = (row[c] - side*below[c])*inv;
}

void VECTOR_CLONES
spline_substitute_row_over(gdouble *restrict row,
                           const gdouble *restrict eliminated,
                           gdouble side, gdouble inv, gint n)
{
    gint c = 0, j;

    for (; c + ROW_CHUNK <= n; c += ROW_CHUNK) {
        for (j = 0; j < ROW_CHUNK; j++)
            row[c + j] = (eliminated[c + j] - side*row[c + j])*inv;
    }
    for (; c < n; c++)
        row[c] = (eliminated[c] - side*row[c])*inv;
}
