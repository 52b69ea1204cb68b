/*
 *  One simscan experiment judged three ways: the contaminated image, paper
 *  mode and continuous mode.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <math.h>
#include <string.h>
#include "continuous-compensate.h"
#include "paper-compensate.h"
#include "stripe-geometry.h"
#include "particle-detect.h"
#include "simscan-run.h"
#include "continuous-simscan-case.h"

/* Knots per image row of the exact trajectory: the spline through them is
 * then exact to far below a thousandth of a pixel. */
#define EXACT_KNOTS_PER_ROW 1

typedef struct {
    const SimscanScene *scene;
    const SimscanMeasurement *m;
    gdouble r_px;
    gdouble match;
    gdouble dx_m, dy_m;
} Judge;

/* Where every particle should be in an image showing the sample as it was
 * at time t (per particle when times is not NULL). */
static gdouble*
truth_at(const SimscanScene *scene, gdouble t, const gdouble *times)
{
    gint n = sim_sample_n_particles(scene->sample), i;
    gdouble *truth = g_new(gdouble, 2*MAX(n, 1)), x, y, px, py;

    for (i = 0; i < n; i++) {
        sim_sample_particle(scene->sample, i, &x, &y, NULL);
        drift_model_eval(&scene->drift, times ? times[i] : t, &px, &py);
        truth[2*i] = simscan_scene_column(scene, x + px);
        truth[2*i + 1] = simscan_scene_row(scene, y + py);
    }
    return truth;
}

static void
judge_field(const Judge *judge, GwyDataField *field, const gdouble *truth,
            CentreError *error)
{
    const SimscanScene *scene = judge->scene;
    GArray *found = particle_detect(field, &scene->detect, NULL, NULL);

    centre_error_measure(found, truth, truth,
                         sim_sample_n_particles(scene->sample),
                         scene->scan.xres, scene->scan.yres,
                         judge->r_px + 2.0, judge->match,
                         judge->dx_m, judge->dy_m, error);
    g_array_free(found, TRUE);
}

/* The stripe whose drift paper mode applies to stripe s: itself when
 * measured, else the nearest measured one (lower index on a tie). */
static gint
stripe_used(const SimscanMeasurement *m, gint s)
{
    gint d;

    for (d = 0; d < m->n_stripes; d++) {
        if (s - d >= 0 && m->scans[s - d].found)
            return s - d;
        if (s + d < m->n_stripes && m->scans[s + d].found)
            return s + d;
    }
    return s;
}

/* The sample as it was at t scanned without drift or noise: what a perfect
 * compensation showing that moment would give, and the detector's own error
 * on it. */
static void
judge_truth_image(const Judge *judge, gdouble t, CentreError *error)
{
    const SimscanScene *scene = judge->scene;
    SimScanParams params = scene->scan;
    GwyDataField *field;
    gdouble *truth, px, py;

    drift_model_eval(&scene->drift, t, &px, &py);
    params.xoff -= px;
    params.yoff -= py;
    field = sim_scan_truth(scene->sample, &params);
    truth = truth_at(scene, t, NULL);
    judge_field(judge, field, truth, error);
    g_free(truth);
    g_object_unref(field);
}

/* Paper mode shows each stripe as it was at the local scan of the stripe
 * whose drift moved it. */
static void
judge_paper(const Judge *judge, CentreError *error)
{
    const SimscanScene *scene = judge->scene;
    const SimscanMeasurement *m = judge->m;
    gint n = sim_sample_n_particles(scene->sample), yres = scene->scan.yres;
    gdouble *times = g_new(gdouble, MAX(n, 1)), *truth;
    gint i, row;

    for (i = 0; i < n; i++) {
        row = CLAMP((gint)floor(m->truth_px[2*i + 1] + 0.5), 0, yres-1);
        times[i] = m->scans[stripe_used(m, stripe_of_row(row, m->n_stripes,
                                                         yres))].t_local;
    }
    truth = truth_at(scene, 0.0, times);
    judge_field(judge, m->compensated, truth, error);
    g_free(truth);
    g_free(times);
}

