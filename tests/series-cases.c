/*
 *  Simulated frame series corrected by the core and judged against the
 *  simulator's truth.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <string.h>
#include <math.h>
#include <libprocess/gwyprocess.h>
#include "scanner.h"
#include "sim-random.h"
#include "displacement-measure.h"
#include "registration-frames.h"
#include "series-cases.h"

/* The sizes of hidden-effect-cases.c: 1 um frames of 128 x 128 pixels
 * (7.8 nm), 0.5 s per line, frames back to back. */
#define RES 128
#define LINE_TIME 0.5
#define FRAME_TIME (RES*LINE_TIME)
#define FIELD 1e-6
#define MARGIN 0.3e-6
#define PARTICLE_RADIUS 20e-9

/* Raw-channel artefacts relative to the particles' height. */
#define RAW_SIZE 3.0

/* The disturbed frame slipped by this much (px) and came back. */
#define SLIP_X 6.0
#define SLIP_Y -4.0

/* Stripes of lines the corrected frames are judged in. */
#define JUDGE_STRIPES 8

/* Lines this close to a jump are left out of the trajectory error. */
#define JUMP_LINES 3
/* A line shows nothing when its mean square after its best quadratic
 * along the line stays below this (m^2): the noise of 0.2 nm alone gives
 * 4e-20, lines cutting particles 2e-17 to 1e-16. */
#define FEATURELESS_LINE 1e-18

static SimSample*
case_sample(guint32 base_seed, gint i)
{
    SimParticleParams pp;

    sim_particle_params_init(&pp);
    pp.xreal = pp.yreal = FIELD + 2.0*MARGIN;
    pp.radius = PARTICLE_RADIUS;
    pp.count = 90;
    return sim_sample_new_particles(&pp, base_seed + 1000*i);
}

static void
case_scan_params(SimScanParams *sp, const SimSample *sample, gint k)
{
    sim_scan_params_init(sp, sample, RES, RES);
    sp->xreal = sp->yreal = FIELD;
    sp->xoff = sp->yoff = MARGIN;
    sp->line_time = LINE_TIME;
    sp->frame_start = k*FRAME_TIME;
    sp->noise_rms = 0.2e-9;
}

FrameSeries*
series_case_scan(guint32 base_seed, gint i, const DriftModel *model,
                 const SeriesCaseOptions *options, GwyDataField ***truth)
{
    SimSample *sample = case_sample(base_seed, i);
    FrameSeries *series;
    SimScanParams sp;
    ScanTiming timing;
    DriftModel slipped;
    gint k;

    if (!sample)
        return NULL;
    series = frame_series_new();
    if (truth)
        *truth = g_new0(GwyDataField*, 2*SERIES_CASE_FRAMES);
    for (k = 0; k < SERIES_CASE_FRAMES; k++) {
        GwyDataField *field;
        gchar *label = g_strdup_printf("frame%d", k);

        case_scan_params(&sp, sample, k);
        sp.noise_seed = base_seed + 1000*i + k;
        drift_model_copy(&slipped, model);
        if (k == options->disturbed) {
            slipped.p0[0] += SLIP_X*FIELD/RES;
            slipped.p0[1] += SLIP_Y*FIELD/RES;
        }
        field = sim_scan_frame(sample, &slipped, &sp);
        drift_model_clear(&slipped);
        if (truth)
            (*truth)[SERIES_CASE_FRAMES + k] = gwy_data_field_duplicate(field);
        if (options->raw)
            frame_add_raw_artefacts(gwy_data_field_get_data(field), RES, RES,
                                    RAW_SIZE*2.0*PARTICLE_RADIUS,
                                    base_seed + 7919*i + k);
        sim_scan_params_timing(&sp, &timing);
        frame_series_append(series, field, label, &timing);
        if (truth)
            (*truth)[k] = sim_scan_truth(sample, &sp);
        g_object_unref(field);
        g_free(label);
    }
    sim_sample_free(sample);
    return series;
}

static gboolean
near_jump(const DriftModel *model, gdouble t)
{
    return (model->type == DRIFT_MODEL_JUMP
            && fabs(t - model->t_jump) < JUMP_LINES*LINE_TIME);
}

