/*
 *  Continuous (line-by-line, sub-pixel) compensation driven by a drift
 *  trajectory over scan time.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <math.h>
#include <string.h>
#include "continuous-compensate.h"
#include "interpolation-kernels.h"
#include "prefilter-rows.h"
#include "row-combine.h"
#include "row-resample.h"
#include "missing-data.h"
#include "localscan-intl.h"

/*
 * The image is resampled in two separable passes.  First every scanned row
 * is shifted in x by the x drift at each pixel's own scan time, which
 * removes the shear within the line.  Then every output row is rebuilt
 * from the x-corrected rows at its source row rho, the solution of
 * rho - Dy(t(rho)) = r, which removes the stretch of the slow axis.  Within
 * one row the x drift is taken as linear in the column (the trace takes
 * half a line time, over which the curvature of any thermal drift is
 * negligible), so the source column is affine in the output column; in y
 * the whole row uses the drift at its centre pixel, ignoring the drift
 * during the half line time of one trace (|vy| L/4 px at most).
 *
 * This file is the orchestration: trajectory -> where each row takes its
 * data from (ResamplePlan) -> x-corrected rows -> output rows and mask.
 * The parts live in
 *   interpolation-kernels.[ch]  Gwyddion's tap weights, computed inline;
 *   row-resample.[ch]           x resampling of one scanned row;
 *   spline-prefilter.[ch]       the B-spline/o-MOMS coefficient system;
 *   prefilter-rows.[ch]         its y direction, through a ring of rows;
 *   row-combine.[ch]            output rows written past the caches;
 *   vector-loops.h              row chunks and the AVX2 clones.
 *
 * Speed (bench/bench-continuous, within a few times a memcpy of the image):
 * rows stream through small rings, never a full-size intermediate image.
 * The x prefilter runs eight rows side by side; the y prefilter is solved
 * in blocks of rows through a ring, and each output row is made while its
 * coefficient rows are still in cache.  Row loops run in chunks of constant
 * length, which GCC vectorises at -O2; the hot ones are compiled for AVX2
 * too; output rows bypass the caches.
 */

/* x-corrected rows kept while rebuilding the output without a y
 * prefilter: four taps, mirrored at the image edges, always fall within
 * four consecutive rows, and rho grows with the output row, so each source
 * row is x-corrected once. */
enum { RING_ROWS = 8 };

/* Where each output row and each source row takes its data from. */
typedef struct {
    gdouble *x_start;   /* source column of output column 0, per source row */
    gdouble *x_step;    /* source columns per output column, per source row */
    gint *valid_first;  /* columns with an x source, per source row */
    gint *valid_last;
    gdouble *rho;       /* source row per output row; NaN = no source */
} ResamplePlan;

/* The output image being made and what its rows without a source get. */
typedef struct {
    const ResamplePlan *plan;
    gint xres;
    gint yres;
    gdouble fill_value;
    gdouble *result;
    gdouble *mask;      /* may be NULL */
} OutputImage;

GQuark
continuous_compensate_error_quark(void)
{
    return g_quark_from_static_string("continuous-compensate-error-quark");
}

static gboolean
check_inputs(gint xres, gint yres, const ScanTiming *timing,
             GwyInterpolationType interpolation, GError **error)
{
    if (timing->xres != xres || timing->yres != yres
        || !isfinite(timing->line_time) || timing->line_time <= 0.0
        || !isfinite(timing->frame_start)) {
        g_set_error(error, CONTINUOUS_COMPENSATE_ERROR,
                    CONTINUOUS_COMPENSATE_ERROR_TIMING,
                    _("scan timing (%d x %d pixels, line time %g s) does not "
                    "describe the %d x %d image"),
                    timing->xres, timing->yres, timing->line_time,
                    xres, yres);
        return FALSE;
    }
    if (interpolation <= GWY_INTERPOLATION_NONE
        || interpolation > GWY_INTERPOLATION_SCHAUM) {
        g_set_error(error, CONTINUOUS_COMPENSATE_ERROR,
                    CONTINUOUS_COMPENSATE_ERROR_INTERPOLATION,
                    _("interpolation type %d cannot resample an image"),
                    (gint)interpolation);
        return FALSE;
    }
    return TRUE;
}

/* Per source row: the drift at the row's centre pixel and its change along
 * the row.  A feature truly at column c appears at x = c + f0 + f1 (x - xm),
 * so x = (c + f0 - f1 xm)/(1 - f1). */