static gboolean
judge_continuous(const Judge *judge, const DriftTrajectory *trajectory,
                 GwyInterpolationType interpolation, CentreError *error,
                 GError **gerror)
{
    const SimscanScene *scene = judge->scene;
    GwyDataField *image = scene->image;
    GwyDataField *result = gwy_data_field_new_alike(image, FALSE);
    gint xres = scene->scan.xres, yres = scene->scan.yres;
    const gdouble *a = gwy_data_field_get_data_const(image);
    gdouble *truth;
    gboolean ok;

    ok = continuous_compensate_trajectory(a, xres, yres, trajectory,
                                          &scene->timing, interpolation,
                                          paper_image_mean(a, xres, yres),
                                          gwy_data_field_get_data(result),
                                          NULL, gerror);
    if (ok) {
        gwy_data_field_invalidate(result);
        truth = truth_at(scene,
                         drift_trajectory_reference_time(trajectory), NULL);
        judge_field(judge, result, truth, error);
        g_free(truth);
    }
    g_object_unref(result);
    return ok;
}

/* The table with the local scans' dx_exact, dy_exact replaced by what a
 * perfect local scan measures (same times). */
static DriftTable*
perfect_table(const SimscanMeasurement *m)
{
    DriftTable *table = drift_table_copy(m->table);
    gint s;

    for (s = 0; s < m->n_stripes; s++) {
        if (!table->rows[s].has_drift)
            continue;
        drift_table_set_extra(table, s, "dx_exact", m->true_dx[s]);
        drift_table_set_extra(table, s, "dy_exact", m->true_dy[s]);
    }
    return table;
}

/* The drift model itself, sampled at every line, as seen from t_ref. */
static DriftTrajectory*
exact_trajectory(const SimscanScene *scene, gdouble t_ref)
{
    gint yres = scene->scan.yres, n = EXACT_KNOTS_PER_ROW*yres + 1, k;
    gdouble t_end = scan_timing_frame_end(&scene->timing);
    gdouble t0 = scene->timing.frame_start, sx = scene->scan.xres/scene->scan.xreal;
    gdouble sy = yres/scene->scan.yreal, rx, ry, px, py;
    DriftMeasurement *meas = g_new(DriftMeasurement, n);
    DriftTrajectory *trajectory;

    drift_model_eval(&scene->drift, t_ref, &rx, &ry);
    for (k = 0; k < n; k++) {
        meas[k].t_a = t0 + (t_end - t0)*k/(n - 1.0);
        meas[k].t_b = t_ref;
        drift_model_eval(&scene->drift, meas[k].t_a, &px, &py);
        meas[k].dx = (px - rx)*sx;
        meas[k].dy = (py - ry)*sy;
    }
    trajectory = drift_trajectory_new(meas, n, NULL);
    g_free(meas);
    return trajectory;
}

/* The sample particle nearest to (col, row) as the image shows them. */
static gint
nearest_shown(const SimscanMeasurement *m, gdouble col, gdouble row)
{
    gdouble best = G_MAXDOUBLE, d2;
    gint i, found = 0;

    for (i = 0; i < m->n_particles; i++) {
        d2 = ((m->shown_px[2*i] - col)*(m->shown_px[2*i] - col)
              + (m->shown_px[2*i + 1] - row)*(m->shown_px[2*i + 1] - row));
        if (d2 < best) {
            best = d2;
            found = i;
        }
    }
    return found;
}

/* The local scans' error, and its two parts: the displayed centre found in
 * the image, and the actual centre found by the local scan. */
