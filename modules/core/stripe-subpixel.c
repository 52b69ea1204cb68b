/*
 *  Sub-pixel shift of a stripe: Gauss-Newton matching of the stripe
 *  against the reference interpolated at fractional shifts.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <math.h>
#include <string.h>
#include "stripe-subpixel.h"
#include "interpolation-kernels.h"

/*
 * Why not a finer fit to the correlation map.  The map of a stripe of few
 * rows is not symmetric about its true peak: one step up brings a reference
 * row above the stripe into the match, one step down a row below it, and the
 * two differ.  A peak model fitted to the map's samples (a 3x3 quadratic, a
 * Gaussian, an upsampled cross-correlation) lands off the true shift by up to
 * a tenth of a pixel even on whole-pixel shifts.  Matching the stripe itself
 * against the reference at fractional shifts has no such bias: at the true
 * shift the moved reference equals the stripe up to noise.
 *
 * The drift also moves on while the stripe is scanned (by up to a couple of
 * pixels in the first stripe, as the scanner settles).  A single shift then
 * fits the rows with the most texture best, not the stripe's mean drift, so
 * the model lets the shift change linearly over the rows and reports it at
 * the stripe's centre row, which is the mean of a linear drift.
 *
 * The model is: the reference, sampled with Keys' cubic kernel at
 * (r - dy - vy t, c - dx - vx t), t = r - centre, equals gain*stripe + offset
 * + trend(c) over the stripe's pixels, weighted by the column window,
 * with trend a polynomial of low degree along x.  The two frames of a raw channel
 * carry planes and bows of their own (the scanner's tilt and bow, slow
 * undulation), which no levelling can take from one frame without moving
 * with its content; fitted here, as nuisances beside the shift, they take
 * no part in it.  Linearised about
 * the current shift with the stripe's own gradients, the unknowns gain,
 * offset and gain times the steps of dy, dx, vy, vx are a linear
 * least-squares problem whose matrix depends only on the stripe and the rows
 * that meet the reference, so each step costs one interpolation of the
 * reference and a few dot products.  Because the stripe's gradients stand in
 * for the moved reference's, the steps converge to the exact match (the
 * residual then has no component along them) and only their length depends
 * on the approximation.
 */

/* The x trend: Legendre polynomials of degree 1 to TREND_TERMS in the
 * column scaled to [-1, 1].  A plane and a bow take the first two, exactly,
 * as the conditioning removes them from one frame and perhaps not from
 * the other (frame-conditioning.c); slow undulation the rest.  More terms
 * cost time and precision. */
#define TREND_TERMS 4

/* Unknowns: gain, offset, gain times the steps of dy, dx, the x trend's
 * coefficients and gain times the steps of vy, vx. */
enum {
    ROW_REGRESSORS = 4 + TREND_TERMS,  /* stripe, 1, d/dy, d/dx, the x trend;
                                          d/dy and d/dx times t too */
    ROW_TERMS = ROW_REGRESSORS*(ROW_REGRESSORS + 1)/2,
    BASE_PARAMS = ROW_REGRESSORS,
    MAX_PARAMS = ROW_REGRESSORS + 2,
};

#define MAX_ITERATIONS 32
/* Steps shorter than this (px, per axis) end the iteration. */
#define CONVERGED_STEP 5e-3
/* Fewer of the stripe's rows than this on the reference is too little to
 * refine on. */
#define MIN_ROWS_FRACTION 0.25
/* Columns the match needs at least. */
#define MIN_COLUMNS 8
/* The least share of a stripe's weight (of its rows on the frame) whose
 * reference samples must be made of pixels present, as at least half of a
 * stripe must lie on the reference: the correlation map counts a hole's
 * pixels as zeros on the reference, and a stripe whose content lay in a
 * band of missing rows was matched on the few rows beside it elsewhere
 * (7.8 px off, sigma 1.8 px; test_scattered_missing, seed 2018). */
#define MIN_PRESENT_SHARE 0.5
/* Stripes of fewer rows, or with less than this fraction of their rows on
 * the reference, are matched with one shift for all rows: the change of the
 * shift over the rows would be too uncertain, and for a stripe partly off
 * the reference its value at the centre row an extrapolation. */
#define MIN_ROWS_FOR_VELOCITY 6
#define MIN_VELOCITY_FRACTION 0.5
/* Longest step (px, per axis, and of the shift at the first or last row
 * by the rates): a start far from the match, such as a whole-pixel peak on
 * the edge of the overlap, overshoots with the full Gauss-Newton step. */
#define MAX_STEP 0.5
/* How far (px) the drift may move the stripe's first or last row away from
 * its centre; a larger change within a stripe is not believed. */
#define MAX_SPREAD 2.0
/* The least share of a stripe's texture on either side of its centre row
 * that lets the shift's change over the rows be measured. */
#define VELOCITY_MIN_SIDE_SHARE 0.2

struct _StripeSubpixel {
    const gdouble *image;
    const gdouble *reference;
    const gdouble *window;
    const gdouble *weight;    /* image validity, NULL: all valid */
    const gdouble *ref_weight; /* reference validity, NULL: all valid */
    gint xres;
    gint yres;
    gint max_height;
    gint edge_margin;
    gdouble *pixel_weight;    /* max_height x xres: window times validity
                                 of the pixel and its gradient's taps */
    gdouble *weighted_value;  /* pixel_weight*stripe */
    gdouble *weighted_grad_y; /* window*d(stripe)/dy */
    gdouble *weighted_grad_x;
    gdouble *row_offset;      /* max_height x ROW_REGRESSORS: each row's
                                 products with the constant, uncentred */
    gdouble *row_normal;      /* max_height x ROW_TERMS: each row's products
                                 of the row regressors, upper triangle */
    gdouble *row_adjusted;    /* max_height x ROW_TERMS: a row's terms, and */
    gdouble *offset_adjusted; /* max_height x ROW_REGRESSORS: its offsets,
                                 without the pixels whose reference sample
                                 reaches a missing pixel at the current
                                 shift */
    gdouble *column_valid;    /* xres: the reference's validity along y */
    gdouble *used_weight;     /* xres: the current row's weights as used */
    gdouble *column;          /* xres: reference interpolated along y */
    gdouble *trend;           /* TREND_TERMS x xres: the x trend's terms */
    gdouble *row_scratch;     /* (2 + TREND_TERMS) x xres: a row's
                                 gradients and weighted trend */
    gdouble *residual;        /* max_height x xres: weighted residual of the
                                 final match, for its uncertainty */
    gboolean *row_dropped;    /* max_height: rows that left the reference */
};

