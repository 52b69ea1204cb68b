/*
 *  Correcting a whole frame series: measure, fit one trajectory, flag the
 *  frames that disagree, correct every frame line by line.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <string.h>
#include <math.h>
#include <libprocess/gwyprocess.h>
#include "json-values.h"
#include "continuous-compensate.h"
#include "drift-trajectory.h"
#include "series-correction.h"
#include "localscan-intl.h"

/* A frame is flagged when even its best-agreeing pair lies this many times
 * the series' typical pair residual from the trajectory, and at least
 * FLAG_FLOOR_PX: below a pixel a disagreement does not spoil a corrected
 * frame, whatever the series' noise. */
#define FLAG_RATIO 4.0
#define FLAG_FLOOR_PX 1.0

/* A pair counts as registered with this many accepted blocks. */
#define PAIR_MIN_BLOCKS 3

/* Residuals this large (px RMS) mean the chosen model does not follow the
 * drift: the corrected frames then keep that much of it. */
#define MODEL_WARN_PX 1.0

GQuark
series_correction_error_quark(void)
{
    return g_quark_from_static_string("series-correction-error-quark");
}

static void
add_warning(SeriesCorrection *correction, gchar *text)
{
    g_ptr_array_add(correction->warnings, text);
}

/* The fit of every model to the measurements whose weight in `weights` is
 * positive; measurements the fit cuts as gross outliers get weight 0. */
static gboolean
fit_models(SeriesCorrection *correction, const gdouble *weights)
{
    FitReport *fit = &correction->fit;
    gboolean *kept = g_new(gboolean, MAX(fit->n_meas, 1));
    gint i;

    for (i = 0; i < fit->n_meas; i++)
        fit->meas[i].weight = weights[i];
    fit->chosen = drift_fit_select_kept(fit->meas, fit->n_meas,
                                        &fit->fit_options, fit->fits, kept);
    for (i = 0; i < fit->n_meas; i++) {
        if (!kept[i])
            fit->meas[i].weight = 0.0;
    }
    g_free(kept);
    return fit->chosen >= 0;
}

static gint
compare_doubles(gconstpointer a, gconstpointer b)
{
    gdouble x = *(const gdouble*)a, y = *(const gdouble*)b;

    return (x > y) - (x < y);
}

static gdouble
median_of(gdouble *values, gint n)
{
    if (n <= 0)
        return NAN;
    qsort(values, n, sizeof(gdouble), compare_doubles);
    return (n % 2) ? values[n/2] : 0.5*(values[n/2 - 1] + values[n/2]);
}

/* |measured - fitted| of a measurement in pixels. */
static gdouble
residual_px(const SeriesCorrection *correction, const DriftMeasurement *m)
{
    const DriftFit *fit = correction->fit.fits + correction->fit.chosen;
    gdouble dx, dy;

    drift_fit_predict(fit, m, &dx, &dy);
    return hypot((m->dx - dx)/correction->xstep,
                 (m->dy - dy)/correction->ystep);
}

/* Each frame's residual is that of its best-agreeing pair: a disturbed
 * frame disagrees with every partner, its partners agree with others. */
static void
judge_frames(SeriesCorrection *correction, const gdouble *registered)
{
    const FitReport *fit = &correction->fit;
    gint nf = correction->n_frames, i, a, b, count;
    gdouble *values = g_new(gdouble, MAX(fit->n_meas, nf) + 1), r;

    for (a = 0; a < nf; a++) {
        correction->frames[a].residual_px = NAN;
        correction->frames[a].n_pairs = 0;
    }
    for (a = 1; a < nf; a++) {
        for (b = 0; b < a; b++) {
            count = 0;
            for (i = 0; i < fit->n_meas; i++) {
                const DriftMeasurement *m = fit->meas + i;

                if (m->frame_a == a && m->frame_b == b && registered[i] > 0.0)
                    values[count++] = residual_px(correction, m);
            }
            if (count < PAIR_MIN_BLOCKS)
                continue;
            r = median_of(values, count);
            for (i = 0; i < 2; i++) {
                SeriesFrameVerdict *v = correction->frames + (i ? b : a);

                v->n_pairs++;
                if (!(v->residual_px <= r))
                    v->residual_px = r;
            }
        }
    }
    count = 0;
    for (a = 0; a < nf; a++) {
        if (isfinite(correction->frames[a].residual_px))
            values[count++] = correction->frames[a].residual_px;
    }
    correction->typical_px = median_of(values, count);
    g_free(values);
}

