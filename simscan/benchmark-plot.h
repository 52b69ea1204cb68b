/*
 *  The benchmark's figure: trajectory error per case and method.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef SIMSCAN_BENCHMARK_PLOT_H
#define SIMSCAN_BENCHMARK_PLOT_H

#include <glib.h>
#include "benchmark-score.h"

G_BEGIN_DECLS

/* An SVG of horizontal bars, one group per case, one bar per method: the
 * trajectory RMS on a log axis (failed results marked).  scores holds
 * case i, method j at i*n_methods + j. */
gchar*  benchmark_plot_svg  (gchar **cases,
                             gchar **methods,
                             const BenchmarkScore *scores);

G_END_DECLS

#endif