typedef struct {
    gint first;               /* the stripe's image rows */
    gint height;
    gdouble centre;           /* t = i - centre for row first + i */
    gint nparams;             /* BASE_PARAMS, or MAX_PARAMS with the
                                 velocity */
    gint col_lo;              /* columns matched, [col_lo, col_hi) */
    gint col_hi;
} StripeSpan;

typedef struct {
    gdouble dy, dx;           /* at the centre row */
    gdouble vy, vx;           /* px per row */
} StripeMotion;

StripeSubpixel*
stripe_subpixel_new(const gdouble *image, const gdouble *reference, const gdouble *weight,
                    const gdouble *ref_weight, gint xres, gint yres, const gdouble *window,
                    gint max_height, gint edge_margin)
{
    StripeSubpixel *sp;
    gsize plane;

    g_return_val_if_fail(image && reference && window, NULL);
    g_return_val_if_fail(xres >= 1 && yres >= 1 && max_height >= 1, NULL);
    sp = g_new0(StripeSubpixel, 1);
    sp->image = image;
    sp->reference = reference;
    sp->window = window;
    sp->weight = weight;
    sp->ref_weight = ref_weight;
    sp->xres = xres;
    sp->yres = yres;
    sp->max_height = max_height;
    sp->edge_margin = MAX(edge_margin, 0);
    plane = (gsize)max_height*xres;
    sp->pixel_weight = g_new(gdouble, plane);
    sp->weighted_value = g_new(gdouble, plane);
    sp->residual = g_new(gdouble, plane);
    sp->weighted_grad_y = g_new(gdouble, plane);
    sp->weighted_grad_x = g_new(gdouble, plane);
    sp->row_normal = g_new(gdouble, (gsize)max_height*ROW_TERMS);
    sp->row_offset = g_new(gdouble, (gsize)max_height*ROW_REGRESSORS);
    sp->row_adjusted = g_new(gdouble, (gsize)max_height*ROW_TERMS);
    sp->offset_adjusted = g_new(gdouble, (gsize)max_height*ROW_REGRESSORS);
    sp->column = g_new(gdouble, xres);
    sp->column_valid = g_new(gdouble, xres);
    sp->used_weight = g_new(gdouble, xres);
    sp->trend = g_new(gdouble, TREND_TERMS*(gsize)xres);
    sp->row_scratch = g_new(gdouble, (2 + TREND_TERMS)*(gsize)xres);
    for (gint c = 0; c < xres; c++) {
        gdouble u = (xres > 1) ? 2.0*c/(xres - 1) - 1.0 : 0.0, p0 = 1.0, p1 = u, p2;

        /* Bonnet's recursion: (k + 1) P_{k+1} = (2k + 1) u P_k - k P_{k-1}. */
        for (gint k = 1; k <= TREND_TERMS; k++) {
            sp->trend[(k - 1)*xres + c] = p1;
            p2 = ((2*k + 1)*u*p1 - k*p0)/(k + 1);
            p0 = p1;
            p1 = p2;
        }
    }
    sp->row_dropped = g_new(gboolean, max_height);
    return sp;
}

void
stripe_subpixel_free(StripeSubpixel *sp)
{
    if (!sp)
        return;
    g_free(sp->pixel_weight);
    g_free(sp->weighted_value);
    g_free(sp->residual);
    g_free(sp->weighted_grad_y);
    g_free(sp->weighted_grad_x);
    g_free(sp->row_normal);
    g_free(sp->row_offset);
    g_free(sp->row_adjusted);
    g_free(sp->offset_adjusted);
    g_free(sp->column_valid);
    g_free(sp->used_weight);
    g_free(sp->column);
    g_free(sp->trend);
    g_free(sp->row_scratch);
    g_free(sp->row_dropped);
    g_free(sp);
}

/* Index of the product of row regressors a <= b in a row's terms. */
static gint
row_term(gint a, gint b)
{
    return a*ROW_REGRESSORS - a*(a - 1)/2 + (b - a);
}

/* The image row r, or the edge row beyond the frame. */
static const gdouble*
image_row_clamped(const StripeSubpixel *sp, gint r)
{
    return sp->image + (gsize)CLAMP(r, 0, sp->yres - 1)*sp->xres;
}

/* The product of the weights of the pixel and of its gradients' taps: 1
 * where all are valid, 0 where one is missing, less where one is a missing
 * pixel the conditioning restored among data. */
static gdouble
tap_validity(const StripeSubpixel *sp, gint r, gint c)
{
    const gdouble *w = sp->weight;
    gint xres = sp->xres, m = sp->edge_margin;

    if (r < m || r >= sp->yres - m || c < m || c >= xres - m)
        return 0.0;
    if (!w)
        return 1.0;
    return (w[(gsize)r*xres + c]*w[(gsize)r*xres + c - 1]*w[(gsize)r*xres + c + 1]
            *w[(gsize)CLAMP(r - 1, 0, sp->yres - 1)*xres + c]
            *w[(gsize)CLAMP(r + 1, 0, sp->yres - 1)*xres + c]);
}

/* Every scan line has an offset of its own that the frames need not share
 * (the feedback's set point wanders between lines): the match fits one
 * offset per row.  Eliminated row by row, it leaves the other regressors
 * and the reference's samples centred on the row's weighted means.  Row
 * i's products with the constant are kept in row_offset, and the products
 * among the other regressors are centred here; the constant's own entry
 * (the row's weight) stays, with no coupling, so the common offset the
 * normal matrix still carries comes out 0. */
static void
centre_terms(gdouble *terms, gdouble *offset)
{
    gdouble w1 = terms[row_term(1, 1)];
    gint a, b;

    for (a = 0; a < ROW_REGRESSORS; a++)
        offset[a] = terms[row_term(MIN(a, 1), MAX(a, 1))];
    if (!(w1 > 0.0))
        return;
    for (a = 0; a < ROW_REGRESSORS; a++) {
        for (b = a; b < ROW_REGRESSORS; b++) {
            if (a != 1 && b != 1)
                terms[row_term(a, b)] -= offset[a]*offset[b]/w1;
            else if (a != b)
                terms[row_term(a, b)] = 0.0;
        }
    }
}

