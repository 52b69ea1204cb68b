/*
 *  Conditioning of raw instrument channels before registration.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <math.h>
#include <string.h>
#include <libgwyddion/gwymacros.h>
#include <libgwyddion/gwymath.h>
#include "coprime-step.h"
#include "frame-conditioning.h"
#include "median.h"

/*
 * Why each step (docs/registration.md has the whole story).
 *
 * Raw AFM channels carry, on top of the sample: a plane and a bow from the
 * scanner, an offset on every scan line (the feedback's set point wanders
 * between lines), and 1/f noise that makes the low spatial frequencies
 * wander from frame to frame.  Correlation of two raw frames is dominated
 * by these, which differ between the frames, so the sample's features are
 * buried.  The steps remove them in order of size:
 *
 * 1. Line offsets by the median of the differences between adjacent lines:
 *    robust to features that cross lines (their differences are few), and
 *    it removes the plane's slope along y with the offsets.  Its small
 *    errors add up along y into a slow wander, which step 3 removes.
 * 2. The median of every pixel and its neighbours above and below: a
 *    glitch of the feedback (a stroke, a scar) lasts a stretch of one scan
 *    line and differs between the frames, while features of the sample
 *    span several lines.  Left in, strokes decide the fine match.
 * 3. A band-pass, the difference of two Gaussian blurs: the wide one (a
 *    twentieth of the smaller side, the same physical size along both
 *    axes) takes the plane's slope along x, the scanner's bow, what is
 *    left of the slow wander and the 1/f noise, the
 *    narrow one (a pixel of each axis) takes pixel noise, which would
 *    otherwise dilute the gradients the sub-pixel match steps along.  Both frames get the same filter, which moves no
 *    feature, so the shift between them is unchanged.
 * 4. Each line's median once more: the band-pass leaves a little of the
 *    line offsets that the narrow blur spread over neighbouring lines.
 * 5. Values beyond CLIP_SIGMAS robust standard deviations are clipped: a
 *    spike left over must not outweigh the rest of a stripe.
 *
 * Nothing is fitted to a frame's content and subtracted in its own
 * coordinates (a polynomial bow, say): such a function moves with the
 * content when the frame is shifted, so the two frames would be levelled
 * differently by exactly the shift being measured (on an exactly shifted
 * frame, a cubic bow fitted to the column medians cost 0.05 px; without it
 * the error is 0.008 px).  Line offsets are the exception the sub-pixel
 * match absorbs: it fits an offset per line itself.
 *
 * Missing pixels take part in none of the estimates: medians and fits skip
 * them, and the blurs are normalised convolutions (blur of value times
 * weight over blur of weight).  Those among data (scattered ones) leave
 * with the band-pass's estimate and the narrow blur's coverage for weight
 * (restore_scattered_missing), the others (holes) with value 0 and weight
 * 0.  Every sample the matches interpolate reaches 16 pixels and every
 * gradient 5: had each missing pixel kept weight 0, 20 % of the pixels
 * missing at random would have left 3 % of the reference's samples, and
 * up to 4 of a pair's 16 stripes had no sub-pixel match (79 of 96 given
 * over six pairs, those given 0.24 px rms from the clean pairs' shifts).
 */

/* The wide blur's sigma as a fraction of the smaller physical side. */
#define BAND_WIDE_FRACTION (1.0/20.0)
/* The narrow blur's sigma in pixels of each axis (it is against pixel
 * noise, which is noise per pixel whatever the pixel's size): at least
 * this, more where noise outweighs the features (see noise_scale). */
#define BAND_NARROW_PX 1.0
/* The narrow blur stays below this fraction of the wide one. */
#define NARROW_MAX_FRACTION 0.25
/* Blurs wider than this (px) run as three box passes (exact enough for a
 * low-frequency cut, and O(1) per pixel); narrower ones with a Gaussian
 * kernel. */
#define BOX_FROM_SIGMA 2.5
/* Below this blurred weight a pixel has no valid neighbour in reach. */
#define MIN_BLURRED_WEIGHT 1e-6
/* A missing pixel where at least this share of the narrow blur's weight
 * falls on valid pixels lies among data: the blur's estimate takes its
 * place.  Inside a straight edge of a hole the share is under a half (0.30
 * for a blur of a pixel), so a hole keeps its size but for the pixels at
 * its convex corners (0.51 at the corner pixel), where data lie on three
 * sides.  A scattered missing pixel has 0.84 with every neighbour valid,
 * 0.67 on average with a fifth of them missing. */
