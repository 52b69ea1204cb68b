/*
 *  The series correction (modules/core/series-correction.h) on simulated
 *  series with a random drift effect hidden in them (drawn as
 *  hidden-effect-cases.c draws it, seeded): the trajectory on every scan
 *  line, the corrected frames against the drift-free truth, the effect
 *  named, a disturbed frame flagged and no other; and the outputs: the
 *  trajectory CSV, the JSON and the common area.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <stdlib.h>
#include <string.h>
#include <math.h>
#include <check.h>
#include <json-glib/json-glib.h>
#include <libgwyddion/gwyddion.h>
#include <libprocess/gwyprocess.h>
#include "hidden-effect-cases.h"
#include "series-cases.h"
#include "displacement-measure.h"
#include "median.h"
#include "test-common.h"

/* What the soaks of docs/series.md allow (over every scan line of every
 * frame but the disturbed one, lines within 3 of a jump left out, and
 * featureless lines the correction reports it cannot place): the
 * typical case is 0.02 to 0.05 px; over 172 seeds (2580 cases) the worst
 * were a trajectory of 0.27 px, a stripe of 0.38 px and a frame of
 * 0.32 px, a fast settling whose excess travel is read a few per cent
 * short (seed 8000147) or an oscillation beside a slipped frame (seed
 * 8000189).  Later soaks found fast settlings whose frames lay 0.44 and
 * 0.40 px off (seeds 800000065 and 576000040, case 1 and 6; 0.40 and
 * 0.36 px since blocks are timed at the row the registration measured):
 * frame 0's first rows, the only view of the settling's start, read
 * 0.4-0.5 px off in every pair alike (docs/series.md, not done yet). */
#define TRAJECTORY_RMS_MAX 0.4
#define STRIPE_MAX 0.5
#define FRAME_MAX 0.4
/* A random walk of 0.02 nm/s per sqrt(s): the trajectory without its mean
 * error (docs/series.md; typically under 0.1 px, 1.06 px at worst over
 * those seeds, where the flexible trajectory reads frame 0's own drift
 * worse than the best model: held-out error does not always pick the
 * truer trajectory). */
#define WALK_RELATIVE_MAX 2.0

/* Cases: effect hidden_case_effect(_i), raw channels for every other
 * round of the effects, a disturbed frame in the third round. */
#define N_CASES (3*SERIES_CASE_EFFECTS)

static guint32 base_seed;

/* Case i of the series scanned under model, corrected and judged. */
static void
check_model_case(gint i, const DriftModel *model_given,
                 const SeriesCaseOptions *options)
{
    DriftModel model;
    GwyDataField **truth = NULL;
    SeriesCaseResult r;
    FrameSeries *series;
    gint k;

    drift_model_copy(&model, model_given);
    series = series_case_scan(base_seed, i, &model, options, &truth);
    ck_assert(series != NULL);
    ck_assert_msg(series_case_judge(series, truth, &model, options, &r),
                  "case %d (seed %u): the correction failed", i, base_seed);
    printf("case %2d %-11s raw %d disturbed %2d: trajectory rms %.3f px "
           "(worst line %.3f), stripes %.3f px, frames %.3f px, named %d, "
           "flagged %d\n", i, drift_model_type_name(model.type),
           options->raw, options->disturbed, r.trajectory_rms_px,
           r.trajectory_worst_px, r.stripe_worst_px, r.frame_worst_px,
           r.effect_named, r.flagged);
    fflush(stdout);
    ck_assert_msg(r.effect_named, "case %d (seed %u): %s not named", i,
                  base_seed, drift_model_type_name(model.type));
    ck_assert_msg(r.trajectory_rms_px <= TRAJECTORY_RMS_MAX,
                  "case %d (seed %u): trajectory rms %g px", i, base_seed,
                  r.trajectory_rms_px);
    ck_assert_msg(r.stripe_worst_px <= STRIPE_MAX,
                  "case %d (seed %u): a stripe keeps %g px", i, base_seed,
                  r.stripe_worst_px);
    ck_assert_msg(r.frame_worst_px <= FRAME_MAX,
                  "case %d (seed %u): a frame lies %g px from the truth", i,
                  base_seed, r.frame_worst_px);
    ck_assert_msg(r.flagged == (options->disturbed >= 0),
                  "case %d (seed %u): %d frames flagged", i, base_seed,
                  r.flagged);
    if (options->disturbed >= 0)
        ck_assert_msg(r.disturbed_flagged,
                      "case %d (seed %u): frame %d (slipped) not flagged", i,
                      base_seed, options->disturbed);
    for (k = 0; k < 2*SERIES_CASE_FRAMES; k++)
        g_object_unref(truth[k]);
    g_free(truth);
    frame_series_free(series);
    drift_model_clear(&model);
}

static void
check_case(gint i, const SeriesCaseOptions *options)
{
    DriftModel model;

    hidden_case_draw(base_seed, i, &model);
    check_model_case(i, &model, options);
    drift_model_clear(&model);
}

START_TEST(test_hidden_drift_corrected)
{
    SeriesCaseOptions options;

    options.raw = (_i/SERIES_CASE_EFFECTS) % 2;
    options.disturbed = -1;
    /* An inner frame: the first or the last frame slipped is a jump at
     * its border, which nothing can tell from a real one. */
    if (_i >= 2*SERIES_CASE_EFFECTS) {
        GRand *rng = g_rand_new_with_seed(base_seed + _i);

        options.disturbed = g_rand_int_range(rng, 1, SERIES_CASE_FRAMES - 1);
        g_rand_free(rng);
    }
    check_case(_i, &options);
}
END_TEST

/* A line judged by one drift only must stand well above the typical
 * match of the lines around (a few 1e-18 m^2) to count: at 2.1e-17 m^2 it
 * did not, and seed 370001600 drew a sample whose only evidence it was. */
#define JUDGED_LINE_TEXTURE 5e-17

typedef gboolean (*LinesWanted)(const gdouble *texture,
                                const ScanTiming *timing,
                                const DriftModel *model);

/* Whether frame 0 of case i scanned under model has the lines wanted,
 * judged by their textures (series_case_line_texture). */
static gboolean
first_frame_lines(guint32 seed, gint i, const DriftModel *model,
                  const SeriesCaseOptions *options, LinesWanted wanted)
{
    FrameSeries *series = series_case_scan(seed, i, model, options, NULL);
    const ScanTiming *timing;
    gdouble *texture;
    gboolean found;
    gint r;

    ck_assert(series != NULL);
    timing = &series->frames[0].timing;
    texture = g_new(gdouble, timing->yres);
    for (r = 0; r < timing->yres; r++)
        texture[r] = series_case_line_texture(series->frames[0].field, r);
    found = wanted(texture, timing, model);
    g_free(texture);
    frame_series_free(series);
    return found;
}

/* Whether the first line of frame 0 that the judge counts after the jump
 * (3 lines past it and more) shows particles and is not the frame's last
 * line: a featureless line matches either drift, and the last line's
 * content lies past the last line of every later frame, so nothing in the
 * data says on which side of the jump they lie. */
static gboolean
judged_line_has_evidence(const gdouble *texture, const ScanTiming *timing,
                         const DriftModel *model)
{
    gint r;

    for (r = 0; r < timing->yres; r++) {
        if (scan_timing_rows_time(timing, r, r+1) >= model->t_jump + 1.5)
            return r < timing->yres - 1 && texture[r] > JUDGED_LINE_TEXTURE;
    }
    return FALSE;
}

