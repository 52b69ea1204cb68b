/*
 *  Resampling of scanned rows in x, with the shear within the line.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <math.h>
#include <string.h>
#include "interpolation-kernels.h"
#include "row-resample.h"
#include "vector-loops.h"

/* Padding of the x coefficient rows, which spline_prefilter_batch() writes
 * across, eight at a time: rows a multiple of 4 KiB apart (xres 4096 is 32
 * KiB) would all fall into the same cache sets and keep evicting each
 * other. */
enum { PREFILTER_ROW_PAD = 8 };

/* One output pixel at source position x (clamped to the image's extent:
 * values beyond it only feed neighbours of filled pixels), with mirrored
 * taps near the ends. */
KERNEL_INLINE gdouble
resample_pixel(GwyInterpolationType type, const gdouble *src, gint n,
               gdouble x)
{
    gdouble w[KERNEL_TAPS], frac;
    gint i;

    x = CLAMP(x, -0.5, n - 0.5);
    i = kernel_tap_below(x, &frac);
    kernel_weights(type, frac, w);
    return (w[0]*src[kernel_mirror_index(i-1, n)]
            + w[1]*src[kernel_mirror_index(i, n)]
            + w[2]*src[kernel_mirror_index(i+1, n)]
            + w[3]*src[kernel_mirror_index(i+2, n)]);
}

/* Output pixels from c on that read the source at the same offset d = i - c
 * with all four taps inside: the last such pixel, or c - 1 if c is not one.
 * x_step is within a hair of 1, so runs span most of the row. */
static gint
constant_offset_run(gdouble x_start, gdouble x_step, gint n, gint c, gint *d)
{
    gdouble x = x_start + x_step*c, e = x_step - 1.0, frac, span;
    gint i, last;

    if (!(x >= 1.0 && x < n - 3.0))
        return c - 1;
    i = (gint)x;
    *d = i - c;
    frac = x - i;
    /* Stop a pixel early so rounding cannot carry frac out of [0, 1). */
    if (e > 0.0)
        span = (1.0 - frac)/e - 1.0;
    else if (e < 0.0)
        span = frac/(-e) - 1.0;
    else
        span = n;
    last = (span < n) ? c + (gint)MAX(span, 0.0) : n - 1;
    return MIN(last, MIN(n - 4 - *d, n - 1));
}

/* Output pixels first .. last, all reading the source at the offset
 * d = i - c with four taps inside.  The position is computed per pixel
 * from the column, never stepped on (x_start + x_step c rounds differently
 * from one column to the next, exactly as Gwyddion's c + shift does), with
 * columns counted in doubles, which hold integers exactly.  With
 * eliminate, q times prev is subtracted (the y prefilter's forward
 * elimination, done while the values are at hand). */
KERNEL_INLINE void
resample_run(GwyInterpolationType type, gboolean eliminate,
             const gdouble *restrict src, gint d,
             gdouble x_start, gdouble x_step, gint first, gint last,
             const gdouble *restrict prev, gdouble q, gdouble *restrict dest)
{
    const gdouble *s = src + d;
    gdouble w[KERNEL_TAPS], column, offset = d, v;
    gint c = first, j;

    for (; c + ROW_CHUNK - 1 <= last; c += ROW_CHUNK) {
        column = c;
        for (j = 0; j < ROW_CHUNK; j++) {
            kernel_weights(type, ((x_start + x_step*(column + j))
                                  - ((column + j) + offset)), w);
            v = kernel_apply(type, s + c + j, w);
            dest[c + j] = eliminate ? v - q*prev[c + j] : v;
        }
    }
    for (; c <= last; c++) {
        kernel_weights(type, (x_start + x_step*c) - (c + d), w);
        v = kernel_apply(type, s + c, w);
        dest[c] = eliminate ? v - q*prev[c] : v;
    }
}

/* Resamples one row: dest[c] = src at x_start + x_step*c (minus q prev[c]
 * with eliminate).  Within runs of constant tap offset the taps are read
 * without index arithmetic or edge checks, so the loop is a straight
 * polynomial-and-dot-product.  Pixels whose source lies beyond an end of
 * the row all take the value there (resample_pixel() clamps), computed
 * once per end: a series drifting by more than a frame puts most pixels
 * of its late frames there, and computing their mirrored taps pixel by
 * pixel took two thirds of the time of correcting 1000 frames.  The
 * statements are those of the pixel-by-pixel path, so each compiled
 * version rounds as before, to the last bit. */
