/*
 *  The normalised cross-correlation of one stripe of an image with a
 *  reference frame, over a window of shifts around any centre.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <math.h>
#include <string.h>
#include <libgwyddion/gwymacros.h>
#include "stripe-correlation.h"
#include "fft-correlation.h"

/*
 * The measure is the zero-mean normalised cross-correlation (ZNCC) over the
 * part of the stripe that overlaps the reference at each shift, so a bright
 * or rough region of the reference cannot win over the matching one, and a
 * shift that moves the stripe partly off the reference is judged on the
 * shared part only.
 *
 * Only the cross term needs an FFT: the stripe against the slab of
 * reference rows and columns that the window of shifts can reach, wherever
 * the window lies (a frame offset by a third of its size costs what an
 * unshifted one does).  The other sums are rectangle sums from summed-area
 * tables made per stripe: the stripe's, and the reference's over the same
 * slab (tables of the whole reference cost more fresh memory than all the
 * slabs' work on large frames, and every thread needed its own).
 *
 * Missing pixels (weight 0) have value 0 in the conditioned frames.  In the
 * stripe they are left out of every sum; in the reference they add nothing
 * to the cross term and to the reference's sums, which lowers the
 * correlation a little where the stripe meets many of them.  Every pixel
 * present counts once, whatever its weight: the sums are of plain values,
 * and a weight below 1 (a missing pixel the conditioning restored among
 * data) is the sub-pixel match's business.
 */

struct _StripeCorrelation {
    const ConditionedFrame *image;
    const ConditionedFrame *reference;
    gint max_height;
    gint max_ry;
    gint max_rx;
    gdouble min_overlap;
    gint max_slab;          /* rows of the largest slab */
    gdouble *ref_sum;       /* (max_slab+1) x (xres+1) summed-area tables of */
    gdouble *ref_sq_sum;    /* the current slab's reference rows */
    gint slab_first;        /* the first reference row in them */
    gdouble *tmpl_sum;      /* (max_height+1) x (xres+1) */
    gdouble *tmpl_sq_sum;
    gdouble *tmpl_count;
    gdouble *stripe;        /* max_height x xres scratch */
    FFTCorrelation *fc;
};

/* What a summed-area table sums. */
typedef enum {
    SUM_VALUES,
    SUM_SQUARES,
    SUM_PRESENT,   /* how many values are above 0 (weights: pixels present) */
} SummedQuantity;

/* table[(r+1)*(xres+1) + c+1] = sum of what values[i][j] gives over
 * i <= r, j <= c. */
static void
summed_area_table(const gdouble *values, gint xres, gint yres, SummedQuantity what, gdouble *table)
{
    gint r, c, w = xres + 1;

    memset(table, 0, w*sizeof(gdouble));
    for (r = 0; r < yres; r++) {
        const gdouble *row = values + (gsize)r*xres;
        gdouble *t = table + (gsize)(r + 1)*w, *above = t - w, s = 0.0;

        t[0] = 0.0;
        /* One loop per quantity: the tables are built for every stripe of
         * every pair, and a test per pixel cost what the sum does. */
        switch (what) {
            case SUM_VALUES:
            for (c = 0; c < xres; c++)
                t[c + 1] = above[c + 1] + (s += row[c]);
            break;

            case SUM_SQUARES:
            for (c = 0; c < xres; c++)
                t[c + 1] = above[c + 1] + (s += row[c]*row[c]);
            break;

            case SUM_PRESENT:
            for (c = 0; c < xres; c++)
                t[c + 1] = above[c + 1] + (s += (row[c] > 0.0));
            break;
        }
    }
}

/* Sum over rows [r0, r1) and columns [c0, c1) of a table of width w. */
static gdouble
rectangle_sum(const gdouble *table, gint w, gint r0, gint r1, gint c0, gint c1)
{
    return (table[(gsize)r1*w + c1] - table[(gsize)r0*w + c1]
            - table[(gsize)r1*w + c0] + table[(gsize)r0*w + c0]);
}

