/*
 *  Correcting a whole frame series: measure, fit one trajectory, flag the
 *  frames that disagree, correct every frame line by line.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <string.h>
#include <stdlib.h>
#include <math.h>
#include <libprocess/gwyprocess.h>
#include "coprime-step.h"
#include "json-values.h"
#include "jump-votes.h"
#include "continuous-compensate.h"
#include "drift-trajectory.h"
#include "localscan-channel.h"
#include "median.h"
#include "missing-data.h"
#include "series-correction.h"
#include "trajectory-csv.h"
#include "localscan-intl.h"

/* A frame is flagged when even its best-agreeing pair lies this many times
 * the series' typical pair residual from the trajectory, and at least
 * FLAG_FLOOR_PX: below a pixel a disagreement does not spoil a corrected
 * frame, whatever the series' noise. */
#define FLAG_RATIO 4.0
#define FLAG_FLOOR_PX 1.0

/* An effect larger than this fraction of the frame's smaller side is not
 * believed: the frames would not overlap across it. */
#define PLAUSIBLE_EFFECT 0.5
/* An effect smaller than this (px) is not named. */
#define EFFECT_MIN_PX 0.1

/* A frame is judged by the fit of the others only when at least this many
 * others remain: two frames are one pair, which any model fits. */
#define LEAVE_OUT_MIN_OTHERS 3

/* Lines a registered block has at least: sparse content leaves shorter
 * blocks empty. */
#define MIN_BLOCK_LINES 8

/* Knots of the flexible trajectory in all (a dense solve of this size is
 * milliseconds; the trajectory between blocks is smooth anyway). */
#define SMOOTH_KNOTS 400
/* The flexible trajectory must predict held-out blocks better than the
 * chosen model by this much (px) besides the fit's relative gain: near
 * the registration's noise relative gains are noise.  A tenth of a pixel
 * kept the model where random walks gained 0.06-0.09 px and the model's
 * frames lay 1.4-2.4 px off (seeds 4000014, 1101160, 1100245). */
#define SMOOTH_MIN_GAIN_PX 0.05
/* ... and stray from it by at most this many times the model's RMS
 * residual plus SMOOTH_DEPARTURE_PX: a random walk strays from any model
 * by pixels where the model leaves a few tenths (seeds 1100245, 1100306 of
 * test-series-correction: the model kept, 1.1-1.7 px off); the swings
 * the guard is for are ten times the model's residual and more. */
#define SMOOTH_MAX_DEPARTURE 12.0
#define SMOOTH_DEPARTURE_PX 1.0
/* The guard holds only where the model explains the blocks within this
 * (px RMS): a random walk leaves any model a few tenths and more (0.17 px
 * on seed 1101160, where the flexible trajectory departs 6.8 px from the
 * model and lies 0.24 px from the truth, the model 1.4 px); the swing the
 * guard is for came with a model 0.1 px from its blocks. */
#define MODEL_EXPLAINS_PX 0.15

/* Blocks are shortened when the drift changes by more than this (px)
 * within a block of one frame than within its partner's (finer_blocks):
 * by FINER_BLOCKS, down to FINE_BLOCK_LINES lines, at most FINER_ROUNDS
 * times (a settling beside a slipped frame, seed 14000616: 0.38 px after
 * one round, 0.14 px after two). */
#define BLOCK_SHAPE_PX 0.5
#define FINER_BLOCKS 1.5
#define FINE_BLOCK_LINES 4
#define FINER_ROUNDS 2

/* At most this many measurements enter the fit (fit_models). */
#define FIT_MAX_MEASUREMENTS 4000

/* Leaving a disturbed frame out makes the others agree this many times
 * better. */
#define LEAVE_OUT_GAIN 2.0
/* Candidates this close in the others' agreement are told apart by the
 * simplicity of the others' model, then by where they lie: block
 * registration noise alone spreads readings that explain the frames alike
 * by half as much again (a jump inside frame 0 with frame 1 slipped, seed
 * 30477 of test-series-correction: 0.10 against 0.15 px). */
#define LEAVE_OUT_TIE 2.0
/* A disturbed frame disagrees with the others everywhere; a frame that
 * agrees with them in part (more than this fraction of its blocks) holds
 * an effect of its own, such as a jump inside it.  Where a frame that
 * agrees nowhere explains the rest within LEAVE_OUT_WIDE_TIE of the best,
 * it is the one flagged: with frame 1 slipped and a jump late in frame 0,
 * leaving frame 0 out reads the slip as a jump between frames 1 and 2 and
 * fits the rest 2-3 times better than leaving frame 1 out, whose jump
 * inside frame 0 the straddling blocks blur (seeds 7000245, 7000287:
 * frame 0 flagged, the slip taken for drift, 3.4-6.9 px). */
#define LEAVE_OUT_PART_AGREES 0.1
#define LEAVE_OUT_WIDE_TIE 4.0

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

/* The size of the effect a fit names (nm): a jump's step, an
 * oscillation's amplitude, settling's excess travel u tau, how far an
 * acceleration bends the drift over the series (span s); 0 for none. */
static gdouble
effect_size_nm(const DriftFit *fit, gdouble span)
{
    DriftFitParameters p;

    drift_fit_parameters(fit, &p);
    switch (fit->type) {
        case DRIFT_MODEL_JUMP:
        return hypot(p.step_nm[0], p.step_nm[1]);

        case DRIFT_MODEL_OSCILLATION:
        return hypot(p.amplitude_nm[0], p.amplitude_nm[1]);

        case DRIFT_MODEL_SETTLING:
        return hypot(p.u_nm_per_s[0], p.u_nm_per_s[1])*p.tau_s;

        case DRIFT_MODEL_ACCELERATION:
        return 0.25*hypot(p.accel_nm_per_s2[0], p.accel_nm_per_s2[1])*span*span;

        default:
        return 0.0;
    }
}

/* The chosen fit, or constant drift when the chosen effect is larger than
 * the frames could show (a fit bending to a few failed registrations), or
 * smaller than EFFECT_MIN_PX: measurements of steady drift so exact that a
 * jump of a thousandth of a pixel passes every relative test change no
 * corrected frame, and name no effect.  An effect refused as too large is
 * told in refused_type and refused_nm (refused_type may be NULL). */
static gint
plausible_choice(const SeriesCorrection *correction, const DriftFit *fits,
                 gint n_fits, gint chosen, gint *refused_type,
                 gdouble *refused_nm)
{
    gdouble size, pixel = 1e9*MIN(correction->xstep, correction->ystep);
    gboolean too_large;
    gint i;

    if (chosen < 0 || fits[chosen].type == DRIFT_MODEL_NONE)
        return chosen;
    size = effect_size_nm(fits + chosen, correction->span_s);
    too_large = !(size <= PLAUSIBLE_EFFECT*correction->frame_nm);
    if (!too_large && size >= EFFECT_MIN_PX*pixel)
        return chosen;
    if (refused_type && too_large) {
        *refused_type = fits[chosen].type;
        *refused_nm = size;
    }
    for (i = 0; i < n_fits; i++) {
        if (fits[i].type == DRIFT_MODEL_NONE && fits[i].ok)
            return i;
    }
    return -1;
}

/* Every how many measurements a long series fits one: about count/most,
 * sharing no factor with the blocks per pair, nor with the taller blocks of
 * its rigid older pairs (displacement_tall_blocks), so that the subset
 * takes every block position in turn (exactly so where every block
 * registered; the stride counts registered blocks).  A stride of 2 with 16
 * blocks took the even blocks of every pair and never the last one. */
static gint
subset_stride(gint count, gint most, gint n_blocks)
{
    gint tall = displacement_tall_blocks(MAX(n_blocks, 1));

    /* No factor of either: none of their product. */
    return (gint)coprime_step((count + most - 1)/most, (gsize)MAX(n_blocks, 1)*tall);
}

/* How many pairs of frames the measurements with weight come from: 0, 1,
 * or 2 for two or more; *frame_a, *frame_b get the first one's frames.
 * From one pair (two frames, or three with the middle one flagged), a
 * jump between its frames is the velocity over again, any size of it
 * fits, and refusing it is nothing the user needs to hear ("a jump of
 * 2.04e+03 nm was fitted and refused" on two clean frames); other effects
 * refused are told whatever the pairs. */
static gint
pairs_used(const DriftMeasurement *meas, gint n, gint *frame_a, gint *frame_b)
{
    gint i, first = -1;

    for (i = 0; i < n; i++) {
        if (!(meas[i].weight > 0.0))
            continue;
        if (first < 0) {
            first = i;
            *frame_a = meas[i].frame_a;
            *frame_b = meas[i].frame_b;
        }
        else if (meas[i].frame_a != meas[first].frame_a
                 || meas[i].frame_b != meas[first].frame_b)
            return 2;
    }
    return (first >= 0) ? 1 : 0;
}

/* The fit of every model to the measurements whose weight in `weights` is
 * positive; measurements the fit cuts as gross outliers get weight 0.  A
 * long series fits every stride-th of them only (FIT_MAX_MEASUREMENTS in
 * all, spread over every pair and block): the searches of a jump's time and
 * an oscillation's period grow with the measurements times their count,
 * and a few thousand measurements determine a handful of parameters as
 * well as fifty thousand. */