#define RESTORE_MIN_COVERAGE 0.5
/* Clip at this many robust standard deviations (1.4826 MAD). */
#define CLIP_SIGMAS 4.0
/* The clip needs the spread of the values, not its last digit: the median
 * of |v| over a sample of about this many pixels at most (a full-frame
 * median was a fifth of the band-pass on 4096 x 4096). */
#define CLIP_SAMPLE 65536
/* The plane along x and the bow: a quadratic, fitted to column medians
 * over about this many lines. */
#define COLUMN_TREND_DEGREE 2
#define COLUMN_TREND_LINES 256
/* A line's offset is the median of at most about this many of its pixels
 * (evenly spaced): far more than an offset needs, and the medians of
 * every line were a third of conditioning a 4096 x 4096 frame. */
#define LINE_MEDIAN_SAMPLES 2048

static void
mark_valid(ConditionedFrame *frame, const gdouble *data, const gdouble *exclude)
{
    gsize k, n = (gsize)frame->xres*frame->yres, valid = 0;

    for (k = 0; k < n; k++) {
        gboolean ok = isfinite(data[k]) && !(exclude && exclude[k] > 0.5);

        frame->weight[k] = ok ? 1.0 : 0.0;
        frame->data[k] = ok ? data[k] : 0.0;
        valid += ok;
    }
    frame->valid_fraction = (gdouble)valid/n;
}

/* Median of the valid values among count taken with stride; buf holds
 * count values.  FALSE when none is valid. */
static gboolean
valid_median(const gdouble *values, const gdouble *weight, gint count, gint stride,
             gdouble *buf, gdouble *median)
{
    gint k, m = 0;

    for (k = 0; k < count; k++) {
        if (weight[(gsize)k*stride] > 0.0)
            buf[m++] = values[(gsize)k*stride];
    }
    if (!m)
        return FALSE;
    *median = median_in_place(buf, m);
    return TRUE;
}

/* The step between the pixels of a line of xres that its median takes. */
static gint
line_median_step(gint xres)
{
    return MAX(1, xres/LINE_MEDIAN_SAMPLES);
}

static void
align_lines_by_median_differences(ConditionedFrame *frame)
{
    gint xres = frame->xres, yres = frame->yres, step = line_median_step(xres), r, c, m;
    gdouble *buf = g_new(gdouble, xres), offset = 0.0, *row, *prev;
    const gdouble *w, *pw;

    for (r = 1; r < yres; r++) {
        row = frame->data + (gsize)r*xres;
        prev = row - xres;
        w = frame->weight + (gsize)r*xres;
        pw = w - xres;
        m = 0;
        for (c = 0; c < xres; c += step) {
            if (w[c] > 0.0 && pw[c] > 0.0)
                buf[m++] = row[c] - prev[c];
        }
        /* A line with nothing in common with the one above keeps its own
         * level; step 3 takes care of what that leaves. */
        offset = m ? median_in_place(buf, m) : 0.0;
        for (c = 0; c < xres; c++)
            row[c] -= offset;
    }
    g_free(buf);
}

/* A raw channel's plane along x and the scanner's bow: a polynomial in x
 * fitted to the column medians of the aligned lines, taken from every line.
 * What this fit takes from the content, and what it leaves of the frame's
 * own trend, differs between two frames by a slow function of x, which the
 * sub-pixel match fits beside the shift (stripe-subpixel.c); here it keeps
 * a strong plane from ruling the correlation maps (over a stripe's window
 * their mean removal does not take a plane) and the filters' edges (with
 * the frames' own planes, 15 % of the stripes of synthetic raw pairs were
 * found at size 1, 2 % at size 3; without them all). */
static gdouble
column_coordinate(gint c, gint xres)
{
    return (xres > 1) ? 2.0*c/(xres - 1) - 1.0 : 0.0;
}

static gdouble
polynomial_value(const gdouble *coeffs, gint degree, gdouble u)
{
    gdouble value = coeffs[degree];
    gint k;

    for (k = degree - 1; k >= 0; k--)
        value = value*u + coeffs[k];
    return value;
}

