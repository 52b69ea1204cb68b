/*
 *  `simscan fit`: drift models fitted to a time series of frames, written
 *  as the JSON of shared/spec/interfaces.md section 3.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef SIMSCAN_FIT_COMMAND_H
#define SIMSCAN_FIT_COMMAND_H

#include <glib.h>
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

/* Measures the displacements of the series and fits every model. */
gboolean  fit_report_compute  (const FrameSeries *series,
                               const DisplacementOptions *doptions,
                               const DriftFitOptions *foptions,
                               FitReport *report);
void      fit_report_clear    (FitReport *report);
/* The interfaces.md JSON (plus frames, notes and measurement counts). */
gchar*    fit_report_to_json  (const FitReport *report,
                               const FrameSeries *series);

/* The subcommand; argv[0] is "fit".  Returns the exit status. */
int       simscan_fit_main    (int argc, char **argv);

G_END_DECLS

#endif