static gboolean
fit_models(SeriesCorrection *correction, const gdouble *weights, gint n_blocks)
{
    FitReport *fit = &correction->fit;
    gboolean *kept = g_new(gboolean, MAX(fit->n_meas, 1));
    gint i, used = 0, stride, a, b;

    for (i = 0; i < fit->n_meas; i++)
        used += (weights[i] > 0.0);
    stride = subset_stride(used, FIT_MAX_MEASUREMENTS, n_blocks);
    for (i = used = 0; i < fit->n_meas; i++) {
        fit->meas[i].weight = weights[i];
        if (weights[i] > 0.0 && used++ % stride)
            fit->meas[i].weight = 0.0;
    }
    fit->chosen = drift_fit_select_kept(fit->meas, fit->n_meas,
                                        &fit->fit_options, fit->fits, kept);
    /* Only the last fit's refusal is told, once (warn_about_fit): every
     * fit of the rounds said it before, twice where a frame was flagged. */
    correction->refused_type = -1;
    fit->chosen = plausible_choice(correction, fit->fits, fit->n_fits, fit->chosen,
                                   &correction->refused_type, &correction->refused_nm);
    if (correction->refused_type == DRIFT_MODEL_JUMP
        && pairs_used(fit->meas, fit->n_meas, &a, &b) < 2)
        correction->refused_type = -1;
    for (i = 0; i < fit->n_meas; i++) {
        if (!kept[i])
            fit->meas[i].weight = 0.0;
    }
    g_free(kept);
    return fit->chosen >= 0;
}

/* |measured - fitted| of a measurement in pixels; fit NULL: the
 * trajectory the series is corrected with. */
static gdouble
residual_px(const SeriesCorrection *correction, const DriftFit *fit,
            const DriftMeasurement *m)
{
    gdouble dx, dy;

    if (!fit && correction->use_smooth)
        smooth_trajectory_predict(correction->smooth, m, &dx, &dy);
    else
        drift_fit_predict(fit ? fit : correction->fit.fits + correction->fit.chosen,
                          m, &dx, &dy);
    return hypot((m->dx - dx)/correction->xstep,
                 (m->dy - dy)/correction->ystep);
}

/* Each frame's measurements grouped by the other frame of their pair,
 * partners ascending and measurements in order within each: a frame's
 * pairs are read without a pass over the whole series for each frame
 * (a thousand frames have fifty thousand measurements). */
typedef struct {
    gint *first;      /* frame k's entries: first[k] .. first[k+1] - 1 */
    gint *meas;       /* the measurement of each entry */
    gint *partner;    /* the other frame of its pair */
} FramePairs;

static gint
compare_int64(gconstpointer a, gconstpointer b)
{
    gint64 x = *(const gint64*)a, y = *(const gint64*)b;

    return (x > y) - (x < y);
}

/* Sorting (frame, partner, measurement) keys gives the grouping. */
static void
frame_pairs_init(FramePairs *pairs, const FitReport *report, gint nf)
{
    gint64 n = report->n_meas, *keys = g_new(gint64, 2*n + 1);
    gint i, e, m = 0;

    for (i = 0; i < n; i++) {
        gint64 a = report->meas[i].frame_a, b = report->meas[i].frame_b;

        if (a == b)
            continue;
        keys[m++] = (a*nf + b)*n + i;
        keys[m++] = (b*nf + a)*n + i;
    }
    qsort(keys, m, sizeof(gint64), compare_int64);
    pairs->first = g_new0(gint, nf + 1);
    pairs->meas = g_new(gint, MAX(m, 1));
    pairs->partner = g_new(gint, MAX(m, 1));
    for (e = 0; e < m; e++) {
        pairs->meas[e] = keys[e] % n;
        pairs->partner[e] = (keys[e]/n) % nf;
        pairs->first[keys[e]/n/nf + 1]++;
    }
    for (i = 0; i < nf; i++)
        pairs->first[i + 1] += pairs->first[i];
    g_free(keys);
}

static void
frame_pairs_clear(FramePairs *pairs)
{
    g_free(pairs->first);
    g_free(pairs->meas);
    g_free(pairs->partner);
}

/* Frame k against a fit: the residual of its best-agreeing pair (the median
 * over the pair's registered blocks) with a frame not flagged, or with any
 * when all its partners are flagged.  A disturbed frame disagrees with
 * every partner; its partners agree with others.  *n_pairs gets the
 * number of registered pairs of k. */
static gdouble
frame_residual(const SeriesCorrection *correction, const DriftFit *fit,
               const FramePairs *pairs, gint k, const gdouble *registered,
               gint *n_pairs, gdouble *values)
{
    const FitReport *report = &correction->fit;
    gdouble best[2] = { NAN, NAN }, r;
    gint e, next, i, j, count, partner_flagged;

    *n_pairs = 0;
    for (e = pairs->first[k]; e < pairs->first[k+1]; e = next) {
        j = pairs->partner[e];
        count = 0;
        for (next = e; next < pairs->first[k+1] && pairs->partner[next] == j; next++) {
            i = pairs->meas[next];
            if (registered[i] > 0.0)
                values[count++] = residual_px(correction, fit, report->meas + i);
        }
        if (count < PAIR_MIN_BLOCKS)
            continue;
        (*n_pairs)++;
        r = median_in_place(values, count);
        partner_flagged = correction->frames[j].flagged;
        if (!(best[partner_flagged] <= r))
            best[partner_flagged] = r;
    }
    return isnan(best[0]) ? best[1] : best[0];
}

/* Every frame's residual against the chosen fit; typical_px the median of
 * those not flagged. */
static void
judge_frames(SeriesCorrection *correction, const gdouble *registered)
{
    const FitReport *report = &correction->fit;
    gint nf = correction->n_frames, k, count = 0;
    gdouble *values = g_new(gdouble, report->n_meas + nf + 1);
    gdouble *typical = values + report->n_meas;
    FramePairs pairs;

    frame_pairs_init(&pairs, report, nf);
    for (k = 0; k < nf; k++) {
        SeriesFrameVerdict *v = correction->frames + k;

        v->residual_px = frame_residual(correction, NULL, &pairs, k, registered,
                                        &v->n_pairs, values);
        if (!v->flagged && isfinite(v->residual_px))
            typical[count++] = v->residual_px;
    }
    correction->typical_px = median_in_place(typical, count);
    frame_pairs_clear(&pairs);
    g_free(values);
}

static void
flag_frame(SeriesFrameVerdict *v, gdouble residual, gdouble typical)
{
    v->flagged = TRUE;
    v->reason = g_strdup_printf(_("disagrees with the trajectory of the "
                                  "other frames by %.2f px (typical "
                                  "%.2f px)"), residual, typical);
}

static gboolean
beyond_limit(gdouble residual, gdouble typical)
{
    return residual > MAX(FLAG_RATIO*typical, FLAG_FLOOR_PX);
}

/* Frames more than half missing (docs/missing-data.md) say too little to
 * be measured: flagged before any fit, still corrected. */
static void
flag_mostly_missing(SeriesCorrection *correction, const FrameSeries *series)
{
    gint k;

    for (k = 0; k < series->n_frames; k++) {
        GwyDataField *field = series->frames[k].field;
        gsize n = (gsize)gwy_data_field_get_xres(field)*gwy_data_field_get_yres(field);
        gsize missing = missing_data_count(gwy_data_field_get_data_const(field), n);

        if (missing > MISSING_DATA_MAX_FRACTION*n) {
            correction->frames[k].flagged = TRUE;
            correction->frames[k].reason
                = g_strdup_printf(_("%.0f %% of its pixels are missing"),
                                  100.0*missing/n);
        }
    }
}

/* Frames registered against no other frame. */
static void
flag_unregistered(SeriesCorrection *correction)
{
    gint k;

    for (k = 0; k < correction->n_frames; k++) {
        SeriesFrameVerdict *v = correction->frames + k;

        if (!v->flagged && !v->n_pairs) {
            v->flagged = TRUE;
            v->reason = g_strdup(_("could not be registered against any "
                                   "other frame"));
        }
    }
}

/* A long series: frames far from the fit of all (judge_frames first). */
static void
flag_outlying(SeriesCorrection *correction)
{
    gint k;

    for (k = 0; k < correction->n_frames; k++) {
        SeriesFrameVerdict *v = correction->frames + k;

        if (!v->flagged && v->n_pairs
            && beyond_limit(v->residual_px, correction->typical_px))
            flag_frame(v, v->residual_px, correction->typical_px);
    }
}

/* A frame left out, as a candidate for flagging. */
typedef struct {
    gint frame;
    gdouble residual;     /* its residual against the others' fit */
    gdouble typical;      /* the others' typical residual */
    gdouble spread;       /* the others' mean block residual */
    gdouble agreeing;     /* the fraction of its blocks that agree with the
                             others' fit */
    gint n_params;        /* of the model the others chose */
    DriftFit fit;         /* that model */
} LeftOut;

/* Whether a block of the measurement lies within a block's length of the
 * fit's jump: its lines hold both sides of the jump, and it registers as
 * neither (nor as their mean), whatever the trajectory. */
static gboolean
straddles_jump(const DriftFit *fit, const DriftMeasurement *m)
{
    gdouble reach = m->span > 0.0 ? m->span : 0.0;

    return (fit->type == DRIFT_MODEL_JUMP
            && (fabs(m->t_a - fit->nonlinear) <= reach
                || fabs(m->t_b - fit->nonlinear) <= reach));
}

/* The mean residual (px) of the registered blocks between frames neither k
 * nor flagged, each clipped at ten times their median (and at least a
 * pixel) so that a failed registration counts as a bad one, not as a
 * thousand.  Unlike the frames' best-pair residuals it sees a frame that
 * fits only in part.  Blocks straddling the fit's jump are left out: they
 * disagree with any fit, and in a clean series a handful of them outweigh
 * everything else (a jump inside frame 0 with frame 1 slipped, seed
 * 560100716: 0.09 px leaving frame 1 out against 0.009 px leaving frame 0
 * out, whose fit puts its jump between frames, where no block is). */