/* Whether the fitted trend stands out of the column medians' scatter
 * about it: a frame without a plane or bow (a synthetic one, or one
 * levelled already) has column medians that a quadratic follows only by
 * chance, and taking that chance curve from every line paints a bow into
 * its featureless regions, which then correlate (a flat stripe scored
 * 0.11 instead of 0.05). */
static gboolean
column_trend_stands_out(const gdouble *xs, const gdouble *meds, gint m, const gdouble *coeffs)
{
    gdouble mean = 0.0, trend2 = 0.0, resid2 = 0.0, f;
    gint j;

    for (j = 0; j < m; j++)
        mean += polynomial_value(coeffs, COLUMN_TREND_DEGREE, xs[j])/m;
    for (j = 0; j < m; j++) {
        f = polynomial_value(coeffs, COLUMN_TREND_DEGREE, xs[j]);
        trend2 += (f - mean)*(f - mean);
        resid2 += (meds[j] - f)*(meds[j] - f);
    }
    return trend2 > resid2;
}

static void
remove_column_trend(ConditionedFrame *frame)
{
    gint xres = frame->xres, yres = frame->yres, r, c, m = 0;
    /* A few hundred lines give each column's median to far better than a
     * quadratic needs; all of a large frame's cost a gather per pixel. */
    gint step = MAX(1, yres/COLUMN_TREND_LINES), lines = (yres + step - 1)/step;
    gdouble *buf = g_new(gdouble, lines), *xs = g_new(gdouble, xres), *meds = g_new(gdouble, xres);
    gdouble coeffs[COLUMN_TREND_DEGREE + 1], trend;

    for (c = 0; c < xres; c++) {
        if (valid_median(frame->data + c, frame->weight + c, lines, step*xres, buf, meds + m))
            xs[m++] = column_coordinate(c, xres);
    }
    if (m > 2*(COLUMN_TREND_DEGREE + 1)) {
        gwy_math_fit_polynom(m, xs, meds, COLUMN_TREND_DEGREE, coeffs);
        if (column_trend_stands_out(xs, meds, m, coeffs)) {
            for (c = 0; c < xres; c++) {
                trend = polynomial_value(coeffs, COLUMN_TREND_DEGREE, column_coordinate(c, xres));
                for (r = 0; r < yres; r++)
                    frame->data[(gsize)r*xres + c] -= trend;
            }
        }
    }
    g_free(meds);
    g_free(xs);
    g_free(buf);
}

/* Three box passes of this half-width have the variance of a Gaussian of
 * sigma. */
static gint
box_half_width(gdouble sigma)
{
    return MAX(1, (gint)floor(0.5*(sqrt(4.0*sigma*sigma + 1.0) - 1.0) + 0.5));
}

/* Box sum of half-width h along a line of len values with stride, zero
 * outside; tmp holds len + 1 values. */
static void
box_line(gdouble *line, gint len, gint stride, gint h, gdouble *tmp)
{
    gint i;

    tmp[0] = 0.0;
    for (i = 0; i < len; i++)
        tmp[i+1] = tmp[i] + line[(gsize)i*stride];
    for (i = 0; i < len; i++)
        line[(gsize)i*stride] = tmp[MIN(len, i + h + 1)] - tmp[MAX(0, i - h)];
}

static gdouble*
gaussian_kernel(gdouble sigma, gint *half)
{
    gint h = MAX(1, (gint)ceil(3.0*sigma)), k;
    gdouble *kernel = g_new(gdouble, 2*h + 1);

    for (k = -h; k <= h; k++)
        kernel[k + h] = exp(-0.5*k*k/(sigma*sigma));
    *half = h;
    return kernel;
}

/* Gaussian-kernel sum along a line (stride), zero outside; tmp holds len. */
static void
kernel_line(gdouble *line, gint len, gint stride, const gdouble *kernel, gint h, gdouble *tmp)
{
    gint i, k;

    for (i = 0; i < len; i++)
        tmp[i] = line[(gsize)i*stride];
    for (i = 0; i < len; i++) {
        gdouble s = 0.0;

        for (k = MAX(-h, -i); k <= MIN(h, len - 1 - i); k++)
            s += kernel[k + h]*tmp[i + k];
        line[(gsize)i*stride] = s;
    }
}

