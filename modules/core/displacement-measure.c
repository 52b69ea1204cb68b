/*
 *  Displacement measurements of a frame series: blocks of lines registered
 *  by the core's stripe registration (stripe-registration.h), searched
 *  around the frame's overall shift, chained across frames.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <string.h>
#include <math.h>
#include <libprocess/gwyprocess.h>
#include "parallel-run.h"
#include "stripe-registration.h"
#include "displacement-measure.h"

void
displacement_options_init(DisplacementOptions *options)
{
    options->n_blocks = 16;
    options->max_shift = 0.25;
    options->block_range = 0.08;
    options->min_score = 0.3;
    options->pair_reach = 0;
}

/* The stripes' shifts (px) and the score the fit weighs them by: the
 * correlation at the peak, for blocks the registration accepted. */
static void
copy_shifts(const StripeShift *shifts, gint n, gdouble *dx, gdouble *dy,
            gdouble *score)
{
    gint s;

    for (s = 0; s < n; s++) {
        dx[s] = shifts[s].dx;
        dy[s] = shifts[s].dy;
        score[s] = shifts[s].accepted ? CLAMP(shifts[s].peak, 0.0, 1.0) : 0.0;
    }
}

/* The narrow blur a pair whose blocks mostly fail to register at the
 * frames' own band is tried with again: a fraction of the frame's smaller
 * side, at least a few pixels.  The band the frames' noise calls for suits
 * most series, and a wider one registers fewer of their blocks (HS-AFM:
 * 285 of 336 blocks at 1 % against 300 at their own); the raw FastScan
 * channels register almost nothing there (3 of 48 blocks) and 11 at 1 %,
 * which close as before (at 2 %, 16 with a residual 40 % larger); the
 * benchmark's 64 x 64 movie follows its oscillation to 0.70 px RMS with
 * 2 px against 1.14 px without.  A blur given to every frame beforehand,
 * mirrored at the frame's edges, pulled the first and last blocks
 * 0.02-0.03 px along y, which the fit of a long series turned into a
 * velocity 0.3-0.5 % off (0.5 px RMS over 300 frames of
 * bench/bench-series); the registration's own blur is normalised at the
 * edges, and its sub-pixel match keeps clear of its reach. */
#define WIDER_BAND_FRACTION 0.01
#define WIDER_BAND_MIN_PX 2.0

/* The pair's frame shift and blocks with a narrow blur of at least
 * min_narrow px; returns how many blocks were accepted. */
static gint
register_in_band(const StripeRegistrationFrame *image,
                 const StripeRegistrationFrame *reference, gint xres, gint yres,
                 gint n, const DisplacementOptions *options, const gdouble *guess,
                 gdouble min_narrow, StripeShift *whole, StripeShift *shifts)
{
    gdouble radius, centre[2] = { 0.0, 0.0 };
    gdouble *pdx = g_new(gdouble, n), *pdy = g_new(gdouble, n);
    gint s, side = MIN(xres, yres), accepted = 0;
    gboolean ok;

    radius = MAX(options->block_range*side, 4.0);
    /* The frame's overall shift first, so that blocks (less content, more
     * prone to a wrong peak) search near it only. */
    if (guess) {
        centre[0] = guess[0];
        centre[1] = guess[1];
    }
    memset(whole, 0, sizeof(StripeShift));
    memset(shifts, 0, n*sizeof(StripeShift));
    /* To whole pixels, near enough: the blocks search around it. */
    ok = stripe_registration_frame_shift(image, reference, centre[0], centre[1],
                                         guess ? radius : MAX(options->max_shift*side, 2.0),
                                         min_narrow, whole);
    if (!ok)
        whole->peak = -1.0;
    else if (whole->peak > -1.0) {
        centre[0] = whole->dx;
        centre[1] = whole->dy;
    }
    whole->dx = centre[0];
    whole->dy = centre[1];
    for (s = 0; s < n; s++) {
        pdx[s] = centre[0];
        pdy[s] = centre[1];
    }
    if (!ok || !stripe_registration_measure_around_frames(image, reference, n, pdx, pdy, radius,
                                                          min_narrow,
                                                          STRIPE_REGISTRATION_DEFAULT_MIN_SCORE,
                                                          shifts, NULL))
        memset(shifts, 0, n*sizeof(StripeShift));
    for (s = 0; s < n; s++)
        accepted += shifts[s].accepted;
    g_free(pdx);
    g_free(pdy);
    return accepted;
}