static gdouble
others_spread(const SeriesCorrection *correction, const DriftFit *fit, gint k,
              const gdouble *registered, gdouble *values)
{
    const FitReport *report = &correction->fit;
    gdouble clip, sum = 0.0;
    gint i, n = 0;

    for (i = 0; i < report->n_meas; i++) {
        const DriftMeasurement *m = report->meas + i;

        if (registered[i] > 0.0 && m->frame_a != k && m->frame_b != k
            && !correction->frames[m->frame_a].flagged
            && !correction->frames[m->frame_b].flagged
            && !straddles_jump(fit, m))
            values[n++] = residual_px(correction, fit, m);
    }
    if (!n)
        return NAN;
    clip = MAX(10.0*median_in_place(values, n), 1.0);
    for (i = 0; i < n; i++)
        sum += MIN(values[i], clip);
    return sum/n;
}

/* The fraction of frame k's registered blocks with frames not flagged that
 * lie within the flagging limit of a fit. */
static gdouble
agreeing_blocks(const SeriesCorrection *correction, const DriftFit *fit,
                gint k, const gdouble *registered, gdouble typical)
{
    const FitReport *report = &correction->fit;
    gint i, count = 0, agree = 0, j;

    for (i = 0; i < report->n_meas; i++) {
        const DriftMeasurement *m = report->meas + i;

        if (registered[i] <= 0.0 || (m->frame_a != k && m->frame_b != k))
            continue;
        j = (m->frame_a == k) ? m->frame_b : m->frame_a;
        if (correction->frames[j].flagged)
            continue;
        count++;
        agree += !beyond_limit(residual_px(correction, fit, m), typical);
    }
    return count ? (gdouble)agree/count : 0.0;
}

/* The fit of the frames neither k nor flagged: frame k's residual
 * against it, the typical residual of the others and their spread. */
static gboolean
fit_leaving_out(const SeriesCorrection *correction, const FramePairs *pairs,
                gint k, const gdouble *registered, DriftMeasurement *work,
                gdouble *values, LeftOut *result)
{
    const FitReport *report = &correction->fit;
    DriftFit fits[FIT_REPORT_MAX_MODELS];
    DriftFitOptions options = report->fit_options;
    gint nf = correction->n_frames, i, j, chosen, n_pairs, count = 0;
    gdouble *others = g_new(gdouble, MAX(nf, 1)), r;

    result->frame = k;
    memcpy(work, report->meas, report->n_meas*sizeof(DriftMeasurement));
    for (i = 0; i < report->n_meas; i++) {
        gint a = work[i].frame_a, b = work[i].frame_b;

        work[i].weight = registered[i];
        if (a == k || b == k || correction->frames[a].flagged
            || correction->frames[b].flagged)
            work[i].weight = 0.0;
    }
    /* Candidates are compared, not reported: the criterion without the
     * cross-validation, a fit per frame affordable. */
    options.n_folds = 0;
    chosen = drift_fit_select(work, report->n_meas, &options, fits);
    chosen = plausible_choice(correction, fits, report->n_fits, chosen, NULL, NULL);
    if (chosen >= 0) {
        result->fit = fits[chosen];
        result->n_params = fits[chosen].n_params;
        result->residual = frame_residual(correction, fits + chosen, pairs,
                                          k, registered, &n_pairs, values);
        for (j = 0; j < nf; j++) {
            if (j == k || correction->frames[j].flagged)
                continue;
            r = frame_residual(correction, fits + chosen, pairs, j,
                               registered, &n_pairs, values);
            if (isfinite(r))
                others[count++] = r;
        }
        result->typical = median_in_place(others, count);
        result->spread = others_spread(correction, fits + chosen, k,
                                       registered, values);
        result->agreeing = agreeing_blocks(correction, fits + chosen, k,
                                           registered, result->typical);
    }
    g_free(others);
    return (chosen >= 0 && count >= 2 && isfinite(result->residual)
            && isfinite(result->spread));
}

/* Of candidates whose others agree nearly as well as the best, the one
 * whose others need the simplest model: a slip in frame 1 of a steady
 * series can be read as frame 0 cut off by a jump, or as frame 1 out of
 * line.  Agreement is the others' spread, which sees a frame that fits
 * only in part (a jump inside a slipped frame read as a jump at its end).
 * Of those, an inner frame before the first or the last: either end frame
 * out of line reads as a jump at its border, so any inner frame slipped can
 * be read as the end frame cut off by a jump that undoes the slip (a
 * settling in frame 0 with frame 1 slipped, a jump inside frame 0 with
 * frame 1 slipped). */
static gboolean
is_end_frame(gint k, gint n_frames)
{
    return k == 0 || k == n_frames - 1;
}

static gint
pick_left_out(const LeftOut *cand, gint n, gint n_frames)
{
    gdouble lowest = G_MAXDOUBLE, tie = LEAVE_OUT_TIE;
    gboolean nowhere = FALSE, end, best_end;
    gint i, best = -1;

    for (i = 0; i < n; i++)
        lowest = MIN(lowest, cand[i].spread);
    for (i = 0; i < n; i++) {
        if (cand[i].spread <= LEAVE_OUT_WIDE_TIE*lowest
            && cand[i].agreeing <= LEAVE_OUT_PART_AGREES)
            nowhere = TRUE;
    }
    if (nowhere)
        tie = LEAVE_OUT_WIDE_TIE;
    for (i = 0; i < n; i++) {
        if (cand[i].spread > tie*lowest
            || (nowhere && cand[i].agreeing > LEAVE_OUT_PART_AGREES))
            continue;
        end = is_end_frame(cand[i].frame, n_frames);
        best_end = best >= 0 && is_end_frame(cand[best].frame, n_frames);
        if (best < 0 || cand[i].n_params < cand[best].n_params
            || (cand[i].n_params == cand[best].n_params
                && (best_end > end
                    || (best_end == end
                        && cand[i].spread < cand[best].spread))))
            best = i;
    }
    return best;
}

/* A short series: a frame is flagged when it lies far from the trajectory
 * of the others, and it stood out already (far from the fit of all) or the
 * others agree much better without it (a disturbed frame bends the models
 * that can bend towards itself).  Not an end frame for the second reason
 * alone: the bend is then a jump at its border, which the fit of all
 * explains as well as a slip (a jump in frame 0's last three lines was
 * taken for frame 0 disturbed, seed 13000196: 4.3 px), and a jump it is
 * read as.  A frame that merely holds an effect of
 * its own (settling in the first frame, a jump) is no such frame: the fit
 * of all explained it, and the others agreed as well with it as without
 * it.  The others' agreement is both their typical best-pair residual and
 * the spread of all their pairs: a slipped inner frame that the fit of all
 * explains as a jump at its end leaves the best pair of each other frame
 * fitting, but not all their pairs (seed 2034865279: frame 3 slipped,
 * typical 0.12 px with it and 0.08 px without, spread 0.10 px without it;
 * frame 2 was flagged in its place, 3.3 px).  The rest are then judged
 * again without it, against the fit of the others of that round (the fit
 * of all still bends towards the flagged frame). */
