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
 * The model is: the reference, moved by d and sampled with Keys' cubic
 * kernel, equals gain*stripe + offset over the stripe's pixels, weighted by
 * the column window.  Linearised about the current d with the stripe's own
 * gradients, the unknowns gain, offset, gain*step_y and gain*step_x are a
 * linear least-squares problem whose matrix depends only on the stripe and
 * the rows that meet the reference, so each step costs one interpolation of
 * the reference and four dot products.  Because the stripe's gradients stand
 * in for the moved reference's, the steps converge to the exact match (the
 * residual then has no component along them) and only their length depends
 * on the approximation.
 */

/* Unknowns: gain, offset, gain*step_y, gain*step_x. */
enum { PARAMS = 4, NORMAL_TERMS = PARAMS*(PARAMS + 1)/2 };

#define MAX_ITERATIONS 8
/* Steps shorter than this (px, per axis) end the iteration. */
#define CONVERGED_STEP 1e-3
/* Fewer of the stripe's rows than this on the reference is too little to
 * refine on. */
#define MIN_ROWS_FRACTION 0.25
/* Columns the match needs at least. */
#define MIN_COLUMNS 8

struct _StripeSubpixel {
    const gdouble *image;
    const gdouble *reference;
    const gdouble *window;
    gint xres;
    gint yres;
    gint max_height;
    gdouble *weighted_value;  /* max_height x xres: window*stripe */
    gdouble *weighted_grad_y; /* window*d(stripe)/dy */
    gdouble *weighted_grad_x;
    gdouble *row_normal;      /* max_height x NORMAL_TERMS: each row's part of
                                 the normal matrix, upper triangle by rows */
    gdouble *rows_x;          /* (max_height + 3) x xres: reference rows
                                 interpolated along x */
};

typedef struct {
    gint first;               /* the stripe's image rows */
    gint height;
    gint col_lo;              /* columns matched, [col_lo, col_hi) */
    gint col_hi;
} StripeSpan;

StripeSubpixel*
stripe_subpixel_new(const gdouble *image, const gdouble *reference, gint xres, gint yres,
                    const gdouble *window, gint max_height)
{
    StripeSubpixel *sp;
    gsize plane;

    g_return_val_if_fail(image && reference && window, NULL);
    g_return_val_if_fail(xres >= 1 && yres >= 1 && max_height >= 1, NULL);
    sp = g_new0(StripeSubpixel, 1);
    sp->image = image;
    sp->reference = reference;
    sp->window = window;
    sp->xres = xres;
    sp->yres = yres;
    sp->max_height = max_height;
    plane = (gsize)max_height*xres;
    sp->weighted_value = g_new(gdouble, plane);
    sp->weighted_grad_y = g_new(gdouble, plane);
    sp->weighted_grad_x = g_new(gdouble, plane);
    sp->row_normal = g_new(gdouble, (gsize)max_height*NORMAL_TERMS);
    sp->rows_x = g_new(gdouble, (gsize)(max_height + 3)*xres);
    return sp;
}

void
stripe_subpixel_free(StripeSubpixel *sp)
{
    if (!sp)
        return;
    g_free(sp->weighted_value);
    g_free(sp->weighted_grad_y);
    g_free(sp->weighted_grad_x);
    g_free(sp->row_normal);
    g_free(sp->rows_x);
    g_free(sp);
}

/* The image row next to r on the given side, r itself at the frame's edge. */
static const gdouble*
image_row_clamped(const StripeSubpixel *sp, gint r)
{
    return sp->image + (gsize)CLAMP(r, 0, sp->yres - 1)*sp->xres;
}

static void
add_row_normal(gdouble *normal, const gdouble *u, gdouble w)
{
    gint a, b, k = 0;

    for (a = 0; a < PARAMS; a++) {
        for (b = a; b < PARAMS; b++)
            normal[k++] += w*u[a]*u[b];
    }
}

/* The weighted stripe, its weighted gradients, and each row's normal-matrix
 * terms for the regressors (stripe, 1, d/dy, d/dx). */
