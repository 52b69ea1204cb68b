/*
 *  FFT cross-correlation of real arrays at one padded size (FFTW plumbing
 *  for the stripe registration).
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_FFT_CORRELATION_H
#define LOCALSCAN_FFT_CORRELATION_H

#include <glib.h>

G_BEGIN_DECLS

typedef struct _FFTCorrelation FFTCorrelation;

/* Plans are made once here (FFTW_ESTIMATE) and reused by every run.  Making
 * and destroying FFTW plans is serialised by a lock, because FFTW's planner
 * is not thread-safe; runs themselves may go in parallel on distinct objects. */
FFTCorrelation* fft_correlation_new          (gint rows, gint cols);
void            fft_correlation_free         (FFTCorrelation *fc);
gint            fft_correlation_rows         (const FFTCorrelation *fc);
gint            fft_correlation_cols         (const FFTCorrelation *fc);

/* Real rows x cols buffers, row-major, that the caller fills (zeros where
 * nothing is placed: fft_correlation_clear() zeroes both). */
gdouble*        fft_correlation_template     (FFTCorrelation *fc);
gdouble*        fft_correlation_field        (FFTCorrelation *fc);
void            fft_correlation_clear        (FFTCorrelation *fc);

/* Transforms the template buffer and keeps its spectrum, so one template can
 * be correlated with many fields. */
void            fft_correlation_set_template (FFTCorrelation *fc);

/* Correlates the kept template with the field buffer (circularly):
 * result[a*cols + b] = sum_ij template[i][j] field[(i+a) % rows][(j+b) % cols].
 * The returned buffer belongs to fc and is overwritten by the next run. */
const gdouble*  fft_correlation_run          (FFTCorrelation *fc);

/* The power spectrum |X_k|^2 (k = 0 .. len/2) of each of nrows rows of len
 * values, averaged over the rows (power has len/2 + 1 entries). */
void            fft_mean_row_power           (const gdouble *rows,
                                              gint nrows,
                                              gint len,
                                              gdouble *power);

/* The smallest size >= size with only the factors 2, 3, 5 and 7. */
gint            fft_correlation_nice_size    (gint size);

G_END_DECLS

#endif