static gboolean
plan_columns(const DriftTrajectory *trajectory, const ScanTiming *timing,
             ResamplePlan *plan, GError **error)
{
    gint xres = timing->xres, yres = timing->yres, i;
    gdouble xm = 0.5*(xres - 1), dt_dcol = timing->line_time/(2.0*xres);
    gdouble t, dx, dy, vx, vy, f1, step;

    for (i = 0; i < yres; i++) {
        t = scan_timing_pixel_time(timing, i, xm);
        drift_trajectory_eval(trajectory, t, &dx, &dy);
        drift_trajectory_velocity(trajectory, t, &vx, &vy);
        f1 = vx*dt_dcol;
        if (!(fabs(f1) < 0.5) || !isfinite(dx)) {
            g_set_error(error, CONTINUOUS_COMPENSATE_ERROR,
                        CONTINUOUS_COMPENSATE_ERROR_TOO_FAST,
                        _("x drift of %g px per pixel in row %d is too fast "
                        "to compensate"), f1, i);
            return FALSE;
        }
        step = 1.0/(1.0 - f1);
        plan->x_step[i] = step;
        plan->x_start[i] = (dx - f1*xm)*step;
        row_resample_valid_range(plan->x_start[i], step, xres,
                                 plan->valid_first + i, plan->valid_last + i);
    }
    return TRUE;
}

/* The slow-axis map g(rho) = rho - Dy(t(rho)) sampled at the rows -1 .. yres
 * (t at each row's centre pixel). */
static gboolean
sample_row_map(const DriftTrajectory *trajectory, const ScanTiming *timing,
               gdouble *g, GError **error)
{
    gint yres = timing->yres, k;
    gdouble xm = 0.5*(timing->xres - 1), dx, dy;

    for (k = -1; k <= yres; k++) {
        drift_trajectory_eval(trajectory,
                              scan_timing_pixel_time(timing, k, xm), &dx, &dy);
        g[k+1] = k - dy;
        if (!isfinite(g[k+1]) || (k > -1 && !(g[k+1] > g[k]))) {
            g_set_error(error, CONTINUOUS_COMPENSATE_ERROR,
                        CONTINUOUS_COMPENSATE_ERROR_TOO_FAST,
                        _("y drift near row %d is a line or more per line, "
                        "too fast to compensate"), k);
            return FALSE;
        }
    }
    return TRUE;
}

/* Per output row r: the source row rho with g(rho) = r, inverted linearly
 * between the sampled rows and polished with one Newton step on the
 * trajectory itself (whole-pixel drift stays exact: the step is then 0). */
static gboolean
plan_rows(const DriftTrajectory *trajectory, const ScanTiming *timing,
          ResamplePlan *plan, GError **error)
{
    gint yres = timing->yres, r, j = 0;
    gdouble xm = 0.5*(timing->xres - 1), rho, t, dx, dy, vx, vy, slope;
    gdouble dt_drow = (timing->direction == SCAN_DIRECTION_UP
                       ? -timing->line_time : timing->line_time);
    gdouble *g = g_new(gdouble, yres + 2);

    if (!sample_row_map(trajectory, timing, g, error)) {
        g_free(g);
        return FALSE;
    }
    for (r = 0; r < yres; r++) {
        plan->rho[r] = NAN;
        if (r < g[0] || r > g[yres+1])
            continue;
        while (j < yres && g[j+1] < r)
            j++;
        rho = (j - 1) + (r - g[j])/(g[j+1] - g[j]);
        t = scan_timing_pixel_time(timing, rho, xm);
        drift_trajectory_eval(trajectory, t, &dx, &dy);
        drift_trajectory_velocity(trajectory, t, &vx, &vy);
        slope = 1.0 - vy*dt_drow;
        if (slope > 0.0)
            rho -= (rho - dy - r)/slope;
        if (rho >= -0.5 && rho <= yres - 0.5)
            plan->rho[r] = rho;
    }
    g_free(g);
    return TRUE;
}

static void
resample_plan_init(ResamplePlan *plan, gint yres)
{
    plan->x_start = g_new(gdouble, 3*yres);
    plan->x_step = plan->x_start + yres;
    plan->rho = plan->x_step + yres;
    plan->valid_first = g_new(gint, 2*yres);
    plan->valid_last = plan->valid_first + yres;
}

