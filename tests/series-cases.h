/*
 *  Simulated frame series with a random drift effect, corrected by the
 *  core's series correction and judged against the simulator's truth:
 *  shared by tests/test-series-correction and bench/study-series.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef TESTS_SERIES_CASES_H
#define TESTS_SERIES_CASES_H

#include <glib.h>
#include "drift-model.h"
#include "frame-series.h"
#include "series-correction.h"
#include "hidden-effect-cases.h"

G_BEGIN_DECLS

#define SERIES_CASE_FRAMES 5
#define SERIES_CASE_EFFECTS HIDDEN_CASE_EFFECTS

typedef struct {
    gboolean raw;           /* raw-channel artefacts on every frame */
    gint disturbed;         /* this frame's content is disturbed; -1: none */
} SeriesCaseOptions;

/* What the correction achieved against the truth. */
typedef struct {
    gdouble trajectory_rms_px;   /* over every scan line of every frame,
                                    lines within 3 of a jump left out,
                                    and featureless lines in the
                                    correction's jump window */
    gdouble trajectory_worst_px;
    gdouble trajectory_relative_px; /* the same RMS without the mean error:
                                       how well the frames overlay, whatever
                                       the absolute reference */
    gboolean smooth_used;        /* the flexible trajectory corrected them */
    gdouble model_relative_px;   /* the chosen model's trajectory_relative_px,
                                    whether it corrected them or not */
    gdouble stripe_worst_px;     /* the drift a stripe of 16 lines of a
                                    corrected frame keeps, worst of all */
    gdouble frame_worst_px;      /* corrected frames registered as a whole
                                    against the drift-free truth, worst */
    gboolean effect_named;       /* the fit named the drawn effect */
    gint flagged;                /* frames flagged */
    gboolean disturbed_flagged;  /* the disturbed frame among them */
} SeriesCaseResult;

/* The drift of case i is hidden_case_draw()'s (hidden-effect-cases.h):
 * effect i % SERIES_CASE_EFFECTS at the hidden effect tests' sizes.
 * The frames scanned under model; truth (may be NULL) gets the drift-free
 * frames (references held by the caller). */
FrameSeries*  series_case_scan    (guint32 base_seed, gint i,
                                   const DriftModel *model,
                                   const SeriesCaseOptions *options,
                                   GwyDataField ***truth);
/* A random-walk drift (no model explains it) for case i: velocity up to
 * 0.1 nm/s, diffusion sigma nm/s per sqrt(s) in steps of 2 s. */
void          series_case_draw_walk(guint32 base_seed, gint i, gdouble sigma,
                                    DriftModel *model);
/* Corrects the series with the core and judges it; FALSE when the
 * correction failed. */
gboolean      series_case_judge   (const FrameSeries *series,
                                   GwyDataField **truth,
                                   const DriftModel *model,
                                   const SeriesCaseOptions *options,
                                   SeriesCaseResult *result);

/* The mean square of line r of field after its best quadratic along the
 * line: about 1e-19 m^2 on a featureless line (noise of 0.2 nm), 2e-17 to
 * 1e-16 m^2 where it cuts particles. */
gdouble       series_case_line_texture(GwyDataField *field, gint r);

G_END_DECLS

#endif