/* A jump lines_lo to lines_hi lines before the end of frame 0 (128
 * lines of 0.5 s), a step of 3.5-6 px down and up to 1 px across, on a
 * slow drift. */
static void
draw_end_jump(GRand *rng, gdouble lines_lo, gdouble lines_hi,
              DriftModel *model)
{
    gdouble px = 1e-6/128.0;

    drift_model_init(model, DRIFT_MODEL_JUMP);
    model->v[0] = g_rand_double_range(rng, -0.05e-9, 0.05e-9);
    model->v[1] = g_rand_double_range(rng, -0.05e-9, 0.05e-9);
    model->t_jump = 64.0 - 0.5*g_rand_double_range(rng, lines_lo, lines_hi);
    model->step[0] = px*g_rand_double_range(rng, -1.0, 1.0);
    model->step[1] = px*g_rand_double_range(rng, 3.5, 6.0);
}

/* A jump in the last lines of the first frame, whose next frame slipped
 * (flagged, left out): the step moves those lines' content down out of
 * every later frame under the drift without it, and no earlier frame
 * shows it, so only their match under the drift with it tells that they
 * lie after the jump.  Without that evidence the jump went into the
 * slipped frame, and those lines kept the whole step (5.4 px; seed
 * 310000476, case 13).  Frames of 128 lines of 0.5 s, back to back; the
 * jump 4.5-6.5 lines before the end of frame 0 (so that the judge counts
 * a line after it other than the last), a step of 3.5-6 px down and up to
 * 1 px across; the sample drawn again until the first line judged after
 * the jump shows particles (one draw in three, and up to 11 draws over
 * 93 loops of seeds 100-130: twenty
 * draws were not always enough, seed 573000288; each run of the loop
 * draws its cases from its own hundred). */
/* check(loop) as seed draws it: the replay of a draw that failed once,
 * whatever the seed of this run. */
static void
replay_draw(guint32 seed, void (*check)(gint), gint loop)
{
    guint32 saved = base_seed;

    base_seed = seed;
    check(loop);
    base_seed = saved;
}

static void
check_jump_before_slipped_frame(gint loop)
{
    GRand *rng = test_rand_salted(base_seed, 4000 + loop);
    SeriesCaseOptions options = { FALSE, 1 };
    DriftModel model;
    gint attempt, i = 300 + 100*loop;

    for (attempt = 0; attempt < 100; attempt++, i++) {
        draw_end_jump(rng, 4.5, 6.5, &model);
        if (first_frame_lines(base_seed, i, &model, &options,
                              judged_line_has_evidence))
            break;
    }
    ck_assert_msg(attempt < 100, "seed %u: no sample shows particles after the jump", base_seed);
    printf("jump before slipped frame %d: case %d, sample drawn %d times\n", loop, i, attempt + 1);
    check_model_case(i, &model, &options);
    drift_model_clear(&model);
    g_rand_free(rng);
}

START_TEST(test_jump_before_slipped_frame)
{
    check_jump_before_slipped_frame(_i);
}
END_TEST

/* The draw of seed 20000352, loop 2 (case 504): the lines after a jump
 * 1.5 s before frame 0's end matched their content under the drift with
 * the step five times better than a typical line matches (6.3e-19 against
 * 3.3e-18), but their content a step further off cost only 6.5 times the
 * typical match, not the 8 times a one-sided line's control had to, so
 * they told nothing; the jump went 2 s late and a textured line kept
 * 5.3 px (jump-votes.c, evidence_costs).  Replayed whatever the seed. */
START_TEST(test_jump_lines_matching_better_than_typical)
{
    replay_draw(20000352, check_jump_before_slipped_frame, 2);
}
END_TEST

/* The draw of seed 68000484, loop 1 (case 401): textured lines after a
 * jump 4.5-6.5 lines before frame 0's end cost more under the fitted
 * drift with the step than a pixel off (the fit a fraction of a pixel
 * off there), so were no minima and told nothing, and a stripe kept
 * 0.56 px; each side is now matched within half a pixel of its fitted
 * place (series-correction.c, side_mismatch).  Replayed whatever the
 * seed. */
START_TEST(test_jump_lines_a_fraction_off_the_fit)
{
    replay_draw(68000484, check_jump_before_slipped_frame, 1);
}
END_TEST

/* Whether every line of frame 0 from the jump's to the last shows
 * nothing (series_case_line_texture below 1e-18 m^2). */
static gboolean
featureless_after_jump(const gdouble *texture, const ScanTiming *timing,
                       const DriftModel *model)
{
    gint r;

    for (r = 0; r < timing->yres; r++) {
        if (scan_timing_row_start(timing, r) + timing->line_time > model->t_jump
            && !(texture[r] < 1e-18))
            return FALSE;
    }
    return TRUE;
}

/* The same jump in frame 0's last 2-5 lines before a slipped frame, but
 * those lines show nothing, nor would they without the jump
 * (featureless_without_jump): no line places the jump, and the correction
 * must say between which times it may lie (the true time among them),
 * and correct the rest as well as ever (the judge leaves out the
 * featureless lines in that window).  Seed 480000936 of
 * test_hidden_drift_corrected drew such a case: 5.9 px on a featureless
 * last line, and no word of it. */
static void check_jump_in_featureless_lines(gint loop, gboolean both_sides);

static void
check_featureless_as_scanned(gint loop)
{
    check_jump_in_featureless_lines(loop, FALSE);
}

static void
check_featureless_either_way(gint loop)
{
    check_jump_in_featureless_lines(loop, TRUE);
}

START_TEST(test_jump_in_featureless_lines)
{
    check_featureless_either_way(_i);
}
END_TEST

/* The draw of seed 900000136, loop 0 (case 611): a line before the jump,
 * compared over part of its width, was judged by the texture of the
 * whole line and voted after the jump, and the featureless lines were
 * not reported (docs/series.md, step 5).  Replayed whatever the seed. */
START_TEST(test_jump_in_featureless_lines_partly_predicted)
{
    replay_draw(900000136, check_featureless_as_scanned, 0);
}
END_TEST

/* The draw of seed 40100081, loop 0 (case 634): frame 0's featureless
 * lines just before the jump, which the drift with the step puts on a
 * particle of the frame after the slipped one, were seen under that
 * drift only and, their texture far below the typical line's match,
 * told nothing; two featureless lines 8 lines earlier that leaned
 * towards the step by noise placed the jump there, and a stripe kept
 * 2.6 px (jump-votes.c, featureless_on_texture).  Replayed whatever the
 * seed. */
START_TEST(test_jump_featureless_lines_on_particle)
{
    replay_draw(40100081, check_featureless_either_way, 0);
}
END_TEST

/* The draw of seed 68000339, loop 1 (case 1044): frame 0's featureless
 * line just after the jump, whose content the fitted drift with the step
 * put 0.5 px off, beside a particle's steep rim, was taken for a
 * featureless line on texture and voted before the jump: the jump was
 * put a line late and the featureless lines were not reported.  Replayed
 * whatever the seed. */
START_TEST(test_jump_featureless_line_beside_a_rim)
{
    replay_draw(68000339, check_featureless_either_way, 1);
}
END_TEST

/* Whether frame 0's lines from the jump on would show nothing without
 * the jump either.  Featureless lines where the drift without the step
 * puts particles do place the jump: they match only the drift with it.
 * Seed 20000358 drew such lines (case 845): the correction placed the
 * jump at 62.00 s, the truth 62.004 s, and was taken to task for not
 * reporting them tied. */