static void
resample_plan_clear(ResamplePlan *plan)
{
    g_free(plan->x_start);
    g_free(plan->valid_first);
}

/* With whole source rows only, the output rows are x-corrected rows as
 * they are, and B-spline and o-MOMS need no coefficients along y. */
static gboolean
any_source_row_fractional(const ResamplePlan *plan, gint yres)
{
    gint r;

    for (r = 0; r < yres; r++) {
        if (!isnan(plan->rho[r]) && plan->rho[r] != floor(plan->rho[r]))
            return TRUE;
    }
    return FALSE;
}

static gdouble*
output_row(const OutputImage *output, gint r)
{
    return output->result + r*(gsize)output->xres;
}

static void
fill_row(gdouble *dest, gdouble *mask_row, gint first, gint end,
         gdouble fill_value)
{
    gint c;

    for (c = first; c < end; c++)
        dest[c] = fill_value;
    if (mask_row) {
        for (c = first; c < end; c++)
            mask_row[c] = 1.0;
    }
}

/* Fills output row r where it has no source: all of it without a source
 * row, else the columns the nearest source row has no x source for.  The
 * mask is zero already (cleared in one go, which is several times faster
 * than row by row). */
static void
finish_row(const OutputImage *output, gint r)
{
    const ResamplePlan *plan = output->plan;
    gint xres = output->xres, nearest, first, last;
    gdouble *dest = output_row(output, r);
    gdouble *mask_row = output->mask ? output->mask + r*(gsize)xres : NULL;
    gdouble rho = plan->rho[r], fill_value = output->fill_value;

    if (isnan(rho)) {
        fill_row(dest, mask_row, 0, xres, fill_value);
        return;
    }
    nearest = CLAMP((gint)floor(rho + 0.5), 0, output->yres-1);
    first = plan->valid_first[nearest];
    last = plan->valid_last[nearest];
    if (first > last) {
        fill_row(dest, mask_row, 0, xres, fill_value);
        return;
    }
    fill_row(dest, mask_row, 0, first, fill_value);
    fill_row(dest, mask_row, last + 1, xres, fill_value);
}

/* The last few x-corrected rows, by row index. */
typedef struct {
    RowResampler *resampler;
    gint tags[RING_ROWS];
    gdouble *rows;
} RowRing;

static void
row_ring_init(RowRing *ring, RowResampler *resampler)
{
    gint k;

    ring->resampler = resampler;
    ring->rows = g_new(gdouble, RING_ROWS*(gsize)resampler->xres);
    for (k = 0; k < RING_ROWS; k++)
        ring->tags[k] = -1;
}

/* x-corrected row i, computed unless still in the ring. */
static const gdouble*
row_ring_corrected(RowRing *ring, gint i)
{
    gdouble *row = ring->rows + (i % RING_ROWS)*(gsize)ring->resampler->xres;

    if (ring->tags[i % RING_ROWS] != i) {
        row_resampler_correct_row(ring->resampler, i, NULL, 0.0, row);
        ring->tags[i % RING_ROWS] = i;
    }
    return row;
}

/* Output row r (with a source row) from the x-corrected rows around its
 * source row; the outer taps are not even x-corrected when their weights
 * are zero. */
static void
make_row_from_ring(RowRing *ring, const OutputImage *output,
                   GwyInterpolationType interpolation, gint r)
{
    const gdouble *rows[KERNEL_TAPS];
    gdouble w[KERNEL_TAPS], frac;
    gint xres = output->xres, i, k, tap;
    gboolean outer;

    i = kernel_tap_below(output->plan->rho[r], &frac);
    if (frac == 0.0) {
        row_copy_streamed(row_ring_corrected(ring, i), xres,
                          output_row(output, r));
        return;
    }
    kernel_weights(interpolation, frac, w);
    outer = (w[0] != 0.0 || w[3] != 0.0);
    for (k = 0; k < KERNEL_TAPS; k++) {
        tap = kernel_mirror_index(i - 1 + k, output->yres);
        rows[k] = ((k == 1 || k == 2 || outer)
                   ? row_ring_corrected(ring, tap)
                   : NULL);
    }
    row_combine_streamed(rows, w, xres, output_row(output, r));
}

/* Kernels interpolating the data directly, and B-spline and o-MOMS at
 * whole source rows: each output row from the x-corrected rows around its
 * source row, made on demand into a small ring (no full-size intermediate
 * image is written and read back). */
