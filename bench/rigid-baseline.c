/*
 *  The rigid frame-to-frame correction peers use, as the baseline the
 *  series benchmark compares against: each frame registered against the
 *  previous one by whole-frame FFT phase correlation, the shifts summed,
 *  and every frame moved back by one constant sub-pixel shift.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <math.h>
#include <complex.h>
#include <fftw3.h>
#include <libprocess/gwyprocess.h>
#include "rigid-baseline.h"

typedef struct {
    gint xres, yres;
    gint nspec;
    gdouble *window;
    gdouble *real;             /* the windowed frame, then the correlation */
    fftw_complex *spectrum[2]; /* previous and current frame, alternating */
    fftw_complex *cross;
    fftw_plan forward, backward;
} PhaseCorrelation;

/* A Hann window in each direction: without it the frame edges, which do
 * not match across the periodic boundary the FFT assumes, give a peak at
 * zero shift that competes with the true one. */
static void
make_window(gdouble *window, gint xres, gint yres)
{
    gint i, j;

    for (i = 0; i < yres; i++) {
        gdouble wy = 0.5 - 0.5*cos(2.0*G_PI*(i + 0.5)/yres);

        for (j = 0; j < xres; j++)
            window[i*xres + j] = wy*(0.5 - 0.5*cos(2.0*G_PI*(j + 0.5)/xres));
    }
}

static PhaseCorrelation*
phase_correlation_new(gint xres, gint yres)
{
    PhaseCorrelation *pc = g_new0(PhaseCorrelation, 1);

    pc->xres = xres;
    pc->yres = yres;
    pc->nspec = yres*(xres/2 + 1);
    pc->window = g_new(gdouble, xres*yres);
    make_window(pc->window, xres, yres);
    pc->real = fftw_alloc_real(xres*yres);
    pc->spectrum[0] = fftw_alloc_complex(pc->nspec);
    pc->spectrum[1] = fftw_alloc_complex(pc->nspec);
    pc->cross = fftw_alloc_complex(pc->nspec);
    /* One plan serves both spectra (fftw_execute_dft_r2c with the other
     * array; fftw_alloc gives them the same alignment). */
    pc->forward = fftw_plan_dft_r2c_2d(yres, xres, pc->real, pc->spectrum[0], FFTW_ESTIMATE);
    pc->backward = fftw_plan_dft_c2r_2d(yres, xres, pc->cross, pc->real, FFTW_ESTIMATE);
    return pc;
}

static void
phase_correlation_free(PhaseCorrelation *pc)
{
    fftw_destroy_plan(pc->forward);
    fftw_destroy_plan(pc->backward);
    fftw_free(pc->real);
    fftw_free(pc->spectrum[0]);
    fftw_free(pc->spectrum[1]);
    fftw_free(pc->cross);
    g_free(pc->window);
    g_free(pc);
}

/* The spectrum of the mean-subtracted, windowed frame into spectrum[which];
 * the mean goes first so the window does not turn it into a bump. */
static void
load_spectrum(PhaseCorrelation *pc, GwyDataField *field, gint which)
{
    const gdouble *data = gwy_data_field_get_data_const(field);
    gdouble mean = gwy_data_field_get_avg(field);
    gint i, n = pc->xres*pc->yres;

    for (i = 0; i < n; i++)
        pc->real[i] = (data[i] - mean)*pc->window[i];
    fftw_execute_dft_r2c(pc->forward, pc->real, pc->spectrum[which]);
}

/* The normalised cross-power spectrum transformed back: a peak at the
 * shift (rows, cols) that carries the previous frame onto the current one
 * (cur(x) = prev(x - s) makes it exp(-i w s), whose inverse is a delta at
 * +s).  Only the phase is kept, which is what makes the peak sharp. */
static void
correlate(PhaseCorrelation *pc, gint prev, gint cur)
{
    const fftw_complex *a = pc->spectrum[cur], *b = pc->spectrum[prev];
    gint i;

    for (i = 0; i < pc->nspec; i++) {
        fftw_complex z = a[i]*conj(b[i]);
        gdouble m = cabs(z);

        pc->cross[i] = m > 1e-300 ? z/m : 0.0;
    }
    fftw_execute(pc->backward);
}

/* The value at (i + u, j + v) of the periodic correlation. */
static gdouble
wrapped(const PhaseCorrelation *pc, gint i, gint j, gint u, gint v)
{
    gint ii = (i + u + pc->yres) % pc->yres, jj = (j + v + pc->xres) % pc->xres;

    return pc->real[ii*pc->xres + jj];
}

/* One-dimensional parabola vertex through (-1, fm), (0, f0), (1, fp),
 * limited to half a pixel: the fallback when the 3x3 fit has no maximum. */
static gdouble
parabola_vertex(gdouble fm, gdouble f0, gdouble fp)
{
    gdouble den = fm - 2.0*f0 + fp;

    if (den >= 0.0)
        return 0.0;
    return CLAMP(0.5*(fm - fp)/den, -0.5, 0.5);
}