StripeCorrelation*
stripe_correlation_new(const ConditionedFrame *image, const ConditionedFrame *reference,
                       gint max_height, gint max_ry, gint max_rx, gdouble min_overlap)
{
    StripeCorrelation *sc;
    gint xres, yres;

    g_return_val_if_fail(image && reference, NULL);
    g_return_val_if_fail(image->xres == reference->xres && image->yres == reference->yres, NULL);
    g_return_val_if_fail(max_height >= 1 && max_ry >= 0 && max_rx >= 0, NULL);
    xres = image->xres;
    yres = image->yres;
    sc = g_new0(StripeCorrelation, 1);
    sc->image = image;
    sc->reference = reference;
    sc->max_height = max_height;
    sc->max_ry = max_ry;
    sc->max_rx = max_rx;
    sc->min_overlap = min_overlap;
    sc->max_slab = MIN(max_height + 2*max_ry, yres);
    sc->ref_sum = g_new(gdouble, (gsize)(sc->max_slab + 1)*(xres + 1));
    sc->ref_sq_sum = g_new(gdouble, (gsize)(sc->max_slab + 1)*(xres + 1));
    sc->tmpl_sum = g_new(gdouble, (gsize)(max_height + 1)*(xres + 1));
    sc->tmpl_sq_sum = g_new(gdouble, (gsize)(max_height + 1)*(xres + 1));
    sc->tmpl_count = g_new(gdouble, (gsize)(max_height + 1)*(xres + 1));
    sc->stripe = g_new(gdouble, (gsize)max_height*xres);
    sc->fc = fft_correlation_new(fft_correlation_nice_size(max_height + 2*max_ry),
                                 fft_correlation_nice_size(xres + 2*max_rx));
    return sc;
}

void
stripe_correlation_free(StripeCorrelation *sc)
{
    if (!sc)
        return;
    fft_correlation_free(sc->fc);
    g_free(sc->stripe);
    g_free(sc->tmpl_count);
    g_free(sc->tmpl_sq_sum);
    g_free(sc->tmpl_sum);
    g_free(sc->ref_sq_sum);
    g_free(sc->ref_sum);
    g_free(sc);
}

/* The stripe, zero-mean over its pixels present and 0 where missing, into
 * the FFT template (rows cols apart) and its own summed-area tables. */
static void
prepare_template(StripeCorrelation *sc, gint first, gint end)
{
    const ConditionedFrame *image = sc->image;
    gint xres = image->xres, h = end - first, cols = fft_correlation_cols(sc->fc), i;
    gsize k, n = (gsize)h*xres;
    const gdouble *v = image->data + (gsize)first*xres, *wt = image->weight + (gsize)first*xres;
    gdouble *tmpl = fft_correlation_template(sc->fc), s = 0.0, w = 0.0, mean;

    for (k = 0; k < n; k++) {
        if (wt[k] > 0.0) {
            s += v[k];
            w += 1.0;
        }
    }
    mean = (w > 0.0) ? s/w : 0.0;
    for (k = 0; k < n; k++)
        sc->stripe[k] = (wt[k] > 0.0) ? v[k] - mean : 0.0;
    for (i = 0; i < h; i++)
        memcpy(tmpl + (gsize)i*cols, sc->stripe + (gsize)i*xres, xres*sizeof(gdouble));
    summed_area_table(sc->stripe, xres, h, SUM_VALUES, sc->tmpl_sum);
    summed_area_table(sc->stripe, xres, h, SUM_SQUARES, sc->tmpl_sq_sum);
    summed_area_table(wt, xres, h, SUM_PRESENT, sc->tmpl_count);
    fft_correlation_set_template(sc->fc);
}

/* Reference rows first - cy - ry .. and columns -cx - rx .., the reach of
 * the window; zero outside the frame. */
static void
prepare_slab(StripeCorrelation *sc, gint first, gint end, const StripeCorrelationMap *map)
{
    const ConditionedFrame *ref = sc->reference;
    gint xres = ref->xres, cols = fft_correlation_cols(sc->fc);
    gint top = first - map->cy - map->ry, left = -map->cx - map->rx;
    gint rows = end - first + 2*map->ry, width = xres + 2*map->rx, k, c0, c1;
    gdouble *field = fft_correlation_field(sc->fc);

    c0 = MAX(0, -left);
    c1 = MIN(width, xres - left);
    for (k = 0; k < rows; k++) {
        gint r = top + k;

        if (r < 0 || r >= ref->yres || c1 <= c0)
            continue;
        memcpy(field + (gsize)k*cols + c0, ref->data + (gsize)r*xres + left + c0,
               (c1 - c0)*sizeof(gdouble));
    }
}

