/*
 *  The cases of the public drift benchmark: one table of what each case
 *  is, and the seeded draw of its drift.  Sizes of the drift are drawn in
 *  pixels of the frame, so the same case means the same difficulty at any
 *  resolution (docs/benchmark.md lists the ranges).
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <math.h>
#include "sim-random.h"
#include "benchmark-cases.h"

/* Lines within this many line times of a jump are scored by nobody: a
 * line scanned across the jump holds both positions. */
#define JUMP_LINES 3

/* How the frames of a case are laid out. */
typedef enum {
    LAYOUT_STANDARD,    /* 5 frames of 128 x 128 (full: 8 of 256 x 256) */
    LAYOUT_NONSQUARE,   /* the same area in half as many, taller rows */
    LAYOUT_MOVIE,       /* HS-AFM-like: 24 frames of 64 x 64 at 2 ms/line
                           (full: 100 frames) */
    LAYOUT_SLOW,        /* 3 frames of 256 x 256 at 1 s/line (full: 512) */
} Layout;

typedef enum {
    DRAW_CONSTANT,
    DRAW_SETTLING,
    DRAW_OSCILLATION,
    DRAW_JUMP,
    DRAW_ACCELERATION,
    DRAW_CREEP,
    DRAW_RANDOM_WALK,
    DRAW_LARGE_OFFSET,
} DriftDraw;

typedef struct {
    const gchar *name;
    const gchar *summary;
    BenchmarkSample sample;
    Layout layout;
    DriftDraw draw;
    gboolean raw;
    gboolean missing;
    gboolean disturbed;
} CaseSpec;

static const CaseSpec case_specs[] = {
    { "constant", "constant velocity", BENCHMARK_SAMPLE_PARTICLES,
      LAYOUT_STANDARD, DRAW_CONSTANT, FALSE, FALSE, FALSE },
    { "settling", "settling (exponential)", BENCHMARK_SAMPLE_PARTICLES,
      LAYOUT_STANDARD, DRAW_SETTLING, FALSE, FALSE, FALSE },
    { "oscillation", "oscillation", BENCHMARK_SAMPLE_PARTICLES,
      LAYOUT_STANDARD, DRAW_OSCILLATION, FALSE, FALSE, FALSE },
    { "jump", "sudden jump", BENCHMARK_SAMPLE_PARTICLES,
      LAYOUT_STANDARD, DRAW_JUMP, FALSE, FALSE, FALSE },
    { "acceleration", "constant acceleration", BENCHMARK_SAMPLE_PARTICLES,
      LAYOUT_STANDARD, DRAW_ACCELERATION, FALSE, FALSE, FALSE },
    { "creep", "frame-start creep", BENCHMARK_SAMPLE_PARTICLES,
      LAYOUT_STANDARD, DRAW_CREEP, FALSE, FALSE, FALSE },
    { "random-walk", "random walk", BENCHMARK_SAMPLE_PARTICLES,
      LAYOUT_STANDARD, DRAW_RANDOM_WALK, FALSE, FALSE, FALSE },
    { "large-offset", "a third of the frame over the series",
      BENCHMARK_SAMPLE_PARTICLES, LAYOUT_STANDARD, DRAW_LARGE_OFFSET,
      FALSE, FALSE, FALSE },
    { "raw-channel", "settling, raw-channel artefacts",
      BENCHMARK_SAMPLE_PARTICLES, LAYOUT_STANDARD, DRAW_SETTLING,
      TRUE, FALSE, FALSE },
    { "missing-pixels", "constant, missing pixels", BENCHMARK_SAMPLE_PARTICLES,
      LAYOUT_STANDARD, DRAW_CONSTANT, FALSE, TRUE, FALSE },
    { "disturbed-frame", "constant, one frame slipped",
      BENCHMARK_SAMPLE_PARTICLES, LAYOUT_STANDARD, DRAW_CONSTANT,
      FALSE, FALSE, TRUE },
    { "non-square", "settling, pixels twice as tall",
      BENCHMARK_SAMPLE_PARTICLES, LAYOUT_NONSQUARE, DRAW_SETTLING,
      FALSE, FALSE, FALSE },
    { "film", "settling on a measured film", BENCHMARK_SAMPLE_FILM,
      LAYOUT_STANDARD, DRAW_SETTLING, FALSE, FALSE, FALSE },
    { "movie", "HS-AFM-like movie, oscillation", BENCHMARK_SAMPLE_PARTICLES,
      LAYOUT_MOVIE, DRAW_OSCILLATION, FALSE, FALSE, FALSE },
    { "movie-minicircles", "HS-AFM movie of measured DNA, constant",
      BENCHMARK_SAMPLE_MINICIRCLES, LAYOUT_MOVIE, DRAW_CONSTANT,
      TRUE, FALSE, FALSE },
    { "slow-hires", "slow high-resolution frames, settling",
      BENCHMARK_SAMPLE_PARTICLES, LAYOUT_SLOW, DRAW_SETTLING,
      FALSE, FALSE, FALSE },
};

