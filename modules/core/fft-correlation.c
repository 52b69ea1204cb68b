/*
 *  FFT cross-correlation of real arrays at one padded size (FFTW plumbing
 *  for the stripe registration).
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <string.h>
#include <complex.h>
#include <fftw3.h>
#include "fft-correlation.h"

struct _FFTCorrelation {
    gint rows;
    gint cols;
    gint spectrum_size;
    gdouble *template_data;
    gdouble *field_data;
    gdouble *result;
    fftw_complex *template_spectrum;
    fftw_complex *field_spectrum;
    fftw_plan template_forward;
    fftw_plan field_forward;
    fftw_plan backward;
};

G_LOCK_DEFINE_STATIC(fftw_planner);

FFTCorrelation*
fft_correlation_new(gint rows, gint cols)
{
    FFTCorrelation *fc;
    gsize nreal;

    g_return_val_if_fail(rows >= 1 && cols >= 1, NULL);
    fc = g_new0(FFTCorrelation, 1);
    fc->rows = rows;
    fc->cols = cols;
    fc->spectrum_size = rows*(cols/2 + 1);
    nreal = (gsize)rows*cols;
    fc->template_data = fftw_alloc_real(nreal);
    fc->field_data = fftw_alloc_real(nreal);
    fc->result = fftw_alloc_real(nreal);
    fc->template_spectrum = fftw_alloc_complex(fc->spectrum_size);
    fc->field_spectrum = fftw_alloc_complex(fc->spectrum_size);

    G_LOCK(fftw_planner);
    fc->template_forward = fftw_plan_dft_r2c_2d(rows, cols, fc->template_data, fc->template_spectrum,
                                                FFTW_ESTIMATE);
    fc->field_forward = fftw_plan_dft_r2c_2d(rows, cols, fc->field_data, fc->field_spectrum, FFTW_ESTIMATE);
    /* c2r overwrites its input; the field spectrum is recomputed every run. */
    fc->backward = fftw_plan_dft_c2r_2d(rows, cols, fc->field_spectrum, fc->result, FFTW_ESTIMATE);
    G_UNLOCK(fftw_planner);

    fft_correlation_clear(fc);
    return fc;
}

void
fft_correlation_free(FFTCorrelation *fc)
{
    if (!fc)
        return;
    G_LOCK(fftw_planner);
    fftw_destroy_plan(fc->template_forward);
    fftw_destroy_plan(fc->field_forward);
    fftw_destroy_plan(fc->backward);
    G_UNLOCK(fftw_planner);
    fftw_free(fc->template_data);
    fftw_free(fc->field_data);
    fftw_free(fc->result);
    fftw_free(fc->template_spectrum);
    fftw_free(fc->field_spectrum);
    g_free(fc);
}

gint
fft_correlation_rows(const FFTCorrelation *fc)
{
    return fc->rows;
}

gint
fft_correlation_cols(const FFTCorrelation *fc)
{
    return fc->cols;
}

gdouble*
fft_correlation_template(FFTCorrelation *fc)
{
    return fc->template_data;
}

gdouble*
fft_correlation_field(FFTCorrelation *fc)
{
    return fc->field_data;
}

void
fft_correlation_clear(FFTCorrelation *fc)
{
    gsize nreal = (gsize)fc->rows*fc->cols;

    memset(fc->template_data, 0, nreal*sizeof(gdouble));
    memset(fc->field_data, 0, nreal*sizeof(gdouble));
}

void
fft_correlation_set_template(FFTCorrelation *fc)
{
    fftw_execute(fc->template_forward);
}

/* sum_i t[i] f[i+a] has the spectrum conj(T) F; FFTW's unnormalised round
 * trip multiplies by rows*cols, divided out here. */
const gdouble*
fft_correlation_run(FFTCorrelation *fc)
{
    gdouble scale = 1.0/((gdouble)fc->rows*fc->cols);
    gint k;

    fftw_execute(fc->field_forward);
    for (k = 0; k < fc->spectrum_size; k++)
        fc->field_spectrum[k] *= scale*conj(fc->template_spectrum[k]);
    fftw_execute(fc->backward);
    return fc->result;
}

void
fft_mean_row_power(const gdouble *rows, gint nrows, gint len, gdouble *power)
{
    gdouble *line = fftw_alloc_real(MAX(len, 1));
    fftw_complex *spectrum = fftw_alloc_complex(len/2 + 1);
    fftw_plan forward;
    gint r, k;

    G_LOCK(fftw_planner);
    forward = fftw_plan_dft_r2c_1d(len, line, spectrum, FFTW_ESTIMATE);
    G_UNLOCK(fftw_planner);
    memset(power, 0, (len/2 + 1)*sizeof(gdouble));
    for (r = 0; r < nrows; r++) {
        memcpy(line, rows + (gsize)r*len, len*sizeof(gdouble));
        fftw_execute(forward);
        for (k = 0; k <= len/2; k++)
            power[k] += (creal(spectrum[k])*creal(spectrum[k]) + cimag(spectrum[k])*cimag(spectrum[k]))/nrows;
    }
    G_LOCK(fftw_planner);
    fftw_destroy_plan(forward);
    G_UNLOCK(fftw_planner);
    fftw_free(line);
    fftw_free(spectrum);
}

gint
fft_correlation_nice_size(gint size)
{
    static const gint factors[] = { 2, 3, 5, 7 };
    gint n, m;
    guint i;

    for (n = MAX(size, 1); ; n++) {
        m = n;
        for (i = 0; i < G_N_ELEMENTS(factors); i++) {
            while (m % factors[i] == 0)
                m /= factors[i];
        }
        if (m == 1)
            return n;
    }
}