/* Whether a blur of sigma (px) along lines of len values changes them. */
static gboolean
blur_reaches(gdouble sigma, gint len)
{
    return sigma >= 0.2 && len >= 2;
}

/* Unnormalised blur (zero outside) of one axis: lines of len values with
 * stride, count of them, first values step apart. */
static void
blur_axis(gdouble *data, gint len, gint count, gint stride, gint step, gdouble sigma)
{
    gdouble *tmp, *kernel = NULL;
    gint l, pass, h = 0;

    if (!blur_reaches(sigma, len))
        return;
    tmp = g_new(gdouble, len + 1);
    if (sigma >= BOX_FROM_SIGMA)
        h = box_half_width(sigma);
    else
        kernel = gaussian_kernel(sigma, &h);
    for (l = 0; l < count; l++) {
        gdouble *line = data + (gsize)l*step;

        if (kernel)
            kernel_line(line, len, stride, kernel, h, tmp);
        else {
            for (pass = 0; pass < 3; pass++)
                box_line(line, len, stride, h, tmp);
        }
    }
    g_free(kernel);
    g_free(tmp);
}

/* Box sums of half-width h down the columns, zero outside, in place: a
 * window sliding down whole rows, so that every step is a pass along
 * memory (column by column, each value was a cache miss on large frames).
 * The rows that leave the window are kept in ring (h + 1 rows) from before
 * they were overwritten. */
static void
box_columns(gdouble *data, gint xres, gint yres, gint h, gdouble *acc, gdouble *ring)
{
    gsize line = xres*sizeof(gdouble);
    gint r, c;

    memset(acc, 0, line);
    for (r = 0; r <= MIN(h, yres - 1); r++) {
        const gdouble *row = data + (gsize)r*xres;

        for (c = 0; c < xres; c++)
            acc[c] += row[c];
    }
    for (r = 0; r < yres; r++) {
        gdouble *row = data + (gsize)r*xres;

        memcpy(ring + (gsize)(r % (h + 1))*xres, row, line);
        memcpy(row, acc, line);
        if (r + h + 1 < yres) {
            const gdouble *entering = data + (gsize)(r + h + 1)*xres;

            for (c = 0; c < xres; c++)
                acc[c] += entering[c];
        }
        if (r - h >= 0) {
            const gdouble *leaving = ring + (gsize)((r - h) % (h + 1))*xres;

            for (c = 0; c < xres; c++)
                acc[c] -= leaving[c];
        }
    }
}

/* Gaussian-kernel sums down the columns, zero outside, in place, row by
 * row; ring keeps the h + 1 rows up to the current one from before they
 * were overwritten, out holds a row. */
static void
kernel_columns(gdouble *data, gint xres, gint yres, const gdouble *kernel, gint h, gdouble *ring,
               gdouble *out)
{
    gsize line = xres*sizeof(gdouble);
    gint r, k, c;

    for (r = 0; r < yres; r++) {
        gdouble *row = data + (gsize)r*xres;

        memcpy(ring + (gsize)(r % (h + 1))*xres, row, line);
        memset(out, 0, line);
        for (k = MAX(-h, -r); k <= MIN(h, yres - 1 - r); k++) {
            const gdouble *in = (k <= 0) ? ring + (gsize)((r + k) % (h + 1))*xres : row + (gsize)k*xres;
            gdouble w = kernel[k + h];

            for (c = 0; c < xres; c++)
                out[c] += w*in[c];
        }
        memcpy(row, out, line);
    }
}

/* The blur along y of blur_axis(), done down the columns. */
static void
blur_columns(gdouble *data, gint xres, gint yres, gdouble sigma)
{
    gdouble *kernel, *ring, *row;
    gint h, pass;

    if (!blur_reaches(sigma, yres))
        return;
    row = g_new(gdouble, xres);
    if (sigma >= BOX_FROM_SIGMA) {
        h = box_half_width(sigma);
        ring = g_new(gdouble, (gsize)(h + 1)*xres);
        for (pass = 0; pass < 3; pass++)
            box_columns(data, xres, yres, h, row, ring);
    }
    else {
        kernel = gaussian_kernel(sigma, &h);
        ring = g_new(gdouble, (gsize)(h + 1)*xres);
        kernel_columns(data, xres, yres, kernel, h, ring, row);
        g_free(kernel);
    }
    g_free(ring);
    g_free(row);
}

