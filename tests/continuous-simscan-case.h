/*
 *  One simscan experiment judged three ways: the contaminated image, paper
 *  mode and continuous mode, each against the sample at the moment it
 *  shows.  Shared by bench/study-accuracy and tests/test-continuous-simscan.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_CONTINUOUS_SIMSCAN_CASE_H
#define LOCALSCAN_CONTINUOUS_SIMSCAN_CASE_H

#include <glib.h>
#include <libprocess/gwyprocessenums.h>
#include "centre-error.h"
#include "simscan-config.h"

G_BEGIN_DECLS

typedef enum {
    ACCURACY_BEFORE,                 /* the contaminated image */
    ACCURACY_PAPER,                  /* paper mode, per stripe at its t_local */
    ACCURACY_CONTINUOUS,             /* continuous mode, at its t_ref */
    ACCURACY_PAPER_SIMSCAN_REF,      /* paper mode at the scans' start */
    ACCURACY_CONTINUOUS_TRUE_TABLE,  /* continuous, perfect local scans */
    ACCURACY_CONTINUOUS_EXACT,       /* continuous, the exact trajectory */
    ACCURACY_TRUTH,                  /* the sample at t_ref scanned without
                                        drift: the detector's own error there,
                                        continuous mode's floor */
    ACCURACY_NFIGURES
} AccuracyFigure;

typedef struct {
    CentreError error[ACCURACY_NFIGURES];
    gint n_measured;                 /* stripes the local scans measured */
    gdouble measurement_rms_px;      /* dx_exact, dy_exact vs perfect scans */
    gdouble displayed_rms_px;        /* of it: the detected displayed centre
                                        vs where the image shows the particle */
    gdouble actual_rms_px;           /* and the local scan's actual centre vs
                                        the particle's position then */
    gdouble t_ref;                   /* continuous mode's reference time, s */
} AccuracyCase;

/* Builds config's scene, runs its local scans over config->n_stripes and
 * measures every figure, continuous mode with the given kernel.  FALSE with
 * error set when the scene cannot be made or no stripe was measured. */
gboolean  accuracy_case_run  (const SimscanConfig *config,
                              GwyInterpolationType interpolation,
                              AccuracyCase *result,
                              GError **error);

G_END_DECLS

#endif