static void
flag_frames(SeriesCorrection *correction)
{
    gdouble limit = MAX(FLAG_RATIO*correction->typical_px, FLAG_FLOOR_PX);
    gint a;

    for (a = 0; a < correction->n_frames; a++) {
        SeriesFrameVerdict *v = correction->frames + a;

        if (v->flagged)
            continue;
        if (!v->n_pairs) {
            v->flagged = TRUE;
            v->reason = g_strdup(_("could not be registered against any "
                                   "other frame"));
        }
        else if (v->residual_px > limit) {
            v->flagged = TRUE;
            v->reason = g_strdup_printf(_("disagrees with the trajectory of "
                                          "the other frames by %.2f px "
                                          "(typical %.2f px)"),
                                        v->residual_px,
                                        correction->typical_px);
        }
    }
}

/* The measurements of flagged frames get weight 0; TRUE when any did. */
static gboolean
drop_flagged(SeriesCorrection *correction, const gdouble *registered,
             gdouble *weights)
{
    const FitReport *fit = &correction->fit;
    gboolean any = FALSE;
    gint i;

    for (i = 0; i < fit->n_meas; i++) {
        const DriftMeasurement *m = fit->meas + i;

        weights[i] = registered[i];
        if (correction->frames[m->frame_a].flagged
            || correction->frames[m->frame_b].flagged) {
            any |= (weights[i] > 0.0);
            weights[i] = 0.0;
        }
    }
    return any;
}

static void
warn_about_fit(SeriesCorrection *correction, const gdouble *registered)
{
    const FitReport *fit = &correction->fit;
    const DriftFit *chosen = fit->fits + fit->chosen;
    gint i, n_reg = 0;
    gdouble rms_px;

    for (i = 0; i < fit->n_meas; i++)
        n_reg += (registered[i] > 0.0);
    if (2*n_reg < fit->n_meas)
        add_warning(correction,
                    g_strdup_printf(_("only %d of %d blocks could be "
                                      "registered: the trajectory rests on "
                                      "few measurements"),
                                    n_reg, fit->n_meas));
    rms_px = 1e-9*chosen->rms_nm/MIN(correction->xstep, correction->ystep);
    if (rms_px > MODEL_WARN_PX)
        add_warning(correction,
                    g_strdup_printf(_("the fitted model leaves %.2f px RMS "
                                      "between the measurements: the "
                                      "corrected frames keep drift of that "
                                      "order"), rms_px));
}

static void
prepare_options(const FrameSeries *series, const DisplacementOptions *doptions,
                const DriftFitOptions *foptions, DisplacementOptions *d,
                DriftFitOptions *f)
{
    const ScanTiming *timing = &series->frames[0].timing;

    if (doptions)
        *d = *doptions;
    else {
        displacement_options_init(d);
        d->n_blocks = MIN(d->n_blocks, MAX(timing->yres/4, 1));
        if (series->n_frames > SERIES_CORRECTION_ALL_PAIRS_UP_TO)
            d->pair_reach = SERIES_CORRECTION_PAIR_REACH;
    }
    if (foptions)
        *f = *foptions;
    else
        drift_fit_options_init(f);
    if (f->min_period <= 0.0)
        f->min_period = drift_fit_min_period(timing->line_time, timing->yres,
                                             d->n_blocks);
}

gboolean
series_correction_compute(const FrameSeries *series,
                          const DisplacementOptions *doptions,
                          const DriftFitOptions *foptions,
                          SeriesCorrection *correction, GError **error)
{
    DisplacementOptions d;
    FitReport *fit = &correction->fit;
    gdouble *registered, *weights;
    gboolean ok;
    guint i;

    memset(correction, 0, sizeof(SeriesCorrection));
    correction->n_frames = series->n_frames;
    correction->frames = g_new0(SeriesFrameVerdict, series->n_frames);
    correction->warnings = g_ptr_array_new_with_free_func(g_free);
    correction->xstep = frame_series_dx(series);
    correction->ystep = frame_series_dy(series);
    for (i = 0; i < series->notes->len; i++)
        add_warning(correction,
                    g_strdup(g_ptr_array_index(series->notes, i)));
    prepare_options(series, doptions, foptions, &d, &fit->fit_options);
    fit->meas = displacement_measure_series(series, &d, &fit->n_meas);
    drift_fit_candidates(&fit->n_fits);
    registered = g_new(gdouble, 2*MAX(fit->n_meas, 1));
    weights = registered + MAX(fit->n_meas, 1);
    for (i = 0; i < (guint)fit->n_meas; i++)
        registered[i] = fit->meas[i].weight;
    /* Disturbed frames are judged against the fit of all, then left out;
     * the frames are judged again against the fit without them. */
    if ((ok = fit_models(correction, registered))) {
        judge_frames(correction, registered);
        flag_frames(correction);
        if (drop_flagged(correction, registered, weights)
            && !fit_models(correction, weights)) {
            /* Too little was left: keep every frame in the fit. */
            ok = fit_models(correction, registered);
        }
    }
    if (ok) {
        judge_frames(correction, registered);
        flag_frames(correction);
        warn_about_fit(correction, registered);
    }
    else
        g_set_error(error, SERIES_CORRECTION_ERROR,
                    SERIES_CORRECTION_ERROR_FIT,
                    _("too few blocks of the frames could be registered "
                      "against each other to fit a drift trajectory"));
    g_free(registered);
    return ok;
}

