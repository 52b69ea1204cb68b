/*
 *  Displacement measurements of a frame series by block registration
 *  (masked normalised cross-correlation through FFTW).
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <string.h>
#include <math.h>
#include <fftw3.h>
#include <libprocess/gwyprocess.h>
#include "displacement-measure.h"

/* Correlation workspace for one image/reference pair: padded to twice the
 * frame so that no shift wraps around. */
typedef struct {
    gint xres, yres, px, py, nc;
    gdouble *real;
    fftw_complex *ref, *ref2, *refmask;      /* spectra of the reference */
    fftw_complex *blk, *blk2, *blkmask, *prod;
    gdouble *num, *den_b, *den_r, *overlap;
    fftw_plan forward, backward;
    const gdouble *image;
} Correlator;

void
displacement_options_init(DisplacementOptions *options)
{
    options->n_blocks = 16;
    options->max_shift = 0.25;
    options->block_range = 0.08;
    options->min_score = 0.3;
    options->all_pairs = TRUE;
    options->smooth = 0.01;
}

/* Separable Gaussian blur of one axis (stride 1: rows, stride xres:
 * columns), mirrored at the edges. */
static void
blur_axis(gdouble *data, gint len, gint count, gint step, gint stride,
          gdouble sigma)
{
    gint r = (gint)ceil(3.0*sigma), i, k, l;
    gdouble *kernel, *line, sum = 0.0;

    if (sigma < 0.3 || len < 2)
        return;
    r = MIN(r, len - 1);
    kernel = g_new(gdouble, 2*r + 1);
    line = g_new(gdouble, len);
    for (k = -r; k <= r; k++)
        sum += kernel[k + r] = exp(-0.5*k*k/(sigma*sigma));
    for (k = 0; k <= 2*r; k++)
        kernel[k] /= sum;
    for (l = 0; l < count; l++) {
        gdouble *base = data + l*stride;

        for (i = 0; i < len; i++)
            line[i] = base[i*step];
        for (i = 0; i < len; i++) {
            gdouble v = 0.0;
            for (k = -r; k <= r; k++) {
                gint j = i + k;
                j = (j < 0) ? -j : (j >= len ? 2*len - 2 - j : j);
                v += kernel[k + r]*line[j];
            }
            base[i*step] = v;
        }
    }
    g_free(kernel);
    g_free(line);
}

/* Line levelling: AFM rows carry independent offsets that would otherwise
 * dominate the correlation; then a blur of the same physical size along
 * both axes (pixels need not be square), which keeps a periodic background
 * finer than the blur from pinning blocks to the wrong period; unit RMS. */
static gdouble*
level_lines(const gdouble *data, gint xres, gint yres,
            gdouble sigma_x, gdouble sigma_y)
{
    gdouble *out = g_new(gdouble, xres*yres), *row = g_new(gdouble, xres);
    gdouble sum2 = 0.0, med;
    gint i, j;

    for (i = 0; i < yres; i++) {
        memcpy(row, data + i*xres, xres*sizeof(gdouble));
        med = gwy_math_median(xres, row);
        for (j = 0; j < xres; j++) {
            out[i*xres + j] = data[i*xres + j] - med;
            sum2 += out[i*xres + j]*out[i*xres + j];
        }
    }
    blur_axis(out, xres, yres, 1, xres, sigma_x);
    blur_axis(out, yres, xres, xres, 1, sigma_y);
    sum2 = 0.0;
    for (i = 0; i < xres*yres; i++)
        sum2 += out[i]*out[i];
    sum2 = sqrt(sum2/(xres*yres));
    for (i = 0; i < xres*yres; i++)
        out[i] /= (sum2 > 0.0) ? sum2 : 1.0;
    g_free(row);
    return out;
}

static void
forward_of(Correlator *c, const gdouble *src, gint r0, gint r1,
           gboolean squared, gboolean mask, fftw_complex *dest)
{
    gint i, j;

    memset(c->real, 0, c->px*c->py*sizeof(gdouble));
    for (i = r0; i < r1; i++) {
        for (j = 0; j < c->xres; j++) {
            gdouble v = src[i*c->xres + j];
            c->real[i*c->px + j] = mask ? 1.0 : (squared ? v*v : v);
        }
    }
    fftw_execute_dft_r2c(c->forward, c->real, dest);
}

/* dest = IFFT(a conj(b)), i.e. dest(s) = sum_y a(y) b(y - s). */
static void
correlate_spectra(Correlator *c, const fftw_complex *a, const fftw_complex *b,
                  gdouble *dest)
{
    gint k;

    for (k = 0; k < c->nc; k++) {
        c->prod[k][0] = a[k][0]*b[k][0] + a[k][1]*b[k][1];
        c->prod[k][1] = a[k][1]*b[k][0] - a[k][0]*b[k][1];
    }
    fftw_execute_dft_c2r(c->backward, c->prod, dest);
}