const gchar*
benchmark_sample_name(BenchmarkSample sample)
{
    static const gchar *const names[] = {
        "synthetic particles", "particles-film (measured)",
        "hsafm-minicircles (measured)",
    };

    return names[sample];
}

static void
layout_geometry(BenchmarkCase *bc, Layout layout, BenchmarkSize size)
{
    gboolean full = (size == BENCHMARK_SIZE_FULL);

    bc->direction = SCAN_DIRECTION_DOWN;
    switch (layout) {
        case LAYOUT_NONSQUARE:
        bc->xres = full ? 256 : 128;
        bc->yres = bc->xres/2;
        bc->n_frames = full ? 8 : 5;
        bc->line_time = 1.0;
        break;

        case LAYOUT_MOVIE:
        bc->xres = bc->yres = 64;
        bc->n_frames = full ? 100 : 24;
        bc->line_time = 0.002;
        break;

        case LAYOUT_SLOW:
        bc->xres = bc->yres = full ? 512 : 256;
        bc->n_frames = 3;
        bc->line_time = full ? 0.5 : 1.0;
        break;

        default:
        bc->xres = bc->yres = full ? 256 : 128;
        bc->n_frames = full ? 8 : 5;
        bc->line_time = full ? 0.25 : 0.5;
        break;
    }
    /* 7.8 nm pixels along x on the synthetic particles (20 nm radius). */
    bc->field = bc->xres*(1e-6/128.0);
}

static gdouble
uniform(SimRandom *rng, gdouble lo, gdouble hi)
{
    return lo + (hi - lo)*sim_random_uniform(rng);
}

/* A vector of the given length (px) in a random direction, in metres. */
static void
random_vector_px(SimRandom *rng, gdouble length, gdouble px, gdouble *v)
{
    gdouble angle = uniform(rng, 0.0, 2.0*G_PI);

    v[0] = length*px*cos(angle);
    v[1] = length*px*sin(angle);
}