/* The reference's summed-area tables over the rows the window reaches
 * (within the frame). */
static void
prepare_slab_sums(StripeCorrelation *sc, gint first, gint end, const StripeCorrelationMap *map)
{
    const ConditionedFrame *ref = sc->reference;
    gint r0 = MAX(0, first - map->cy - map->ry), r1 = MIN(ref->yres, end - map->cy + map->ry);

    sc->slab_first = r0;
    r1 = MAX(r1, r0);
    summed_area_table(ref->data + (gsize)r0*ref->xres, ref->xres, r1 - r0, SUM_VALUES, sc->ref_sum);
    summed_area_table(ref->data + (gsize)r0*ref->xres, ref->xres, r1 - r0, SUM_SQUARES, sc->ref_sq_sum);
}

gdouble
stripe_correlation_map_at(const StripeCorrelationMap *map, gint dy, gint dx)
{
    if (ABS(dy - map->cy) > map->ry || ABS(dx - map->cx) > map->rx)
        return STRIPE_CORRELATION_NONE;
    return map->values[(dy - map->cy + map->ry)*(2*map->rx + 1) + dx - map->cx + map->rx];
}

void
stripe_correlation_map(StripeCorrelation *sc, gint first, gint end, StripeCorrelationMap *map)
{
    gint xres = sc->image->xres, yres = sc->image->yres, h = end - first;
    gint cols = fft_correlation_cols(sc->fc), tw = xres + 1, iy, ix, span_x = 2*map->rx + 1;
    gdouble total, min_weight;
    const gdouble *cross;

    g_return_if_fail(first >= 0 && end <= yres && h >= 1 && h <= sc->max_height);
    g_return_if_fail(map->ry >= 0 && map->ry <= sc->max_ry && map->rx >= 0 && map->rx <= sc->max_rx);
    fft_correlation_clear(sc->fc);
    prepare_template(sc, first, end);
    prepare_slab(sc, first, end, map);
    prepare_slab_sums(sc, first, end, map);
    cross = fft_correlation_run(sc->fc);
    total = rectangle_sum(sc->tmpl_count, tw, 0, h, 0, xres);
    min_weight = MAX(sc->min_overlap*total, 1.0);

    for (iy = 0; iy <= 2*map->ry; iy++) {
        gint dy = map->cy - map->ry + iy;
        /* Stripe rows i meet reference rows first + i - dy. */
        gint ilo = MAX(0, dy - first), ihi = MIN(h, yres - first + dy);

        for (ix = 0; ix < span_x; ix++) {
            gint dx = map->cx - map->rx + ix;
            gint lo = MAX(0, dx), hi = MIN(xres, xres + dx);
            gdouble *out = map->values + (gsize)iy*span_x + ix;
            gdouble w, st, stt, sr, srr, str, vt, vr;

            *out = STRIPE_CORRELATION_NONE;
            if (ihi <= ilo || hi <= lo)
                continue;
            w = rectangle_sum(sc->tmpl_count, tw, ilo, ihi, lo, hi);
            if (w < min_weight)
                continue;
            st = rectangle_sum(sc->tmpl_sum, tw, ilo, ihi, lo, hi);
            stt = rectangle_sum(sc->tmpl_sq_sum, tw, ilo, ihi, lo, hi);
            sr = rectangle_sum(sc->ref_sum, tw, first + ilo - dy - sc->slab_first,
                               first + ihi - dy - sc->slab_first, lo - dx, hi - dx);
            srr = rectangle_sum(sc->ref_sq_sum, tw, first + ilo - dy - sc->slab_first,
                                first + ihi - dy - sc->slab_first, lo - dx, hi - dx);
            str = cross[(gsize)(2*map->ry - iy)*cols + (2*map->rx - ix)];
            vt = stt - st*st/w;
            vr = srr - sr*sr/w;
            /* A flat stripe or reference patch matches nothing. */
            if (!(vt > 1e-12*stt) || !(vr > 1e-12*srr)) {
                *out = 0.0;
                continue;
            }
            *out = (str - st*sr/w)/sqrt(vt*vr);
        }
    }
}