static void
flag_by_leaving_out(SeriesCorrection *correction, const gdouble *registered)
{
    const FitReport *report = &correction->fit;
    gint nf = correction->n_frames, k, round, n, best;
    DriftMeasurement *work = g_new(DriftMeasurement, MAX(report->n_meas, 1));
    gdouble *values = g_new(gdouble, MAX(report->n_meas, 1));
    gdouble agreement = correction->typical_px;
    gdouble *in_all = g_new(gdouble, MAX(nf, 1));
    LeftOut *cand = g_new(LeftOut, MAX(nf, 1)), c;
    DriftFit reference = report->fits[report->chosen];
    FramePairs pairs;

    frame_pairs_init(&pairs, report, nf);
    for (k = 0; k < nf; k++)
        in_all[k] = correction->frames[k].residual_px;
    for (round = 0; round < MAX(nf/3, 1); round++) {
        gint others = -1;

        for (k = 0; k < nf; k++)
            others += !correction->frames[k].flagged;
        if (others < LEAVE_OUT_MIN_OTHERS)
            break;
        n = 0;
        for (k = 0; k < nf; k++) {
            if (correction->frames[k].flagged
                || !fit_leaving_out(correction, &pairs, k, registered, work,
                                    values, &c))
                continue;
            if (beyond_limit(c.residual, c.typical)
                && ((!is_end_frame(k, nf)
                     && (agreement > LEAVE_OUT_GAIN*c.typical
                         || others_spread(correction, &reference, k, registered,
                                          values) > LEAVE_OUT_GAIN*c.spread))
                    || beyond_limit(in_all[k], agreement)))
                cand[n++] = c;
        }
        if ((best = pick_left_out(cand, n, nf)) < 0)
            break;
        c = cand[best];
        flag_frame(correction->frames + c.frame, c.residual, c.typical);
        agreement = c.typical;
        reference = c.fit;
    }
    frame_pairs_clear(&pairs);
    g_free(cand);
    g_free(in_all);
    g_free(work);
    g_free(values);
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

/* Knots of the flexible trajectory: evenly within each frame, as many as
 * its blocks up to SMOOTH_KNOTS in all (between frames nothing is
 * measured: the penalty bridges the gap). */
static gdouble*
smooth_knots(const FrameSeries *series, gint n_blocks, gint *n)
{
    gint per = CLAMP(SMOOTH_KNOTS/MAX(series->n_frames, 1), 2, MAX(n_blocks, 2));
    gdouble *knots = g_new(gdouble, per*series->n_frames + 1), t, start, span;
    gint k, j;

    *n = 0;
    for (k = 0; k < series->n_frames; k++) {
        start = series->frames[k].timing.frame_start;
        span = scan_timing_frame_end(&series->frames[k].timing) - start;
        for (j = 0; j < per; j++) {
            t = start + (j + 0.5)*span/per;
            if (!*n || t > knots[*n - 1])
                knots[(*n)++] = t;
        }
    }
    return knots;
}

/* The largest distance (px) between the flexible trajectory and the
 * chosen model over every line of the frames not flagged. */
static gdouble
smooth_departure(const SeriesCorrection *correction, const FrameSeries *series)
{
    const DriftFit *fit = correction->fit.fits + correction->fit.chosen;
    gdouble worst = 0.0, t, sx, sy, mx, my, mx0, my0;
    gint k, r;

    drift_fit_eval(fit, 0.0, &mx0, &my0);
    for (k = 0; k < series->n_frames; k++) {
        const ScanTiming *timing = &series->frames[k].timing;

        for (r = 0; r < timing->yres && !correction->frames[k].flagged; r++) {
            t = scan_timing_rows_time(timing, r, r+1);
            smooth_trajectory_eval(correction->smooth, t, &sx, &sy);
            drift_fit_eval(fit, t, &mx, &my);
            worst = MAX(worst, hypot((sx - mx + mx0)/correction->xstep,
                                     (sy - my + my0)/correction->ystep));
        }
    }
    return worst;
}

/* The flexible trajectory beside the chosen model; it is used when it
 * predicts held-out blocks better by the fit's cv_gain: no model explains
 * the drift (a random walk, creep of no simple form).  Not when it strays
 * from the model much farther than the model's own residual: differences
 * between frames do not see a shape repeated in every frame, and a
 * flexible trajectory can swing by many pixels within each frame while it
 * fits every block (seed 1411410649 of test-series-correction: 13 px
 * against a jump model 0.1 px from its blocks, whose held-out error
 * suffered from re-searching the jump in each fold). */
static void
fit_smooth(SeriesCorrection *correction, const FrameSeries *series,
           gint n_blocks)
{
    const FitReport *fit = &correction->fit;
    const DriftFit *chosen = fit->fits + fit->chosen;
    gdouble *knots, pixel_nm;
    gint n;

    knots = smooth_knots(series, n_blocks, &n);
    correction->smooth = smooth_trajectory_fit(fit->meas, fit->n_meas, knots,
                                               n, fit->fit_options.n_folds);
    g_free(knots);
    /* Better by the gain and by a tenth of a pixel: where the model
     * predicts to the registration's noise, the flexible trajectory's
     * relative gains are noise, and its freedom (a shape repeated in every
     * frame is unseen) costs more than they bring (a jump read by the
     * model to the line, then drawn pixels off by the flexible one). */
    pixel_nm = 1e9*MIN(correction->xstep, correction->ystep);
    correction->use_smooth
        = (correction->smooth && isfinite(chosen->cv_rms_nm)
           && correction->smooth->cv_rms_nm
              < (1.0 - fit->fit_options.cv_gain)*chosen->cv_rms_nm
           && chosen->cv_rms_nm - correction->smooth->cv_rms_nm
              >= SMOOTH_MIN_GAIN_PX*pixel_nm
           && (chosen->rms_nm > MODEL_EXPLAINS_PX*pixel_nm
               || smooth_departure(correction, series)
                  <= SMOOTH_MAX_DEPARTURE*chosen->rms_nm/pixel_nm + SMOOTH_DEPARTURE_PX));
}

static void
warn_about_fit(SeriesCorrection *correction, const gdouble *registered)
{
    const FitReport *fit = &correction->fit;
    const DriftFit *chosen = fit->fits + fit->chosen;
    gint i, n_reg = 0, a, b;
    gdouble rms_px;

    if (correction->refused_type >= 0)
        add_warning(correction,
                    g_strdup_printf(_("a %s of %.3g nm was fitted and "
                                      "refused: more than half the frame"),
                                    drift_model_type_name(correction->refused_type),
                                    correction->refused_nm));
    for (i = 0; i < fit->n_meas; i++)
        n_reg += (registered[i] > 0.0);
    if (2*n_reg < fit->n_meas)
        add_warning(correction,
                    g_strdup_printf(_("only %d of %d blocks could be "
                                      "registered: the trajectory rests on "
                                      "few measurements"),
                                    n_reg, fit->n_meas));
    /* Two frames measure one displacement per block: a drift that
     * changes between them (a jump, a drift speeding up) and steady drift
     * fit alike (a run on series with a known drift: a jump of (5, -3)
     * px between two frames read as steady drift, 3.2 px RMS off, in
     * silence). */
    if (pairs_used(fit->meas, fit->n_meas, &a, &b) == 1)
        add_warning(correction,
                    g_strdup_printf(_("the trajectory rests on one pair of frames "
                                      "(%d and %d): a change of the drift between "
                                      "them (a jump, a drift speeding up) cannot be "
                                      "told from steady drift, and the frames are "
                                      "corrected as if the drift were steady"),
                                    MIN(a, b), MAX(a, b)));
    rms_px = 1e-9*(correction->use_smooth ? correction->smooth->rms_nm
                                          : chosen->rms_nm)
             /MIN(correction->xstep, correction->ystep);
    if (rms_px > MODEL_WARN_PX)
        add_warning(correction,
                    g_strdup_printf(_("the fitted model leaves %.2f px RMS "
                                      "between the measurements: the "
                                      "corrected frames keep drift of that "
                                      "order"), rms_px));
}

/* Which side of a jump a trajectory follows: the fit itself, the drift
 * without the step, or with the step from the start; and, to tell what a
 * displacement by the step costs a line's match, the step taken twice, or
 * taken away from the drift without it. */
typedef enum {
    JUMP_AS_FITTED,
    JUMP_NEVER,
    JUMP_ALWAYS,
    JUMP_TWICE,
    JUMP_BACKWARDS,
} JumpSide;

/* p(t) - p(0) of a fit in pixels, a jump's step taken as side says. */
static void
fit_eval_side(const DriftFit *fit, gdouble xstep, gdouble ystep, gdouble t,
              JumpSide side, gdouble *dx, gdouble *dy)
{
    gdouble x, y, x0, y0, sign = 0.0;

    drift_fit_eval(fit, t, &x, &y);
    drift_fit_eval(fit, 0.0, &x0, &y0);
    if (fit->type == DRIFT_MODEL_JUMP && fit->creep == DRIFT_FIT_CREEP_NONE) {
        gboolean after = (t >= fit->nonlinear);

        if (side == JUMP_NEVER && after)
            sign = -1.0;
        else if (side == JUMP_ALWAYS && !after)
            sign = 1.0;
        else if (side == JUMP_TWICE)
            sign = after ? 1.0 : 2.0;
        else if (side == JUMP_BACKWARDS)
            sign = after ? -2.0 : -1.0;
    }
    *dx = (x - x0 + sign*1e-9*fit->coef[0][1])/xstep;
    *dy = (y - y0 + sign*1e-9*fit->coef[1][1])/ystep;
}

static void
eval_side(const SeriesCorrection *correction, gdouble t, JumpSide side,
          gdouble *dx, gdouble *dy)
{
    if (correction->use_smooth) {
        smooth_trajectory_eval(correction->smooth, t, dx, dy);
        *dx /= correction->xstep;
        *dy /= correction->ystep;
        return;
    }
    fit_eval_side(correction->fit.fits + correction->fit.chosen,
                  correction->xstep, correction->ystep, t, side, dx, dy);
}

/* How many block spans on either side of the fitted jump time the jump is
 * looked for line by line. */
#define JUMP_SEARCH_BLOCKS 3.0
/* Frames this far from a line's own compared with it. */
#define JUMP_PARTNER_REACH 2
/* Rows of the line-by-line work space: a predicted line and the two rows
 * line_residual() works in, a row that stays zero (a line's texture is
 * its mismatch with it), and the places (place_line(), 3 rows each) of a
 * line's content under the drift without the step, with it and its
 * control's. */
#define JUMP_WORK_ROWS 13

/* Where frame j saw the content of frame k's line r, with the drift of
 * line r taken from `side`: each pixel's true position, then where frame
 * j saw it (its row's own time found by two fixed-point steps).  place
 * holds 3 rows of xres: the column before frame j's drift, that drift's
 * column part (apart, so that sample_place() adds an offset to it as the
 * prediction always did, to the last bit) and the row in frame j.  Found
 * once for the place and every offset around it: the drift's evaluation
 * costs far more than sampling. */
static void
place_line(const SeriesCorrection *correction, const SeriesFrame *fk,
           const SeriesFrame *fj, gint r, JumpSide side, gdouble *place)
{
    gint xres = fk->timing.xres, c, it;
    gdouble t, dx, dy, x, y, yj, tj, jx, jy;

    for (c = 0; c < xres; c++) {
        t = scan_timing_pixel_time(&fk->timing, r, c);
        eval_side(correction, t, side, &dx, &dy);
        x = c - dx;
        y = r - dy;
        yj = y;
        jx = jy = 0.0;
        for (it = 0; it < 2; it++) {
            tj = scan_timing_pixel_time(&fj->timing, yj, x + jx);
            eval_side(correction, tj, JUMP_AS_FITTED, &jx, &jy);
            yj = y + jy;
        }
        place[c] = x;
        place[xres + c] = jx;
        place[2*xres + c] = yj;
    }
}

/* Frame j's data (ref, xres by yres) at the place of each pixel of a line
 * (place_line()) moved by (off_x, off_y) px, sampled bilinearly; NAN
 * outside frame j. */
static void
sample_place(gint xres, gint yres, const gdouble *ref, const gdouble *place,
             gdouble off_x, gdouble off_y, gdouble *line)
{
    gint c, x0, y0;
    gdouble x, yj, fx, fy;

    for (c = 0; c < xres; c++) {
        x = place[c] + (place[xres + c] + off_x);
        yj = place[2*xres + c] + off_y;
        x0 = (gint)floor(x);
        y0 = (gint)floor(yj);
        if (x0 < 0 || y0 < 0 || x0 + 1 >= xres || y0 + 1 >= yres) {
            line[c] = NAN;
            continue;
        }
        fx = x - x0;
        fy = yj - y0;
        line[c] = ((1.0 - fy)*((1.0 - fx)*ref[y0*xres + x0] + fx*ref[y0*xres + x0 + 1])
                   + fy*((1.0 - fx)*ref[(y0 + 1)*xres + x0]
                         + fx*ref[(y0 + 1)*xres + x0 + 1]));
    }
}

/* The mean squared difference of a line and its prediction over the
 * pixels both have, after the best quadratic in the column is taken out
 * of the difference: line offsets, tilts and bows along x differ between
 * raw frames and do not count, and a featureless line costs the same under
 * either drift, where a correlation of its noise would pull the jump
 * anywhere.  Raw data, not conditioned: conditioning filters across lines
 * and so carries content from beyond the jump into the lines before it
 * (a particle's halo), which then match the wrong side (a jump 5 lines
 * into a frame was placed at its first line).  NAN when too little of the
 * line is predicted.  With against_zero, the line's own texture over those
 * same pixels (the prediction only says which pixels count).  u and d are
 * work space of n. */
static gdouble
line_residual(const gdouble *data, const gdouble *pred, gint n,
              gboolean against_zero, gdouble *u, gdouble *d)
{
    gdouble coeffs[3], sdd = 0.0, e;
    gint c, m = 0;

    for (c = 0; c < n; c++) {
        if (!isfinite(pred[c]) || !isfinite(data[c]))
            continue;
        u[m] = (2.0*c - (n - 1))/MAX(n - 1, 1);
        d[m] = against_zero ? data[c] : data[c] - pred[c];
        m++;
    }
    if (m < 8)
        return NAN;
    gwy_math_fit_polynom(m, u, d, 2, coeffs);
    for (c = 0; c < m; c++) {
        e = d[c] - (coeffs[0] + u[c]*(coeffs[1] + u[c]*coeffs[2]));
        sdd += e*e;
    }
    return sdd/m;
}

static gdouble
line_mismatch(const gdouble *data, const gdouble *pred, gint n, gdouble *u,
              gdouble *d)
{
    return line_residual(data, pred, n, FALSE, u, d);
}

/* The texture of a line where pred has values: a line compared over part
 * of its width is judged by what that part shows.  Measured over the whole
 * line, a particle in columns the prediction does not reach made a line
 * whose compared part was as featureless as its prediction look like a
 * close match of textured content, and a line before a jump voted after
 * it (test-series-correction seed 900000136, case 611). */
static gdouble
line_texture_where(const gdouble *data, const gdouble *pred, gint n,
                   gdouble *u, gdouble *d)
{
    return line_residual(data, pred, n, TRUE, u, d);
}

/* The lowest mismatch of a line (data row) with its content at place
 * (place_line()) moved from base (the best place that side_mismatch()
 * found) a pixel left, right, up or down (NAN where none of them lies in
 * the other frame): a line under its right drift costs less where it is
 * than a pixel off (jump-votes.c).  From a best place at the edge of the
 * searched square, the place a pixel back lies inside the square's
 * reflection and may cost no less than the best: the minimum is then
 * judged by three directions.  line is work space of 3 rows. */
static gdouble
nearby_mismatch(const SeriesFrame *fk, const gdouble *ref,
                const gdouble *place, const gdouble *base, const gdouble *row,
                gdouble *line)
{
    static const gdouble offsets[4][2] = { { -1, 0 }, { 1, 0 }, { 0, -1 }, { 0, 1 } };
    gint xres = fk->timing.xres, yres = fk->timing.yres, i;
    gdouble lowest = NAN, e;

    for (i = 0; i < 4; i++) {
        sample_place(xres, yres, ref, place, base[0] + offsets[i][0],
                     base[1] + offsets[i][1], line);
        e = line_mismatch(row, line, xres, line + xres, line + 2*xres);
        if (!isnan(e) && !(lowest <= e))
            lowest = e;
    }
    return lowest;
}

/* The mismatch of line r of frame k with its content as frame j shows it
 * under `side`, the lowest within reach px in x and y of the place that
 * drift predicts (five places a side; NAN where that place is not in
 * frame j), and the offset where it is lowest (offset may be NULL).  Near
 * a jump the fitted drift is only about half a pixel accurate: the step
 * and the velocity are fitted with the jump where the blocks put it.  At
 * the exact place, a featureless line after a jump whose content lies
 * beside a particle's steep rim met the rim 0.5 px off and was voted
 * before the jump (test-series-correction seed 68000339), and a textured
 * line after one cost more than a pixel off, so was no minimum and told
 * nothing (seed 68000484).  line is work space of 3 rows; place (3 rows)
 * is left holding the place of the line's content under `side`
 * (place_line()). */
static gdouble
side_mismatch(const SeriesCorrection *correction, const SeriesFrame *fk,
              const SeriesFrame *fj, const gdouble *ref, gint r,
              JumpSide side, gdouble reach, const gdouble *row, gdouble *line,
              gdouble *place, gdouble *offset)
{
    gint xres = fk->timing.xres, yres = fk->timing.yres, i, j;
    gdouble lowest, e, step = 0.5*reach, best[2] = { 0.0, 0.0 };

    place_line(correction, fk, fj, r, side, place);
    sample_place(xres, yres, ref, place, 0.0, 0.0, line);
    lowest = line_mismatch(row, line, xres, line + xres, line + 2*xres);
    for (i = -2; i <= 2 && !isnan(lowest) && reach > 0.0; i++) {
        for (j = -2; j <= 2; j++) {
            if (!i && !j)
                continue;
            sample_place(xres, yres, ref, place, step*j, step*i, line);
            e = line_mismatch(row, line, xres, line + xres, line + 2*xres);
            if (e < lowest) {
                lowest = e;
                best[0] = step*j;
                best[1] = step*i;
            }
        }
    }
    if (offset) {
        offset[0] = best[0];
        offset[1] = best[1];
    }
    return lowest;
}

/* How far side_mismatch() looks around each drift's place, px: half a
 * pixel, the fit's accuracy near a jump, but no more than a quarter of the
 * step (along the axis it moves most), so that the squares searched around
 * the two drifts' places stay half a step apart: a smaller step would let
 * the drift on the wrong side reach the right place. */
#define JUMP_PLACE_REACH 0.5

static gdouble
jump_place_reach(const SeriesCorrection *correction)
{
    const DriftFit *fit = correction->fit.fits + correction->fit.chosen;
    gdouble sx = fabs(1e-9*fit->coef[0][1]/correction->xstep);
    gdouble sy = fabs(1e-9*fit->coef[1][1]/correction->ystep);

    return fmin(JUMP_PLACE_REACH, 0.25*fmax(sx, sy));
}

/* How well line r of frame k matches the frames near it (those not
 * flagged, up to JUMP_PARTNER_REACH away: the next frame may be flagged,
 * the previous one may not show the line's content) with the drift
 * without the step and with it, each within reach of its place
 * (side_mismatch()).  Frames that show the line's content under both
 * count alone when there are any: content seen under one only is compared
 * with nothing under the other.  line is work space of JUMP_WORK_ROWS
 * rows. */
static void
line_costs(const SeriesCorrection *correction, const FrameSeries *series,
           gint k, gint r, gdouble reach, gdouble *line, LineEvidence *ev)
{
    const SeriesFrame *fk = series->frames + k, *fj;
    gint j, count = 0, nb = 0, na = 0, xres = fk->timing.xres;
    const gdouble *row = gwy_data_field_get_data_const(fk->field) + (gsize)r*xres;
    gdouble eb, ea, ec, en, sb = 0.0, sa = 0.0, ob = 0.0, oa = 0.0, cb = 0.0, ca = 0.0;
    gdouble near_a = 0.0, near_b = 0.0, cost_a = 0.0, cost_b = 0.0;
    gdouble et, ew, ta = 0.0, tb = 0.0, wa = 0.0, wb = 0.0;
    gdouble off_b[2], off_a[2], *offset;
    gdouble *u = line + xres, *d = u + xres, *zeros = d + xres;
    gdouble *place_b = zeros + xres, *place_a = place_b + 3*xres;
    gdouble *place_c = place_a + 3*xres, *place;
    const gdouble *ref;

    for (j = k - JUMP_PARTNER_REACH; j <= k + JUMP_PARTNER_REACH; j++) {
        if (j == k || j < 0 || j >= series->n_frames
            || correction->frames[j].flagged)
            continue;
        fj = series->frames + j;
        ref = gwy_data_field_get_data_const(fj->field);
        eb = side_mismatch(correction, fk, fj, ref, r, JUMP_NEVER, reach, row,
                           line, place_b, off_b);
        ea = side_mismatch(correction, fk, fj, ref, r, JUMP_ALWAYS, reach, row,
                           line, place_a, off_a);
        if (!isnan(eb) && !isnan(ea)) {
            sb += eb;
            sa += ea;
            count++;
            continue;
        }
        if (isnan(eb) && isnan(ea))
            continue;
        offset = isnan(eb) ? off_a : off_b;
        place = isnan(eb) ? place_a : place_b;
        sample_place(xres, fk->timing.yres, ref, place, offset[0], offset[1], line);
        et = line_mismatch(zeros, line, xres, u, d);
        ew = line_texture_where(row, line, xres, u, d);
        en = nearby_mismatch(fk, ref, place, offset, row, line);
        ec = side_mismatch(correction, fk, fj, ref, r,
                           isnan(eb) ? JUMP_TWICE : JUMP_BACKWARDS, reach, row,
                           line, place_c, NULL);
        if (isnan(ec))
            continue;
        if (isnan(eb)) {
            oa += ea;
            ca += ec;
            ta += et;
            wa += ew;
            if (!isnan(en)) {
                near_a += en;
                cost_a += ea;
            }
            na++;
        }
        else {
            ob += eb;
            cb += ec;
            tb += et;
            wb += ew;
            if (!isnan(en)) {
                near_b += en;
                cost_b += eb;
            }
            nb++;
        }
    }
    ev->two_sided = (count > 0);
    ev->before = count ? sb/count : (nb ? ob/nb : NAN);
    ev->after = count ? sa/count : (na ? oa/na : NAN);
    ev->control = (count || (nb && na)) ? NAN : (nb ? cb/nb : (na ? ca/na : NAN));
    /* The partners that show the line's content a pixel off too decide
     * whether it is a minimum: scaled so that cost < nearby holds as their
     * mean cost is below their mean nearby one. */
    ev->nearby = NAN;
    if (!isnan(ev->control) && (nb ? cost_b : cost_a) > 0.0)
        ev->nearby = (nb ? ev->before*near_b/cost_b : ev->after*near_a/cost_a);
    else if (!isnan(ev->control) && (nb ? near_b : near_a) > 0.0)
        ev->nearby = INFINITY;
    /* Only a one-sided line is judged by its texture. */
    ev->texture = ev->unrelated = NAN;
    if (!isnan(ev->control)) {
        ev->texture = (nb ? wb/nb : wa/na);
        ev->unrelated = ev->texture + (nb ? tb/nb : ta/na);
    }
}

/* Where the lines are looked at: window seconds of lines scanned by frames
 * not flagged on either side of the fitted time, counted across flagged
 * frames and pauses between frames, which show nothing of the jump: a
 * fitted time in a flagged frame, or in the first lines of the frame after
 * it, may belong to the last lines of the frame before it (the blocks
 * place the jump no closer; test-series-correction seeds 700000014 and
 * 810000003 put it into the second line of the frame after a flagged
 * one, and the featureless lines at the end of the frame before it,
 * where it lay, were never looked at). */
static gdouble
window_edge(const SeriesCorrection *correction, const FrameSeries *series,
            gdouble t, gdouble window, gint direction)
{
    gdouble edge = t, left = window, start, end, seen;
    gint k, i, nf = series->n_frames;

    for (i = 0; i < nf && left > 0.0; i++) {
        k = (direction > 0) ? i : nf-1 - i;
        if (correction->frames[k].flagged)
            continue;
        start = series->frames[k].timing.frame_start;
        end = scan_timing_frame_end(&series->frames[k].timing);
        if (direction > 0 ? end <= t : start >= t)
            continue;
        /* The part of this frame's lines on the window's side of t. */
        seen = (direction > 0) ? end - MAX(start, t) : MIN(end, t) - start;
        if (seen >= left)
            return (direction > 0) ? MAX(start, t) + left : MIN(end, t) - left;
        left -= seen;
        edge = (direction > 0) ? end : start;
    }
    return (left > 0.0) ? edge + direction*left : edge;
}

static void
jump_search_window(const SeriesCorrection *correction,
                   const FrameSeries *series, gdouble t, gdouble window,
                   gdouble *t_lo, gdouble *t_hi)
{
    *t_lo = window_edge(correction, series, t, window, -1);
    *t_hi = window_edge(correction, series, t, window, +1);
}

/* Equally good splits first .. last leave the jump anywhere from the end
 * of line first-1 to the start of line last: lines without evidence, or a
 * flagged frame or a pause between frames, whose lines nobody judges.  The
 * blocks' fit is then the best guess, kept within that span; in the middle
 * of a gap, a guess at its edge would put lines of a trusted frame on the
 * wrong side. */
static gdouble
jump_within_ties(gdouble fitted, const gdouble *when, const gdouble *ends,
                 gint n, gint first, gint last, gdouble t_lo, gdouble t_hi)
{
    gdouble lo = (first > 0) ? ends[first-1] : t_lo;
    gdouble hi = (last < n) ? when[last] : t_hi;

    if (first == last)
        return when[first];
    return CLAMP(fitted, lo, hi);
}

/* The fit places a jump within a block or so (blocks straddling it register
 * to either side).  Line by line, against a neighbouring frame, the lines
 * before the jump match the drift without the step and those after it the
 * drift with it: the jump goes where the two runs meet best.  Lines of
 * every frame within the search window count (a jump near a frame's end
 * may lie in the next). */
static void
localise_jump(SeriesCorrection *correction, const FrameSeries *series,
              gdouble block_span)
{
    DriftFit *fit = correction->fit.fits + correction->fit.chosen;
    gint nf = series->n_frames, k, r, i, n = 0, first, last, lo, hi, most = 0;
    gdouble *line, *when, *ends, t, t_lo, t_hi, reach;
    LineEvidence *evidence;
    gint *frame;

    if (fit->type != DRIFT_MODEL_JUMP || nf < 2)
        return;
    jump_search_window(correction, series, fit->nonlinear,
                       JUMP_SEARCH_BLOCKS*block_span, &t_lo, &t_hi);
    for (k = 0; k < nf; k++)
        most += series->frames[k].timing.yres;
    line = g_new0(gdouble, JUMP_WORK_ROWS*series->frames[0].timing.xres);
    reach = jump_place_reach(correction);
    when = g_new(gdouble, 2*most);
    ends = when + most;
    frame = g_new(gint, most);
    evidence = g_new0(LineEvidence, most);
    /* The lines around the jump in the order they were scanned. */
    for (k = 0; k < nf; k++) {
        const SeriesFrame *fk = series->frames + k;

        /* A flagged frame's lines are out of line under either drift. */
        for (i = 0; i < fk->timing.yres && !correction->frames[k].flagged; i++) {
            r = (fk->timing.direction == SCAN_DIRECTION_UP) ? fk->timing.yres-1 - i : i;
            t = scan_timing_rows_time(&fk->timing, r, r+1);
            if (t < t_lo || t > t_hi)
                continue;
            line_costs(correction, series, k, r, reach, line, evidence + n);
            evidence[n].frame_edge = (i == 0 || i == fk->timing.yres-1);
            when[n] = scan_timing_row_start(&fk->timing, r);
            ends[n] = when[n] + fk->timing.line_time;
            frame[n] = k;
            n++;
        }
    }
    correction->jump_tied_lines = 0;
    if (jump_votes_split_loose(evidence, frame, n, &first, &last, &lo, &hi)) {
        fit->nonlinear = jump_within_ties(fit->nonlinear, when, ends, n,
                                          first, last, t_lo, t_hi);
        correction->jump_tied_lines = hi - lo;
        /* The lines either side of the tie may hold the jump themselves
         * (5.6 ms into the first line after it, the jump lay outside a
         * window that ended where that line began: seed 800000458 of
         * test-series-correction): the window takes them in. */
        correction->jump_window[0] = (lo > 0) ? when[lo-1] : t_lo;
        correction->jump_window[1] = (hi < n) ? ends[hi] : t_hi;
    }
    g_free(evidence);
    g_free(frame);
    g_free(line);
    g_free(when);
}

/* A jump whose lines tie over this many lines or more is reported: the
 * trajectory on them is a guess (a single line between two runs is the
 * jump's own). */
#define JUMP_TIED_WARN_LINES 2

/* Whether frame k was scanned, at least in part, within the jump's
 * window. */
static gboolean
frame_within_window(const SeriesCorrection *correction,
                    const FrameSeries *series, gint k)
{
    const ScanTiming *timing = &series->frames[k].timing;

    return (timing->frame_start < correction->jump_window[1]
            && scan_timing_frame_end(timing) > correction->jump_window[0]);
}

/* The lines that tie around the chosen jump (featureless, or seen by no
 * other frame) are corrected by the blocks' guess: the data cannot tell
 * where in them the jump lies, and the user is told which times those
 * are (a jump in the last featureless lines of a frame before a flagged
 * one, seed 480000936 of test-series-correction: their drift is 5.9 px
 * either way, and no particle on them shows it). */
static void
warn_about_jump(SeriesCorrection *correction, const FrameSeries *series)
{
    const DriftFit *chosen = correction->fit.fits + correction->fit.chosen;

    GString *text;
    gint k, n_flagged = 0;

    /* What is not reported is no window at all (the trajectory is the
     * flexible one, or a line or none ties). */
    if (correction->use_smooth || chosen->type != DRIFT_MODEL_JUMP
        || correction->jump_tied_lines < JUMP_TIED_WARN_LINES) {
        correction->jump_tied_lines = 0;
        return;
    }
    correction->jump_window[0] = MAX(correction->jump_window[0], 0.0);
    correction->jump_window[1] = MIN(correction->jump_window[1], correction->span_s);
    /* Seconds to four digits: lines of HS-AFM movies take a millisecond. */
    text = g_string_new(NULL);
    g_string_printf(text, _("the jump at %.6g s may lie anywhere from %.6g s "
                            "to %.6g s: %d scan lines there show nothing "
                            "that surely places them before or after it"),
                    chosen->nonlinear, correction->jump_window[0],
                    correction->jump_window[1], correction->jump_tied_lines);
    for (k = 0; k < correction->n_frames; k++)
        n_flagged += (correction->frames[k].flagged
                      && frame_within_window(correction, series, k));
    if (n_flagged)
        g_string_append_printf(text, _(", and %d flagged frames lie within "
                                       "it"), n_flagged);
    add_warning(correction, g_string_free(text, FALSE));
}

/* Blocks straddling the jump pull the fitted time and with it the step and
 * the velocity; once the lines place the jump, the model is refitted with
 * the jump there and the lines looked at again under the better model
 * (a jump placed 4 lines early by the blocks stayed there when the
 * lines were judged by the model fitted to that early time). */
#define JUMP_LOCATE_ROUNDS 3

static void
locate_jump(SeriesCorrection *correction, const FrameSeries *series,
            gdouble block_span)
{
    FitReport *report = &correction->fit;
    DriftFit *fit = report->fits + report->chosen;
    gdouble before;
    gint round;

    for (round = 0; round < JUMP_LOCATE_ROUNDS; round++) {
        before = fit->nonlinear;
        localise_jump(correction, series, block_span);
        if (fit->type != DRIFT_MODEL_JUMP
            || fit->creep != DRIFT_FIT_CREEP_NONE
            || fit->nonlinear == before)
            break;
        if (!drift_fit_refit_at(report->meas, report->n_meas, fit->nonlinear, fit)) {
            /* A time the blocks cannot fit a step at (every block spans
             * it): the trajectory stays as fitted, and a window of tied
             * lines that leaves its jump out is no longer about it. */
            fit->nonlinear = before;
            if (before < correction->jump_window[0] || before > correction->jump_window[1])
                correction->jump_tied_lines = 0;
            break;
        }
    }
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
        d->n_blocks = MIN(d->n_blocks, MAX(timing->yres/MIN_BLOCK_LINES, 1));
        if (series->n_frames > SERIES_CORRECTION_ALL_PAIRS_UP_TO)
            d->pair_reach = SERIES_CORRECTION_PAIR_REACH;
    }
    if (foptions)
        *f = *foptions;
    else
        drift_fit_options_init(f);
    fit_report_options_for_series(f, series);
    if (f->min_period <= 0.0)
        f->min_period = drift_fit_min_period(timing->line_time, timing->yres,
                                             d->n_blocks);
}