static void
rebuild_rows_streaming(RowResampler *resampler, const OutputImage *output,
                       GwyInterpolationType interpolation)
{
    RowRing ring;
    gint r;

    row_ring_init(&ring, resampler);
    for (r = 0; r < output->yres; r++) {
        if (!isnan(output->plan->rho[r]))
            make_row_from_ring(&ring, output, interpolation, r);
        finish_row(output, r);
    }
    g_free(ring.rows);
}

/* Where an output row takes its data from the coefficient rows, worked out
 * once per row; ready is the coefficient row whose making completes its
 * taps (-1: the row has no source). */
typedef struct {
    gint taps[KERNEL_TAPS];
    gdouble w[KERNEL_TAPS];
    gint ready;
} OutputRow;

/* Taps, weights and the coefficient row completing them, for every output
 * row.  Rows come in blocks top-down, bottom-up within a block, so taps
 * in an earlier block are done before those in the block of the highest
 * tap. */
static void
output_rows_plan(const ResamplePlan *plan, gint yres,
                 GwyInterpolationType interpolation, OutputRow *out)
{
    gint r, i, k, lowest, highest;
    gdouble frac;

    for (r = 0; r < yres; r++) {
        out[r].ready = -1;
        if (isnan(plan->rho[r]))
            continue;
        i = kernel_tap_below(plan->rho[r], &frac);
        lowest = yres;
        highest = 0;
        for (k = 0; k < KERNEL_TAPS; k++) {
            out[r].taps[k] = kernel_mirror_index(i - 1 + k, yres);
            lowest = MIN(lowest, out[r].taps[k]);
            highest = MAX(highest, out[r].taps[k]);
        }
        kernel_weights(interpolation, frac, out[r].w);
        out[r].ready = MAX(lowest, highest - highest % PREFILTER_ROWS_BLOCK);
    }
}

static void
make_row_from_coeffs(const PrefilterRows *prefilter_rows,
                     const OutputImage *output, const OutputRow *out, gint r)
{
    const gdouble *rows[KERNEL_TAPS];
    gint k;

    for (k = 0; k < KERNEL_TAPS; k++)
        rows[k] = prefilter_rows_get(prefilter_rows, out->taps[k]);
    row_combine_streamed(rows, out->w, output->xres, output_row(output, r));
}

/* Makes the coefficient rows first .. end-1, bottom-up, and the output
 * rows r_first .. r_end-1 (those completed in this block) as soon as
 * their last tap is made, while their taps are still in cache. */
static void
rebuild_block(PrefilterRows *prefilter_rows, const OutputImage *output,
              const OutputRow *out, gint first, gint end,
              gint r_first, gint r_end)
{
    gint i, r = r_end - 1;

    prefilter_rows_begin_block(prefilter_rows, end);
    for (i = end - 1; i >= first; i--) {
        prefilter_rows_make(prefilter_rows, i);
        for (; r >= r_first && out[r].ready >= i; r--) {
            make_row_from_coeffs(prefilter_rows, output, out + r, r);
            finish_row(output, r);
        }
        for (; r >= r_first && out[r].ready < 0; r--)
            finish_row(output, r);
    }
}

/* B-spline and o-MOMS with fractional source rows need coefficients along
 * y, the solution of a tridiagonal system over each whole column.  They
 * are made block by block (output rows are independent, so their order
 * does not matter). */
static void
rebuild_rows_prefiltered(RowResampler *resampler, const OutputImage *output,
                         GwyInterpolationType interpolation)
{
    gint yres = output->yres, first, end, r_first, r_end = 0;
    OutputRow *out = g_new(OutputRow, yres);
    PrefilterRows prefilter_rows;

    output_rows_plan(output->plan, yres, interpolation, out);
    prefilter_rows_init(&prefilter_rows, resampler, interpolation);
    for (first = 0; first < yres; first += PREFILTER_ROWS_BLOCK) {
        end = MIN(first + PREFILTER_ROWS_BLOCK, yres);
        /* The output rows completed in this block (ready is monotonic). */
        r_first = r_end;
        while (r_end < yres && out[r_end].ready < end)
            r_end++;
        rebuild_block(&prefilter_rows, output, out, first, end,
                      r_first, r_end);
    }
    prefilter_rows_clear(&prefilter_rows);
    g_free(out);
}