static void
blur(gdouble *data, gint xres, gint yres, gdouble sigma_x, gdouble sigma_y)
{
    blur_axis(data, xres, yres, 1, xres, sigma_x);
    blur_columns(data, xres, yres, sigma_y);
}

/* The blur of a frame of ones is the product of the blurs of a row and of
 * a column of ones (the blur is separable): where every pixel is valid,
 * the normalisation costs two lines instead of a second blurred frame. */
static void
divide_by_blurred_ones(gdouble *values, gint xres, gint yres, gdouble sigma_x, gdouble sigma_y)
{
    gdouble *wx = g_new(gdouble, xres), *wy = g_new(gdouble, yres);
    gint r, c;

    for (c = 0; c < xres; c++)
        wx[c] = 1.0;
    for (r = 0; r < yres; r++)
        wy[r] = 1.0;
    blur_axis(wx, xres, 1, 1, xres, sigma_x);
    blur_axis(wy, yres, 1, 1, yres, sigma_y);
    for (r = 0; r < yres; r++) {
        gdouble *row = values + (gsize)r*xres;

        for (c = 0; c < xres; c++)
            row[c] /= wx[c]*wy[r];
    }
    g_free(wx);
    g_free(wy);
}

/* The normalised blur of the valid values, in values (data times weight
 * on entry): where no valid pixel is within reach, 0.  all_valid: every
 * weight is 1 (the frame's valid_fraction says so).  Returns the blur's
 * coverage (freed by the caller): at each pixel the share of the weight a
 * whole neighbourhood would have had that valid pixels gave; NULL when
 * every pixel is valid (all 1). */
static gdouble*
normalised_blur(gdouble *values, const gdouble *weight, gboolean all_valid, gint xres, gint yres,
                gdouble sigma_x, gdouble sigma_y)
{
    gsize k, n = (gsize)xres*yres;
    gdouble *weights;

    blur(values, xres, yres, sigma_x, sigma_y);
    if (all_valid) {
        divide_by_blurred_ones(values, xres, yres, sigma_x, sigma_y);
        return NULL;
    }
    weights = g_memdup2(weight, n*sizeof(gdouble));
    blur(weights, xres, yres, sigma_x, sigma_y);
    for (k = 0; k < n; k++)
        values[k] = (weights[k] > MIN_BLURRED_WEIGHT) ? values[k]/weights[k] : 0.0;
    divide_by_blurred_ones(weights, xres, yres, sigma_x, sigma_y);
    return weights;
}

/* The wide blur's sigma along x (px; along y it is this over the aspect). */
static gdouble
wide_sigma(const ConditionedFrame *frame, gdouble pixel_aspect)
{
    return BAND_WIDE_FRACTION*MIN(frame->xres, frame->yres*pixel_aspect);
}

/* Mean squared difference of valid pixels lag apart along the lines. */
static gdouble
structure_function(const ConditionedFrame *frame, gint lag)
{
    gint xres = frame->xres, r, c;
    gdouble s = 0.0, count = 0.0, d;

    for (r = 0; r < frame->yres; r++) {
        const gdouble *row = frame->data + (gsize)r*xres, *w = frame->weight + (gsize)r*xres;

        for (c = 0; c + lag < xres; c++) {
            if (w[c] > 0.0 && w[c + lag] > 0.0) {
                d = row[c + lag] - row[c];
                s += d*d;
                count += 1.0;
            }
        }
    }
    return count > 0.0 ? s/count : 0.0;
}

