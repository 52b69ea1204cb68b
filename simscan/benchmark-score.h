/*
 *  `simscan score`: a method's results on the benchmark against its truth.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef SIMSCAN_BENCHMARK_SCORE_H
#define SIMSCAN_BENCHMARK_SCORE_H

#include <glib.h>

G_BEGIN_DECLS

/* One method on one case.  Figures not scored are NAN (no corrected
 * frames, no flags given). */
typedef struct {
    gchar *failure;              /* why the result could not be scored, or
                                    NULL */
    gdouble trajectory_rms_px;   /* over every line of the trusted frames,
                                    lines within 3 of a jump left out */
    gdouble trajectory_worst_px;
    gdouble frame_rms_px;        /* corrected frames against the drift-free
                                    truth, stripe by stripe */
    gdouble frame_worst_px;
    gint stripes_lost;           /* stripes of corrected frames that do not
                                    register against the truth at all */
    gint stripes_judged;         /* of how many */
    gint flags_missed;           /* disturbed frames not flagged; -1: no
                                    flags given */
    gint flags_false;            /* trusted frames flagged; -1 likewise */
    gint disturbed;              /* disturbed frames in the case */
} BenchmarkScore;

/* Scores the result folders of one case (one per method: trajectory.csv,
 * optionally corrected.gwy and flagged.txt or result.json;
 * docs/benchmark.md) against the case's truth folder, read once for all
 * of them, into scores[0 .. n-1].  A result that cannot be scored is a
 * failure in its score (FALSE is returned only when the truth itself
 * cannot be read, with error set). */
gboolean  benchmark_score_case   (const gchar *truth_case_dir,
                                  gchar **result_case_dirs,
                                  gint n,
                                  BenchmarkScore *scores,
                                  GError **error);
void      benchmark_score_clear  (BenchmarkScore *score);

G_END_DECLS

#endif