/* displacement_register_blocks() for prepared frames (either may be NULL:
 * nothing registered). */
static void
register_prepared(const StripeRegistrationFrame *image,
                  const StripeRegistrationFrame *reference, gint xres, gint yres,
                  gint n, const DisplacementOptions *options,
                  const gdouble *guess, gdouble *dx, gdouble *dy,
                  gdouble *score, gdouble *global)
{
    StripeShift whole, other_whole, *shifts = g_new0(StripeShift, n), *other = g_new0(StripeShift, n);
    gint best = 0;

    if (image && reference) {
        best = register_in_band(image, reference, xres, yres, n, options, guess, 0.0, &whole, shifts);
        if (2*best < n
            && register_in_band(image, reference, xres, yres, n, options, guess,
                                MAX(WIDER_BAND_FRACTION*MIN(xres, yres), WIDER_BAND_MIN_PX),
                                &other_whole, other) > best) {
            StripeShift *kept = shifts;

            whole = other_whole;
            shifts = other;
            other = kept;
        }
    }
    else {
        memset(&whole, 0, sizeof(whole));
        whole.peak = -1.0;
        if (guess) {
            whole.dx = guess[0];
            whole.dy = guess[1];
        }
    }
    copy_shifts(shifts, n, dx, dy, score);
    if (global) {
        global[0] = whole.dx;
        global[1] = whole.dy;
        global[2] = CLAMP(whole.peak, 0.0, 1.0);
    }
    g_free(other);
    g_free(shifts);
}

void
displacement_register_blocks(const gdouble *image, const gdouble *reference,
                             gint xres, gint yres, gint n,
                             const DisplacementOptions *options,
                             gdouble pixel_aspect, const gdouble *guess,
                             gdouble *dx, gdouble *dy, gdouble *score,
                             gdouble *global)
{
    DisplacementOptions defaults;
    StripeRegistrationFrame *a, *b;

    if (!options) {
        displacement_options_init(&defaults);
        options = &defaults;
    }
    /* The raw data go to the registration's own conditioning, with the
     * pixels' physical aspect, as a single pair's channels go. */
    a = stripe_registration_frame_new(image, xres, yres, pixel_aspect);
    b = stripe_registration_frame_new(reference, xres, yres, pixel_aspect);
    register_prepared(a, b, xres, yres, n, options, guess, dx, dy, score,
                      global);
    stripe_registration_frame_free(a);
    stripe_registration_frame_free(b);
}

/* The row a block's registration speaks for: its rows weighted by their
 * detail (squared differences along the line, which line offsets do not
 * touch).  A block registers where its features are; when the drift moves
 * fast, its centre row's moment can be seconds off theirs.  The centre
 * row when the block has no detail (or no finite pixel). */
static gdouble
detail_row(const gdouble *data, gint xres, gint r0, gint r1)
{
    gdouble wsum = 0.0, rsum = 0.0, w, d;
    gint r, c;

    for (r = r0; r < r1; r++) {
        const gdouble *row = data + (gsize)r*xres;

        for (c = 1, w = 0.0; c < xres; c++) {
            d = row[c] - row[c-1];
            if (isfinite(d))
                w += d*d;
        }
        wsum += w;
        rsum += w*r;
    }
    return (wsum > 0.0 && isfinite(rsum)) ? rsum/wsum : 0.5*(r0 + r1 - 1);
}

