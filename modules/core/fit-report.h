/*
 *  The drift fit of a frame series: the displacements between its frames
 *  measured (displacement-measure.h), every drift model fitted and one
 *  chosen (drift-fit.h), and the report as the JSON `simscan fit` writes.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_FIT_REPORT_H
#define LOCALSCAN_FIT_REPORT_H

#include <glib.h>
#include <json-glib/json-glib.h>
#include "frame-series.h"
#include "displacement-measure.h"
#include "drift-fit.h"

G_BEGIN_DECLS

#define FIT_REPORT_MAX_MODELS 8

/* Everything one fit of a series produced. */
typedef struct {
    DriftMeasurement *meas;
    gint n_meas;
    gint n_fits;
    DriftFit fits[FIT_REPORT_MAX_MODELS];
    gint chosen;              /* index into fits, -1 when nothing fitted */
    DriftFitOptions fit_options;  /* the options the fits were made with */
} FitReport;

/* Sets what options leaves to the series (the outlier floor from its
 * pixel size). */
void      fit_report_options_for_series(DriftFitOptions *options,
                                        const FrameSeries *series);
/* Measures the displacements of the series and fits every model. */
gboolean  fit_report_compute  (const FrameSeries *series,
                               const DisplacementOptions *doptions,
                               const DriftFitOptions *foptions,
                               FitReport *report);
void      fit_report_clear    (FitReport *report);
/* The fit's members of that JSON (effect, parameters, velocity_nm_per_s,
 * models, measurement counts) into an object being built. */
void      fit_report_add_members(JsonBuilder *builder,
                                 const FitReport *report);
/* The JSON of docs/cli.md (plus frames, notes and measurement counts). */
gchar*    fit_report_to_json  (const FitReport *report,
                               const FrameSeries *series);

G_END_DECLS

#endif