/* The output image from the planned rows. */
static void
rebuild_image(const gdouble *a, const OutputImage *output,
              GwyInterpolationType interpolation)
{
    const ResamplePlan *plan = output->plan;
    gint xres = output->xres, yres = output->yres;
    gdouble centre = 0.0, side = 0.0;
    RowResampler resampler;

    if (output->mask)
        memset(output->mask, 0, xres*(gsize)yres*sizeof(gdouble));
    row_resampler_init(&resampler, a, xres, yres,
                       plan->x_start, plan->x_step, interpolation);
    if (kernel_needs_prefilter(interpolation, &centre, &side)
        && any_source_row_fractional(plan, yres))
        rebuild_rows_prefiltered(&resampler, output, interpolation);
    else
        rebuild_rows_streaming(&resampler, output, interpolation);
    row_stream_finish();
    row_resampler_clear(&resampler);
}

/* Missing input pixels (docs/missing-data.md): the image is resampled with
 * them set to the fill value, so that no NaN spreads through a kernel (or
 * along a whole row through the B-spline prefilter); output pixels whose
 * nearest source pixel is missing are then filled and marked as pixels with
 * no source are.  Which ones those are comes from resampling the image of
 * missing pixels with the nearest-neighbour kernel along the same plan.
 * Images with no missing pixel take the plain path. */
static void
rebuild_image_with_missing(const gdouble *a, const OutputImage *output,
                           GwyInterpolationType interpolation)
{
    gsize n = (gsize)output->xres*output->yres, i;
    OutputImage marks = *output;
    gdouble *filled, *nearest;

    if (!missing_data_count(a, n)) {
        rebuild_image(a, output, interpolation);
        return;
    }
    filled = missing_data_filled_copy(a, n, output->fill_value);
    rebuild_image(filled, output, interpolation);
    for (i = 0; i < n; i++)
        filled[i] = isfinite(a[i]) ? 0.0 : 1.0;
    nearest = g_new(gdouble, n);
    marks.fill_value = 0.0;
    marks.result = nearest;
    marks.mask = NULL;
    rebuild_image(filled, &marks, GWY_INTERPOLATION_ROUND);
    for (i = 0; i < n; i++) {
        if (nearest[i] > 0.5) {
            output->result[i] = output->fill_value;
            if (output->mask)
                output->mask[i] = 1.0;
        }
    }
    g_free(nearest);
    g_free(filled);
}

/* NULL timing means frame start 0, 1 s per line, scanning down. */
static const ScanTiming*
timing_or_default(const ScanTiming *timing, gint xres, gint yres,
                  ScanTiming *default_timing)
{
    if (timing)
        return timing;
    scan_timing_init(default_timing, xres, yres, 0.0, 1.0,
                     SCAN_DIRECTION_DOWN);
    return default_timing;
}

/* How far row j stands out of its neighbours above and below somewhere
 * along it: its largest local maximum or minimum along y.  G_MAXDOUBLE at
 * the frame's edges. */
static gdouble
row_prominence(const gdouble *a, gint xres, gint yres, gint j)
{
    const gdouble *above, *row, *below;
    gdouble best = 0.0, hi, lo;
    gint c;

    if (j < 1 || j >= yres - 1)
        return G_MAXDOUBLE;
    above = a + (j - 1)*(gsize)xres;
    row = above + xres;
    below = row + xres;
    for (c = 0; c < xres; c++) {
        if (!isfinite(above[c]) || !isfinite(row[c]) || !isfinite(below[c]))
            continue;
        hi = fmax(above[c], below[c]);
        lo = fmin(above[c], below[c]);
        best = fmax(best, fmax(row[c] - hi, lo - row[c]));
    }
    return best;
}

/* Nearest-neighbour resampling along y drops a source row wherever the
 * drift compresses the frame (the rounded source rows of two output rows
 * two apart), and which one is where the rounding happens to cross: a
 * particle's peak on it is lost (2.6-4.1 % of its height in about one
 * draw in a hundred of test-height-keeping).  Either neighbour of that row
 * can be dropped instead, moving one output row by just over half a pixel
 * (the rounding's own error), so the row that stands out least of the
 * three is dropped.  Only between fractional source rows: whole-pixel
 * drift keeps paper mode's rows exactly. */