static void
measurement_error(const SimscanScene *scene, const SimscanMeasurement *m,
                  AccuracyCase *result)
{
    gdouble sum = 0.0, sum_disp = 0.0, sum_act = 0.0, ex, ey, x, y, px, py;
    const LocalScanParticle *scan;
    gint s, i;

    result->n_measured = 0;
    for (s = 0; s < m->n_stripes; s++) {
        scan = m->scans + s;
        if (!scan->found)
            continue;
        ex = scan->dx - m->true_dx[s];
        ey = scan->dy - m->true_dy[s];
        sum += ex*ex + ey*ey;
        i = nearest_shown(m, scan->x_disp, scan->y_disp);
        ex = scan->x_disp - m->shown_px[2*i];
        ey = scan->y_disp - m->shown_px[2*i + 1];
        sum_disp += ex*ex + ey*ey;
        sim_sample_particle(scene->sample, i, &x, &y, NULL);
        drift_model_eval(&scene->drift, scan->t_local, &px, &py);
        ex = scan->x_act - simscan_scene_column(scene, x + px);
        ey = scan->y_act - simscan_scene_row(scene, y + py);
        sum_act += ex*ex + ey*ey;
        result->n_measured++;
    }
    if (result->n_measured) {
        result->measurement_rms_px = sqrt(sum/result->n_measured);
        result->displayed_rms_px = sqrt(sum_disp/result->n_measured);
        result->actual_rms_px = sqrt(sum_act/result->n_measured);
    }
}

static gboolean
judge_all(const Judge *judge, GwyInterpolationType interpolation,
          AccuracyCase *result, GError **error)
{
    const SimscanScene *scene = judge->scene;
    const SimscanMeasurement *m = judge->m;
    DriftTrajectory *trajectory;
    DriftTable *table;
    gboolean ok;

    result->error[ACCURACY_BEFORE] = m->before;
    result->error[ACCURACY_PAPER_SIMSCAN_REF] = m->after;
    judge_paper(judge, result->error + ACCURACY_PAPER);
    measurement_error(scene, m, result);

    trajectory = drift_trajectory_new_from_table(m->table, judge->dx_m,
                                                 judge->dy_m, &scene->timing,
                                                 error);
    if (!trajectory)
        return FALSE;
    result->t_ref = drift_trajectory_reference_time(trajectory);
    judge_truth_image(judge, result->t_ref, result->error + ACCURACY_TRUTH);
    ok = judge_continuous(judge, trajectory, interpolation,
                          result->error + ACCURACY_CONTINUOUS, error);
    drift_trajectory_free(trajectory);
    if (!ok)
        return FALSE;

    table = perfect_table(m);
    trajectory = drift_trajectory_new_from_table(table, judge->dx_m,
                                                 judge->dy_m, &scene->timing,
                                                 error);
    drift_table_free(table);
    if (!trajectory)
        return FALSE;
    ok = judge_continuous(judge, trajectory, interpolation,
                          result->error + ACCURACY_CONTINUOUS_TRUE_TABLE,
                          error);
    drift_trajectory_free(trajectory);
    if (!ok)
        return FALSE;

    trajectory = exact_trajectory(scene, result->t_ref);
    ok = judge_continuous(judge, trajectory, interpolation,
                          result->error + ACCURACY_CONTINUOUS_EXACT, error);
    drift_trajectory_free(trajectory);
    return ok;
}

gboolean
accuracy_case_run(const SimscanConfig *config,
                  GwyInterpolationType interpolation,
                  AccuracyCase *result, GError **error)
{
    SimscanScene *scene;
    SimscanMeasurement *m;
    Judge judge;
    gboolean ok;

    memset(result, 0, sizeof(AccuracyCase));
    if (!(scene = simscan_scene_new(config, NULL, error)))
        return FALSE;
    if (!(m = simscan_measure(scene, config->n_stripes, error))) {
        simscan_scene_free(scene);
        return FALSE;
    }
    judge.scene = scene;
    judge.m = m;
    judge.dx_m = gwy_data_field_get_dx(scene->image);
    judge.dy_m = gwy_data_field_get_dy(scene->image);
    judge.r_px = config->particles.radius/judge.dx_m;
    judge.match = fmax(2.0, 0.45*config->particles.min_spacing/judge.dx_m);
    ok = m->have_errors && judge_all(&judge, interpolation, result, error);
    simscan_measurement_free(m);
    simscan_scene_free(scene);
    return ok;
}