static gboolean
featureless_without_jump(guint32 seed, gint i, const DriftModel *model,
                         const SeriesCaseOptions *options)
{
    DriftModel without;
    gboolean featureless;

    drift_model_copy(&without, model);
    without.step[0] = without.step[1] = 0.0;
    featureless = first_frame_lines(seed, i, &without, options, featureless_after_jump);
    drift_model_clear(&without);
    return featureless;
}

/* Samples drawn at most for one featureless end of frame 0: about one
 * draw in 80 has it (draws 11, 18, 89 and, for seed 20000246, 217 of a
 * soak), so 200 failed about one seed in 100; 3000 fail one in e^37, and
 * the draws cost seconds only where they are needed.  Loop 1 still
 * starts at case 800, as every seed drew it before (loop 0 may draw on
 * into those cases: the loops then share a sample, nothing more). */
#define FEATURELESS_DRAWS 3000

/* Loop `loop` of test_jump_in_featureless_lines, drawn from base_seed;
 * both_sides: the lines featureless without the jump too (the replay of
 * seed 900000136 draws as that seed did, its lines featureless as
 * scanned only). */
static void
check_jump_in_featureless_lines(gint loop, gboolean both_sides)
{
    GRand *rng = test_rand_salted(base_seed, 5000 + loop);
    SeriesCaseOptions options = { FALSE, 1 };
    DriftModel model;
    SeriesCorrection correction;
    FrameSeries *series;
    gint attempt, i = 600 + 200*loop;
    gboolean warned = FALSE;
    guint w;

    for (attempt = 0; attempt < FEATURELESS_DRAWS; attempt++, i++) {
        draw_end_jump(rng, 2.0, 5.0, &model);
        if (first_frame_lines(base_seed, i, &model, &options, featureless_after_jump)
            && (!both_sides || featureless_without_jump(base_seed, i, &model, &options)))
            break;
    }
    ck_assert_msg(attempt < FEATURELESS_DRAWS, "seed %u: no sample is featureless after the jump",
                  base_seed);
    series = series_case_scan(base_seed, i, &model, &options, NULL);
    ck_assert(series_correction_compute(series, NULL, NULL, &correction, NULL));
    for (w = 0; w < correction.warnings->len; w++)
        warned |= (strstr(g_ptr_array_index(correction.warnings, w), "may lie anywhere") != NULL);
    printf("featureless %d (case %d): jump at %.2f s, window %.2f-%.2f s, %d lines tied\n",
           loop, i, model.t_jump, correction.jump_window[0], correction.jump_window[1],
           correction.jump_tied_lines);
    ck_assert_msg(warned && correction.jump_tied_lines >= 2,
                  "case %d (seed %u): %d lines tied, not reported", i, base_seed,
                  correction.jump_tied_lines);
    /* A jump during a line's retrace shows from the next line on: the
     * window may begin up to a line after it. */
    /* And no wider than the frame and a half that such a window can span
     * (from the jump's frame into the frames after the slipped one): a
     * window over the whole series would hide every error. */
    ck_assert_msg(correction.jump_window[1] - correction.jump_window[0] <= 96.0,
                  "case %d (seed %u): window %g-%g s", i, base_seed,
                  correction.jump_window[0], correction.jump_window[1]);
    ck_assert_msg(correction.jump_window[0] - series->frames[0].timing.line_time < model.t_jump
                  && model.t_jump <= correction.jump_window[1],
                  "case %d (seed %u): jump at %g s outside %g-%g s", i, base_seed,
                  model.t_jump, correction.jump_window[0], correction.jump_window[1]);
    series_correction_clear(&correction);
    frame_series_free(series);
    check_model_case(i, &model, &options);
    drift_model_clear(&model);
    g_rand_free(rng);
}

/* Progress of the correction: fractions recorded; stop_at (>= 0) makes the
 * call of that number stop it. */
typedef struct {
    gdouble fractions[64];
    gint n;
    gint stop_at;
} ProgressLog;

static gboolean
log_progress(gdouble fraction, gpointer user_data)
{
    ProgressLog *log = (ProgressLog*)user_data;

    if (log->n < (gint)G_N_ELEMENTS(log->fractions))
        log->fractions[log->n] = fraction;
    return log->n++ != log->stop_at;
}

static FrameSeries* steady_series(gint n_frames, gint yres, gdouble vx_px, gdouble vy_px);
static void steady_trajectory_error(const SeriesCorrection *correction,
                                    const FrameSeries *series, gdouble vx, gdouble vy,
                                    gdouble *rms, gdouble *worst);

/* The correction tells how far it has come, from 0 to 1 in order, ending
 * at 1, after each chunk of frames of a long series (40 frames: three
 * chunks, then the fit); stopped at its second report, in the middle of
 * the measurement, it fails as cancelled and holds nothing half-made
 * (valgrind and ASan see the rest), and so it does stopped at its last. */
START_TEST(test_progress_and_cancel)
{
    ProgressLog log = { { 0.0 }, 0, -1 };
    Progress progress = { log_progress, &log, 0.0, 1.0 };
    SeriesCorrection correction;
    FrameSeries *series = steady_series(40, 64, 0.8, 0.5);
    GError *error = NULL;
    gint k, n_reports;

    ck_assert(series_correction_compute_progress(series, NULL, NULL, &progress,
                                                 &correction, &error));
    series_correction_clear(&correction);
    ck_assert_int_ge(log.n, 4);
    n_reports = log.n;
    for (k = 1; k < MIN(log.n, (gint)G_N_ELEMENTS(log.fractions)); k++)
        ck_assert_msg(log.fractions[k] >= log.fractions[k-1] && log.fractions[k] <= 1.0,
                      "report %d: %g after %g", k, log.fractions[k], log.fractions[k-1]);
    ck_assert(log.fractions[MIN(log.n, (gint)G_N_ELEMENTS(log.fractions)) - 1] == 1.0);

    for (k = 0; k < 2; k++) {
        log.n = 0;
        log.stop_at = k ? n_reports - 1 : 1;
        ck_assert(!series_correction_compute_progress(series, NULL, NULL, &progress,
                                                      &correction, &error));
        ck_assert(g_error_matches(error, SERIES_CORRECTION_ERROR,
                                  SERIES_CORRECTION_ERROR_CANCELLED));
        ck_assert_int_eq(log.n, log.stop_at + 1);
        g_clear_error(&error);
        series_correction_clear(&correction);
    }
    frame_series_free(series);
}
END_TEST

/* A random walk: no model explains it, and the flexible trajectory
 * corrects the frames unless a model predicts nearly as well (a mild walk
 * is an acceleration); either way the frames overlay, whatever the
 * absolute reference (the walk's first seconds, which fix where the
 * sample was at t = 0, are measured by the first blocks alone). */
START_TEST(test_random_walk_smooth)
{
    SeriesCaseOptions options = { _i % 2, -1 };
    DriftModel model;
    GwyDataField **truth = NULL;
    SeriesCaseResult r;
    FrameSeries *series;
    gint k;

    series_case_draw_walk(base_seed, _i, 0.02, &model);
    series = series_case_scan(base_seed, 200 + _i, &model, &options, &truth);
    ck_assert(series != NULL);
    ck_assert_msg(series_case_judge(series, truth, &model, &options, &r),
                  "walk %d (seed %u): the correction failed", _i, base_seed);
    printf("walk %d raw %d: smooth %d, trajectory rms %.3f px, without its "
           "mean %.3f px (the best model's %.3f px)\n", _i, options.raw,
           r.smooth_used, r.trajectory_rms_px, r.trajectory_relative_px,
           r.model_relative_px);
    fflush(stdout);
    ck_assert_msg(r.trajectory_relative_px <= WALK_RELATIVE_MAX,
                  "walk %d (seed %u): the frames overlay within %g px", _i,
                  base_seed, r.trajectory_relative_px);
    for (k = 0; k < 2*SERIES_CASE_FRAMES; k++)
        g_object_unref(truth[k]);
    g_free(truth);
    frame_series_free(series);
    drift_model_clear(&model);
}
END_TEST

