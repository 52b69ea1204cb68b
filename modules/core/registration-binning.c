/*
 *  Registration of large frames at half resolution, where their texture
 *  holds nothing finer than the full-resolution match would use.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <math.h>
#include <string.h>
#include "registration-binning.h"
#include "fft-correlation.h"
#include "median.h"

/*
 * Why (docs/registration.md, "Large frames"): conditioning and the
 * sub-pixel match cost in proportion to the pixels, and a 1024 x 1024 pair
 * took a quarter of the time of Gwyddion's own one-dimensional drift
 * estimate; the issue asks a tenth.  The band-pass keeps little above a
 * quarter of a cycle per pixel (its narrow blur, a pixel wide, passes 8 %
 * of the power there), so on a texture whose features span several pixels
 * the frames binned 2 x 2 carry what the match uses: the stripes of the
 * benchmark's pair come within 0.017 px of the truth against 0.008 px,
 * in a third of the time.  A texture finer than that (a lattice of a few
 * pixels' period) would alias in the binned frames; it is registered at
 * full resolution.
 */

/* Lines sampled for the spectrum, along each axis. */
#define SAMPLE_LINES 64
/* Fewer whole sampled lines than this tell nothing. */
#define MIN_SAMPLE_LINES 8
/* Texture above this frequency (cycles per px) is fine: binned by two,
 * its period would be under 2.5 px, at or near the binned frame's Nyquist
 * frequency (a quarter of a cycle per px), where the match's
 * interpolation no longer follows it. */
#define FINE_FROM 0.2
/* The binned frame's Nyquist frequency, cycles per px of the frame. */
#define BINNED_NYQUIST 0.25
/* The white noise floor is this quantile of the power above this
 * frequency. */
#define NOISE_BAND_FROM 0.4
#define NOISE_QUANTILE 0.2
/* The narrow blur of the band-pass (frame-conditioning.c), px: the
 * power it passes at frequency f is exp(-4 pi^2 sigma^2 f^2). */
#define NARROW_SIGMA 1.0
/* Frequencies below this many cycles per line are the band-pass's wide
 * cut's (a twentieth of the frame), not the registered texture. */
#define LOWEST_CYCLES 4
/* At most this share of the registered texture may lie above the binned
 * Nyquist frequency. */
#define FINE_SHARE_MAX 0.05
/* Each binned stripe keeps at least this many rows. */
#define BINNED_MIN_STRIPE_ROWS 8

/* How much the match uses texture at frequency f (cycles per px): the
 * narrow blur passes exp(-4 pi^2 sigma^2 f^2) of its power, and the match
 * steps along its gradients, whose power goes with f^2. */
static gdouble
registered_weight(gdouble f)
{
    return f*f*exp(-4.0*G_PI*G_PI*NARROW_SIGMA*NARROW_SIGMA*f*f);
}

/* Removes the least-squares line from v and tapers it (Hann). */
static void
detrend_and_taper(gdouble *v, gint len)
{
    gdouble sv = 0.0, sxx = 0.0, sxv = 0.0, x, a, b;
    gint i;

    /* x centred: the mean and the slope separate. */
    for (i = 0; i < len; i++) {
        x = i - 0.5*(len - 1);
        sv += v[i];
        sxx += x*x;
        sxv += x*v[i];
    }
    a = sv/len;
    b = (sxx > 0.0) ? sxv/sxx : 0.0;
    for (i = 0; i < len; i++) {
        x = i - 0.5*(len - 1);
        v[i] = (v[i] - a - b*x)*0.5*(1.0 - cos(2.0*G_PI*(i + 0.5)/len));
    }
}

/* The i-th of count lines sampled across size: one in each of count
 * equal parts, at a place within it that varies from part to part (the
 * golden ratio's multiples): evenly spaced lines see a lattice whose period
 * divides their spacing at one phase, where it may vanish (a 4 px lattice
 * sampled every 8 columns read as no texture along y). */
static gint
sampled_line(gint i, gint count, gint size)
{
    gdouble where = i + fmod(0.5 + i*0.6180339887498949, 1.0);

    return CLAMP((gint)(where*size/count), 0, size - 1);
}

/* Sampled lines along x (rows) or y (columns), each whole (no missing
 * pixel); columns with each row's median over the sampled columns taken
 * out first, as the scan lines' offsets (white along y, they would be
 * noise floor, but large).  Returns how many were taken into lines
 * (count x len). */