KERNEL_INLINE void
resample_row_with(GwyInterpolationType type, gboolean eliminate,
                  const gdouble *restrict src, gint n,
                  gdouble x_start, gdouble x_step,
                  const gdouble *restrict prev, gdouble q,
                  gdouble *restrict dest)
{
    gint c = 0, d, last, side = 0, clamped_side;
    gdouble x, clamped_value = 0.0;

    while (c < n) {
        x = x_start + x_step*c;
        clamped_side = (x <= -0.5) ? -1 : (x >= n - 0.5) ? 1 : 0;
        if (clamped_side && clamped_side == side) {
            dest[c] = clamped_value;
            if (eliminate)
                dest[c] -= q*prev[c];
            c++;
            continue;
        }
        last = constant_offset_run(x_start, x_step, n, c, &d);
        if (last < c) {
            dest[c] = resample_pixel(type, src, n, x);
            side = clamped_side;
            clamped_value = dest[c];
            if (eliminate)
                dest[c] -= q*prev[c];
            c++;
            continue;
        }
        resample_run(type, eliminate, src, d, x_start, x_step, c, last,
                     prev, q, dest);
        c = last + 1;
    }
}

/* resample_row_with() for one kernel, with the elimination fused for the
 * kernels that have a prefilter; returns whether it was.  Always inlined
 * with type a constant, so the test folds away and each kernel keeps its
 * own loop. */
KERNEL_INLINE gboolean
resample_row_as(GwyInterpolationType type, const gdouble *restrict src,
                gint n, gdouble x_start, gdouble x_step,
                const gdouble *restrict prev, gdouble q,
                gdouble *restrict dest)
{
    if (prev && (type == GWY_INTERPOLATION_BSPLINE
                 || type == GWY_INTERPOLATION_OMOMS)) {
        resample_row_with(type, TRUE, src, n, x_start, x_step, prev, q, dest);
        return TRUE;
    }
    resample_row_with(type, FALSE, src, n, x_start, x_step, NULL, 0.0, dest);
    return FALSE;
}

/* Each case names its kernel as a constant (see resample_row_as()). */
#define RESAMPLE_ROW_CASE(kernel) \
    case kernel: \
    fused = resample_row_as(kernel, src, n, x_start, x_step, prev, q, dest); \
    break

/* One specialised loop per kernel, so the weights are computed inline
 * (prev may be NULL for no elimination). */
static void VECTOR_CLONES
resample_row(GwyInterpolationType type, const gdouble *restrict src, gint n,
             gdouble x_start, gdouble x_step,
             const gdouble *restrict prev, gdouble q, gdouble *restrict dest)
{
    gboolean fused = FALSE;

    switch (type) {
        RESAMPLE_ROW_CASE(GWY_INTERPOLATION_ROUND);
        RESAMPLE_ROW_CASE(GWY_INTERPOLATION_LINEAR);
        RESAMPLE_ROW_CASE(GWY_INTERPOLATION_KEY);
        RESAMPLE_ROW_CASE(GWY_INTERPOLATION_SCHAUM);
        RESAMPLE_ROW_CASE(GWY_INTERPOLATION_NNA);
        RESAMPLE_ROW_CASE(GWY_INTERPOLATION_BSPLINE);
        RESAMPLE_ROW_CASE(GWY_INTERPOLATION_OMOMS);

        default:
        g_assert_not_reached();
        break;
    }
    if (prev && !fused)
        spline_eliminate_row(dest, prev, q, n);
}

#undef RESAMPLE_ROW_CASE

/* dest = src shifted by a whole number of columns, edge values beyond. */
static void
shift_row_whole(const gdouble *src, gint n, gint shift, gdouble *dest)
{
    gint c, first = CLAMP(-shift, 0, n), end = CLAMP(n - shift, first, n);

    for (c = 0; c < first; c++)
        dest[c] = src[0];
    if (end > first)
        memcpy(dest + first, src + first + shift,
               (end - first)*sizeof(gdouble));
    for (c = end; c < n; c++)
        dest[c] = src[n-1];
}

/* Columns c whose source x_start + x_step*c lies within [-0.5, n-0.5];
 * the same expression as in resample_row_with(), so the mask agrees with
 * the clamping exactly. */