static gboolean warned_of(const SeriesCorrection *correction, const gchar *text);

/* A steady drift of vx_px and vy_px per frame (96 x yres px, lines of
 * 1 s) over a field of Gaussian bumps, each line sampled exactly where
 * the drift puts it (an interpolated canvas would smooth each frame by its
 * own sub-pixel phase, which biased the registration by about 0.1 % of a
 * long travel); content at (x, y) appears at (x + dx, y + dy).  The bumps
 * lie on 160 x 160 px around the frames, wider where the travel needs. */
static FrameSeries*
steady_series(gint n_frames, gint yres, gdouble vx_px, gdouble vy_px)
{
    FrameSeries *series = frame_series_new();
    GRand *rng = g_rand_new_with_seed(base_seed);
    gint travel = (gint)ceil(n_frames*MAX(fabs(vx_px), fabs(vy_px))) + 2;
    gint xres = 96, canvas = 160, x0 = 30, y0 = 40, k, r, c, b, n_bumps;
    gdouble *bx, *by;

    if (travel > 28 || yres > 64) {
        x0 = y0 = travel;
        canvas = MAX(xres, yres) + 2*travel;
    }
    /* 120 bumps on 160 x 160 px, as dense on a larger canvas. */
    n_bumps = (gint)ceil(120.0*canvas*canvas/(160.0*160.0));
    bx = g_new(gdouble, 2*n_bumps);
    by = bx + n_bumps;
    for (b = 0; b < n_bumps; b++) {
        bx[b] = g_rand_double_range(rng, 0, canvas);
        by[b] = g_rand_double_range(rng, 0, canvas);
    }
    for (k = 0; k < n_frames; k++) {
        GwyDataField *field = gwy_data_field_new(xres, yres, xres*1e-9,
                                                 yres*1e-9, TRUE);
        gdouble *d = gwy_data_field_get_data(field);
        ScanTiming timing;

        scan_timing_init(&timing, xres, yres, k*yres*1.0, 1.0,
                         SCAN_DIRECTION_DOWN);
        for (r = 0; r < yres; r++) {
            gdouble t = scan_timing_rows_time(&timing, r, r+1)/yres;
            /* Line r shows the field at (c + x0 - dx, r + y0 - dy). */
            gdouble x = x0 - vx_px*t, y = r + y0 - vy_px*t, ey;

            for (b = 0; b < n_bumps; b++) {
                /* exp(-d^2/8) is below 1e-7 beyond 11 px. */
                if (fabs(y - by[b]) > 11.0)
                    continue;
                ey = exp(-(y - by[b])*(y - by[b])/8.0);
                for (c = MAX((gint)floor(bx[b] - x - 11.0), 0);
                     c <= MIN((gint)ceil(bx[b] - x + 11.0), xres - 1); c++)
                    d[r*xres + c] += ey*exp(-(c + x - bx[b])*(c + x - bx[b])/8.0);
            }
        }
        gwy_si_unit_set_from_string(gwy_data_field_get_si_unit_xy(field), "m");
        frame_series_append(series, field, "steady", &timing);
        g_object_unref(field);
    }
    g_free(bx);
    g_rand_free(rng);
    return series;
}

START_TEST(test_outputs)
{
    FrameSeries *series = steady_series(3, 64, 4.0, 0.0);
    SeriesCorrection correction;
    GError *error = NULL;
    gchar *csv, *json, **lines;
    JsonParser *parser = json_parser_new();
    JsonObject *root;
    JsonArray *frames;
    gint i, n_data = 0, first_data = -1;
    gdouble t, dx, dy;

    ck_assert_msg(series_correction_compute(series, NULL, NULL, &correction,
                                            &error),
                  "%s", error ? error->message : "?");
    /* Three frames, three pairs: no warning of one pair. */
    ck_assert(!warned_of(&correction, "one pair of frames"));
    csv = series_correction_trajectory_csv(&correction, series);
    lines = g_strsplit(csv, "\n", -1);
    for (i = 0; lines[i] && lines[i][0]; i++) {
        if (lines[i][0] == '#')
            continue;
        if (first_data < 0) {
            ck_assert_str_eq(lines[i], "frame,row,t_s,dx_px,dy_px");
            first_data = i;
            continue;
        }
        n_data++;
    }
    ck_assert_int_eq(n_data, 3*64);
    /* Frame 1, row 10: 4 px per frame of 64 s, fitted. */
    ck_assert(sscanf(lines[first_data + 1 + 64 + 10], "1,10,%lf,%lf,%lf",
                     &t, &dx, &dy) == 3);
    ck_assert_msg(fabs(t - 74.25) < 1e-6, "t %g", t);
    ck_assert_msg(fabs(dx - 4.0*t/64.0) < 0.05 && fabs(dy) < 0.05,
                  "line drift %g, %g px, expected %g, 0", dx, dy, 4.0*t/64.0);
    json = series_correction_to_json(&correction, series);
    ck_assert(json_parser_load_from_data(parser, json, -1, NULL));
    root = json_node_get_object(json_parser_get_root(parser));
    ck_assert_msg(g_str_equal(json_object_get_string_member(root, "effect"), "none"),
                  "a steady drift named %s (seed %u): %s",
                  json_object_get_string_member(root, "effect"), base_seed, json);
    ck_assert(json_object_has_member(root, "velocity_nm_per_s"));
    ck_assert(json_object_has_member(root, "models"));
    ck_assert(json_object_has_member(root, "warnings"));
    frames = json_object_get_array_member(root, "frames");
    ck_assert_int_eq(json_array_get_length(frames), 3);
    for (i = 0; i < 3; i++) {
        JsonObject *f = json_array_get_object_element(frames, i);

        ck_assert_int_eq(json_object_get_int_member(f, "index"), i);
        ck_assert(!json_object_get_boolean_member(f, "flagged"));
        ck_assert(json_object_get_null_member(f, "reason"));
        ck_assert_msg(fabs(json_object_get_double_member(f, "t_start_s") - 64.0*i) < 1e-9,
                      "frame %d starts at %g s", i,
                      json_object_get_double_member(f, "t_start_s"));
        ck_assert(json_object_get_double_member(f, "residual_px") < 0.1);
    }
    g_strfreev(lines);
    g_free(csv);
    g_free(json);
    g_object_unref(parser);
    series_correction_clear(&correction);
    frame_series_free(series);
}
END_TEST

/* Whether a warning of the correction holds text. */
static gboolean
warned_of(const SeriesCorrection *correction, const gchar *text)
{
    return test_strings_hold(correction->warnings, text);
}

/* A featureless frame between two good ones (a constant, or zeros: a
 * channel that recorded nothing) is flagged, and the two others are
 * registered against each other as if it were absent: the drift drawn at
 * random (2-6 px per frame each way) within 0.15 px per frame, what one
 * pair of 96 x 64 px frames up to 12 px apart gives (0.09 px per frame in
 * seed 800000011).  The pairs with the featureless frame registered no
 * block, and their overall shifts, noise, centred the search of the other
 * pair: 4 of its 16 blocks found, the drift read 100 px wrong (the
 * hostile-input run).  Nor is a jump between the two frames, which one
 * pair cannot tell from the velocity, refused aloud.  (A frame of white
 * noise there is not drawn: its blocks match the bumps by chance often
 * enough that in 5 of 96 seeds it went unflagged or bent the drift;
 * docs/series.md, what is not done yet.) */