static void
centre_row_terms(StripeSubpixel *sp, gint i)
{
    centre_terms(sp->row_normal + (gsize)i*ROW_TERMS, sp->row_offset + (gsize)i*ROW_REGRESSORS);
}

/* The dot product of a and b over columns lo .. hi - 1, in four running
 * sums: one sum's chain of additions would make every pixel wait for the
 * one before. */
static gdouble
columns_dot(const gdouble *a, const gdouble *b, gint lo, gint hi)
{
    gdouble s0 = 0.0, s1 = 0.0, s2 = 0.0, s3 = 0.0;
    gint c = lo;

    for (; c + 4 <= hi; c += 4) {
        s0 += a[c]*b[c];
        s1 += a[c+1]*b[c+1];
        s2 += a[c+2]*b[c+2];
        s3 += a[c+3]*b[c+3];
    }
    for (; c < hi; c++)
        s0 += a[c]*b[c];
    return (s0 + s1) + (s2 + s3);
}

/* columns_dot() with b all ones. */
static gdouble
columns_sum(const gdouble *a, gint lo, gint hi)
{
    gdouble s0 = 0.0, s1 = 0.0, s2 = 0.0, s3 = 0.0;
    gint c = lo;

    for (; c + 4 <= hi; c += 4) {
        s0 += a[c];
        s1 += a[c+1];
        s2 += a[c+2];
        s3 += a[c+3];
    }
    for (; c < hi; c++)
        s0 += a[c];
    return (s0 + s1) + (s2 + s3);
}

/* Row i's weighted stripe and gradients, and its products of the row
 * regressors (stripe, 1, d/dy, d/dx, the x trend), upper triangle by rows:
 * first the regressors along the row, then each product as one pass over
 * it. */
static void
prepare_row(StripeSubpixel *sp, const StripeSpan *span, gint i)
{
    gint xres = sp->xres, r = span->first + i, lo = span->col_lo, hi = span->col_hi, c, a, b;
    const gdouble *row = sp->image + (gsize)r*xres;
    const gdouble *above = image_row_clamped(sp, r - 1), *below = image_row_clamped(sp, r + 1);
    gdouble *pw = sp->pixel_weight + (gsize)i*xres;
    gdouble *wv = sp->weighted_value + (gsize)i*xres;
    gdouble *wgy = sp->weighted_grad_y + (gsize)i*xres;
    gdouble *wgx = sp->weighted_grad_x + (gsize)i*xres;
    gdouble *gy = sp->row_scratch, *gx = gy + xres, *wtrend = gx + xres;
    gdouble *terms = sp->row_normal + (gsize)i*ROW_TERMS;
    gdouble inv_dist = 1.0/(MIN(r + 1, sp->yres - 1) - MAX(r - 1, 0)), w;
    const gdouble *plain[ROW_REGRESSORS], *weighted[ROW_REGRESSORS];

    for (c = lo; c < hi; c++) {
        w = sp->window[c]*tap_validity(sp, r, c);
        pw[c] = w;
        gy[c] = (below[c] - above[c])*inv_dist;
        gx[c] = 0.5*(row[c+1] - row[c-1]);
        wv[c] = w*row[c];
        wgy[c] = w*gy[c];
        wgx[c] = w*gx[c];
    }
    for (a = 0; a < TREND_TERMS; a++) {
        const gdouble *t = sp->trend + (gsize)a*xres;
        gdouble *wt = wtrend + (gsize)a*xres;

        for (c = lo; c < hi; c++)
            wt[c] = pw[c]*t[c];
        plain[4 + a] = t;
        weighted[4 + a] = wt;
    }
    plain[0] = row;
    plain[1] = NULL;
    plain[2] = gy;
    plain[3] = gx;
    weighted[0] = wv;
    weighted[1] = pw;
    weighted[2] = wgy;
    weighted[3] = wgx;
    for (a = 0; a < ROW_REGRESSORS; a++) {
        for (b = a; b < ROW_REGRESSORS; b++) {
            /* Regressor 1 is the constant. */
            terms[row_term(a, b)] = (b == 1) ? columns_sum(weighted[a], lo, hi)
                                             : columns_dot(weighted[a], plain[b], lo, hi);
        }
    }
    centre_row_terms(sp, i);
}

/* The regressors beyond the row's own are its gradients times t. */
static gint
row_regressor_of(gint a, gint *t_power)
{
    *t_power = (a >= ROW_REGRESSORS);
    return (a >= ROW_REGRESSORS) ? a - ROW_REGRESSORS + 2 : a;
}

/* Adds row i's share (at offset t from the centre) to the normal matrix. */
static void
add_row_normal(const gdouble *terms, gint nparams, gdouble t,
               gdouble normal[MAX_PARAMS][MAX_PARAMS])
{
    gdouble power[3] = { 1.0, t, t*t };
    gint a, b, ra, rb, pa, pb;

    for (a = 0; a < nparams; a++) {
        ra = row_regressor_of(a, &pa);
        for (b = a; b < nparams; b++) {
            rb = row_regressor_of(b, &pb);
            normal[a][b] += power[pa + pb]*terms[row_term(MIN(ra, rb), MAX(ra, rb))];
        }
    }
}

/* Solves normal x = rhs, normal given by its upper triangle (Gaussian
 * elimination with partial pivoting); FALSE when it is singular. */
static gboolean
solve_normal(gdouble normal[MAX_PARAMS][MAX_PARAMS], const gdouble *rhs, gint n, gdouble *x)
{
    gdouble a[MAX_PARAMS][MAX_PARAMS + 1], f, scale = 0.0;
    gint i, j, k, p;

    for (i = 0; i < n; i++) {
        for (j = i; j < n; j++) {
            a[i][j] = a[j][i] = normal[i][j];
            scale = MAX(scale, fabs(normal[i][j]));
        }
        a[i][n] = rhs[i];
    }
    for (i = 0; i < n; i++) {
        p = i;
        for (j = i + 1; j < n; j++) {
            if (fabs(a[j][i]) > fabs(a[p][i]))
                p = j;
        }
        if (!(fabs(a[p][i]) > 1e-12*scale))
            return FALSE;
        for (j = 0; j <= n; j++) {
            f = a[i][j];
            a[i][j] = a[p][j];
            a[p][j] = f;
        }
        for (j = i + 1; j < n; j++) {
            f = a[j][i]/a[i][i];
            for (k = i; k <= n; k++)
                a[j][k] -= f*a[i][k];
        }
    }
    for (i = n - 1; i >= 0; i--) {
        f = a[i][n];
        for (j = i + 1; j < n; j++)
            f -= a[i][j]*x[j];
        x[i] = f/a[i][i];
    }
    return TRUE;
}