void
row_resample_valid_range(gdouble x_start, gdouble x_step, gint n,
                         gint *first, gint *last)
{
    gdouble lo = -0.5, hi = n - 0.5;
    gdouble cf = ceil((lo - x_start)/x_step);
    gdouble cl = floor((hi - x_start)/x_step);
    gint f, l;

    cf = CLAMP(cf, -1.0, (gdouble)n);
    cl = CLAMP(cl, -1.0, (gdouble)n);
    f = (gint)cf;
    l = (gint)cl;
    while (f > 0 && x_start + x_step*(f - 1) >= lo)
        f--;
    while (f < n && !(x_start + x_step*f >= lo))
        f++;
    while (l < n-1 && x_start + x_step*(l + 1) <= hi)
        l++;
    while (l >= 0 && !(x_start + x_step*l <= hi))
        l--;
    *first = MAX(f, 0);
    *last = MIN(l, n-1);
}

void
row_resampler_init(RowResampler *resampler, const gdouble *a, gint xres,
                   gint yres, const gdouble *x_start, const gdouble *x_step,
                   GwyInterpolationType interpolation)
{
    gdouble centre, side;
    gsize stride = xres + PREFILTER_ROW_PAD;

    resampler->a = a;
    resampler->xres = xres;
    resampler->yres = yres;
    resampler->x_start = x_start;
    resampler->x_step = x_step;
    resampler->interpolation = interpolation;
    resampler->prefilter_x = kernel_needs_prefilter(interpolation,
                                                    &centre, &side);
    resampler->lanes = NULL;
    resampler->coeffs = NULL;
    resampler->coeff_stride = stride;
    resampler->batch_first = -1;
    resampler->batch_count = 0;
    if (resampler->prefilter_x) {
        spline_prefilter_init(&resampler->x_prefilter, xres, centre, side);
        resampler->lanes = g_new(gdouble, SPLINE_PREFILTER_BATCH*(gsize)xres);
        resampler->coeffs = g_new(gdouble, SPLINE_PREFILTER_BATCH*stride);
    }
}

void
row_resampler_clear(RowResampler *resampler)
{
    if (resampler->prefilter_x)
        spline_prefilter_clear(&resampler->x_prefilter);
    g_free(resampler->lanes);
    g_free(resampler->coeffs);
}

/* A shift by whole columns is a copy: no kernel weights, and the values
 * stay exact (so whole-pixel drift gives paper mode's result). */
static gboolean
row_shift_is_whole(const RowResampler *resampler, gint i)
{
    gdouble x_start = resampler->x_start[i];

    return (resampler->x_step[i] == 1.0 && x_start == floor(x_start)
            && fabs(x_start) <= resampler->xres);
}

/* Prefilters the batch of rows holding source row i: the rows from i on
 * (or, at the bottom, the last ones), each only once when rows are asked
 * for in order.  Images with fewer rows than a batch go row by row. */
static void
row_resampler_prefilter_batch(RowResampler *resampler, gint i)
{
    gint xres = resampler->xres, yres = resampler->yres, first;

    if (yres < SPLINE_PREFILTER_BATCH) {
        memcpy(resampler->coeffs, resampler->a + i*(gsize)xres,
               xres*sizeof(gdouble));
        spline_prefilter_row(&resampler->x_prefilter, resampler->coeffs);
        resampler->batch_first = i;
        resampler->batch_count = 1;
        return;
    }
    first = MIN(i, yres - SPLINE_PREFILTER_BATCH);
    spline_prefilter_batch(&resampler->x_prefilter, resampler->lanes,
                           resampler->a + first*(gsize)xres, xres,
                           resampler->coeffs, resampler->coeff_stride);
    resampler->batch_first = first;
    resampler->batch_count = SPLINE_PREFILTER_BATCH;
}

/* The x coefficients of source row i. */
static const gdouble*
row_resampler_coeffs(RowResampler *resampler, gint i)
{
    gint offset = i - resampler->batch_first;

    if (offset < 0 || offset >= resampler->batch_count) {
        row_resampler_prefilter_batch(resampler, i);
        offset = i - resampler->batch_first;
    }
    return resampler->coeffs + offset*resampler->coeff_stride;
}

void
row_resampler_correct_row(RowResampler *resampler, gint i,
                          const gdouble *restrict prev, gdouble q,
                          gdouble *restrict dest)
{
    gint xres = resampler->xres;
    const gdouble *src = resampler->a + i*(gsize)xres;

    if (row_shift_is_whole(resampler, i)) {
        shift_row_whole(src, xres, (gint)resampler->x_start[i], dest);
        if (prev)
            spline_eliminate_row(dest, prev, q, xres);
        return;
    }
    if (resampler->prefilter_x)
        src = row_resampler_coeffs(resampler, i);
    resample_row(resampler->interpolation, src, xres,
                 resampler->x_start[i], resampler->x_step[i], prev, q, dest);
}