static void check_featureless_frame_between(gint zeros);

START_TEST(test_featureless_frame_between)
{
    check_featureless_frame_between(_i);
}
END_TEST

/* Seed 19386928, the constant frame: a jump was fitted between frames 0
 * and 2, where every block of their one pair spans it, a step of 168 nm
 * that the velocity made up for, and the drift was read 26 px off
 * (drift-fit.c, jump_separable).  Replayed whatever the seed. */
START_TEST(test_featureless_frame_jump_unseparable)
{
    replay_draw(19386928, check_featureless_frame_between, 0);
}
END_TEST

/* The middle frame a constant (zeros FALSE) or zeros. */
static void
check_featureless_frame_between(gint zeros)
{
    GRand *rng = test_rand_salted(base_seed, 6000 + zeros);
    gdouble vx = (g_rand_boolean(rng) ? 1 : -1)*g_rand_double_range(rng, 2.0, 6.0);
    gdouble vy = (g_rand_boolean(rng) ? 1 : -1)*g_rand_double_range(rng, 2.0, 6.0);
    FrameSeries *series = steady_series(3, 64, vx, vy);
    SeriesCorrection correction;
    GError *error = NULL;
    gdouble dx, dy, t;
    gint i;

    gwy_data_field_fill(series->frames[1].field, zeros ? 0.0 : 3e-9);
    ck_assert_msg(series_correction_compute(series, NULL, NULL, &correction, &error),
                  "seed %u: %s", base_seed, error ? error->message : "?");
    ck_assert_msg(correction.frames[1].flagged && !correction.frames[0].flagged
                  && !correction.frames[2].flagged,
                  "seed %u: flagged %d %d %d", base_seed, correction.frames[0].flagged,
                  correction.frames[1].flagged, correction.frames[2].flagged);
    for (i = 0; i < 3; i++) {
        t = 64.0*i + 32.0;
        series_correction_eval(&correction, t, &dx, &dy);
        ck_assert_msg(fabs(dx - vx*t/64.0) < 0.15*t/64.0 + 0.05 && fabs(dy - vy*t/64.0) < 0.15*t/64.0 + 0.05,
                      "seed %u: drift (%g, %g) px at %g s, truth (%g, %g)", base_seed, dx, dy, t,
                      vx*t/64.0, vy*t/64.0);
    }
    ck_assert_msg(!warned_of(&correction, "refused"), "seed %u: a refused effect reported", base_seed);
    /* Frames 0 and 2 alone measure the drift: a change of it between them
     * would go unseen, which is said. */
    ck_assert_msg(warned_of(&correction, "the trajectory rests on one pair of frames (0 and 2)"),
                  "seed %u: no warning of the one pair", base_seed);
    series_correction_clear(&correction);
    frame_series_free(series);
    g_rand_free(rng);
}


/* A frame of white noise between two good ones matches a few blocks of
 * each by chance, and the guess chained through those pairs (their frame
 * shifts, noise) must not decide where the two good frames are searched:
 * their pair is measured as if the noise frame were absent.  Around such
 * a guess 4 of 8 blocks had matched chance content, the frames correlating
 * at 0.40 there: the drift came 3-44 px wrong in 6 of 496 draws of the
 * whole correction.  The drift is drawn anew for each of 16 series. */
static void check_white_noise_frame_between(void);

START_TEST(test_white_noise_frame_between)
{
    check_white_noise_frame_between();
}
END_TEST

/* Seed 991000118, draw 15: the search around the guess chained through
 * the noise frame matched 6 blocks 33 px off, as many as the frame
 * searched blind matched at the truth, and the tie kept the guided ones
 * (displacement-measure.c, better_blocks).  Replayed whatever the seed. */
START_TEST(test_white_noise_frame_tie)
{
    guint32 saved = base_seed;

    base_seed = 991000118;
    check_white_noise_frame_between();
    base_seed = saved;
}
END_TEST

/* Seed 66000257, draw 2: both pairs with the noise frame accepted 4 of 8
 * blocks by chance (half: not weak by their count), the frames
 * correlating at 0.25 and 0.19 as a whole, so the guess chained through
 * them was not doubted and the good frames' pair, searched only around
 * it, read (-14.3, 13.8) px off the truth from 4 blocks correlating at
 * 0.5, where the frame searched blind gives 7 blocks at 0.98
 * (displacement-measure.c, WEAK_FRAME_CORRELATION).  Replayed whatever
 * the seed. */
START_TEST(test_white_noise_frame_half_by_chance)
{
    guint32 saved = base_seed;

    base_seed = 66000257;
    check_white_noise_frame_between();
    base_seed = saved;
}
END_TEST

/* The 16 draws of test_white_noise_frame_between from base_seed. */
static void
check_white_noise_frame_between(void)
{
    GRand *rng = test_rand_salted(base_seed, 6100);
    guint32 saved = base_seed;
    gint draw;

    for (draw = 0; draw < 16; draw++) {
        gdouble vx = (g_rand_boolean(rng) ? 1 : -1)*g_rand_double_range(rng, 2.0, 6.0);
        gdouble vy = (g_rand_boolean(rng) ? 1 : -1)*g_rand_double_range(rng, 2.0, 6.0);
        FrameSeries *series;
        DisplacementOptions options;
        DriftMeasurement *meas;
        gdouble *d, xstep, ystep, ex, ey, errors_x[16], errors_y[16];
        gint k, n, i, good = 0;

        base_seed = g_rand_int(rng);
        series = steady_series(3, 64, vx, vy);
        d = gwy_data_field_get_data(series->frames[1].field);
        for (k = 0; k < 96*64; k++)
            d[k] = 1e-9*g_rand_double_range(rng, -1.0, 1.0);
        gwy_data_field_invalidate(series->frames[1].field);
        displacement_options_init(&options);
        /* As the correction registers frames of 64 rows. */
        options.n_blocks = 8;
        meas = displacement_measure_series(series, &options, &n);
        xstep = frame_series_dx(series);
        ystep = frame_series_dy(series);
        /* The pair as the fit weighs it: its blocks' median error (one
         * block can be off on its own, noise frame or not). */
        for (i = 0; i < n; i++) {
            if (meas[i].frame_a != 2 || meas[i].frame_b != 0 || !(meas[i].weight > 0.0))
                continue;
            errors_x[good] = meas[i].dx/xstep - vx*(meas[i].t_a - meas[i].t_b)/64.0;
            errors_y[good] = meas[i].dy/ystep - vy*(meas[i].t_a - meas[i].t_b)/64.0;
            good++;
        }
        ck_assert_msg(good >= 4, "seed %u draw %d: %d blocks of frames 2-0", saved, draw, good);
        ex = median_in_place(errors_x, good);
        ey = median_in_place(errors_y, good);
        ck_assert_msg(fabs(ex) < 1.0 && fabs(ey) < 1.0,
                      "seed %u draw %d: frames 2-0 read (%.2f, %.2f) px from the truth", saved, draw, ex, ey);
        g_free(meas);
        frame_series_free(series);
    }
    base_seed = saved;
    g_rand_free(rng);
}

/* Every frame the same constant (a channel that recorded nothing, kept
 * three times): a few blocks match by chance, each frame is flagged as
 * registered against none, and the correction fails saying so, rather
 * than correcting the frames from blocks that matched nothing (it wrote
 * them with exit status 0 before). */