static void
prepare_stripe(StripeSubpixel *sp, const StripeSpan *span)
{
    gint xres = sp->xres, i, c, r;

    for (i = 0; i < span->height; i++) {
        const gdouble *row, *above, *below;
        gdouble *normal = sp->row_normal + (gsize)i*NORMAL_TERMS;
        gdouble u[PARAMS], dist;
        gsize k;

        r = span->first + i;
        row = sp->image + (gsize)r*xres;
        above = image_row_clamped(sp, r - 1);
        below = image_row_clamped(sp, r + 1);
        dist = (gdouble)(MIN(r + 1, sp->yres - 1) - MAX(r - 1, 0));
        memset(normal, 0, NORMAL_TERMS*sizeof(gdouble));
        for (c = span->col_lo; c < span->col_hi; c++) {
            gdouble w = sp->window[c];

            u[0] = row[c];
            u[1] = 1.0;
            u[2] = (below[c] - above[c])/dist;
            u[3] = 0.5*(row[c+1] - row[c-1]);
            k = (gsize)i*xres + c;
            sp->weighted_value[k] = w*u[0];
            sp->weighted_grad_y[k] = w*u[2];
            sp->weighted_grad_x[k] = w*u[3];
            add_row_normal(normal, u, w);
        }
    }
}

/* Solves the symmetric system given by its upper triangle (Gaussian
 * elimination with partial pivoting); FALSE when it is singular. */
static gboolean
solve_normal(const gdouble *upper, const gdouble *rhs, gdouble *x)
{
    gdouble a[PARAMS][PARAMS + 1], f, scale = 0.0;
    gint i, j, p, k = 0;

    for (i = 0; i < PARAMS; i++) {
        for (j = i; j < PARAMS; j++) {
            a[i][j] = a[j][i] = upper[k++];
            scale = MAX(scale, fabs(a[i][j]));
        }
        a[i][PARAMS] = rhs[i];
    }
    for (i = 0; i < PARAMS; i++) {
        p = i;
        for (j = i + 1; j < PARAMS; j++) {
            if (fabs(a[j][i]) > fabs(a[p][i]))
                p = j;
        }
        if (!(fabs(a[p][i]) > 1e-12*scale))
            return FALSE;
        for (j = 0; j <= PARAMS; j++) {
            f = a[i][j];
            a[i][j] = a[p][j];
            a[p][j] = f;
        }
        for (j = i + 1; j < PARAMS; j++) {
            f = a[j][i]/a[i][i];
            for (k = i; k <= PARAMS; k++)
                a[j][k] -= f*a[i][k];
        }
    }
    for (i = PARAMS - 1; i >= 0; i--) {
        f = a[i][PARAMS];
        for (j = i + 1; j < PARAMS; j++)
            f -= a[i][j]*x[j];
        x[i] = f/a[i][i];
    }
    return TRUE;
}

/* Reference rows ref_first .. ref_first + count - 1 interpolated along x at
 * columns c + kx + fx, for the matched columns. */
static void
interpolate_rows_x(StripeSubpixel *sp, const StripeSpan *span, gint ref_first, gint count, gint kx,
                   const gdouble *wx)
{
    gint xres = sp->xres, k, c;

    for (k = 0; k < count; k++) {
        const gdouble *src = sp->reference + (gsize)(ref_first + k)*xres + kx;
        gdouble *dest = sp->rows_x + (gsize)k*xres;

        for (c = span->col_lo; c < span->col_hi; c++)
            dest[c] = wx[0]*src[c-1] + wx[1]*src[c] + wx[2]*src[c+1] + wx[3]*src[c+2];
    }
}

/* One Gauss-Newton step from the shift (dy, dx): the reference sampled at
 * (r - dy, c - dx) regressed on the stripe and its gradients.  FALSE when
 * too few rows meet the reference or the fit has no positive gain. */