static void
correlator_init(Correlator *c, const gdouble *image, const gdouble *reference,
                gint xres, gint yres)
{
    c->xres = xres;
    c->yres = yres;
    c->px = gwy_fft_find_nice_size(2*xres);
    c->py = gwy_fft_find_nice_size(2*yres);
    c->nc = c->py*(c->px/2 + 1);
    c->real = fftw_malloc(c->px*c->py*sizeof(gdouble));
    c->ref = fftw_malloc(7*c->nc*sizeof(fftw_complex));
    c->ref2 = c->ref + c->nc;
    c->refmask = c->ref2 + c->nc;
    c->blk = c->refmask + c->nc;
    c->blk2 = c->blk + c->nc;
    c->blkmask = c->blk2 + c->nc;
    c->prod = c->blkmask + c->nc;
    c->num = g_new(gdouble, 4*c->px*c->py);
    c->den_b = c->num + c->px*c->py;
    c->den_r = c->den_b + c->px*c->py;
    c->overlap = c->den_r + c->px*c->py;
    c->forward = fftw_plan_dft_r2c_2d(c->py, c->px, c->real, c->ref,
                                      FFTW_ESTIMATE | FFTW_UNALIGNED);
    c->backward = fftw_plan_dft_c2r_2d(c->py, c->px, c->prod, c->num,
                                       FFTW_ESTIMATE | FFTW_UNALIGNED);
    c->image = image;
    forward_of(c, reference, 0, yres, FALSE, FALSE, c->ref);
    forward_of(c, reference, 0, yres, TRUE, FALSE, c->ref2);
    forward_of(c, reference, 0, yres, FALSE, TRUE, c->refmask);
}

static void
correlator_free(Correlator *c)
{
    fftw_destroy_plan(c->forward);
    fftw_destroy_plan(c->backward);
    fftw_free(c->real);
    fftw_free(c->ref);
    g_free(c->num);
}

/* Normalised correlation at shift (sy, sx); -2 where the overlap is too
 * small to be trusted. */
static gdouble
ncc_at(const Correlator *c, gint sy, gint sx, gdouble min_overlap)
{
    gint k = ((sy % c->py + c->py) % c->py)*c->px + (sx % c->px + c->px) % c->px;
    gdouble den = c->den_b[k]*c->den_r[k];

    if (c->overlap[k] < min_overlap || den <= 0.0)
        return -2.0;
    return c->num[k]/sqrt(den);
}

static gdouble
parabola_offset(gdouble left, gdouble centre, gdouble right)
{
    gdouble d = left - 2.0*centre + right;

    if (d >= 0.0 || left < -1.5 || right < -1.5)
        return 0.0;
    return CLAMP(0.5*(left - right)/d, -0.5, 0.5);
}

/* Registers rows [r0, r1) of the image, searching around (cx, cy). */
static void
register_block(Correlator *c, gint r0, gint r1, gdouble cx, gdouble cy,
               gint rx, gint ry, gdouble *dx, gdouble *dy, gdouble *score)
{
    gdouble best = -2.0, v, min_overlap = 0.5*(r1 - r0)*c->xres;
    gint sx, sy, bx = 0, by = 0, ix = (gint)floor(cx + 0.5),
         iy = (gint)floor(cy + 0.5);

    forward_of(c, c->image, r0, r1, FALSE, FALSE, c->blk);
    forward_of(c, c->image, r0, r1, TRUE, FALSE, c->blk2);
    forward_of(c, c->image, r0, r1, FALSE, TRUE, c->blkmask);
    correlate_spectra(c, c->blk, c->ref, c->num);
    correlate_spectra(c, c->blk2, c->refmask, c->den_b);
    correlate_spectra(c, c->blkmask, c->ref2, c->den_r);
    correlate_spectra(c, c->blkmask, c->refmask, c->overlap);
    /* c2r leaves every value scaled by the transform size; the ratio
     * num/sqrt(den_b den_r) is not, the overlap count is. */
    min_overlap *= (gdouble)c->px*c->py;
    for (sy = iy - ry; sy <= iy + ry; sy++) {
        for (sx = ix - rx; sx <= ix + rx; sx++) {
            if (abs(sy) >= c->yres || abs(sx) >= c->xres)
                continue;
            v = ncc_at(c, sy, sx, min_overlap);
            if (v > best) {
                best = v;
                bx = sx;
                by = sy;
            }
        }
    }
    if (best <= -2.0) {
        *dx = *dy = 0.0;
        *score = 0.0;
        return;
    }
    *dx = bx + parabola_offset(ncc_at(c, by, bx-1, min_overlap), best,
                               ncc_at(c, by, bx+1, min_overlap));
    *dy = by + parabola_offset(ncc_at(c, by-1, bx, min_overlap), best,
                               ncc_at(c, by+1, bx, min_overlap));
    *score = CLAMP(best, 0.0, 1.0);
}