START_TEST(test_all_frames_flagged_refused)
{
    FrameSeries *series = steady_series(3, 64, 3.0, 1.0);
    SeriesCorrection correction;
    GError *error = NULL;
    gint k;

    for (k = 0; k < 3; k++)
        gwy_data_field_fill(series->frames[k].field, 1e-9);
    ck_assert(!series_correction_compute(series, NULL, NULL, &correction, &error));
    ck_assert(g_error_matches(error, SERIES_CORRECTION_ERROR, SERIES_CORRECTION_ERROR_FIT));
    printf("all frames featureless: %s\n", error->message);
    ck_assert_msg(strstr(error->message, "no two frames agree on a drift trajectory (featureless "
                         "frames, frames of other areas, or a drift that moves the content more "
                         "than a quarter of the frame along an axis from frame to frame)"),
                  "%s", error->message);
    g_clear_error(&error);
    series_correction_clear(&correction);
    frame_series_free(series);
}
END_TEST

/* Two frames, the second featureless (a channel that recorded nothing):
 * refused, naming the frame (it said only that too few blocks
 * registered). */
START_TEST(test_featureless_second_of_two_named)
{
    FrameSeries *series = steady_series(2, 64, 3.0, 1.0);
    SeriesCorrection correction;
    GError *error = NULL;

    gwy_data_field_fill(series->frames[1].field, 2e-9);
    ck_assert(!series_correction_compute(series, NULL, NULL, &correction, &error));
    ck_assert(g_error_matches(error, SERIES_CORRECTION_ERROR, SERIES_CORRECTION_ERROR_FIT));
    ck_assert_str_eq(error->message, "too few blocks of the frames could be registered against "
                     "each other to fit a drift trajectory: frame 1 (steady) is featureless, "
                     "every pixel the same");
    g_clear_error(&error);
    series_correction_clear(&correction);
    frame_series_free(series);
}
END_TEST

/* The area --crop common keeps is the one the frames not flagged share:
 * frame 0 lacks its first 4 columns, frame 2 its last 4 rows, and frame 1,
 * flagged, a random 1 % of its pixels, which would leave a sliver. */
START_TEST(test_trusted_area_leaves_flagged_frames_out)
{
    GRand *rng = test_rand_salted(base_seed, 7000);
    SeriesCorrection correction;
    GwyDataField *masks[3];
    gint k, i, area[4];

    memset(&correction, 0, sizeof(correction));
    correction.n_frames = 3;
    correction.frames = g_new0(SeriesFrameVerdict, 3);
    correction.frames[1].flagged = TRUE;
    for (k = 0; k < 3; k++)
        masks[k] = gwy_data_field_new(32, 32, 32e-9, 32e-9, TRUE);
    gwy_data_field_area_fill(masks[0], 0, 0, 4, 32, 1.0);
    gwy_data_field_area_fill(masks[2], 0, 28, 32, 4, 1.0);
    for (i = 0; i < 10; i++)
        gwy_data_field_set_val(masks[1], g_rand_int_range(rng, 0, 32), g_rand_int_range(rng, 0, 32), 1.0);
    ck_assert(series_correction_trusted_area(&correction, masks, 3, area));
    ck_assert_msg(area[0] == 4 && area[1] == 0 && area[2] == 28 && area[3] == 28,
                  "seed %u: area col %d row %d, %d x %d", base_seed, area[0], area[1], area[2], area[3]);
    /* Trusted, frame 1 shrinks it. */
    correction.frames[1].flagged = FALSE;
    ck_assert(series_correction_trusted_area(&correction, masks, 3, area));
    ck_assert_msg(area[2]*area[3] < 28*28, "seed %u: %d x %d", base_seed, area[2], area[3]);
    for (k = 0; k < 3; k++)
        g_object_unref(masks[k]);
    g_free(correction.frames);
    g_rand_free(rng);
}
END_TEST

/* The corrected frames of a steady drift show the same content where they
 * overlap, masked where they have none; the common area is where all
 * have data. */
START_TEST(test_frames_overlay)
{
    FrameSeries *series = steady_series(3, 64, 6.0, 0.0);
    SeriesCorrection correction;
    GwyDataField *fixed[3], *mask[3];
    gint k, r, c, area[4], xres = 96, yres = 64, count = 0;
    gdouble diff = 0.0;

    ck_assert(series_correction_compute(series, NULL, NULL, &correction,
                                        NULL));
    for (k = 0; k < 3; k++) {
        fixed[k] = gwy_data_field_new_alike(series->frames[k].field, FALSE);
        mask[k] = gwy_data_field_new_alike(series->frames[k].field, FALSE);
        ck_assert(series_correction_correct_frame(&correction, series, k,
                                                  GWY_INTERPOLATION_BSPLINE,
                                                  fixed[k], mask[k], NULL));
    }
    /* 6 px per frame to the right: the last frame, moved back, has no data
     * for its last 18 columns (its last line was scanned 3 frames on). */
    ck_assert(series_correction_common_area(mask, 3, area, area + 1,
                                            area + 2, area + 3));
    printf("common area: col %d row %d, %d x %d\n", area[0], area[1],
           area[2], area[3]);
    ck_assert_int_eq(area[0], 0);
    ck_assert_int_eq(area[1], 0);
    ck_assert_int_ge(area[2], xres - 20);
    ck_assert_int_le(area[2], xres - 17);
    ck_assert_int_eq(area[3], yres);
    for (r = area[1] + 2; r < area[1] + area[3] - 2; r++) {
        for (c = area[0] + 2; c < area[0] + area[2] - 2; c++) {
            gdouble a = gwy_data_field_get_val(fixed[0], c, r);
            gdouble b = gwy_data_field_get_val(fixed[2], c, r);

            diff += (a - b)*(a - b);
            count++;
        }
    }
    diff = sqrt(diff/count)/gwy_data_field_get_rms(fixed[0]);
    printf("first and last corrected frames differ by %.4f of the rms\n",
           diff);
    ck_assert_msg(diff < 0.05, "corrected frames differ by %g of the rms",
                  diff);
    for (k = 0; k < 3; k++) {
        g_object_unref(fixed[k]);
        g_object_unref(mask[k]);
    }
    series_correction_clear(&correction);
    frame_series_free(series);
}
END_TEST

/* Frames much wider than tall, drifting along their width by 10-14 px per
 * frame: a third of their 32-line height and more, an eighth of their
 * 96-pixel width.  Each axis is searched blind over its own share of the
 * frame (displacement-measure.c, register_in_band); searched within a
 * quarter of the smaller side, every frame was flagged as registered
 * against no other (frames of 256 x 96 px at 51 px per frame, the same).
 * The trajectory must come out on every line, no frame flagged. */