static gboolean
match_step(StripeSubpixel *sp, const StripeSpan *span, gdouble dy, gdouble dx,
           gdouble *step_y, gdouble *step_x)
{
    gint xres = sp->xres, ky = (gint)floor(-dy), kx = (gint)floor(-dx);
    gdouble wy[KERNEL_TAPS], wx[KERNEL_TAPS], normal[NORMAL_TERMS], rhs[PARAMS], p[PARAMS];
    gint ilo, ihi, i, c, t;

    keys_weights(-dy - ky, 1.0 - (-dy - ky), wy);
    keys_weights(-dx - kx, 1.0 - (-dx - kx), wx);
    /* Row i samples reference rows first + i + ky - 1 .. first + i + ky + 2. */
    ilo = MAX(0, 1 - span->first - ky);
    ihi = MIN(span->height, sp->yres - 2 - span->first - ky);
    if (ihi - ilo < MAX(2, (gint)ceil(MIN_ROWS_FRACTION*span->height)))
        return FALSE;
    interpolate_rows_x(sp, span, span->first + ilo + ky - 1, ihi - ilo + 3, kx, wx);

    memset(normal, 0, sizeof(normal));
    memset(rhs, 0, sizeof(rhs));
    for (i = ilo; i < ihi; i++) {
        const gdouble *r0 = sp->rows_x + (gsize)(i - ilo)*xres;
        const gdouble *r1 = r0 + xres, *r2 = r1 + xres, *r3 = r2 + xres;
        const gdouble *wv = sp->weighted_value + (gsize)i*xres;
        const gdouble *wgy = sp->weighted_grad_y + (gsize)i*xres;
        const gdouble *wgx = sp->weighted_grad_x + (gsize)i*xres;
        gdouble s0 = 0.0, s1 = 0.0, s2 = 0.0, s3 = 0.0, v;

        for (c = span->col_lo; c < span->col_hi; c++) {
            v = wy[0]*r0[c] + wy[1]*r1[c] + wy[2]*r2[c] + wy[3]*r3[c];
            s0 += wv[c]*v;
            s1 += sp->window[c]*v;
            s2 += wgy[c]*v;
            s3 += wgx[c]*v;
        }
        rhs[0] += s0;
        rhs[1] += s1;
        rhs[2] += s2;
        rhs[3] += s3;
        for (t = 0; t < NORMAL_TERMS; t++)
            normal[t] += sp->row_normal[(gsize)i*NORMAL_TERMS + t];
    }
    if (!solve_normal(normal, rhs, p) || !(p[0] > 0.0))
        return FALSE;
    *step_y = p[2]/p[0];
    *step_x = p[3]/p[0];
    return TRUE;
}

gboolean
stripe_subpixel_refine(StripeSubpixel *sp, gint first, gint end, gint anchor_dy, gint anchor_dx, gint reach,
                       gdouble *dy, gdouble *dx)
{
    StripeSpan span;
    gdouble y = *dy, x = *dx, step_y, step_x;
    gint iter;

    g_return_val_if_fail(sp && first >= 0 && end <= sp->yres, FALSE);
    g_return_val_if_fail(end - first >= 1 && end - first <= sp->max_height, FALSE);
    g_return_val_if_fail(reach >= 0, FALSE);
    span.first = first;
    span.height = end - first;
    /* Columns whose taps stay on the reference for every dx within reach of
     * the anchor, and whose x gradient is central. */
    span.col_lo = MAX(1, anchor_dx + reach + 1);
    span.col_hi = MIN(sp->xres - 1, sp->xres - 2 - reach + anchor_dx);
    if (span.col_hi - span.col_lo < MIN_COLUMNS)
        return FALSE;
    prepare_stripe(sp, &span);

    for (iter = 0; iter < MAX_ITERATIONS; iter++) {
        if (fabs(y - anchor_dy) > reach || fabs(x - anchor_dx) > reach)
            return FALSE;
        if (!match_step(sp, &span, y, x, &step_y, &step_x))
            return FALSE;
        y += step_y;
        x += step_x;
        if (fabs(step_y) < CONVERGED_STEP && fabs(step_x) < CONVERGED_STEP)
            break;
    }
    if (iter == MAX_ITERATIONS || fabs(y - anchor_dy) > reach || fabs(x - anchor_dx) > reach)
        return FALSE;
    *dy = y;
    *dx = x;
    return TRUE;
}