/* The row's dot products with the reference's samples (sums[a] for
 * regressor a, sums[ROW_REGRESSORS] of the samples' squares), centred like
 * its regressors (centre_row_terms): dots[1] becomes 0 and
 * dots[ROW_REGRESSORS] the sum of the centred samples' squares. */
static void
centre_row_dots(const gdouble *offset, const gdouble *sums, gdouble *dots)
{
    gdouble w1 = offset[1], mean = (w1 > 0.0) ? sums[1]/w1 : 0.0;
    gint a;

    for (a = 0; a < ROW_REGRESSORS; a++)
        dots[a] = (a == 1) ? 0.0 : sums[a] - offset[a]*mean;
    dots[ROW_REGRESSORS] = sums[ROW_REGRESSORS] - sums[1]*mean;
}

/* The row's residual without its own offset: its weighted mean removed
 * (the weights as the row was matched, in used_weight). */
static void
centre_row_residual(StripeSubpixel *sp, const StripeSpan *span, gint i)
{
    gdouble *res = sp->residual + (gsize)i*sp->xres;
    const gdouble *pw = sp->used_weight;
    gdouble sr = 0.0, sw = 0.0, mean;
    gint c;

    for (c = span->col_lo; c < span->col_hi; c++) {
        sr += res[c];
        sw += pw[c];
    }
    mean = (sw > 0.0) ? sr/sw : 0.0;
    for (c = span->col_lo; c < span->col_hi; c++)
        res[c] -= pw[c]*mean;
}

/* The weighted model of the reference at row i, column c, with the row's
 * offset t from the centre, for the fitted parameters p. */
static gdouble
row_model(const StripeSubpixel *sp, const gdouble *p, gint i, gint c, gdouble t)
{
    gsize k = (gsize)i*sp->xres + c;
    gdouble pw = sp->pixel_weight[k], trend = p[1];
    gint a;

    for (a = 0; a < TREND_TERMS; a++)
        trend += p[4 + a]*sp->trend[a*sp->xres + c];
    return (p[0]*sp->weighted_value[k] + pw*trend
            + (p[2] + t*p[BASE_PARAMS])*sp->weighted_grad_y[k]
            + (p[3] + t*p[BASE_PARAMS + 1])*sp->weighted_grad_x[k]);
}

/* Adds pixel c's share to a row's uncentred terms (the regressor products
 * prepare_row sums). */
static void
add_pixel_terms(const StripeSubpixel *sp, gint i, gint c, gdouble *terms)
{
    gsize k = (gsize)i*sp->xres + c;
    gdouble w = sp->pixel_weight[k], wreg[ROW_REGRESSORS];
    gint a, b;

    if (!(w > 0.0))
        return;
    wreg[0] = sp->weighted_value[k];
    wreg[1] = w;
    wreg[2] = sp->weighted_grad_y[k];
    wreg[3] = sp->weighted_grad_x[k];
    for (a = 0; a < TREND_TERMS; a++)
        wreg[4 + a] = w*sp->trend[a*sp->xres + c];
    for (a = 0; a < ROW_REGRESSORS; a++) {
        for (b = a; b < ROW_REGRESSORS; b++)
            terms[row_term(a, b)] += wreg[a]*wreg[b]/w;
    }
}

/* Whether the reference sample of every column of the row is made of
 * pixels present only: column_valid[c] gets the product of the weights of
 * the four reference rows from top on (c in [lo, hi)).  A pixel restored
 * among data (weight below 1) is present, and its sample counts in full:
 * weighing each sample by its taps' weights as the kernel weighs them,
 * tried, moved nothing (20 % of the reference missing at random: 0.033
 * against 0.034 px rms from the clean pairs' shifts over 320 stripes) and
 * summed every row's terms anew at every step. */
static gboolean
reference_columns_valid(StripeSubpixel *sp, gint top, gint lo, gint hi)
{
    const gdouble *w0, *w1, *w2, *w3;
    gboolean all = TRUE;
    gint c;

    if (!sp->ref_weight)
        return TRUE;
    w0 = sp->ref_weight + (gsize)top*sp->xres;
    w1 = w0 + sp->xres;
    w2 = w1 + sp->xres;
    w3 = w2 + sp->xres;
    for (c = lo; c < hi; c++) {
        sp->column_valid[c] = w0[c]*w1[c]*w2[c]*w3[c];
        all = all && sp->column_valid[c] > 0.0;
    }
    return all;
}

/* Whether the reference taps of row i at the shift stay within the frame,
 * away from its edges: taps near the reference's edge would read what the
 * filters moved there, as near the image's.  The columns were prepared for
 * shifts within reach of the anchor; the residual's profile steps beyond
 * it (without this a step ran off the frame and overwrote the heap). */
static gboolean
row_taps_on_frame(const StripeSubpixel *sp, const StripeSpan *span, gint i, gdouble shift_y,
                  gdouble shift_x)
{
    gint ky = (gint)floor(-shift_y), kx = (gint)floor(-shift_x), top = span->first + i + ky - 1;

    return !(top < sp->edge_margin || top + 3 >= sp->yres - sp->edge_margin
             || span->col_lo + kx - 1 < sp->edge_margin
             || span->col_hi + kx + 2 > sp->xres - sp->edge_margin);
}

/* Dot products of row i's weighted regressors with the reference sampled
 * at (r - shift_y, c - shift_x), and the weighted sum of its squares;
 * FALSE if the taps leave the reference.  *terms gets the row's centred
 * products of its regressors to go with them: its own, or, where some of
 * its pixels' samples reach missing reference pixels, those of the others
 * (a missing pixel reads as 0, which pulled stripes crossing a hole in the
 * reference 0.2 px off, 0.8 px at worst).  With fit (all MAX_PARAMS
 * parameters), the weighted residual of the row is kept too. */