START_TEST(test_wide_frames_fast_along_width)
{
    enum { N_FRAMES = 5, YRES = 32 };
    GRand *rng = test_rand_salted(base_seed, 9100);
    gdouble vx = g_rand_double_range(rng, 10.0, 14.0)*(g_rand_boolean(rng) ? 1.0 : -1.0);
    gdouble vy = g_rand_double_range(rng, -1.0, 1.0);
    FrameSeries *series = steady_series(N_FRAMES, YRES, vx, vy);
    SeriesCorrection correction;
    GError *error = NULL;
    gdouble rms, worst;
    gint k;

    ck_assert_msg(series_correction_compute(series, NULL, NULL, &correction, &error),
                  "seed %u, drift (%.2f, %.2f) px per frame: %s", base_seed, vx, vy,
                  error ? error->message : "?");
    for (k = 0; k < N_FRAMES; k++)
        ck_assert_msg(!correction.frames[k].flagged, "seed %u: frame %d flagged: %s", base_seed, k,
                      correction.frames[k].reason);
    steady_trajectory_error(&correction, series, vx, vy, &rms, &worst);
    printf("wide frames, drift (%.2f, %.2f) px per frame: trajectory RMS %.4f px, worst %.4f px\n",
           vx, vy, rms, worst);
    /* 60 px of travel: 61 seeds gave up to 0.096 px RMS, 0.17 px worst
     * (the registration's bias of about 0.2 % of a travel, as in
     * test_long_series). */
    ck_assert_msg(rms <= 0.15 && worst <= 0.3, "seed %u: trajectory RMS %g px, worst %g px",
                  base_seed, rms, worst);
    series_correction_clear(&correction);
    frame_series_free(series);
    g_rand_free(rng);
}
END_TEST

/* Frames prepared for registration are held within a memory budget
 * (displacement_held_frames); a frame no longer held is prepared again
 * for each pair.  With room for one frame, two are prepared per chunk and
 * one older frame is held, and every pair of a short series (all pairs)
 * and of a long one (three older partners) must read bit for bit what the
 * frames all held read. */
START_TEST(test_held_frames_budget)
{
    static const gint sizes[2] = { 6, SERIES_CORRECTION_ALL_PAIRS_UP_TO + 4 };
    DisplacementOptions options;
    DriftMeasurement *all, *few;
    gint s, n_all, n_few, i, chunk, keep;

    for (s = 0; s < 2; s++) {
        FrameSeries *series = steady_series(sizes[s], 64, 0.6, -0.4);

        displacement_options_init(&options);
        options.n_blocks = 8;
        options.pair_reach = s ? SERIES_CORRECTION_PAIR_REACH : 0;
        displacement_held_frames(series, &options, &chunk, &keep);
        ck_assert_int_eq(chunk, 16);
        ck_assert_int_eq(keep, s ? SERIES_CORRECTION_PAIR_REACH : 32);
        all = displacement_measure_series(series, &options, &n_all);
        options.held_bytes = 96*64*40;
        displacement_held_frames(series, &options, &chunk, &keep);
        ck_assert_int_eq(chunk, 2);
        ck_assert_int_eq(keep, 1);
        few = displacement_measure_series(series, &options, &n_few);
        ck_assert_msg(all && few && n_all == n_few && n_all >= 8*(sizes[s] - 1),
                      "%d frames: %d and %d measurements", sizes[s], n_all, n_few);
        for (i = 0; i < n_all; i++) {
            ck_assert_msg(all[i].frame_a == few[i].frame_a && all[i].frame_b == few[i].frame_b
                          && all[i].dx == few[i].dx && all[i].dy == few[i].dy
                          && all[i].t_a == few[i].t_a && all[i].t_b == few[i].t_b
                          && all[i].weight == few[i].weight,
                          "%d frames, measurement %d (frames %d-%d): (%g, %g) against (%g, %g)",
                          sizes[s], i, all[i].frame_a, all[i].frame_b,
                          all[i].dx, all[i].dy, few[i].dx, few[i].dy);
        }
        printf("held frames budget, %d frames: %d measurements alike\n", sizes[s], n_all);
        g_free(all);
        g_free(few);
        frame_series_free(series);
    }
}
END_TEST

/* How far the correction's trajectory lies from steady_series()'s drift
 * (vx, vy px per frame of yres lines) over every line: RMS into *rms,
 * the worst into *worst (px). */
static void
steady_trajectory_error(const SeriesCorrection *correction, const FrameSeries *series,
                        gdouble vx, gdouble vy, gdouble *rms, gdouble *worst)
{
    gint yres = series->frames[0].timing.yres, k, r;
    gdouble sum = 0.0, dx, dy, t, e;

    *worst = 0.0;
    for (k = 0; k < series->n_frames; k++) {
        for (r = 0; r < yres; r++) {
            t = scan_timing_rows_time(&series->frames[k].timing, r, r+1);
            series_correction_eval(correction, t, &dx, &dy);
            e = hypot(dx - vx*t/yres, dy - vy*t/yres);
            sum += e*e;
            *worst = MAX(*worst, e);
        }
    }
    *rms = sqrt(sum/(yres*series->n_frames));
}

/* A series longer than SERIES_CORRECTION_ALL_PAIRS_UP_TO registers each
 * frame against SERIES_CORRECTION_PAIR_REACH older ones only, the older
 * pairs searched narrowly (at least 6 px) around the chained shifts of the
 * consecutive pairs, and those of nearly rigid frames in four blocks of 32
 * lines instead of sixteen of 8 (displacement-measure.c): a steady drift
 * drawn at random (seeded), 2.5 to 4 px per frame, so that an older pair's
 * shift lies beyond the narrow search unless it is centred right, must
 * come out on every line, the older pairs registered and counted in the
 * frames' verdicts. */
START_TEST(test_long_series)
{
    enum { N_FRAMES = SERIES_CORRECTION_ALL_PAIRS_UP_TO + 4, YRES = 128 };
    GRand *rng = g_rand_new_with_seed(base_seed + 17);
    gint k, j, older = 0, older_used = 0, i, pairs = 0, tall = 0;
    gint blocks[N_FRAMES][N_FRAMES];
    gdouble speed = g_rand_double_range(rng, 2.5, 4.0), angle = g_rand_double_range(rng, 0.0, 2.0*G_PI);
    gdouble vx = speed*cos(angle), vy = speed*sin(angle);
    FrameSeries *series = steady_series(N_FRAMES, YRES, vx, vy);
    SeriesCorrection correction;
    GError *error = NULL;
    gdouble rms, worst;

    ck_assert_msg(series_correction_compute(series, NULL, NULL, &correction, &error),
                  "%s", error ? error->message : "?");
    steady_trajectory_error(&correction, series, vx, vy, &rms, &worst);
    memset(blocks, 0, sizeof(blocks));
    for (i = 0; i < correction.fit.n_meas; i++) {
        const DriftMeasurement *m = correction.fit.meas + i;

        if (m->frame_a - m->frame_b >= 2) {
            older++;
            older_used += (m->weight > 0.0);
            blocks[m->frame_a][m->frame_b]++;
        }
    }
    /* Each older pair in sixteen blocks, or in four tall ones where the
     * consecutive pairs between found the frames nearly rigid (most of
     * them: a steady drift). */
    for (k = 0; k < N_FRAMES; k++) {
        for (j = 0; j < k; j++) {
            if (!blocks[k][j])
                continue;
            pairs++;
            tall += (blocks[k][j] == 4);
            ck_assert_msg(blocks[k][j] == 4 || blocks[k][j] == 16, "pair %d-%d in %d blocks", k, j,
                          blocks[k][j]);
        }
    }
    printf("long series of %d frames, drift (%.3f, %.3f) px per frame: trajectory RMS %.4f px, "
           "worst %.4f px; older pairs' blocks used %d of %d in %d pairs, %d of them tall\n",
           N_FRAMES, vx, vy, rms, worst, older_used, older, pairs, tall);
    /* 2n - 5 older pairs (reach 3). */
    ck_assert_int_eq(pairs, 2*N_FRAMES - 5);
    ck_assert_msg(2*tall >= pairs, "only %d of %d older pairs in tall blocks (seed %u)", tall, pairs,
                  base_seed);
    /* Up to 12 px along y, a tenth of a tall block, can leave the
     * reference. */
    ck_assert_msg(older_used >= 0.8*older, "only %d of %d older blocks used (seed %u)", older_used,
                  older, base_seed);
    /* A frame inside the series belongs to three pairs on either side. */
    for (k = 3; k < N_FRAMES - 3; k++)
        ck_assert_msg(correction.frames[k].n_pairs >= 5, "frame %d is in %d registered pairs (seed %u)",
                      k, correction.frames[k].n_pairs, base_seed);
    ck_assert_msg(rms <= 0.08 && worst <= 0.15,
                  "trajectory RMS %g px, worst %g px (seed %u)", rms, worst,
                  base_seed);
    series_correction_clear(&correction);
    frame_series_free(series);
    g_rand_free(rng);
}
END_TEST