static void
draw_drift(BenchmarkCase *bc, DriftDraw draw, SimRandom *rng)
{
    DriftModel *m = &bc->drift;
    gdouble px = bc->field/bc->xres, frame = bc->yres*bc->line_time;
    gdouble span = bc->n_frames*frame;
    DriftModelType type = DRIFT_MODEL_NONE;

    if (draw == DRAW_SETTLING)
        type = DRIFT_MODEL_SETTLING;
    else if (draw == DRAW_OSCILLATION)
        type = DRIFT_MODEL_OSCILLATION;
    else if (draw == DRAW_JUMP)
        type = DRIFT_MODEL_JUMP;
    else if (draw == DRAW_ACCELERATION)
        type = DRIFT_MODEL_ACCELERATION;
    else if (draw == DRAW_RANDOM_WALK)
        type = DRIFT_MODEL_RANDOM_WALK;
    drift_model_init(m, type);
    random_vector_px(rng, uniform(rng, 0.0, 3.0), px, m->p0);
    /* The steady velocity: a travel over the whole series, px. */
    if (draw == DRAW_CONSTANT)
        random_vector_px(rng, uniform(rng, 6.0, 14.0)/span, px, m->v);
    else if (draw == DRAW_LARGE_OFFSET)
        random_vector_px(rng, uniform(rng, 0.28, 0.34)*MIN(bc->xres, bc->yres)
                         /span, px, m->v);
    else
        random_vector_px(rng, uniform(rng, 1.0, 4.0)/span, px, m->v);

    if (draw == DRAW_SETTLING) {
        m->tau = uniform(rng, 0.08, 0.3)*span;
        random_vector_px(rng, uniform(rng, 6.0, 12.0)/m->tau, px, m->u);
    }
    else if (draw == DRAW_OSCILLATION) {
        random_vector_px(rng, uniform(rng, 1.5, 3.0), px, m->a);
        m->period = uniform(rng, 0.5, 1.5)*frame;
        m->phase = uniform(rng, -G_PI, G_PI);
    }
    else if (draw == DRAW_JUMP) {
        random_vector_px(rng, uniform(rng, 3.0, 6.0), px, m->step);
        m->t_jump = uniform(rng, 0.25, 0.75)*span;
    }
    else if (draw == DRAW_ACCELERATION)
        random_vector_px(rng, 2.0*uniform(rng, 5.0, 10.0)/(span*span), px,
                         m->accel);
    else if (draw == DRAW_CREEP) {
        random_vector_px(rng, uniform(rng, 2.0, 4.0), px, m->creep);
        m->creep_tau = uniform(rng, 0.05, 0.15)*frame;
        m->creep_period = frame;
    }
    else if (draw == DRAW_RANDOM_WALK) {
        /* The walk's own excursion, sigma span^1.5/sqrt(3), of 2-4 px. */
        m->walk_sigma = uniform(rng, 2.0, 4.0)*px*sqrt(3.0)/pow(span, 1.5);
        m->walk_dt = span/400.0;
        m->walk_seed = sim_random_uint32(rng);
    }
    drift_model_prepare(m, span + frame);
}

BenchmarkCase*
benchmark_cases_new(BenchmarkSize size, guint32 seed, gint *n)
{
    gint count = G_N_ELEMENTS(case_specs), i;
    BenchmarkCase *cases = g_new0(BenchmarkCase, count);
    SimRandom rng;

    for (i = 0; i < count; i++) {
        const CaseSpec *spec = case_specs + i;
        BenchmarkCase *bc = cases + i;

        /* One stream per case: a case's draw does not depend on others. */
        sim_random_init(&rng, seed, 0xbe4c0000u + i);
        bc->name = g_strdup_printf("%02d-%s", i + 1, spec->name);
        bc->summary = spec->summary;
        bc->sample = spec->sample;
        layout_geometry(bc, spec->layout, size);
        draw_drift(bc, spec->draw, &rng);
        bc->raw = spec->raw;
        bc->missing = spec->missing;
        bc->disturbed = -1;
        if (spec->disturbed) {
            bc->disturbed = 1 + (gint)(sim_random_uniform(&rng)
                                       *(bc->n_frames - 2));
            bc->slip_px[0] = 6.0;
            bc->slip_px[1] = -4.0;
        }
    }
    *n = count;
    return cases;
}

void
benchmark_cases_free(BenchmarkCase *cases, gint n)
{
    gint i;

    for (i = 0; i < n; i++) {
        g_free(cases[i].name);
        drift_model_clear(&cases[i].drift);
    }
    g_free(cases);
}

gdouble
benchmark_case_frame_start(const BenchmarkCase *bc, gint k)
{
    return k*bc->yres*bc->line_time;
}

void
benchmark_case_timing(const BenchmarkCase *bc, gint k, ScanTiming *timing)
{
    scan_timing_init(timing, bc->xres, bc->yres,
                     benchmark_case_frame_start(bc, k), bc->line_time,
                     bc->direction);
}

gboolean
benchmark_case_near_jump(const BenchmarkCase *bc, gdouble t)
{
    return (bc->drift.type == DRIFT_MODEL_JUMP
            && fabs(t - bc->drift.t_jump) < JUMP_LINES*bc->line_time);
}