/* Measures the displacements between the frames in d's blocks, finds the
 * frames that disagree with the rest and fits the trajectory without
 * them.  *registered (n_meas entries, g_free) gets each measurement's
 * weight as registered, frames flagged for missing data left out. */
static gboolean
measure_and_fit(SeriesCorrection *correction, const FrameSeries *series,
                const DisplacementOptions *d, const Progress *progress,
                gdouble **registered, gboolean *cancelled)
{
    FitReport *fit = &correction->fit;
    gdouble *weights;
    gboolean ok;
    gint i;

    fit->meas = displacement_measure_series_progress(series, d, progress,
                                                     &fit->n_meas);
    if ((*cancelled = !fit->meas)) {
        *registered = NULL;
        return FALSE;
    }
    *registered = g_new(gdouble, 2*MAX(fit->n_meas, 1));
    weights = *registered + MAX(fit->n_meas, 1);
    flag_mostly_missing(correction, series);
    for (i = 0; i < fit->n_meas; i++) {
        (*registered)[i] = fit->meas[i].weight;
        if (correction->frames[fit->meas[i].frame_a].flagged
            || correction->frames[fit->meas[i].frame_b].flagged)
            (*registered)[i] = 0.0;
    }
    /* Frames that disagree with the rest are found first, then the
     * trajectory is fitted without them. */
    if (!(ok = fit_models(correction, *registered, d->n_blocks)))
        return FALSE;
    judge_frames(correction, *registered);
    flag_unregistered(correction);
    if (series->n_frames <= SERIES_CORRECTION_LEAVE_OUT_UP_TO)
        flag_by_leaving_out(correction, *registered);
    if (series->n_frames > SERIES_CORRECTION_LEAVE_OUT_UP_TO
        || series->n_frames < LEAVE_OUT_MIN_OTHERS + 1)
        flag_outlying(correction);
    if (drop_flagged(correction, *registered, weights)
        && !fit_models(correction, weights, d->n_blocks)) {
        /* Too little was left: keep every frame in the fit. */
        ok = fit_models(correction, *registered, d->n_blocks);
    }
    return ok;
}