static gboolean
match_row(StripeSubpixel *sp, const StripeSpan *span, gint i, gdouble shift_y, gdouble shift_x,
          const gdouble *fit, gdouble t, gdouble *dots, const gdouble **terms)
{
    gint xres = sp->xres, ky = (gint)floor(-shift_y), kx = (gint)floor(-shift_x);
    gint top = span->first + i + ky - 1, c;
    const gdouble *r0, *r1, *r2, *r3;
    const gdouble *pw = sp->pixel_weight + (gsize)i*xres;
    const gdouble *wv = sp->weighted_value + (gsize)i*xres;
    const gdouble *wgy = sp->weighted_grad_y + (gsize)i*xres;
    const gdouble *wgx = sp->weighted_grad_x + (gsize)i*xres;
    const gdouble *offset = sp->row_offset + (gsize)i*ROW_REGRESSORS, *valid;
    gdouble wy[KERNEL_TAPS], wx[KERNEL_TAPS], sums[ROW_REGRESSORS + 1], v, pv, w;
    gdouble *adjusted = NULL;
    gint a, kept = 0;
    gdouble *col = sp->column;

    if (!row_taps_on_frame(sp, span, i, shift_y, shift_x))
        return FALSE;
    *terms = sp->row_normal + (gsize)i*ROW_TERMS;
    if (!reference_columns_valid(sp, top, span->col_lo + kx - 1, span->col_hi + kx + 2)) {
        /* Summed anew from the pixels kept: subtracting those left out
         * from the row's sums leaves their rounding where most are. */
        adjusted = sp->row_adjusted + (gsize)i*ROW_TERMS;
        memset(adjusted, 0, ROW_TERMS*sizeof(gdouble));
    }
    valid = sp->column_valid + kx;
    keys_weights(-shift_y - ky, 1.0 - (-shift_y - ky), wy);
    keys_weights(-shift_x - kx, 1.0 - (-shift_x - kx), wx);
    r0 = sp->reference + (gsize)top*xres;
    r1 = r0 + xres;
    r2 = r1 + xres;
    r3 = r2 + xres;
    /* Along y first, into reference columns c + kx - 1 .. c + kx + 2. */
    for (c = span->col_lo + kx - 1; c < span->col_hi + kx + 2; c++)
        col[c] = wy[0]*r0[c] + wy[1]*r1[c] + wy[2]*r2[c] + wy[3]*r3[c];
    col += kx;
    memset(sums, 0, sizeof(sums));
    for (c = span->col_lo; c < span->col_hi; c++) {
        w = pw[c];
        if (adjusted) {
            if (!(valid[c-1]*valid[c]*valid[c+1]*valid[c+2] > 0.0)) {
                sp->used_weight[c] = 0.0;
                if (fit)
                    sp->residual[(gsize)i*xres + c] = 0.0;
                continue;
            }
            add_pixel_terms(sp, i, c, adjusted);
            kept += (w > 0.0);
        }
        sp->used_weight[c] = w;
        v = wx[0]*col[c-1] + wx[1]*col[c] + wx[2]*col[c+1] + wx[3]*col[c+2];
        pv = w*v;
        sums[0] += wv[c]*v;
        sums[1] += pv;
        sums[2] += wgy[c]*v;
        sums[3] += wgx[c]*v;
        for (a = 0; a < TREND_TERMS; a++)
            sums[4 + a] += pv*sp->trend[a*xres + c];
        sums[ROW_REGRESSORS] += pv*v;
        if (fit)
            sp->residual[(gsize)i*xres + c] = pv - row_model(sp, fit, i, c, t);
    }
    if (adjusted) {
        gdouble *adjusted_offset = sp->offset_adjusted + (gsize)i*ROW_REGRESSORS;

        /* A row mostly over missing reference pixels is off the reference. */
        if (kept < MIN_COLUMNS)
            return FALSE;
        centre_terms(adjusted, adjusted_offset);
        offset = adjusted_offset;
        *terms = adjusted;
    }
    centre_row_dots(offset, sums, dots);
    if (fit)
        centre_row_residual(sp, span, i);
    return TRUE;
}

/* One Gauss-Newton step from the motion m: the reference sampled along it
 * regressed on the stripe and its gradients.  FALSE when too few rows meet
 * the reference or the fit has no positive gain. */
static gboolean
match_step(StripeSubpixel *sp, const StripeSpan *span, const StripeMotion *m, StripeMotion *step)
{
    gdouble normal[MAX_PARAMS][MAX_PARAMS], rhs[MAX_PARAMS], p[MAX_PARAMS], dots[ROW_REGRESSORS + 1], t;
    const gdouble *terms;
    gint n = span->nparams, i, a, ra, pa, used = 0;

    memset(normal, 0, sizeof(normal));
    memset(rhs, 0, sizeof(rhs));
    for (i = 0; i < span->height; i++) {
        t = i - span->centre;
        /* A row whose taps leave the reference stays out for good: a set of
         * rows changing with the shift can make the steps oscillate between
         * the two sets' matches. */
        if (sp->row_dropped[i])
            continue;
        if (!match_row(sp, span, i, m->dy + m->vy*t, m->dx + m->vx*t, NULL, t, dots, &terms)) {
            sp->row_dropped[i] = TRUE;
            continue;
        }
        used++;
        for (a = 0; a < n; a++) {
            ra = row_regressor_of(a, &pa);
            rhs[a] += (pa ? t : 1.0)*dots[ra];
        }
        add_row_normal(terms, n, t, normal);
    }
    if (used < MAX(2, (gint)ceil(MIN_ROWS_FRACTION*span->height)))
        return FALSE;
    if (!solve_normal(normal, rhs, n, p) || !(p[0] > 0.0))
        return FALSE;
    step->dy = p[2]/p[0];
    step->dx = p[3]/p[0];
    step->vy = (n > BASE_PARAMS) ? p[BASE_PARAMS]/p[0] : 0.0;
    step->vx = (n > BASE_PARAMS) ? p[BASE_PARAMS + 1]/p[0] : 0.0;
    return TRUE;
}

static void
limit_step(StripeMotion *step, gdouble half)
{
    gdouble longest = MAX(fabs(step->dy), fabs(step->dx));

    longest = MAX(longest, half*MAX(fabs(step->vy), fabs(step->vx)));
    if (longest > MAX_STEP) {
        step->dy *= MAX_STEP/longest;
        step->dx *= MAX_STEP/longest;
        step->vy *= MAX_STEP/longest;
        step->vx *= MAX_STEP/longest;
    }
}