/* Two frames of smooth bumps, 128 x 128 px of 0.5 s lines back to back:
 * frame 0 under a settling along y (7.5 px of travel, tau 21.5 s: its
 * first rows squeezed by 0.15 px each), frame 1 nearly still.  The
 * displacement p(t_a) - p(t_b) the series registers for each block is
 * compared with the truth at the moments it is tied to, averaged over the
 * block's span as the fit averages it. */
#define SQUEEZE_TRAVEL_PX 7.5
#define SQUEEZE_TAU 21.5

static gdouble
squeeze_py(gdouble t)
{
    return -SQUEEZE_TRAVEL_PX*(-expm1(-t/SQUEEZE_TAU));
}

/* The mean of squeeze_py() over [t - h, t + h]. */
static gdouble
squeeze_mean_py(gdouble t, gdouble h)
{
    if (!(h > 0.0))
        return squeeze_py(t);
    return -SQUEEZE_TRAVEL_PX*(1.0 - SQUEEZE_TAU*exp(-t/SQUEEZE_TAU)*sinh(h/SQUEEZE_TAU)/h);
}

static FrameSeries*
squeezed_pair(guint32 texture)
{
    FrameSeries *series = frame_series_new();
    GRand *rng = g_rand_new_with_seed(texture);
    gint res = 128, canvas = 200, n_bumps = 400, k, r, c, b;
    gdouble *bx = g_new(gdouble, 2*n_bumps), *by = bx + n_bumps;

    for (b = 0; b < n_bumps; b++) {
        bx[b] = g_rand_double_range(rng, 0, canvas);
        by[b] = g_rand_double_range(rng, 0, canvas);
    }
    for (k = 0; k < 2; k++) {
        GwyDataField *field = gwy_data_field_new(res, res, res*1e-9, res*1e-9, TRUE);
        gdouble *d = gwy_data_field_get_data(field), t, x, y, v;
        ScanTiming timing;

        scan_timing_init(&timing, res, res, k*res*0.5, 0.5, SCAN_DIRECTION_DOWN);
        for (r = 0; r < res; r++) {
            for (c = 0; c < res; c++) {
                /* The pixel shows the sample at its position less the
                 * drift at the moment it is scanned. */
                t = scan_timing_pixel_time(&timing, r, c);
                x = c + 30.0;
                y = r + 30.0 - squeeze_py(t);
                for (b = 0, v = 0.0; b < n_bumps; b++) {
                    if (fabs(x - bx[b]) < 12.0 && fabs(y - by[b]) < 12.0)
                        v += exp(-((x - bx[b])*(x - bx[b]) + (y - by[b])*(y - by[b]))/8.0);
                }
                d[r*res + c] = v;
            }
        }
        gwy_si_unit_set_from_string(gwy_data_field_get_si_unit_xy(field), "m");
        frame_series_append(series, field, "squeezed", &timing);
        g_object_unref(field);
    }
    g_free(bx);
    g_rand_free(rng);
    return series;
}

/* A block's displacement is tied to the moments of the rows whose shift
 * the registration measured.  The first block of frame 1, registered
 * against frame 0 squeezed by the settling, was timed by all its rows
 * although the two within the filters' reach of the frame's top take no
 * part in the match: tied to a moment 0.4 s early, it read the settling's
 * travel 0.08-0.14 px short on every texture (0.10 px on average), the
 * bias that left the fitted settling 0.40-0.44 px off in
 * test_hidden_drift_corrected (seeds 800000065 and 576000040).  Now
 * within 0.05 px on each texture, 0.02 px on average.  Blocks of 4
 * lines, as a fast settling's series ends up measured in. */
START_TEST(test_squeezed_partner_timed)
{
    DisplacementOptions options;
    gdouble err, sum = 0.0, h;
    guint32 texture;
    gint n;

    displacement_options_init(&options);
    options.n_blocks = 32;
    for (texture = 1; texture <= 6; texture++) {
        FrameSeries *series = squeezed_pair(texture);
        DriftMeasurement *meas = displacement_measure_series(series, &options, &n), *m = meas;

        ck_assert(meas && n >= 1 && m->frame_a == 1 && m->frame_b == 0 && m->weight > 0.0);
        h = 0.5*m->span;
        err = 1e9*m->dy - (squeeze_mean_py(m->t_a, h) - squeeze_mean_py(m->t_b, h));
        printf("squeezed partner, texture %u: first block %+.3f px off the truth at "
               "%.2f s, %.2f s\n", texture, err, m->t_a, m->t_b);
        ck_assert_msg(fabs(err) <= 0.06, "texture %u: the first block %g px off at its moments",
                      texture, err);
        sum += err;
        g_free(meas);
        frame_series_free(series);
    }
    ck_assert_msg(fabs(sum/6.0) <= 0.04, "the first block %g px off on average", sum/6.0);
}
END_TEST

int
main(void)
{
    TCase *tc;
    Suite *s = test_suite_new("series-correction", "series", &tc);

    base_seed = test_seed_from_env("test-series-correction");
    gwy_process_type_init();
    tcase_add_loop_test(tc, test_hidden_drift_corrected, 0, N_CASES);
    tcase_add_loop_test(tc, test_jump_before_slipped_frame, 0, 3);
    tcase_add_test(tc, test_jump_lines_matching_better_than_typical);
    tcase_add_loop_test(tc, test_jump_in_featureless_lines, 0, 2);
    tcase_add_test(tc, test_jump_in_featureless_lines_partly_predicted);
    tcase_add_test(tc, test_jump_featureless_lines_on_particle);
    tcase_add_test(tc, test_jump_featureless_line_beside_a_rim);
    tcase_add_test(tc, test_jump_lines_a_fraction_off_the_fit);
    tcase_add_test(tc, test_progress_and_cancel);
    tcase_add_loop_test(tc, test_random_walk_smooth, 0, 2);
    tcase_add_test(tc, test_outputs);
    tcase_add_test(tc, test_white_noise_frame_between);
    tcase_add_test(tc, test_white_noise_frame_tie);
    tcase_add_test(tc, test_white_noise_frame_half_by_chance);
    tcase_add_loop_test(tc, test_featureless_frame_between, 0, 2);
    tcase_add_test(tc, test_featureless_frame_jump_unseparable);
    tcase_add_test(tc, test_all_frames_flagged_refused);
    tcase_add_test(tc, test_featureless_second_of_two_named);
    tcase_add_test(tc, test_trusted_area_leaves_flagged_frames_out);
    tcase_add_test(tc, test_frames_overlay);
    tcase_add_test(tc, test_long_series);
    tcase_add_test(tc, test_held_frames_budget);
    tcase_add_test(tc, test_wide_frames_fast_along_width);
    tcase_add_test(tc, test_squeezed_partner_timed);
    tcase_set_timeout(tc, 120);
    return test_run_suite(s);
}