/* Every frame unjudged again (a new measurement judges them afresh). */
static void
verdicts_reset(SeriesCorrection *correction)
{
    gint k;

    for (k = 0; k < correction->n_frames; k++)
        g_free(correction->frames[k].reason);
    memset(correction->frames, 0, correction->n_frames*sizeof(SeriesFrameVerdict));
}

/* A block registers as one shift, but the drift moves on while its lines
 * are scanned: where it changes within the block differently in the two
 * frames (a settling in its first seconds), the two blocks differ in
 * shape and the shift read is biased (a fast settling's travel read 6-10 %
 * short, 0.4 px over the series, seed 11000392 of test-series-correction).
 * TRUE, with d's blocks shortened, when the fitted trajectory changes by
 * more than BLOCK_SHAPE_PX more within one block of a pair than within the
 * other, and shorter blocks of at least FINE_BLOCK_LINES lines exist. */
static gboolean
finer_blocks(const SeriesCorrection *correction, const FrameSeries *series,
             DisplacementOptions *d)
{
    const FitReport *fit = &correction->fit;
    const DriftFit *chosen = fit->fits + fit->chosen;
    gint yres = series->frames[0].timing.yres, i, finer;
    gdouble worst = 0.0, h, a[2], b[2], c[2], e[2];

    finer = MIN((gint)ceil(FINER_BLOCKS*d->n_blocks), yres/FINE_BLOCK_LINES);
    if (finer <= d->n_blocks)
        return FALSE;
    for (i = 0; i < fit->n_meas; i++) {
        const DriftMeasurement *m = fit->meas + i;

        if (!(m->weight > 0.0) || !(m->span > 0.0))
            continue;
        h = 0.5*m->span;
        drift_fit_eval(chosen, m->t_a + h, a, a + 1);
        drift_fit_eval(chosen, m->t_a - h, b, b + 1);
        drift_fit_eval(chosen, m->t_b + h, c, c + 1);
        drift_fit_eval(chosen, m->t_b - h, e, e + 1);
        worst = MAX(worst, hypot(((a[0] - b[0]) - (c[0] - e[0]))/correction->xstep,
                                 ((a[1] - b[1]) - (c[1] - e[1]))/correction->ystep));
    }
    if (worst <= BLOCK_SHAPE_PX)
        return FALSE;
    d->n_blocks = finer;
    return TRUE;
}