static void
place_dropped_rows(ResamplePlan *plan, const gdouble *a, gint xres, gint yres)
{
    gdouble *rho = plan->rho, p0, p1, p2;
    gint r, i0;

    for (r = 0; r + 1 < yres; r++) {
        if (isnan(rho[r]) || isnan(rho[r+1]) || rho[r] == floor(rho[r]) || rho[r+1] == floor(rho[r+1]))
            continue;
        i0 = (gint)floor(rho[r] + 0.5);
        if ((gint)floor(rho[r+1] + 0.5) != i0 + 2 || i0 + 1 >= yres)
            continue;
        p0 = row_prominence(a, xres, yres, i0);
        p1 = row_prominence(a, xres, yres, i0 + 1);
        p2 = row_prominence(a, xres, yres, i0 + 2);
        if (p0 < p1 && p0 <= p2)
            rho[r] = i0 + 1;
        else if (p2 < p1 && p2 < p0)
            rho[r+1] = i0 + 1;
    }
}

gboolean
continuous_compensate_trajectory(const gdouble *a, gint xres, gint yres,
                                 const DriftTrajectory *trajectory,
                                 const ScanTiming *timing,
                                 GwyInterpolationType interpolation,
                                 gdouble fill_value, gdouble *result,
                                 gdouble *mask, GError **error)
{
    ScanTiming default_timing;
    ResamplePlan plan;
    OutputImage output = { &plan, xres, yres, fill_value, result, mask };
    gboolean ok;

    g_return_val_if_fail(a && result && trajectory, FALSE);
    g_return_val_if_fail(xres >= 1 && yres >= 1, FALSE);
    timing = timing_or_default(timing, xres, yres, &default_timing);
    if (!check_inputs(xres, yres, timing, interpolation, error))
        return FALSE;

    resample_plan_init(&plan, yres);
    ok = (plan_columns(trajectory, timing, &plan, error)
          && plan_rows(trajectory, timing, &plan, error));
    if (ok && interpolation == GWY_INTERPOLATION_ROUND)
        place_dropped_rows(&plan, a, xres, yres);
    if (ok)
        rebuild_image_with_missing(a, &output, interpolation);
    resample_plan_clear(&plan);
    return ok;
}

gboolean
continuous_compensate_table(const gdouble *a, gint xres, gint yres,
                            const DriftTable *table,
                            gdouble x_pixel_size, gdouble y_pixel_size,
                            const ScanTiming *timing,
                            GwyInterpolationType interpolation,
                            gdouble fill_value, gdouble *result,
                            gdouble *mask, GError **error)
{
    ScanTiming default_timing;
    DriftTrajectory *trajectory;
    gboolean ok;

    g_return_val_if_fail(a && result && table, FALSE);
    g_return_val_if_fail(xres >= 1 && yres >= 1, FALSE);
    timing = timing_or_default(timing, xres, yres, &default_timing);
    if (!check_inputs(xres, yres, timing, interpolation, error))
        return FALSE;
    trajectory = drift_trajectory_new_from_table(table, x_pixel_size,
                                                 y_pixel_size, timing, error);
    if (!trajectory)
        return FALSE;
    ok = continuous_compensate_trajectory(a, xres, yres, trajectory, timing,
                                          interpolation, fill_value,
                                          result, mask, error);
    drift_trajectory_free(trajectory);
    return ok;
}

gboolean
continuous_compensate_check_table(gint xres, gint yres, const DriftTable *table,
                                  gdouble x_pixel_size, gdouble y_pixel_size,
                                  const ScanTiming *timing, GwyInterpolationType interpolation,
                                  GError **error)
{
    ScanTiming default_timing;
    DriftTrajectory *trajectory;
    ResamplePlan plan;
    gboolean ok;

    g_return_val_if_fail(table, FALSE);
    g_return_val_if_fail(xres >= 1 && yres >= 1, FALSE);
    timing = timing_or_default(timing, xres, yres, &default_timing);
    if (!check_inputs(xres, yres, timing, interpolation, error))
        return FALSE;
    trajectory = drift_trajectory_new_from_table(table, x_pixel_size, y_pixel_size, timing, error);
    if (!trajectory)
        return FALSE;
    resample_plan_init(&plan, yres);
    ok = (plan_columns(trajectory, timing, &plan, error)
          && plan_rows(trajectory, timing, &plan, error));
    resample_plan_clear(&plan);
    drift_trajectory_free(trajectory);
    return ok;
}