gdouble
conditioned_frame_noise_scale(const ConditionedFrame *frame, gdouble pixel_aspect)
{
    gdouble wide, d1, d2, dl, noise, signal, sigma;

    g_return_val_if_fail(frame, BAND_NARROW_PX);
    if (!(pixel_aspect > 0.0) || !isfinite(pixel_aspect))
        pixel_aspect = 1.0;
    wide = wide_sigma(frame, pixel_aspect);
    /* Along a line, white pixel noise of variance N adds 2N to every
     * squared difference, while a signal smooth at the pixel scale adds
     * four times as much at lag 2 as at lag 1; a lag of half the wide blur
     * sees the features' whole variance S (twice). */
    d1 = structure_function(frame, 1);
    d2 = structure_function(frame, 2);
    dl = structure_function(frame, MAX(3, (gint)(0.5*wide)));
    noise = MAX(0.0, (4.0*d1 - d2)/6.0);
    signal = 0.5*dl - noise;
    /* Blurring by sigma in 2D divides white noise's variance by 4 pi
     * sigma^2: enough for it to fall to the features' variance. */
    sigma = (signal > 0.0) ? sqrt(noise/(4.0*G_PI*signal)) : G_MAXDOUBLE;
    return CLAMP(sigma, BAND_NARROW_PX, MAX(BAND_NARROW_PX, NARROW_MAX_FRACTION*wide));
}

/* Lines the robust pixel noise is estimated on: every NOISE_LINE_STEP-th,
 * plenty for a median and a fraction of the cost of all. */
#define NOISE_LINE_STEP 4

gdouble
conditioned_frame_pixel_noise(const ConditionedFrame *frame)
{
    gint xres = frame->xres, yres = frame->yres, r, c, m = 0;
    gdouble *d = g_new(gdouble, MAX((gsize)(xres - 1)*(yres/NOISE_LINE_STEP + 1), 1)), med;
    gsize k;

    for (r = 0; r < yres; r += NOISE_LINE_STEP) {
        for (c = 0; c + 1 < xres; c++) {
            k = (gsize)r*xres + c;
            if (frame->weight[k] >= 1.0 && frame->weight[k+1] >= 1.0)
                d[m++] = fabs(frame->data[k+1] - frame->data[k]);
        }
    }
    med = m ? median_in_place(d, m) : 0.0;
    g_free(d);
    /* The median |d| of white noise of variance v is 0.6745 sqrt(2 v). */
    return 0.5*(med/0.6745)*(med/0.6745);
}

gdouble*
conditioned_frame_line_variances(const ConditionedFrame *frame)
{
    gint xres = frame->xres, yres = frame->yres, r, c, m;
    gdouble *variance = g_new(gdouble, yres), sum, sum2;

    for (r = 0; r < yres; r++) {
        const gdouble *row = frame->data + (gsize)r*xres, *w = frame->weight + (gsize)r*xres;

        sum = sum2 = 0.0;
        for (c = m = 0; c < xres; c++) {
            if (w[c] >= 1.0) {
                sum += row[c];
                sum2 += row[c]*row[c];
                m++;
            }
        }
        variance[r] = (m >= 8) ? MAX(sum2/m - (sum/m)*(sum/m), 0.0) : NAN;
    }
    return variance;
}

/* A missing pixel among data: the narrow blur there is an estimate as
 * good as its neighbours' (the pixel's own value is a sixth of a
 * pixel-wide blur), which the matches take with the blur's coverage for
 * weight; a scattered missing pixel thus lowers the weight of what it
 * covers and no more.  Anything else missing (a hole, a missing band of
 * lines) stays missing, with weight 0. */
static void
restore_scattered_missing(ConditionedFrame *frame, const gdouble *coverage)
{
    gsize k, n = (gsize)frame->xres*frame->yres;

    for (k = 0; k < n; k++) {
        if (!(frame->weight[k] > 0.0) && coverage[k] >= RESTORE_MIN_COVERAGE)
            frame->weight[k] = MIN(coverage[k], 1.0);
    }
}

/* The narrow blur becomes the levelled frame, the narrow minus the wide
 * the band-passed one; the wide blur runs in the frame's own data, so
 * that a large frame costs one more copy of itself, not three. */