/* How many of the stripe's rows have all their taps on the reference at the
 * shift dy. */
static gint
rows_on_reference(const StripeSubpixel *sp, const StripeSpan *span, gdouble dy)
{
    gint top = span->first + (gint)floor(-dy) - 1;

    gint m = sp->edge_margin;

    return MAX(0, MIN(span->height, sp->yres - m - 3 - top) - MAX(0, m - top));
}

/* Whether m keeps every row's taps on the columns prepared. */
static gboolean
motion_within_reach(const StripeSpan *span, const StripeMotion *m, gint anchor_dy, gint anchor_dx,
                    gint reach)
{
    gdouble half = 0.5*(span->height - 1);

    return (fabs(m->dy - anchor_dy) <= reach && fabs(m->dx - anchor_dx) <= reach
            && fabs(m->vy)*half <= MAX_SPREAD && fabs(m->vx)*half <= MAX_SPREAD);
}

/* Lag-one correlation of the kept residuals along x (row) or y (!row). */
static gdouble
residual_correlation(const StripeSubpixel *sp, const StripeSpan *span, gboolean along_x)
{
    gint xres = sp->xres, i, c;
    gdouble s2 = 0.0, s11 = 0.0;

    for (i = 0; i < span->height; i++) {
        const gdouble *res = sp->residual + (gsize)i*xres;

        if (sp->row_dropped[i])
            continue;
        for (c = span->col_lo; c < span->col_hi; c++) {
            s2 += res[c]*res[c];
            if (along_x && c + 1 < span->col_hi)
                s11 += res[c]*res[c+1];
            else if (!along_x && i + 1 < span->height && !sp->row_dropped[i+1])
                s11 += res[c]*res[c + xres];
        }
    }
    return (s2 > 0.0) ? CLAMP(s11/s2, 0.0, 0.9) : 0.0;
}

/* The weighted residual sum of squares of the reference sampled along the
 * motion m, shifted by (ky, kx) px, against the stripe with its gain, the
 * rows' offsets and the x trend fitted but no gradient (the shift held
 * there); dof gets the weight left for the residual.  FALSE when a row's
 * taps leave the reference or the fit is singular. */
static gboolean
rss_held_at(StripeSubpixel *sp, const StripeSpan *span, const StripeMotion *m, gdouble ky, gdouble kx,
            gdouble *rss, gdouble *dof)
{
    enum { HELD = 1 + TREND_TERMS };
    gdouble normal[MAX_PARAMS][MAX_PARAMS], rhs[MAX_PARAMS], p[MAX_PARAMS], dots[ROW_REGRESSORS + 1];
    gdouble t, vv = 0.0, wsum = 0.0;
    gint reg[HELD], i, a, b;

    reg[0] = 0;
    for (a = 0; a < TREND_TERMS; a++)
        reg[1 + a] = 4 + a;
    memset(normal, 0, sizeof(normal));
    memset(rhs, 0, sizeof(rhs));
    for (i = 0; i < span->height; i++) {
        const gdouble *terms;

        if (sp->row_dropped[i])
            continue;
        t = i - span->centre;
        if (!match_row(sp, span, i, m->dy + ky + m->vy*t, m->dx + kx + m->vx*t, NULL, t, dots, &terms))
            return FALSE;
        for (a = 0; a < HELD; a++) {
            rhs[a] += dots[reg[a]];
            for (b = a; b < HELD; b++)
                normal[a][b] += terms[row_term(MIN(reg[a], reg[b]), MAX(reg[a], reg[b]))];
        }
        vv += dots[ROW_REGRESSORS];
        wsum += terms[row_term(1, 1)];
    }
    if (!(wsum > HELD + 1) || !solve_normal(normal, rhs, HELD, p))
        return FALSE;
    *rss = vv;
    for (a = 0; a < HELD; a++)
        *rss -= p[a]*rhs[a];
    *rss = MAX(*rss, 0.0);
    *dof = wsum - HELD;
    return TRUE;
}

/* The uncertainty (px) the match's residual profile gives along one axis:
 * how much worse the stripe matches 3 px away on either side than where it
 * matched (rss0), against the residual's own variance s2 (times the
 * inflation for its correlation between neighbouring pixels).  Nearer
 * steps add nothing the curvature does not say (401 seeds of the grating
 * test alike with steps of 1 and 3 px or of 3 px alone) and cost a pass
 * over the stripe each.  The normal matrix sees only
 * the curvature where the match converged, which on a ridge (the lines of
 * a grating with a faint roughness) is the curvature of a bump of noise:
 * stripes were given 1.5-3.5 px off with sigma 0.5 px.  Steps that leave
 * the reference are not taken; 0 when none is. */
static gdouble
profile_sigma(StripeSubpixel *sp, const StripeSpan *span, const StripeMotion *m, gboolean along_x,
              gdouble rss0, gdouble dof0, gdouble s2)
{
    static const gdouble steps[] = { 3.0 };
    gdouble rss, dof, sigma = 0.0, k;
    guint j;
    gint sign;

    for (j = 0; j < G_N_ELEMENTS(steps); j++) {
        for (sign = -1; sign <= 1; sign += 2) {
            k = sign*steps[j];
            if (!rss_held_at(sp, span, m, along_x ? 0.0 : k, along_x ? k : 0.0, &rss, &dof)
                || !(dof > 0.0))
                continue;
            /* Where a hole of the reference is reached at one shift and not
             * at another, the two sums run over different pixels: compared
             * per degree of freedom. */
            rss *= dof0/dof;
            /* A step that matches as well says the optimum is that
             * uncertain at least. */
            sigma = MAX(sigma, (rss > rss0) ? steps[j]*sqrt(s2/(rss - rss0)) : steps[j]);
        }
    }
    return sigma;
}

/* The standard uncertainty (px, the larger of dy's and dx's) of the match
 * at m: least squares' own, from the residual and the normal matrix,
 * inflated for the residual's correlation between neighbouring pixels
 * (conditioned frames are smooth over a pixel or two, and what differs
 * between the frames beyond noise is smooth over a feature), which makes
 * fewer independent pixels than there are pixels. */
