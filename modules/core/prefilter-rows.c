/*
 *  The B-spline/o-MOMS prefilter along y of the x-corrected rows, through
 *  a ring of rows.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include "interpolation-kernels.h"
#include "prefilter-rows.h"

void
prefilter_rows_init(PrefilterRows *prefilter_rows, RowResampler *resampler,
                    GwyInterpolationType interpolation)
{
    gdouble centre = 0.0, side = 0.0;
    gint xres = resampler->xres, yres = resampler->yres, warmup;

    kernel_needs_prefilter(interpolation, &centre, &side);
    spline_prefilter_init(&prefilter_rows->prefilter, yres, centre, side);
    warmup = MAX(spline_prefilter_warmup(&prefilter_rows->prefilter), 1);
    prefilter_rows->resampler = resampler;
    prefilter_rows->warmup = warmup;
    /* Alive at once: three coefficient rows before a block (taps of output
     * rows that straddle it), the block and its warm-up rows. */
    prefilter_rows->ring_rows = MIN(yres,
                                    3 + PREFILTER_ROWS_BLOCK + warmup + 1);
    prefilter_rows->rows = g_new(gdouble,
                                 prefilter_rows->ring_rows*(gsize)xres);
    prefilter_rows->scratch = g_new(gdouble, xres);
    prefilter_rows->below = NULL;
    prefilter_rows->next_source = 0;
}

void
prefilter_rows_clear(PrefilterRows *prefilter_rows)
{
    spline_prefilter_clear(&prefilter_rows->prefilter);
    g_free(prefilter_rows->rows);
    g_free(prefilter_rows->scratch);
}

static inline gdouble*
ring_row(const PrefilterRows *prefilter_rows, gint i)
{
    return (gdouble*)prefilter_rows_get(prefilter_rows, i);
}

/* x-corrects and eliminates source rows up to and including last. */
static void
eliminate_down_to(PrefilterRows *prefilter_rows, gint last)
{
    const gdouble *factor = prefilter_rows->prefilter.factor;
    gint i;

    for (i = prefilter_rows->next_source; i <= last; i++) {
        row_resampler_correct_row(prefilter_rows->resampler, i,
                                  i ? ring_row(prefilter_rows, i-1) : NULL,
                                  factor[i], ring_row(prefilter_rows, i));
    }
    prefilter_rows->next_source = MAX(prefilter_rows->next_source, last + 1);
}

/* Eliminates down to the warm-up rows below the block ending at end and
 * runs the warm-up: the coefficient row below the block, or NULL at the
 * bottom of the image (where the substitution starts exactly). */
static const gdouble*
warm_up(PrefilterRows *prefilter_rows, gint end)
{
    const SplinePrefilter *prefilter = &prefilter_rows->prefilter;
    const gdouble *inv_diag = prefilter->inv_diag, *eliminated;
    gdouble *scratch = prefilter_rows->scratch;
    gint xres = prefilter_rows->resampler->xres, start, i, c;

    start = MIN(end - 1 + prefilter_rows->warmup, prefilter->n - 1);
    eliminate_down_to(prefilter_rows, start);
    if (start < end)
        return NULL;
    eliminated = ring_row(prefilter_rows, start);
    for (c = 0; c < xres; c++)
        scratch[c] = eliminated[c]*inv_diag[start];
    for (i = start - 1; i >= end; i--) {
        spline_substitute_row_over(scratch, ring_row(prefilter_rows, i),
                                   prefilter->side, inv_diag[i], xres);
    }
    return scratch;
}

void
prefilter_rows_begin_block(PrefilterRows *prefilter_rows, gint end)
{
    prefilter_rows->below = warm_up(prefilter_rows, end);
}

/* From the row's eliminated values and the coefficient row below. */
void
prefilter_rows_make(PrefilterRows *prefilter_rows, gint i)
{
    const SplinePrefilter *prefilter = &prefilter_rows->prefilter;
    gdouble *row = ring_row(prefilter_rows, i), inv = prefilter->inv_diag[i];
    gint xres = prefilter_rows->resampler->xres, c;

    if (prefilter_rows->below) {
        spline_substitute_row(row, prefilter_rows->below, prefilter->side,
                              inv, xres);
    }
    else {
        for (c = 0; c < xres; c++)
            row[c] *= inv;
    }
    prefilter_rows->below = row;
}