/* The sub-pixel peak offset (x, y) from the least-squares quadric
 * a + bx + cy + dx^2 + ey^2 + gxy over the 3x3 neighbourhood of (i, j).
 * On this grid the basis {x, y, xy, x^2 - 2/3, y^2 - 2/3} is orthogonal,
 * so each coefficient is one weighted sum. */
static void
subpixel_peak(const PhaseCorrelation *pc, gint i, gint j, gdouble *x, gdouble *y)
{
    gdouble b = 0.0, c = 0.0, d = 0.0, e = 0.0, g = 0.0, det;
    gint u, v;

    for (u = -1; u <= 1; u++) {
        for (v = -1; v <= 1; v++) {
            gdouble f = wrapped(pc, i, j, u, v);

            b += v*f/6.0;
            c += u*f/6.0;
            g += u*v*f/4.0;
            d += (v*v - 2.0/3.0)*f/2.0;
            e += (u*u - 2.0/3.0)*f/2.0;
        }
    }
    det = 4.0*d*e - g*g;
    if (d < 0.0 && det > 0.0) {
        *x = (-2.0*b*e + c*g)/det;
        *y = (-2.0*c*d + b*g)/det;
        if (fabs(*x) <= 1.0 && fabs(*y) <= 1.0)
            return;
    }
    *x = parabola_vertex(wrapped(pc, i, j, 0, -1), wrapped(pc, i, j, 0, 0), wrapped(pc, i, j, 0, 1));
    *y = parabola_vertex(wrapped(pc, i, j, -1, 0), wrapped(pc, i, j, 0, 0), wrapped(pc, i, j, 1, 0));
}

/* The highest correlation value with its sub-pixel offset, as a signed
 * shift (indices past half the size are negative shifts). */
static void
find_shift(const PhaseCorrelation *pc, gdouble *dx, gdouble *dy)
{
    gint k, best = 0, n = pc->xres*pc->yres, i, j;
    gdouble x, y;

    for (k = 1; k < n; k++) {
        if (pc->real[k] > pc->real[best])
            best = k;
    }
    i = best/pc->xres;
    j = best % pc->xres;
    subpixel_peak(pc, i, j, &x, &y);
    *dx = (j > pc->xres/2 ? j - pc->xres : j) + x;
    *dy = (i > pc->yres/2 ? i - pc->yres : i) + y;
}

void
rigid_baseline_shifts(const FrameSeries *series, gdouble *dx, gdouble *dy)
{
    GwyDataField *first;
    PhaseCorrelation *pc;
    gint k, prev = 0;

    g_return_if_fail(series && series->n_frames >= 1);
    dx[0] = dy[0] = 0.0;
    first = series->frames[0].field;
    pc = phase_correlation_new(gwy_data_field_get_xres(first), gwy_data_field_get_yres(first));
    load_spectrum(pc, first, prev);
    /* Each frame against the previous one: neighbours overlap most and
     * change least, at the price of the errors adding up along the series. */
    for (k = 1; k < series->n_frames; k++) {
        gdouble sx, sy;

        load_spectrum(pc, series->frames[k].field, 1 - prev);
        correlate(pc, prev, 1 - prev);
        find_shift(pc, &sx, &sy);
        dx[k] = dx[k-1] + sx;
        dy[k] = dy[k-1] + sy;
        prev = 1 - prev;
    }
    phase_correlation_free(pc);
}

void
rigid_baseline_correct(GwyDataField *frame, gdouble dx, gdouble dy, GwyDataField *result)
{
    /* Gwyddion's inverse transform maps result pixel coordinates to frame
     * ones: a pure translation by the shift. */
    gdouble invtrans[6] = { 1.0, 0.0, 0.0, 1.0, dx, dy };

    gwy_data_field_affine(frame, result, invtrans, GWY_INTERPOLATION_BSPLINE,
                          GWY_EXTERIOR_FIXED_VALUE, gwy_data_field_get_avg(frame));
}

/* The range [lo, hi] of result indices whose source index + shift lies in
 * [0, res - 1] for every shift; the tolerance keeps whole-pixel shifts that
 * rounding left a hair off from losing a row. */
static gboolean
common_range(const gdouble *shift, gint n, gint res, gint *lo, gint *len)
{
    gdouble low = 0.0, high = res - 1.0;
    gint k, first, last;

    for (k = 0; k < n; k++) {
        low = MAX(low, -shift[k]);
        high = MIN(high, res - 1.0 - shift[k]);
    }
    first = (gint)ceil(low - 1e-9);
    last = (gint)floor(high + 1e-9);
    *lo = first;
    *len = last - first + 1;
    return last >= first;
}

gboolean
rigid_baseline_crop(const gdouble *dx, const gdouble *dy, gint n, gint xres, gint yres,
                    gint *col, gint *row, gint *width, gint *height)
{
    return common_range(dx, n, xres, col, width) && common_range(dy, n, yres, row, height);
}