/* A series registered pair by pair.  Each frame is prepared once
 * (prepare_series_frame) and held while the frames within reach of it are
 * registered against it.  Frames go in chunks: their preparation, then
 * their consecutive pairs, then their older pairs, each step spread over
 * the processor's cores (the pairs of a step do not depend on each other:
 * an older pair's search starts from the consecutive pairs' shifts).
 * Every pair writes its own place of meas, so the order and the values
 * do not depend on the threads. */
typedef struct {
    const FrameSeries *series;
    const DisplacementOptions *options;
    gint reach;                        /* older frames per frame (all: k) */
    StripeRegistrationFrame **frames;  /* prepared (NULL: not registrable) */
    gboolean *prepared;                /* held in frames */
    gdouble *step;                     /* 3 per frame: the consecutive pair's
                                          overall shift and correlation */
    gint *far_first;                   /* frame k's first older pair */
    DriftMeasurement *meas;            /* every pair's blocks, in order */
} SeriesRegistration;

/* Frames registered per chunk: enough to keep the cores busy, few enough
 * to hold (about 2.5 MB each at 256 x 256 px). */
#define CHUNK_FRAMES 16
/* When every earlier frame is a partner, at most this many frames are
 * held; older ones are prepared anew for each pair. */
#define PREPARED_MAX_FRAMES 32

static StripeRegistrationFrame*
prepare_series_frame(const SeriesRegistration *reg, gint k)
{
    const SeriesFrame *f = reg->series->frames + k;

    return stripe_registration_frame_new(gwy_data_field_get_data_const(f->field), f->timing.xres, f->timing.yres,
                         frame_series_dy(reg->series)/frame_series_dx(reg->series));
}

static void
prepare_task(gpointer data, gint k)
{
    SeriesRegistration *reg = data;

    if (!reg->prepared[k]) {
        reg->frames[k] = prepare_series_frame(reg, k);
        reg->prepared[k] = TRUE;
    }
}

static void
release_frame(SeriesRegistration *reg, gint k)
{
    stripe_registration_frame_free(reg->frames[k]);
    reg->frames[k] = NULL;
    reg->prepared[k] = FALSE;
}

/* Registers frame ka against frame kb into pair slot `pair` of meas;
 * global gets the frame's overall shift.  A frame no longer held is
 * prepared for this pair alone. */
static void
measure_pair(const SeriesRegistration *reg, gint ka, gint kb,
             const gdouble *guess, gdouble *global, gint pair)
{
    const FrameSeries *series = reg->series;
    const DisplacementOptions *options = reg->options;
    const SeriesFrame *fa = series->frames + ka, *fb = series->frames + kb;
    gdouble xstep = frame_series_dx(series), ystep = frame_series_dy(series);
    gint xres = fa->timing.xres, yres = fa->timing.yres, n = options->n_blocks;
    gdouble *dx = g_new(gdouble, n), *dy = g_new(gdouble, n),
            *score = g_new(gdouble, n);
    StripeRegistrationFrame *own_a = NULL, *own_b = NULL;
    gint s;

    if (!reg->prepared[ka])
        own_a = prepare_series_frame(reg, ka);
    if (!reg->prepared[kb])
        own_b = prepare_series_frame(reg, kb);
    register_prepared(reg->prepared[ka] ? reg->frames[ka] : own_a,
                      reg->prepared[kb] ? reg->frames[kb] : own_b,
                      xres, yres, n, options, guess, dx, dy, score, global);
    stripe_registration_frame_free(own_a);
    stripe_registration_frame_free(own_b);
    for (s = 0; s < n; s++) {
        gint r0 = s*yres/n, r1 = (s + 1)*yres/n;
        gdouble ccol = 0.5*(xres - 1), crow;
        DriftMeasurement *m = reg->meas + (gsize)pair*n + s;

        /* The block's content was scanned in the reference dy rows
         * earlier (higher up), dx columns to the left. */
        crow = detail_row(gwy_data_field_get_data_const(fa->field), xres,
                          r0, r1);
        m->t_a = scan_timing_pixel_time(&fa->timing, crow, ccol);
        m->t_b = scan_timing_pixel_time(&fb->timing, crow - dy[s],
                                        ccol - dx[s]);
        m->dx = dx[s]*xstep;
        m->dy = dy[s]*ystep;
        m->weight = (score[s] >= options->min_score) ? score[s] : 0.0;
        m->group = s;
        m->frame_a = ka;
        m->frame_b = kb;
        m->span = (r1 - r0)*fa->timing.line_time;
    }
    g_free(dx);
    g_free(dy);
    g_free(score);
}

