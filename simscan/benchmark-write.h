/*
 *  `simscan benchmark`: the set of cases written to a folder.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef SIMSCAN_BENCHMARK_WRITE_H
#define SIMSCAN_BENCHMARK_WRITE_H

#include <glib.h>
#include "benchmark-cases.h"

G_BEGIN_DECLS

/* Writes the cases of the set into dir (made, or an empty folder): per
 * case a folder with frame-NNN.gwy, truth.gwy, truth.csv and case.json,
 * and benchmark.json listing them (docs/benchmark.md).  Cases whose
 * measured sample is absent from measured_dir are listed as skipped with
 * the reason.  All or nothing: on failure (error set) nothing is left. */
gboolean  benchmark_write  (const gchar *dir,
                            guint32 seed,
                            BenchmarkSize size,
                            const gchar *measured_dir,
                            GError **error);

G_END_DECLS

#endif