static gint
sample_lines(const gdouble *data, gint xres, gint yres, gboolean along_x, gdouble *lines)
{
    gint len = along_x ? xres : yres, across = along_x ? yres : xres;
    gint count = MIN(SAMPLE_LINES, across), taken = 0, i, j, at;
    gdouble *line = lines, *row_level = NULL, *buf;
    gboolean whole;

    if (!along_x) {
        /* Each row's level over the sampled columns. */
        row_level = g_new(gdouble, yres);
        buf = g_new(gdouble, count);
        for (j = 0; j < yres; j++) {
            gint m = 0;

            for (i = 0; i < count; i++) {
                gdouble v = data[(gsize)j*xres + sampled_line(i, count, xres)];

                if (isfinite(v))
                    buf[m++] = v;
            }
            row_level[j] = m ? median_in_place(buf, m) : NAN;
        }
        g_free(buf);
    }
    for (i = 0; i < count; i++) {
        at = sampled_line(i, count, across);
        whole = TRUE;
        for (j = 0; j < len && whole; j++) {
            line[j] = along_x ? data[(gsize)at*xres + j] : data[(gsize)j*xres + at] - row_level[j];
            whole = isfinite(line[j]);
        }
        if (!whole)
            continue;
        detrend_and_taper(line, len);
        line += len;
        taken++;
    }
    g_free(row_level);
    return taken;
}

gdouble
registration_fine_texture_share(const gdouble *data, gint xres, gint yres, gboolean along_x)
{
    gint len = along_x ? xres : yres, across = along_x ? yres : xres;
    gint nk = len/2 + 1, from = (gint)ceil(NOISE_BAND_FROM*len), taken, k, m = 0;
    gdouble *lines, *power, *high, floor_power, f, excess, fine = 0.0, total = 0.0;

    g_return_val_if_fail(data && xres > 0 && yres > 0, 1.0);
    if (len < 4*LOWEST_CYCLES || from >= nk)
        return 1.0;
    lines = g_new(gdouble, (gsize)MIN(SAMPLE_LINES, across)*len);
    taken = sample_lines(data, xres, yres, along_x, lines);
    if (taken < MIN_SAMPLE_LINES) {
        g_free(lines);
        return 1.0;
    }
    power = g_new(gdouble, nk);
    fft_mean_row_power(lines, taken, len, power);
    high = g_new(gdouble, nk - from);
    for (k = from; k < nk; k++)
        high[m++] = power[k];
    /* A low quantile: a lattice's peak in the band is no floor. */
    floor_power = median_kth_in_place(high, m, (gint)(NOISE_QUANTILE*(m - 1)));
    for (k = LOWEST_CYCLES; k < nk; k++) {
        f = (gdouble)k/len;
        excess = MAX(power[k] - floor_power, 0.0);
        total += registered_weight(f)*excess;
        if (f >= BINNED_NYQUIST) {
            /* Binned, texture at f comes back at 0.5 - f, its amplitude
             * times the block mean's cos(pi f), moving against the
             * sample: what the binned match would see of it.  At least
             * what the match uses of it here: just above a quarter cycle
             * the aliased weight is half the weight just below (a 4 px
             * lattice, on the binned Nyquist frequency, read 0.48). */
            fine += MAX(registered_weight(f), cos(G_PI*f)*cos(G_PI*f)*registered_weight(0.5 - f))*excess;
        }
        else if (f >= FINE_FROM)
            fine += registered_weight(f)*excess;
    }
    g_free(high);
    g_free(power);
    g_free(lines);
    return (total > 0.0) ? MIN(fine/total, 1.0) : 1.0;
}

static gboolean
coarse_texture(const gdouble *data, gint xres, gint yres)
{
    return (registration_fine_texture_share(data, xres, yres, TRUE) <= FINE_SHARE_MAX
            && registration_fine_texture_share(data, xres, yres, FALSE) <= FINE_SHARE_MAX);
}

gint
registration_binning_factor(const gdouble *image, const gdouble *reference, gint xres, gint yres, gint n)
{
    g_return_val_if_fail(image && reference, 1);
    if (MIN(xres, yres) < REGISTRATION_BINNING_MIN_SIDE || n < 1
        || (yres/2)/n < BINNED_MIN_STRIPE_ROWS)
        return 1;
    return (coarse_texture(image, xres, yres) && coarse_texture(reference, xres, yres)) ? 2 : 1;
}

gdouble*
registration_bin_frame(const gdouble *data, gint xres, gint yres, gint factor)
{
    gint bx = xres/factor, by = yres/factor, r, c, i, j;
    gdouble *binned, sum, share = 1.0/(factor*factor);
    gboolean whole;

    g_return_val_if_fail(data && factor >= 1 && bx >= 1 && by >= 1, NULL);
    binned = g_new(gdouble, (gsize)bx*by);
    for (r = 0; r < by; r++) {
        for (c = 0; c < bx; c++) {
            sum = 0.0;
            whole = TRUE;
            for (i = 0; i < factor; i++) {
                const gdouble *row = data + (gsize)(r*factor + i)*xres + c*factor;

                for (j = 0; j < factor; j++) {
                    whole = whole && isfinite(row[j]);
                    /* Each share first: four values near the largest
                     * double would overflow their sum. */
                    sum += share*row[j];
                }
            }
            binned[(gsize)r*bx + c] = whole ? sum : NAN;
        }
    }
    return binned;
}