void
series_correction_clear(SeriesCorrection *correction)
{
    gint k;

    fit_report_clear(&correction->fit);
    for (k = 0; k < correction->n_frames && correction->frames; k++)
        g_free(correction->frames[k].reason);
    g_free(correction->frames);
    correction->frames = NULL;
    if (correction->warnings)
        g_ptr_array_free(correction->warnings, TRUE);
    correction->warnings = NULL;
}

void
series_correction_eval(const SeriesCorrection *correction, gdouble t,
                       gdouble *dx_px, gdouble *dy_px)
{
    const DriftFit *fit = correction->fit.fits + correction->fit.chosen;
    gdouble x, y, x0, y0;

    drift_fit_eval(fit, t, &x, &y);
    drift_fit_eval(fit, 0.0, &x0, &y0);
    *dx_px = (x - x0)/correction->xstep;
    *dy_px = (y - y0)/correction->ystep;
}

/* Which side of a jump a trajectory follows: the fit itself, the drift
 * without the step, or with the step from the start. */
typedef enum {
    JUMP_AS_FITTED,
    JUMP_NEVER,
    JUMP_ALWAYS,
} JumpSide;

static void
eval_side(const SeriesCorrection *correction, gdouble t, JumpSide side,
          gdouble *dx, gdouble *dy)
{
    const DriftFit *fit = correction->fit.fits + correction->fit.chosen;
    gdouble sign = 0.0;

    series_correction_eval(correction, t, dx, dy);
    if (side == JUMP_NEVER && t >= fit->nonlinear)
        sign = -1.0;
    else if (side == JUMP_ALWAYS && t < fit->nonlinear)
        sign = 1.0;
    *dx += sign*1e-9*fit->coef[0][1]/correction->xstep;
    *dy += sign*1e-9*fit->coef[1][1]/correction->ystep;
}

/* The trajectory over a frame sampled at every line, as a spline the
 * continuous compensation can follow: t_b = 0 makes t = 0 the moment the
 * corrected frame shows. */
static DriftTrajectory*
frame_trajectory(const SeriesCorrection *correction, const ScanTiming *timing,
                 JumpSide side, GError **error)
{
    gint yres = timing->yres, n = yres + 2, r;
    DriftMeasurement *meas = g_new0(DriftMeasurement, n);
    DriftTrajectory *trajectory;

    for (r = 0; r < n; r++) {
        DriftMeasurement *m = meas + r;

        if (r == 0)
            m->t_a = timing->frame_start;
        else if (r == n-1)
            m->t_a = scan_timing_frame_end(timing);
        else
            m->t_a = scan_timing_rows_time(timing, r-1, r);
        eval_side(correction, m->t_a, side, &m->dx, &m->dy);
        m->weight = 1.0;
    }
    /* Scanning up, the rows' times fall; the spline sorts by time. */
    trajectory = drift_trajectory_new_interpolating(meas, n, error);
    g_free(meas);
    return trajectory;
}

/* A fitted jump while this frame was scanned, or not. */
static gboolean
jump_in_frame(const SeriesCorrection *correction, const ScanTiming *timing)
{
    const DriftFit *fit = correction->fit.fits + correction->fit.chosen;
    gdouble t0 = timing->frame_start, t1 = scan_timing_frame_end(timing);

    return (fit->type == DRIFT_MODEL_JUMP && fit->creep == DRIFT_FIT_CREEP_NONE
            && fit->nonlinear > t0 && fit->nonlinear < t1);
}

static gboolean
compensate_with(const SeriesCorrection *correction, const gdouble *data,
                const ScanTiming *timing, JumpSide side,
                GwyInterpolationType interpolation, gdouble fill,
                gdouble *result, gdouble *mask, GError **error)
{
    DriftTrajectory *trajectory;
    gboolean ok;

    if (!(trajectory = frame_trajectory(correction, timing, side, error)))
        return FALSE;
    ok = continuous_compensate_trajectory(data, timing->xres, timing->yres,
                                          trajectory, timing, interpolation,
                                          fill, result, mask, error);
    drift_trajectory_free(trajectory);
    return ok;
}