gdouble
series_case_line_texture(GwyDataField *field, gint r)
{
    gint xres = gwy_data_field_get_xres(field), c;
    const gdouble *row = gwy_data_field_get_data_const(field) + (gsize)r*xres;
    gdouble *u = g_new(gdouble, xres), coeffs[3], e, sum = 0.0;

    for (c = 0; c < xres; c++)
        u[c] = c;
    gwy_math_fit_polynom(xres, u, row, 2, coeffs);
    for (c = 0; c < xres; c++) {
        e = row[c] - (coeffs[0] + c*(coeffs[1] + c*coeffs[2]));
        sum += e*e;
    }
    g_free(u);
    return sum/xres;
}

/* Line r of a frame (scanned: its scan before raw artefacts), scanned at
 * t, lies where the correction reports that nothing places the jump's
 * lines, and shows nothing itself: its drift is a guess the data cannot
 * check, and the correction says so (a jump in frame 0's last
 * featureless lines before a flagged frame, seed 480000936). */
static gboolean
unplaceable(const SeriesCorrection *correction, GwyDataField *scanned, gint r,
            gdouble t)
{
    return (correction->jump_tied_lines > 0
            && t >= correction->jump_window[0]
            && t <= correction->jump_window[1]
            && series_case_line_texture(scanned, r) < FEATURELESS_LINE);
}

void
series_case_draw_walk(guint32 base_seed, gint i, gdouble sigma,
                      DriftModel *model)
{
    SimRandom rng;
    gdouble speed, angle;

    sim_random_init(&rng, base_seed, 500 + i);
    drift_model_init(model, DRIFT_MODEL_RANDOM_WALK);
    speed = 0.1e-9*sim_random_uniform(&rng);
    angle = 2.0*G_PI*sim_random_uniform(&rng);
    model->v[0] = speed*cos(angle);
    model->v[1] = speed*sin(angle);
    model->walk_sigma = sigma*1e-9;
    model->walk_dt = 2.0;
    model->walk_seed = base_seed + 17*i;
    drift_model_prepare(model, 2.0*SERIES_CASE_FRAMES*FRAME_TIME);
}

static void
judge_trajectory(const SeriesCorrection *correction,
                 const FrameSeries *series, GwyDataField **truth,
                 const DriftModel *model, const SeriesCaseOptions *options,
                 SeriesCaseResult *result)
{
    const DriftFit *fit = correction->fit.fits + correction->fit.chosen;
    gdouble sum = 0.0, worst = 0.0, x0, y0, x, y, fx, fy, t, e, ex, ey;
    gdouble mean[2] = { 0.0, 0.0 }, msum = 0.0, mmean[2] = { 0.0, 0.0 };
    gdouble mx, my, mx0, my0;
    gint k, r, count = 0;

    drift_model_eval(model, 0.0, &x0, &y0);
    for (k = 0; k < series->n_frames; k++) {
        const ScanTiming *timing = &series->frames[k].timing;

        if (k == options->disturbed)
            continue;
        for (r = 0; r < timing->yres; r++) {
            t = scan_timing_rows_time(timing, r, r+1);
            if (near_jump(model, t)
                || unplaceable(correction, truth[SERIES_CASE_FRAMES + k], r, t))
                continue;
            drift_model_eval(model, t, &x, &y);
            series_correction_eval(correction, t, &fx, &fy);
            ex = fx - (x - x0)/correction->xstep;
            ey = fy - (y - y0)/correction->ystep;
            e = hypot(ex, ey);
            mean[0] += ex;
            mean[1] += ey;
            sum += e*e;
            drift_fit_eval(fit, t, &mx, &my);
            drift_fit_eval(fit, 0.0, &mx0, &my0);
            mx = (mx - mx0 - (x - x0))/correction->xstep;
            my = (my - my0 - (y - y0))/correction->ystep;
            mmean[0] += mx;
            mmean[1] += my;
            msum += mx*mx + my*my;
            worst = MAX(worst, e);
            count++;
        }
    }
    result->trajectory_rms_px = sqrt(sum/MAX(count, 1));
    result->trajectory_worst_px = worst;
    mean[0] /= MAX(count, 1);
    mean[1] /= MAX(count, 1);
    result->trajectory_relative_px
        = sqrt(MAX(sum/MAX(count, 1) - mean[0]*mean[0] - mean[1]*mean[1], 0.0));
    result->smooth_used = correction->use_smooth;
    mmean[0] /= MAX(count, 1);
    mmean[1] /= MAX(count, 1);
    result->model_relative_px
        = sqrt(MAX(msum/MAX(count, 1) - mmean[0]*mmean[0] - mmean[1]*mmean[1], 0.0));
}

/* What a stripe of the corrected frame keeps of the drift: the trajectory's
 * error averaged over the stripe's lines (frames disturbed on purpose and
 * lines near a jump left out). */