void
displacement_register_blocks(const gdouble *image, const gdouble *reference,
                             gint xres, gint yres, gint n,
                             const DisplacementOptions *options,
                             gdouble pixel_aspect, const gdouble *guess,
                             gdouble *dx, gdouble *dy, gdouble *score,
                             gdouble *global)
{
    DisplacementOptions defaults;
    gdouble *a, *b, gx, gy, gscore, sigma_x, sigma_y;
    gint s, rg, rb, side = MIN(xres, yres);
    Correlator c;

    if (!options) {
        displacement_options_init(&defaults);
        options = &defaults;
    }
    /* The same physical blur along both axes: pixel_aspect = dy/dx. */
    sigma_x = options->smooth*MIN(xres, yres*pixel_aspect);
    sigma_y = sigma_x/pixel_aspect;
    a = level_lines(image, xres, yres, sigma_x, sigma_y);
    b = level_lines(reference, xres, yres, sigma_x, sigma_y);
    correlator_init(&c, a, b, xres, yres);
    rg = MAX((gint)(options->max_shift*side), 2);
    rb = MAX((gint)(options->block_range*side), 4);
    /* The frame's overall shift first, so that blocks (less content, more
     * prone to a wrong peak) search near it only. */
    if (guess)
        register_block(&c, 0, yres, guess[0], guess[1], rb, rb,
                       &gx, &gy, &gscore);
    else
        register_block(&c, 0, yres, 0.0, 0.0, rg, rg, &gx, &gy, &gscore);
    for (s = 0; s < n; s++) {
        gint r0 = s*yres/n, r1 = (s + 1)*yres/n;

        register_block(&c, r0, r1, gx, gy, rb, rb, dx + s, dy + s, score + s);
    }
    if (global) {
        global[0] = gx;
        global[1] = gy;
        global[2] = gscore;
    }
    correlator_free(&c);
    g_free(a);
    g_free(b);
}

/* Registers frame ka against frame kb and appends the block measurements;
 * global gets the frame's overall shift. */
static void
measure_pair(const FrameSeries *series, gint ka, gint kb,
             const DisplacementOptions *options, const gdouble *guess,
             gdouble *global, GArray *out)
{
    const SeriesFrame *fa = series->frames + ka, *fb = series->frames + kb;
    gdouble xstep = frame_series_dx(series), ystep = frame_series_dy(series);
    gint xres = fa->timing.xres, yres = fa->timing.yres, n = options->n_blocks;
    gdouble *dx = g_new(gdouble, n), *dy = g_new(gdouble, n),
            *score = g_new(gdouble, n);
    gint s;

    displacement_register_blocks(gwy_data_field_get_data_const(fa->field),
                                 gwy_data_field_get_data_const(fb->field),
                                 xres, yres, n, options, ystep/xstep, guess,
                                 dx, dy, score, global);
    for (s = 0; s < n; s++) {
        gint r0 = s*yres/n, r1 = (s + 1)*yres/n;
        gdouble crow = 0.5*(r0 + r1 - 1), ccol = 0.5*(xres - 1);
        DriftMeasurement m;

        /* The block's content was scanned in the reference dy rows
         * earlier (higher up), dx columns to the left. */
        m.t_a = scan_timing_rows_time(&fa->timing, r0, r1);
        m.t_b = scan_timing_pixel_time(&fb->timing, crow - dy[s],
                                       ccol - dx[s]);
        m.dx = dx[s]*xstep;
        m.dy = dy[s]*ystep;
        m.weight = (score[s] >= options->min_score) ? score[s] : 0.0;
        m.group = s;
        m.frame_a = ka;
        m.frame_b = kb;
        g_array_append_val(out, m);
    }
    g_free(dx);
    g_free(dy);
    g_free(score);
}

DriftMeasurement*
displacement_measure_series(const FrameSeries *series,
                            const DisplacementOptions *options, gint *n)
{
    DisplacementOptions defaults;
    GArray *out = g_array_new(FALSE, FALSE, sizeof(DriftMeasurement));
    gint nf = series->n_frames, k, j;
    gdouble *step = g_new0(gdouble, 3*nf), guess[2], global[3];

    if (!options) {
        displacement_options_init(&defaults);
        options = &defaults;
    }
    /* Consecutive frames first: their overall shifts, chained, tell where
     * to look when a frame is registered against an older one, whose shift
     * may exceed any blind search range. */
    for (k = 1; k < nf; k++)
        measure_pair(series, k, k-1, options, NULL, step + 3*k, out);
    for (k = 2; k < nf && options->all_pairs; k++) {
        for (j = k-2; j >= 0; j--) {
            guess[0] = guess[1] = 0.0;
            if (j == k-2) {
                guess[0] = step[3*k] + step[3*(k-1)];
                guess[1] = step[3*k + 1] + step[3*(k-1) + 1];
            }
            else {
                guess[0] = global[0] + step[3*(j+1)];
                guess[1] = global[1] + step[3*(j+1) + 1];
            }
            measure_pair(series, k, j, options, guess, global, out);
        }
    }
    g_free(step);
    *n = out->len;
    return (DriftMeasurement*)g_array_free(out, FALSE);
}