static gboolean
match_uncertainty(StripeSubpixel *sp, const StripeSpan *span, const StripeMotion *m, gdouble *sigma)
{
    gdouble normal[MAX_PARAMS][MAX_PARAMS], rhs[MAX_PARAMS], p[MAX_PARAMS] = { 0 };
    gdouble unit[MAX_PARAMS], inv[MAX_PARAMS], dots[ROW_REGRESSORS + 1], t, vv = 0.0, wsum = 0.0;
    gdouble rss, var_y, var_x, rx, ry, inflation, rss0, dof;
    const gdouble *terms;
    gint n = span->nparams, i, a, ra, pa;

    memset(normal, 0, sizeof(normal));
    memset(rhs, 0, sizeof(rhs));
    for (i = 0; i < span->height; i++) {
        t = i - span->centre;
        if (sp->row_dropped[i]
            || !match_row(sp, span, i, m->dy + m->vy*t, m->dx + m->vx*t, NULL, t, dots, &terms))
            continue;
        for (a = 0; a < n; a++) {
            ra = row_regressor_of(a, &pa);
            rhs[a] += (pa ? t : 1.0)*dots[ra];
        }
        add_row_normal(terms, n, t, normal);
        vv += dots[ROW_REGRESSORS];
        wsum += terms[row_term(1, 1)];
    }
    if (!(wsum > n + 1) || !solve_normal(normal, rhs, n, p) || !(p[0] > 0.0))
        return FALSE;
    rss = vv;
    for (a = 0; a < n; a++)
        rss -= p[a]*rhs[a];
    rss = MAX(rss, 0.0);
    memset(unit, 0, sizeof(unit));
    unit[2] = 1.0;
    if (!solve_normal(normal, unit, n, inv))
        return FALSE;
    var_y = rss/(wsum - n)*inv[2]/(p[0]*p[0]);
    unit[2] = 0.0;
    unit[3] = 1.0;
    if (!solve_normal(normal, unit, n, inv))
        return FALSE;
    var_x = rss/(wsum - n)*inv[3]/(p[0]*p[0]);
    for (i = 0; i < span->height; i++) {
        t = i - span->centre;
        if (!sp->row_dropped[i])
            match_row(sp, span, i, m->dy + m->vy*t, m->dx + m->vx*t, p, t, dots, &terms);
    }
    rx = residual_correlation(sp, span, TRUE);
    ry = residual_correlation(sp, span, FALSE);
    inflation = (1.0 + rx)/(1.0 - rx)*(1.0 + ry)/(1.0 - ry);
    *sigma = sqrt(MAX(var_y, var_x)*inflation);
    if (rss_held_at(sp, span, m, 0.0, 0.0, &rss0, &dof) && dof > 0.0) {
        *sigma = MAX(*sigma, profile_sigma(sp, span, m, FALSE, rss0, dof, rss0/dof*inflation));
        *sigma = MAX(*sigma, profile_sigma(sp, span, m, TRUE, rss0, dof, rss0/dof*inflation));
    }
    return isfinite(*sigma);
}

/* Whether at least MIN_PRESENT_SHARE of the stripe's weight, of its rows
 * whose taps stay on the frame at m, meets reference samples made of
 * pixels present. */
static gboolean
enough_reference_present(StripeSubpixel *sp, const StripeSpan *span, const StripeMotion *m)
{
    gdouble dots[ROW_REGRESSORS + 1], t, sy, sx, total = 0.0, present = 0.0;
    const gdouble *terms;
    gint i;

    if (!sp->ref_weight)
        return TRUE;
    for (i = 0; i < span->height; i++) {
        t = i - span->centre;
        sy = m->dy + m->vy*t;
        sx = m->dx + m->vx*t;
        if (!row_taps_on_frame(sp, span, i, sy, sx))
            continue;
        /* Whether or not the row keeps enough columns, used_weight says
         * which of them met present pixels. */
        match_row(sp, span, i, sy, sx, NULL, t, dots, &terms);
        total += columns_sum(sp->pixel_weight + (gsize)i*sp->xres, span->col_lo, span->col_hi);
        present += columns_sum(sp->used_weight, span->col_lo, span->col_hi);
    }
    return present >= MIN_PRESENT_SHARE*total && total > 0.0;
}

/* Whether the stripe's texture (the energy of its gradients) lies on both
 * sides of its centre row, at least VELOCITY_MIN_SIDE_SHARE of it on each:
 * only then can the change of the shift over the rows be measured and the
 * shift at the centre row be read between textured rows.  Where the
 * texture sits in a few rows at one end (a particle cut by the stripe's
 * border, flat substrate beyond), a rate rests on those rows alone, and
 * the centre row's shift is an extrapolation from them: on a drift-free
 * pair a rate of 0.27 px per row, 5 of its least-squares uncertainties
 * (the frames' difference there is interpolation, not noise), moved it
 * 1.3 px (benchmark seed 188), where one shift measures the stripe. */
static gboolean
texture_on_both_sides(const StripeSubpixel *sp, const StripeSpan *span)
{
    gdouble side[2] = { 0.0, 0.0 }, e, t;
    gint i, c;

    for (i = 0; i < span->height; i++) {
        const gdouble *wgy = sp->weighted_grad_y + (gsize)i*sp->xres;
        const gdouble *wgx = sp->weighted_grad_x + (gsize)i*sp->xres;

        for (c = span->col_lo, e = 0.0; c < span->col_hi; c++)
            e += wgy[c]*wgy[c] + wgx[c]*wgx[c];
        t = i - span->centre;
        if (t <= 0.0)
            side[0] += (t == 0.0) ? 0.5*e : e;
        if (t >= 0.0)
            side[1] += (t == 0.0) ? 0.5*e : e;
    }
    return MIN(side[0], side[1]) >= VELOCITY_MIN_SIDE_SHARE*(side[0] + side[1])
           && side[0] + side[1] > 0.0;
}

/* Gauss-Newton from (dy, dx) with nparams unknowns; TRUE and the motion
 * when it converges within reach of the anchor. */