static void
band_pass(ConditionedFrame *frame, gdouble pixel_aspect, gdouble narrow)
{
    gsize k, n = (gsize)frame->xres*frame->yres;
    gdouble wide = wide_sigma(frame, pixel_aspect);
    gdouble *fine = g_new(gdouble, n), *coarse = frame->data, *coverage;
    gboolean all_valid = (frame->valid_fraction >= 1.0);

    for (k = 0; k < n; k++)
        coarse[k] *= frame->weight[k];
    memcpy(fine, coarse, n*sizeof(gdouble));
    coverage = normalised_blur(fine, frame->weight, all_valid, frame->xres, frame->yres, narrow, narrow);
    g_free(normalised_blur(coarse, frame->weight, all_valid, frame->xres, frame->yres, wide,
                           wide/pixel_aspect));
    if (coverage)
        restore_scattered_missing(frame, coverage);
    g_free(coverage);
    for (k = 0; k < n; k++) {
        gboolean kept = (frame->weight[k] > 0.0);

        frame->data[k] = kept ? fine[k] - coarse[k] : 0.0;
        fine[k] = kept ? fine[k] : 0.0;
    }
    g_free(frame->levelled);
    frame->levelled = fine;
}

static gdouble
median_of_three(gdouble a, gdouble b, gdouble c)
{
    return MAX(MIN(a, b), MIN(MAX(a, b), c));
}

/* Each valid pixel becomes the median of itself and its valid neighbours
 * above and below (of two, the mean); in place, with the line above and
 * the current one kept as they were. */
static void
remove_strokes(ConditionedFrame *frame)
{
    gint xres = frame->xres, yres = frame->yres, r, c;
    gdouble *above = g_new(gdouble, xres), *current = g_new(gdouble, xres), *t;

    for (r = 0; r < yres; r++) {
        gdouble *row = frame->data + (gsize)r*xres;
        const gdouble *below = row + xres, *w = frame->weight + (gsize)r*xres;

        memcpy(current, row, xres*sizeof(gdouble));
        for (c = 0; c < xres; c++) {
            gboolean up = (r > 0 && w[c - xres] > 0.0);
            gboolean down = (r + 1 < yres && w[c + xres] > 0.0);
            gdouble v = current[c];

            if (!(w[c] > 0.0))
                row[c] = 0.0;
            else if (up && down)
                row[c] = median_of_three(above[c], v, below[c]);
            else if (up || down)
                row[c] = 0.5*(v + (up ? above[c] : below[c]));
        }
        t = above;
        above = current;
        current = t;
    }
    g_free(above);
    g_free(current);
}

/* A step through n pixels in lines of xres that takes about count of them
 * and, prime to xres, visits every column alike (a step dividing the line
 * would sample a few columns only). */
static gsize
sample_step(gsize n, gint xres, gsize count)
{
    return coprime_step(n/count, xres);
}

static void
clip_outliers(gdouble *data, const ConditionedFrame *frame)
{
    gsize k, n = (gsize)frame->xres*frame->yres, m = 0, step = sample_step(n, frame->xres, CLIP_SAMPLE);
    gdouble *buf = g_new(gdouble, n/step + 1), limit;

    for (k = 0; k < n; k += step) {
        if (frame->weight[k] > 0.0)
            buf[m++] = fabs(data[k]);
    }
    /* The values are zero-median already, so the median of |v| is the MAD. */
    limit = m ? CLIP_SIGMAS*1.4826*median_in_place(buf, m) : 0.0;
    g_free(buf);
    if (!(limit > 0.0))
        return;
    for (k = 0; k < n; k++)
        data[k] = CLAMP(data[k], -limit, limit);
}

static void
subtract_line_medians(gdouble *data, const ConditionedFrame *frame)
{
    gint xres = frame->xres, step = line_median_step(xres), r, c;
    gdouble *buf = g_new(gdouble, xres), med;

    for (r = 0; r < frame->yres; r++) {
        gdouble *row = data + (gsize)r*xres;
        const gdouble *w = frame->weight + (gsize)r*xres;

        if (!valid_median(row, w, (xres + step - 1)/step, step, buf, &med))
            continue;
        for (c = 0; c < xres; c++)
            row[c] = (w[c] > 0.0) ? row[c] - med : 0.0;
    }
    g_free(buf);
}

static void
normalise_rms(gdouble *data, const ConditionedFrame *frame)
{
    gsize k, n = (gsize)frame->xres*frame->yres;
    gdouble s2 = 0.0, w = 0.0, scale;

    for (k = 0; k < n; k++) {
        s2 += data[k]*data[k]*frame->weight[k];
        w += frame->weight[k];
    }
    scale = (s2 > 0.0 && w > 0.0) ? 1.0/sqrt(s2/w) : 1.0;
    for (k = 0; k < n; k++)
        data[k] *= scale;
}