gboolean
series_correction_compute(const FrameSeries *series,
                          const DisplacementOptions *doptions,
                          const DriftFitOptions *foptions,
                          SeriesCorrection *correction, GError **error)
{
    return series_correction_compute_progress(series, doptions, foptions,
                                              NULL, correction, error);
}

/* The share of the work the first measurement takes, then each round of
 * shorter blocks (FINER_ROUNDS); the fits and the rest take what is left. */
#define PROGRESS_MEASURE 0.75
#define PROGRESS_FINER 0.1

/* Frames not flagged. */
static gint
frames_kept(const SeriesCorrection *correction)
{
    gint k, n = 0;

    for (k = 0; k < correction->n_frames; k++)
        n += !correction->frames[k].flagged;
    return n;
}

/* The reason the first flagged frame was flagged, "" when none is. */
static const gchar*
first_flag_reason(const SeriesCorrection *correction)
{
    gint k;

    for (k = 0; k < correction->n_frames; k++) {
        if (correction->frames[k].flagged && correction->frames[k].reason)
            return correction->frames[k].reason;
    }
    return "";
}

/* The first frame whose pixels are all alike (a channel that recorded
 * nothing), or -1. */
static gint
featureless_frame(const FrameSeries *series)
{
    gdouble min, max;
    gint k;

    for (k = 0; k < series->n_frames; k++) {
        gwy_data_field_get_min_max(series->frames[k].field, &min, &max);
        if (min == max)
            return k;
    }
    return -1;
}

/* Too few blocks registered to fit anything: said with the frame to
 * blame where one is featureless (two frames, the second constant, were
 * refused without a word of it). */
static void
refuse_unregistered(const FrameSeries *series, GError **error)
{
    gint k = featureless_frame(series);

    if (k >= 0)
        g_set_error(error, SERIES_CORRECTION_ERROR, SERIES_CORRECTION_ERROR_FIT,
                    _("too few blocks of the frames could be registered against each "
                      "other to fit a drift trajectory: frame %d (%s) is featureless, "
                      "every pixel the same"), k, series->frames[k].label);
    else
        g_set_error(error, SERIES_CORRECTION_ERROR, SERIES_CORRECTION_ERROR_FIT,
                    _("too few blocks of the frames could be registered "
                      "against each other to fit a drift trajectory"));
}