static gboolean
iterate_match(StripeSubpixel *sp, StripeSpan *span, gint anchor_dy, gint anchor_dx, gint reach,
              StripeMotion *m)
{
    StripeMotion step;
    gint iter, i;

    for (i = 0; i < span->height; i++)
        sp->row_dropped[i] = FALSE;
    for (iter = 0; iter < MAX_ITERATIONS; iter++) {
        /* Once the match moves the stripe half off the reference, it keeps
         * one shift for good (no switching back and forth). */
        if (span->nparams > BASE_PARAMS
            && rows_on_reference(sp, span, m->dy) < MIN_VELOCITY_FRACTION*span->height) {
            span->nparams = BASE_PARAMS;
            m->vy = m->vx = 0.0;
        }
        if (!motion_within_reach(span, m, anchor_dy, anchor_dx, reach)
            || !match_step(sp, span, m, &step))
            return FALSE;
        limit_step(&step, span->centre);
        m->dy += step.dy;
        m->dx += step.dx;
        m->vy += step.vy;
        m->vx += step.vx;
        if (fabs(step.dy) < CONVERGED_STEP && fabs(step.dx) < CONVERGED_STEP
            && fabs(step.vy)*span->centre < CONVERGED_STEP
            && fabs(step.vx)*span->centre < CONVERGED_STEP)
            break;
    }
    return iter < MAX_ITERATIONS && motion_within_reach(span, m, anchor_dy, anchor_dx, reach);
}

/* The image row whose shift one shift for all the rows of the span is:
 * its rows weighted by what each told the match of the shift (the
 * information along y and x, line offsets taken out), rows that carried
 * no weight (within the filters' reach of the frame's edge, off the
 * reference) not counted; the centre row when none told anything.
 * Where the drift changes over the rows, one shift is that of the rows
 * whose texture decides it, not the centre row's, and rows the match did
 * not use decide nothing.  Timed by all its rows, the first 4-line block
 * of a frame registered against a frame squeezed by a fast settling
 * (0.15 px a line) was tied to a moment a row early, its first two rows
 * being within the filters' reach of the frame's top: the settling's
 * travel read 0.13 px short on average over 100 samples of particles
 * (0.01 px over timed by this row, the other blocks' scatter a tenth
 * smaller too), and a fast settling's corrected frames lay up to 0.44 px
 * off (test-series-correction, seeds 800000065 and 576000040). */
static gdouble
single_shift_row(const StripeSubpixel *sp, const StripeSpan *span)
{
    gdouble wsum = 0.0, rsum = 0.0, w;
    gint i;

    for (i = 0; i < span->height; i++) {
        const gdouble *terms = sp->row_normal + (gsize)i*ROW_TERMS;

        if (sp->row_dropped[i])
            continue;
        w = MAX(terms[row_term(2, 2)], 0.0) + MAX(terms[row_term(3, 3)], 0.0);
        wsum += w;
        rsum += w*i;
    }
    return span->first + ((wsum > 0.0 && isfinite(rsum)) ? rsum/wsum : span->centre);
}

/* The match of image rows first .. end-1 (see stripe_subpixel_refine).
 * row gets the image row whose shift it is: the centre row where the
 * shift was let change over the rows (its value is reported there), else
 * single_shift_row(). */
static gboolean
refine_rows(StripeSubpixel *sp, gint first, gint end, gint anchor_dy, gint anchor_dx,
            gint reach, gdouble *dy, gdouble *dx, gdouble *sigma, gdouble *row)
{
    StripeSpan span;
    StripeMotion m;
    gint margin, i;
    gboolean converged;

    span.first = first;
    span.height = end - first;
    span.centre = 0.5*(span.height - 1);
    /* Columns whose taps stay on the reference for every row's dx within
     * reach of the anchor plus the spread, and whose x gradient is central. */
    margin = reach + (gint)ceil(MAX_SPREAD) + 1 + sp->edge_margin;
    span.col_lo = MAX(1, anchor_dx + margin);
    span.col_hi = MIN(sp->xres - 1, sp->xres - 1 - margin + anchor_dx);
    if (span.col_hi - span.col_lo < MIN_COLUMNS)
        return FALSE;
    for (i = 0; i < span.height; i++)
        prepare_row(sp, &span, i);

    m.dy = *dy;
    m.dx = *dx;
    m.vy = m.vx = 0.0;
    span.nparams = (span.height >= MIN_ROWS_FOR_VELOCITY && texture_on_both_sides(sp, &span))
                   ? MAX_PARAMS : BASE_PARAMS;
    converged = iterate_match(sp, &span, anchor_dy, anchor_dx, reach, &m);
    /* Where the frames differ by more than noise, the change of the shift
     * over the rows can be too weakly determined to converge; one shift
     * for the whole stripe still is. */
    if (!converged && span.nparams > BASE_PARAMS) {
        m.dy = *dy;
        m.dx = *dx;
        m.vy = m.vx = 0.0;
        span.nparams = BASE_PARAMS;
        converged = iterate_match(sp, &span, anchor_dy, anchor_dx, reach, &m);
    }
    if (!converged || !enough_reference_present(sp, &span, &m)
        || (sigma && !match_uncertainty(sp, &span, &m, sigma)))
        return FALSE;
    *dy = m.dy;
    *dx = m.dx;
    if (row)
        *row = (span.nparams > BASE_PARAMS) ? first + span.centre : single_shift_row(sp, &span);
    return TRUE;
}

gboolean
stripe_subpixel_refine(StripeSubpixel *sp, gint first, gint end, gint anchor_dy, gint anchor_dx,
                       gint reach, gdouble *dy, gdouble *dx, gdouble *sigma, gdouble *row)
{
    gint m;

    g_return_val_if_fail(sp && first >= 0 && end <= sp->yres, FALSE);
    g_return_val_if_fail(end - first >= 1 && end - first <= sp->max_height, FALSE);
    g_return_val_if_fail(reach >= 0, FALSE);
    /* The filters that conditioned the frames reach edge_margin rows
     * across the stripe's border, where the drift may have jumped: rows
     * that near carry a neighbour's shift (0.2-0.7 px off beside a 4-9 px
     * jump).  They are left out, as many at each end, so the stripe's
     * centre row stays where it was; where too few rows are left to match
     * (a stripe half off the reference), the whole stripe is matched. */
    m = sp->edge_margin;
    if (end - first - 2*m >= MIN_ROWS_FOR_VELOCITY
        && refine_rows(sp, first + m, end - m, anchor_dy, anchor_dx, reach, dy, dx, sigma, row))
        return TRUE;
    return refine_rows(sp, first, end, anchor_dy, anchor_dx, reach, dy, dx, sigma, row);
}
