/*
 *  The drift fit of a frame series: its displacements measured, every
 *  drift model fitted, one chosen, and the JSON report of it all.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <string.h>
#include <math.h>
#include "json-values.h"
#include "fit-report.h"

/* A residual below this part of a pixel is never a failed registration. */
#define OUTLIER_FLOOR_PX 0.25

void
fit_report_options_for_series(DriftFitOptions *options, const FrameSeries *series)
{
    if (!(options->outlier_floor_nm > 0.0) && series->n_frames > 0)
        options->outlier_floor_nm = OUTLIER_FLOOR_PX*1e9*MIN(frame_series_dx(series),
                                                              frame_series_dy(series));
}

gboolean
fit_report_compute(const FrameSeries *series,
                   const DisplacementOptions *doptions,
                   const DriftFitOptions *foptions, FitReport *report)
{
    gboolean *kept;
    gint i;

    memset(report, 0, sizeof(FitReport));
    if (foptions)
        report->fit_options = *foptions;
    else
        drift_fit_options_init(&report->fit_options);
    fit_report_options_for_series(&report->fit_options, series);
    report->meas = displacement_measure_series(series, doptions,
                                               &report->n_meas);
    drift_fit_candidates(&report->n_fits);
    kept = g_new(gboolean, MAX(report->n_meas, 1));
    report->chosen = drift_fit_select_kept(report->meas, report->n_meas,
                                           &report->fit_options, report->fits,
                                           kept);
    /* Gross outliers (failed registrations) count as unused from here on. */
    for (i = 0; i < report->n_meas; i++) {
        if (!kept[i])
            report->meas[i].weight = 0.0;
    }
    g_free(kept);
    return report->chosen >= 0;
}

void
fit_report_clear(FitReport *report)
{
    g_free(report->meas);
    report->meas = NULL;
    report->n_meas = 0;
}

static void
add_parameters(JsonBuilder *b, const DriftFit *fit)
{
    DriftFitParameters p;

    drift_fit_parameters(fit, &p);
    json_builder_set_member_name(b, "parameters");
    json_builder_begin_object(b);
    switch (fit->type) {
        case DRIFT_MODEL_SETTLING:
        json_values_set_number(b, "tau_s", p.tau_s);
        json_values_set_pair(b, "u_nm_per_s", p.u_nm_per_s);
        break;

        case DRIFT_MODEL_OSCILLATION:
        json_values_set_number(b, "period_s", p.period_s);
        json_values_set_pair(b, "amplitude_nm", p.amplitude_nm);
        json_values_set_number(b, "phase_rad", p.phase_rad);
        break;

        case DRIFT_MODEL_JUMP:
        json_values_set_number(b, "t_s", p.t_s);
        json_values_set_pair(b, "step_nm", p.step_nm);
        break;

        case DRIFT_MODEL_ACCELERATION:
        json_values_set_pair(b, "accel_nm_per_s2", p.accel_nm_per_s2);
        break;

        default:
        break;
    }
    json_builder_end_object(b);
    json_values_set_pair(b, "velocity_nm_per_s", p.velocity_nm_per_s);
}

/* The periods the series can show an oscillation with; none (null) when
 * the series is too short for its gaps. */
static void
add_period_range(JsonBuilder *b, const FitReport *report)
{
    gdouble range[2];

    json_builder_set_member_name(b, "observable_period_s");
    if (drift_fit_observable_periods(report->meas, report->n_meas,
                                     &report->fit_options,
                                     range, range + 1))
        json_values_add_pair(b, range);
    else
        json_builder_add_null_value(b);
}

static void
add_models(JsonBuilder *b, const FitReport *report)
{
    gint i;

    json_builder_set_member_name(b, "models");
    json_builder_begin_array(b);
    for (i = 0; i < report->n_fits; i++) {
        const DriftFit *fit = report->fits + i;

        json_builder_begin_object(b);
        json_builder_set_member_name(b, "name");
        json_builder_add_string_value(b, drift_model_type_name(fit->type));
        json_builder_set_member_name(b, "fitted");
        json_builder_add_boolean_value(b, fit->ok);
        if (fit->type == DRIFT_MODEL_OSCILLATION)
            add_period_range(b, report);
        json_values_set_number(b, "rms_nm", fit->rms_nm);
        /* The score is the Bayesian information criterion: lower is
         * better, and each parameter costs log(n). */
        json_values_set_number(b, "score", fit->bic);
        json_values_set_number(b, "cv_rms_nm", fit->cv_rms_nm);
        json_builder_set_member_name(b, "n_params");
        json_builder_add_int_value(b, fit->n_params);
        add_parameters(b, fit);
        json_builder_end_object(b);
    }
    json_builder_end_array(b);
}

static void
add_frames(JsonBuilder *b, const FrameSeries *series)
{
    gint i;

    json_builder_set_member_name(b, "frames");
    json_builder_begin_array(b);
    for (i = 0; i < series->n_frames; i++) {
        const SeriesFrame *f = series->frames + i;

        json_builder_begin_object(b);
        json_builder_set_member_name(b, "label");
        json_values_add_text(b, f->label);
        json_values_set_timing(b, "start_s", &f->timing);
        json_builder_end_object(b);
    }
    json_builder_end_array(b);
    json_builder_set_member_name(b, "notes");
    json_builder_begin_array(b);
    for (i = 0; i < (gint)series->notes->len; i++)
        json_values_add_text(b, g_ptr_array_index(series->notes, i));
    json_builder_end_array(b);
}

void
fit_report_add_members(JsonBuilder *b, const FitReport *report)
{
    gint i, used = 0;

    json_builder_set_member_name(b, "effect");
    json_builder_add_string_value(b, report->chosen >= 0
                                  ? drift_model_type_name(report->fits[report->chosen].type)
                                  : "none");
    if (report->chosen >= 0)
        add_parameters(b, report->fits + report->chosen);
    add_models(b, report);
    for (i = 0; i < report->n_meas; i++)
        used += (report->meas[i].weight > 0.0);
    json_builder_set_member_name(b, "n_measurements");
    json_builder_add_int_value(b, report->n_meas);
    json_builder_set_member_name(b, "n_measurements_used");
    json_builder_add_int_value(b, used);
}

gchar*
fit_report_to_json(const FitReport *report, const FrameSeries *series)
{
    JsonBuilder *b = json_builder_new();

    json_builder_begin_object(b);
    fit_report_add_members(b, report);
    if (series)
        add_frames(b, series);
    json_builder_end_object(b);
    return json_values_finish(b);
}
