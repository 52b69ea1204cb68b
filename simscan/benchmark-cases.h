/*
 *  The cases of the public drift benchmark (docs/benchmark.md): which
 *  series, scanned how, under which drift.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef SIMSCAN_BENCHMARK_CASES_H
#define SIMSCAN_BENCHMARK_CASES_H

#include <glib.h>
#include "drift-model.h"
#include "scan-timing.h"

G_BEGIN_DECLS

/* Bumped whenever a case, a draw or a file of the set changes: results are
 * comparable only within one version. */
#define BENCHMARK_VERSION "1"

typedef enum {
    BENCHMARK_SIZE_SMALL,
    BENCHMARK_SIZE_FULL,
} BenchmarkSize;

/* What is scanned. */
typedef enum {
    BENCHMARK_SAMPLE_PARTICLES,    /* synthetic particles on a rough film */
    BENCHMARK_SAMPLE_FILM,         /* particles-film (measured) */
    BENCHMARK_SAMPLE_MINICIRCLES,  /* hsafm-minicircles frame 0 (measured) */
} BenchmarkSample;

typedef struct {
    gchar *name;               /* "03-oscillation": the folder */
    const gchar *summary;      /* one line for tables */
    BenchmarkSample sample;
    gint xres, yres, n_frames;
    gdouble field;             /* m, the frames' square area */
    gdouble line_time;         /* s */
    ScanDirection direction;
    DriftModel drift;          /* prepared over the series */
    gboolean raw;              /* raw-channel artefacts on every frame */
    gboolean missing;          /* missing pixels (NaN) in every frame */
    gint disturbed;            /* this frame slipped and came back; -1 none */
    gdouble slip_px[2];        /* by how much */
} BenchmarkCase;

/* The cases of a set in order, each drawn from seed (the same seed, the
 * same cases); free with benchmark_cases_free. */
BenchmarkCase*  benchmark_cases_new   (BenchmarkSize size, guint32 seed,
                                       gint *n);
void            benchmark_cases_free  (BenchmarkCase *cases, gint n);

/* The start of frame k, s (frames back to back from t = 0). */
gdouble         benchmark_case_frame_start(const BenchmarkCase *bc, gint k);
/* The scan timing of frame k. */
void            benchmark_case_timing (const BenchmarkCase *bc, gint k,
                                       ScanTiming *timing);
/* Lines this close to a jump are left out of the scores. */
gboolean        benchmark_case_near_jump(const BenchmarkCase *bc, gdouble t);

const gchar*    benchmark_sample_name (BenchmarkSample sample);

G_END_DECLS

#endif