/* No trajectory through a jump can be followed line by line: the lines
 * before it are corrected with the drift before it (continued), the lines
 * after with the drift after it, each from its own lines only (the others
 * missing), and the two joined. */
static gboolean
compensate_across_jump(const SeriesCorrection *correction,
                       const gdouble *data, const ScanTiming *timing,
                       GwyInterpolationType interpolation, gdouble fill,
                       gdouble *result, gdouble *mask, GError **error)
{
    const DriftFit *fit = correction->fit.fits + correction->fit.chosen;
    gint xres = timing->xres, yres = timing->yres, r, c, side;
    gsize n = (gsize)xres*yres;
    gdouble *part = g_new(gdouble, 3*n), *pres = part + n, *pmask = pres + n;
    gboolean ok = TRUE;

    for (side = 0; side < 2 && ok; side++) {
        for (r = 0; r < yres; r++) {
            gboolean after = (scan_timing_rows_time(timing, r, r+1)
                              >= fit->nonlinear);

            for (c = 0; c < xres; c++)
                part[r*xres + c] = (after == side) ? data[r*xres + c] : NAN;
        }
        ok = compensate_with(correction, part, timing,
                             side ? JUMP_ALWAYS : JUMP_NEVER, interpolation,
                             fill, side ? pres : result,
                             side ? pmask : mask, error);
    }
    for (c = 0; ok && c < (gint)n; c++) {
        if (mask[c] > 0.0 && pmask[c] <= 0.0) {
            result[c] = pres[c];
            mask[c] = 0.0;
        }
    }
    g_free(part);
    return ok;
}

gboolean
series_correction_correct_field(const SeriesCorrection *correction,
                                GwyDataField *field, const ScanTiming *timing,
                                GwyInterpolationType interpolation,
                                GwyDataField *result, GwyDataField *mask,
                                GError **error)
{
    gint xres = gwy_data_field_get_xres(field);
    gint yres = gwy_data_field_get_yres(field);
    const gdouble *data = gwy_data_field_get_data_const(field);
    gdouble fill = gwy_data_field_get_avg(field);
    gboolean ok;

    g_return_val_if_fail(timing->xres == xres && timing->yres == yres, FALSE);
    gwy_data_field_resample(result, xres, yres, GWY_INTERPOLATION_NONE);
    gwy_data_field_resample(mask, xres, yres, GWY_INTERPOLATION_NONE);
    gwy_data_field_copy(field, result, FALSE);
    gwy_data_field_copy(field, mask, FALSE);
    gwy_si_unit_set_from_string(gwy_data_field_get_si_unit_z(mask), NULL);
    if (jump_in_frame(correction, timing))
        ok = compensate_across_jump(correction, data, timing, interpolation,
                                    fill, gwy_data_field_get_data(result),
                                    gwy_data_field_get_data(mask), error);
    else
        ok = compensate_with(correction, data, timing, JUMP_AS_FITTED,
                             interpolation, fill,
                             gwy_data_field_get_data(result),
                             gwy_data_field_get_data(mask), error);
    gwy_data_field_invalidate(result);
    gwy_data_field_invalidate(mask);
    return ok;
}

gboolean
series_correction_correct_frame(const SeriesCorrection *correction,
                                const FrameSeries *series, gint k,
                                GwyInterpolationType interpolation,
                                GwyDataField *result, GwyDataField *mask,
                                GError **error)
{
    const SeriesFrame *frame = series->frames + k;

    return series_correction_correct_field(correction, frame->field,
                                           &frame->timing, interpolation,
                                           result, mask, error);
}