static ConditionedFrame*
conditioned_frame_new(gint xres, gint yres)
{
    ConditionedFrame *frame = g_new0(ConditionedFrame, 1);

    frame->xres = xres;
    frame->yres = yres;
    frame->data = g_new(gdouble, (gsize)xres*yres);
    frame->weight = g_new(gdouble, (gsize)xres*yres);
    return frame;
}

ConditionedFrame*
frame_condition_level(const gdouble *data, const gdouble *exclude, gint xres, gint yres)
{
    ConditionedFrame *frame;

    g_return_val_if_fail(data && xres >= 1 && yres >= 1, NULL);
    frame = conditioned_frame_new(xres, yres);
    mark_valid(frame, data, exclude);
    if (!(frame->valid_fraction > 0.0)) {
        conditioned_frame_free(frame);
        return NULL;
    }
    align_lines_by_median_differences(frame);
    remove_strokes(frame);
    remove_column_trend(frame);
    return frame;
}

void
conditioned_frame_band_pass(ConditionedFrame *frame, gdouble pixel_aspect, gdouble narrow_sigma)
{
    g_return_if_fail(frame);
    if (!(pixel_aspect > 0.0) || !isfinite(pixel_aspect))
        pixel_aspect = 1.0;
    frame->narrow_sigma = MAX(narrow_sigma, BAND_NARROW_PX);
    band_pass(frame, pixel_aspect, frame->narrow_sigma);
    subtract_line_medians(frame->data, frame);
    clip_outliers(frame->data, frame);
    normalise_rms(frame->data, frame);
    subtract_line_medians(frame->levelled, frame);
    normalise_rms(frame->levelled, frame);
}

ConditionedFrame*
frame_condition(const gdouble *data, const gdouble *exclude, gint xres, gint yres,
                gdouble pixel_aspect)
{
    ConditionedFrame *frame = frame_condition_level(data, exclude, xres, yres);

    if (frame)
        conditioned_frame_band_pass(frame, pixel_aspect, conditioned_frame_noise_scale(frame, pixel_aspect));
    return frame;
}

ConditionedFrame*
conditioned_frame_downsample(const ConditionedFrame *frame, gint factor)
{
    ConditionedFrame *small;
    gint xres, yres, r, c, i, j;

    g_return_val_if_fail(frame && factor >= 1, NULL);
    xres = MAX(1, frame->xres/factor);
    yres = MAX(1, frame->yres/factor);
    small = conditioned_frame_new(xres, yres);
    small->valid_fraction = 0.0;
    for (r = 0; r < yres; r++) {
        for (c = 0; c < xres; c++) {
            gdouble s = 0.0, w = 0.0;

            for (i = r*factor; i < MIN((r + 1)*factor, frame->yres); i++) {
                for (j = c*factor; j < MIN((c + 1)*factor, frame->xres); j++) {
                    gsize k = (gsize)i*frame->xres + j;

                    s += frame->data[k]*frame->weight[k];
                    w += frame->weight[k];
                }
            }
            small->data[(gsize)r*xres + c] = (w > 0.0) ? s/w : 0.0;
            small->weight[(gsize)r*xres + c] = (w > 0.0) ? 1.0 : 0.0;
            small->valid_fraction += (w > 0.0);
        }
    }
    small->valid_fraction /= (gdouble)xres*yres;
    return small;
}

ConditionedFrame*
conditioned_frame_copy(const ConditionedFrame *frame)
{
    ConditionedFrame *copy;
    gsize size;

    g_return_val_if_fail(frame, NULL);
    size = (gsize)frame->xres*frame->yres*sizeof(gdouble);
    copy = g_memdup2(frame, sizeof(ConditionedFrame));
    copy->data = g_memdup2(frame->data, size);
    copy->weight = g_memdup2(frame->weight, size);
    copy->levelled = frame->levelled ? g_memdup2(frame->levelled, size) : NULL;
    return copy;
}

void
conditioned_frame_free(ConditionedFrame *frame)
{
    if (!frame)
        return;
    g_free(frame->data);
    g_free(frame->weight);
    g_free(frame->levelled);
    g_free(frame);
}