/* Consecutive pairs come first in meas, frame k's as pair k - 1. */
static void
consecutive_task(gpointer data, gint k)
{
    SeriesRegistration *reg = data;

    measure_pair(reg, k, k-1, NULL, reg->step + 3*k, k-1);
}

static gint
oldest_partner(const SeriesRegistration *reg, gint k)
{
    return MAX(k - (reg->reach > 0 ? reg->reach : k), 0);
}

/* Frame k against its older frames, the nearest first: the overall shifts
 * of the consecutive pairs between, chained, tell where to look in an
 * older frame, whose shift may exceed any blind search range. */
static void
older_task(gpointer data, gint k)
{
    SeriesRegistration *reg = data;
    gint nf = reg->series->n_frames, j;
    gdouble guess[2], global[3];

    for (j = k-2; j >= oldest_partner(reg, k); j--) {
        if (j == k-2) {
            guess[0] = reg->step[3*k] + reg->step[3*(k-1)];
            guess[1] = reg->step[3*k + 1] + reg->step[3*(k-1) + 1];
        }
        else {
            guess[0] = global[0] + reg->step[3*(j+1)];
            guess[1] = global[1] + reg->step[3*(j+1) + 1];
        }
        measure_pair(reg, k, j, guess, global,
                     nf - 1 + reg->far_first[k] + (k-2 - j));
    }
}

DriftMeasurement*
displacement_measure_series(const FrameSeries *series,
                            const DisplacementOptions *options, gint *n)
{
    DisplacementOptions defaults;
    SeriesRegistration reg;
    gint nf = series->n_frames, k, k0, k1, keep, released = 0, pairs;

    if (!options) {
        displacement_options_init(&defaults);
        options = &defaults;
    }
    reg.series = series;
    reg.options = options;
    reg.reach = options->pair_reach;
    reg.frames = g_new0(StripeRegistrationFrame*, MAX(nf, 1));
    reg.prepared = g_new0(gboolean, MAX(nf, 1));
    reg.step = g_new0(gdouble, 3*MAX(nf, 1));
    reg.far_first = g_new0(gint, MAX(nf, 1) + 1);
    /* Every consecutive pair first, then the older pairs frame by frame
     * (the fit of a long series takes a spread subset by order). */
    for (k = 0; k < nf; k++)
        reg.far_first[k+1] = reg.far_first[k] + MAX(k-2 - oldest_partner(&reg, k) + 1, 0);
    pairs = MAX(nf - 1, 0) + reg.far_first[nf];
    reg.meas = g_new0(DriftMeasurement, MAX((gsize)pairs*options->n_blocks, 1));
    keep = reg.reach > 0 ? reg.reach : PREPARED_MAX_FRAMES;
    for (k0 = 0; k0 < nf; k0 = k1) {
        k1 = MIN(k0 + CHUNK_FRAMES, nf);
        parallel_run(k0, k1, prepare_task, &reg);
        parallel_run(MAX(k0, 1), k1, consecutive_task, &reg);
        parallel_run(MAX(k0, 2), k1, older_task, &reg);
        /* Frames from k1 on reach back to k1 - keep at most. */
        for (; released < k1 - keep; released++)
            release_frame(&reg, released);
    }
    for (k = 0; k < nf; k++)
        release_frame(&reg, k);
    g_free(reg.frames);
    g_free(reg.prepared);
    g_free(reg.step);
    g_free(reg.far_first);
    *n = pairs*options->n_blocks;
    return reg.meas;
}