gchar*
series_correction_trajectory_csv(const SeriesCorrection *correction,
                                 const FrameSeries *series)
{
    GString *text = g_string_new(NULL);
    gchar t[G_ASCII_DTOSTR_BUF_SIZE], x[G_ASCII_DTOSTR_BUF_SIZE],
          y[G_ASCII_DTOSTR_BUF_SIZE];
    gint k, i, r;

    g_string_append(text, "# drift trajectory p(t) - p(0), t = 0 at the "
                    "start of the first frame, t_s the centre of the line's "
                    "trace\n");
    g_string_append_printf(text, "# pixels of the first frame: dx %s m, ",
                           g_ascii_formatd(x, sizeof(x), "%.6g",
                                           correction->xstep));
    g_string_append_printf(text, "dy %s m\n",
                           g_ascii_formatd(y, sizeof(y), "%.6g",
                                           correction->ystep));
    g_string_append(text, "frame,row,t_s,dx_px,dy_px\n");
    for (k = 0; k < series->n_frames; k++) {
        const ScanTiming *timing = &series->frames[k].timing;

        for (i = 0; i < timing->yres; i++) {
            gdouble dx, dy, when;

            r = (timing->direction == SCAN_DIRECTION_UP) ? timing->yres-1 - i : i;
            when = scan_timing_rows_time(timing, r, r+1);
            series_correction_eval(correction, when, &dx, &dy);
            g_string_append_printf(text, "%d,%d,%s,", k, r,
                                   g_ascii_formatd(t, sizeof(t), "%.6f", when));
            g_string_append_printf(text, "%s,",
                                   g_ascii_formatd(x, sizeof(x), "%.4f", dx));
            g_string_append_printf(text, "%s\n",
                                   g_ascii_formatd(y, sizeof(y), "%.4f", dy));
        }
    }
    return g_string_free(text, FALSE);
}

static void
add_frame_verdicts(JsonBuilder *b, const SeriesCorrection *correction,
                   const FrameSeries *series)
{
    gint k;

    json_builder_set_member_name(b, "frames");
    json_builder_begin_array(b);
    for (k = 0; k < series->n_frames; k++) {
        const SeriesFrameVerdict *v = correction->frames + k;

        json_builder_begin_object(b);
        json_builder_set_member_name(b, "index");
        json_builder_add_int_value(b, k);
        json_builder_set_member_name(b, "title");
        json_builder_add_string_value(b, series->frames[k].label);
        json_values_set_number(b, "t_start_s",
                               series->frames[k].timing.frame_start);
        json_builder_set_member_name(b, "flagged");
        json_builder_add_boolean_value(b, v->flagged);
        json_builder_set_member_name(b, "reason");
        if (v->reason)
            json_builder_add_string_value(b, v->reason);
        else
            json_builder_add_null_value(b);
        json_values_set_number(b, "residual_px", v->residual_px);
        json_builder_end_object(b);
    }
    json_builder_end_array(b);
}

gchar*
series_correction_to_json(const SeriesCorrection *correction,
                          const FrameSeries *series)
{
    JsonBuilder *b = json_builder_new();
    guint i;

    json_builder_begin_object(b);
    fit_report_add_members(b, &correction->fit);
    json_values_set_number(b, "typical_residual_px", correction->typical_px);
    add_frame_verdicts(b, correction, series);
    json_builder_set_member_name(b, "warnings");
    json_builder_begin_array(b);
    for (i = 0; i < correction->warnings->len; i++)
        json_builder_add_string_value(b, g_ptr_array_index(correction->warnings, i));
    json_builder_end_array(b);
    json_builder_end_object(b);
    return json_values_finish(b);
}

/* The largest rectangle under a histogram of column heights ending at
 * row `row`, by the stack of rising heights. */
static void
largest_under_histogram(const gint *height, gint n, gint row, gint *stack,
                        gint *best, gint *rect)
{
    gint top = 0, c, h, left, area;

    for (c = 0; c <= n; c++) {
        h = (c < n) ? height[c] : 0;
        while (top > 0 && height[stack[top-1]] >= h) {
            gint hh = height[stack[--top]];

            left = top ? stack[top-1] + 1 : 0;
            area = hh*(c - left);
            if (area > *best) {
                *best = area;
                rect[0] = left;
                rect[1] = row - hh + 1;
                rect[2] = c - left;
                rect[3] = hh;
            }
        }
        stack[top++] = c;
    }
}

gboolean
series_correction_common_area(GwyDataField **masks, gint n, gint *col,
                              gint *row, gint *width, gint *height)
{
    gint xres = gwy_data_field_get_xres(masks[0]);
    gint yres = gwy_data_field_get_yres(masks[0]);
    gint *h = g_new0(gint, 2*(xres + 1)), *stack = h + xres + 1;
    gint best = 0, rect[4] = { 0, 0, 0, 0 }, r, c, k;

    for (r = 0; r < yres; r++) {
        for (c = 0; c < xres; c++) {
            gboolean covered = TRUE;

            for (k = 0; k < n && covered; k++)
                covered = (gwy_data_field_get_data_const(masks[k])[r*xres + c]
                           <= 0.0);
            h[c] = covered ? h[c] + 1 : 0;
        }
        largest_under_histogram(h, xres, r, stack, &best, rect);
    }
    g_free(h);
    *col = rect[0];
    *row = rect[1];
    *width = rect[2];
    *height = rect[3];
    return best > 0;
}
