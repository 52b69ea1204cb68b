/*
 *  `simscan benchmark` and `simscan score` (docs/benchmark.md).
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef SIMSCAN_BENCHMARK_COMMAND_H
#define SIMSCAN_BENCHMARK_COMMAND_H

G_BEGIN_DECLS

/* argv[0] is the subcommand's name; returns the exit status. */
int  simscan_benchmark_main  (int argc, char **argv);
int  simscan_score_main      (int argc, char **argv);

G_END_DECLS

#endif