gboolean
series_correction_compute_progress(const FrameSeries *series,
                                   const DisplacementOptions *doptions,
                                   const DriftFitOptions *foptions,
                                   const Progress *progress,
                                   SeriesCorrection *correction,
                                   GError **error)
{
    DisplacementOptions d;
    FitReport *fit = &correction->fit;
    gdouble *registered = NULL;
    gboolean ok, cancelled = FALSE, unsupported = FALSE;
    gint round, knot_blocks;
    Progress part;
    guint i;

    memset(correction, 0, sizeof(SeriesCorrection));
    correction->refused_type = -1;
    correction->n_frames = series->n_frames;
    correction->frames = g_new0(SeriesFrameVerdict, series->n_frames);
    correction->warnings = g_ptr_array_new_with_free_func(g_free);
    correction->xstep = frame_series_dx(series);
    correction->ystep = frame_series_dy(series);
    correction->frame_nm = 1e9*MIN(correction->xstep*series->frames[0].timing.xres,
                                   correction->ystep*series->frames[0].timing.yres);
    correction->span_s = scan_timing_frame_end(&series->frames[series->n_frames-1].timing);
    for (i = 0; i < series->notes->len; i++)
        add_warning(correction,
                    g_strdup(g_ptr_array_index(series->notes, i)));
    prepare_options(series, doptions, foptions, &d, &fit->fit_options);
    knot_blocks = d.n_blocks;
    drift_fit_candidates(&fit->n_fits);
    part = progress_part(progress, 0.0, PROGRESS_MEASURE);
    ok = measure_and_fit(correction, series, &d, &part, &registered, &cancelled);
    /* Blocks too long for the drift's own changes: measured again in
     * shorter ones (only when the caller left the blocks to us). */
    for (round = 0; ok && !doptions && round < FINER_ROUNDS
         && finer_blocks(correction, series, &d); round++) {
        if (!foptions)
            fit->fit_options.min_period
                = drift_fit_min_period(series->frames[0].timing.line_time,
                                       series->frames[0].timing.yres,
                                       d.n_blocks);
        g_free(registered);
        g_free(fit->meas);
        fit->meas = NULL;
        verdicts_reset(correction);
        part = progress_part(progress, PROGRESS_MEASURE + round*PROGRESS_FINER,
                             PROGRESS_MEASURE + (round + 1)*PROGRESS_FINER);
        ok = measure_and_fit(correction, series, &d, &part, &registered,
                             &cancelled);
    }
    /* The line-by-line jump and the flexible trajectory take seconds on a
     * long series: a cancel given meanwhile is honoured after them. */
    if (ok && !progress_report(progress, PROGRESS_MEASURE + FINER_ROUNDS*PROGRESS_FINER))
        ok = !(cancelled = TRUE);
    if (ok) {
        locate_jump(correction, series,
                    series->frames[0].timing.yres*series->frames[0].timing.line_time/d.n_blocks);
        /* Knots as for the blocks first asked for: shorter blocks measure a
         * fast drift better, but knots as dense let the flexible
         * trajectory swing with the blocks' noise (a random walk 3.1 px
         * off with knots every 4 lines, 0.06 px with every 8; seed
         * 18000161). */
        fit_smooth(correction, series, knot_blocks);
        judge_frames(correction, registered);
        if (series->n_frames > SERIES_CORRECTION_LEAVE_OUT_UP_TO) {
            flag_outlying(correction);
            judge_frames(correction, registered);
        }
        warn_about_fit(correction, registered);
        warn_about_jump(correction, series);
        ok = !(cancelled = !progress_report(progress, 1.0));
        unsupported = ok && frames_kept(correction) < 2;
        ok = ok && !unsupported;
    }
    if (!ok && cancelled)
        g_set_error(error, SERIES_CORRECTION_ERROR,
                    SERIES_CORRECTION_ERROR_CANCELLED,
                    _("the measurement of the series was cancelled"));
    else if (unsupported)
        g_set_error(error, SERIES_CORRECTION_ERROR,
                    SERIES_CORRECTION_ERROR_FIT,
                    _("%d of the %d frames were flagged (%s): no two frames "
                      "agree on a drift trajectory (featureless frames, frames "
                      "of other areas, or a drift that moves the content more "
                      "than a quarter of the frame along an axis from frame to "
                      "frame)"),
                    series->n_frames - frames_kept(correction), series->n_frames,
                    first_flag_reason(correction));
    else if (!ok)
        refuse_unregistered(series, error);
    g_free(registered);
    return ok;
}

void
series_correction_clear(SeriesCorrection *correction)
{
    gint k;

    fit_report_clear(&correction->fit);
    smooth_trajectory_free(correction->smooth);
    correction->smooth = NULL;
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
    eval_side(correction, t, JUMP_AS_FITTED, dx_px, dy_px);
}

/* The moments a frame's drift is sampled at: every line, and the frame's
 * start and end (the compensation looks a line beyond). */
static DriftMeasurement*
line_samples(const ScanTiming *timing, gint *n)
{
    gint r;
    DriftMeasurement *meas;

    *n = timing->yres + 2;
    meas = g_new0(DriftMeasurement, *n);
    for (r = 0; r < *n; r++) {
        if (r == 0)
            meas[r].t_a = timing->frame_start;
        else if (r == *n - 1)
            meas[r].t_a = scan_timing_frame_end(timing);
        else
            meas[r].t_a = scan_timing_rows_time(timing, r-1, r);
        meas[r].weight = 1.0;
    }
    return meas;
}

/* The samples as a spline the continuous compensation can follow: t_b = 0
 * makes t = 0 the moment the corrected frame shows.  Scanning up, the
 * rows' times fall; the spline sorts by time. */
static DriftTrajectory*
spline_through(DriftMeasurement *meas, gint n, GError **error)
{
    DriftTrajectory *trajectory = drift_trajectory_new_interpolating(meas, n,
                                                                     error);

    g_free(meas);
    return trajectory;
}

DriftTrajectory*
series_fit_trajectory(const DriftFit *fit, gdouble xstep, gdouble ystep,
                      const ScanTiming *timing, GError **error)
{
    gint n, r;
    DriftMeasurement *meas = line_samples(timing, &n);

    for (r = 0; r < n; r++)
        fit_eval_side(fit, xstep, ystep, meas[r].t_a, JUMP_AS_FITTED,
                      &meas[r].dx, &meas[r].dy);
    return spline_through(meas, n, error);
}

static DriftTrajectory*
frame_trajectory(const SeriesCorrection *correction, const ScanTiming *timing,
                 JumpSide side, GError **error)
{
    gint n, r;
    DriftMeasurement *meas = line_samples(timing, &n);

    for (r = 0; r < n; r++)
        eval_side(correction, meas[r].t_a, side, &meas[r].dx, &meas[r].dy);
    return spline_through(meas, n, error);
}

/* A fitted jump while this frame was scanned, or so close to it that the
 * compensation, which looks a line beyond the frame, would see it. */
static gboolean
jump_in_frame(const SeriesCorrection *correction, const ScanTiming *timing)
{
    const DriftFit *fit = correction->fit.fits + correction->fit.chosen;
    gdouble t0 = timing->frame_start - 2.0*timing->line_time;
    gdouble t1 = scan_timing_frame_end(timing) + 2.0*timing->line_time;

    return (!correction->use_smooth
            && fit->type == DRIFT_MODEL_JUMP && fit->creep == DRIFT_FIT_CREEP_NONE
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
    gdouble fill = localscan_fill_value(field, LOCALSCAN_FILL_MEAN);
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
    gdouble dx, dy, when;
    gint k, i, r;

    trajectory_csv_begin(text, "drift trajectory", correction->xstep,
                         correction->ystep);
    for (k = 0; k < series->n_frames; k++) {
        const ScanTiming *timing = &series->frames[k].timing;

        for (i = 0; i < timing->yres; i++) {
            r = (timing->direction == SCAN_DIRECTION_UP) ? timing->yres-1 - i : i;
            when = scan_timing_rows_time(timing, r, r+1);
            series_correction_eval(correction, when, &dx, &dy);
            trajectory_csv_line(text, k, r, when, dx, dy, 4);
        }
    }
    return g_string_free(text, FALSE);
}

/* Which trajectory corrected the frames: the chosen model, or the flexible
 * one where no model explains the drift. */
static void
add_trajectory_choice(JsonBuilder *b, const SeriesCorrection *correction)
{
    const DriftFit *chosen = correction->fit.fits + correction->fit.chosen;

    json_builder_set_member_name(b, "trajectory");
    json_builder_begin_object(b);
    json_builder_set_member_name(b, "model");
    json_builder_add_string_value(b, correction->use_smooth ? "smooth"
                                  : drift_model_type_name(chosen->type));
    json_values_set_number(b, "model_cv_rms_nm", chosen->cv_rms_nm);
    json_values_set_number(b, "smooth_cv_rms_nm",
                           correction->smooth ? correction->smooth->cv_rms_nm
                           : NAN);
    json_values_set_number(b, "smooth_rms_nm",
                           correction->smooth ? correction->smooth->rms_nm : NAN);
    json_builder_set_member_name(b, "smooth_knots");
    json_builder_add_int_value(b, correction->smooth ? correction->smooth->n_knots : 0);
    json_builder_end_object(b);
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
        json_values_add_text(b, series->frames[k].label);
        json_values_set_timing(b, "t_start_s", &series->frames[k].timing);
        json_builder_set_member_name(b, "flagged");
        json_builder_add_boolean_value(b, v->flagged);
        json_builder_set_member_name(b, "reason");
        if (v->reason)
            json_values_add_text(b, v->reason);
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
    add_trajectory_choice(b, correction);
    add_frame_verdicts(b, correction, series);
    json_builder_set_member_name(b, "warnings");
    json_builder_begin_array(b);
    for (i = 0; i < correction->warnings->len; i++)
        json_values_add_text(b, g_ptr_array_index(correction->warnings, i));
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

gboolean
series_correction_trusted_area(const SeriesCorrection *correction,
                               GwyDataField **masks, gint n, gint *area)
{
    GwyDataField **trusted = g_new(GwyDataField*, MAX(n, 1));
    gboolean ok;
    gint k, m = 0;

    for (k = 0; k < n; k++) {
        if (!correction->frames[k].flagged)
            trusted[m++] = masks[k];
    }
    if (!m) {
        for (k = 0; k < n; k++)
            trusted[m++] = masks[k];
    }
    ok = series_correction_common_area(trusted, m, area, area + 1, area + 2, area + 3);
    g_free(trusted);
    return ok;
}

GwyDataField*
series_correction_crop_to_area(GwyDataField *field, const gint *area)
{
    GwyDataField *part = gwy_data_field_area_extract(field, area[0], area[1],
                                                     area[2], area[3]);

    gwy_data_field_set_xoffset(part, gwy_data_field_get_xoffset(field)
                               + gwy_data_field_jtor(field, area[0]));
    gwy_data_field_set_yoffset(part, gwy_data_field_get_yoffset(field)
                               + gwy_data_field_itor(field, area[1]));
    return part;
}