static void
judge_stripes(const SeriesCorrection *correction, const FrameSeries *series,
              GwyDataField **truth, const DriftModel *model,
              const SeriesCaseOptions *options, SeriesCaseResult *result)
{
    gdouble x0, y0, x, y, fx, fy, t, sum[2];
    gint k, s, r, count;

    drift_model_eval(model, 0.0, &x0, &y0);
    result->stripe_worst_px = 0.0;
    for (k = 0; k < series->n_frames; k++) {
        const ScanTiming *timing = &series->frames[k].timing;

        for (s = 0; s < JUDGE_STRIPES && k != options->disturbed; s++) {
            sum[0] = sum[1] = 0.0;
            count = 0;
            for (r = s*RES/JUDGE_STRIPES; r < (s + 1)*RES/JUDGE_STRIPES; r++) {
                t = scan_timing_rows_time(timing, r, r+1);
                if (near_jump(model, t)
                    || unplaceable(correction, truth[SERIES_CASE_FRAMES + k],
                                   r, t))
                    continue;
                drift_model_eval(model, t, &x, &y);
                series_correction_eval(correction, t, &fx, &fy);
                sum[0] += fx - (x - x0)/correction->xstep;
                sum[1] += fy - (y - y0)/correction->ystep;
                count++;
            }
            if (count)
                result->stripe_worst_px = MAX(result->stripe_worst_px,
                                              hypot(sum[0], sum[1])/count);
        }
    }
}

/* Each clean frame corrected and registered as a whole against the
 * drift-free truth: that the correction moves content the right way. */
static gboolean
judge_frames(const SeriesCorrection *correction, const FrameSeries *series,
             GwyDataField **truth, const DriftModel *model,
             const SeriesCaseOptions *options, SeriesCaseResult *result)
{
    gdouble dx, dy, score, p0[2];
    gint k;

    /* The corrected frames show the sample as it was at t = 0, displaced
     * by p(0) from the drift-free truth. */
    drift_model_eval(model, 0.0, p0, p0 + 1);
    p0[0] /= correction->xstep;
    p0[1] /= correction->ystep;
    result->frame_worst_px = 0.0;
    for (k = 0; k < series->n_frames; k++) {
        GwyDataField *field = truth[SERIES_CASE_FRAMES + k];
        GwyDataField *fixed = gwy_data_field_new_alike(field, FALSE);
        GwyDataField *mask = gwy_data_field_new_alike(field, FALSE);
        gboolean ok;

        /* The clean scan of the frame: raw artefacts spoil the measurement,
         * which the trajectory carries, not this comparison. */
        ok = series_correction_correct_field(correction, field,
                                             &series->frames[k].timing,
                                             GWY_INTERPOLATION_BSPLINE,
                                             fixed, mask, NULL);
        if (ok && k != options->disturbed) {
            displacement_register_blocks(gwy_data_field_get_data_const(fixed),
                                         gwy_data_field_get_data_const(truth[k]),
                                         RES, RES, 1, NULL, 1.0, NULL,
                                         &dx, &dy, &score, NULL);
            result->frame_worst_px = MAX(result->frame_worst_px,
                                         score > 0.0
                                         ? hypot(dx - p0[0], dy - p0[1])
                                         : G_MAXDOUBLE);
        }
        g_object_unref(fixed);
        g_object_unref(mask);
        if (!ok)
            return FALSE;
    }
    return TRUE;
}

gboolean
series_case_judge(const FrameSeries *series, GwyDataField **truth,
                  const DriftModel *model, const SeriesCaseOptions *options,
                  SeriesCaseResult *result)
{
    SeriesCorrection correction;
    gboolean ok;
    gint k;

    memset(result, 0, sizeof(SeriesCaseResult));
    if (!series_correction_compute(series, NULL, NULL, &correction, NULL)) {
        series_correction_clear(&correction);
        return FALSE;
    }
    judge_trajectory(&correction, series, truth, model, options, result);
    judge_stripes(&correction, series, truth, model, options, result);
    ok = judge_frames(&correction, series, truth, model, options, result);
    result->effect_named
        = (correction.fit.fits[correction.fit.chosen].type == model->type);
    for (k = 0; k < series->n_frames; k++) {
        result->flagged += correction.frames[k].flagged;
        if (k == options->disturbed && correction.frames[k].flagged)
            result->disturbed_flagged = TRUE;
    }
    series_correction_clear(&correction);
    return ok;
}
