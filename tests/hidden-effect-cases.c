/*
 *  Random drift effects hidden in simulated frame series, and their blind
 *  fit: shared by tests/test-hidden-effects and bench/bench-effect-confusion.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <stdlib.h>
#include <string.h>
#include <math.h>
#include <glib/gstdio.h>
#include <libgwyddion/gwyddion.h>
#include <libgwymodule/gwymodule.h>
#include <app/gwyapp.h>
#include "scanner.h"
#include "sim-random.h"
#include "fit-command.h"
#include "hidden-effect-cases.h"

#define N_FRAMES HIDDEN_CASE_FRAMES
#define RES 128
#define LINE_TIME 0.5
#define FRAME_TIME (RES*LINE_TIME)
#define FIELD 1e-6
#define MARGIN 0.3e-6

/*
 * Parameter ranges (large enough to be seen at 7.8 nm per pixel):
 *   acceleration: |a| t^2/2 over the 256 s of the series 20..50 nm, any
 *                direction
 *   velocity:    |v| <= 0.1 nm/s, any direction
 *   settling:    tau 20..60 s, |u| tau 30..60 nm
 *   oscillation: period 20..60 s, |a| 15..30 nm, any direction and phase;
 *                not within 0.15 cycles per frame of a whole number, and
 *                |a| 2 pi/period at most 2.5 px per 4 s block (see below)
 *   jump:        t_s 30..230 s, |step| 25..50 nm
 * All inside what `simscan fit` can observe in 4 contiguous frames of 64 s
 * (drift_fit_observable_periods): periods from 3 blocks (12 s) up to 1.5
 * cycles over the measured span (about 250 s / 1.5 = 167 s), so 20..60 s is
 * 4 to 12 cycles; tau up to 60 s relaxes well within the series; jumps fall
 * between the first and the last block.
 * Tolerances: tau within 40 %; period within 10 % and |a| within 35 %;
 * t_s within 8 s (two blocks) and the step within 30 % + 4 nm; with no
 * effect, "none" and v within 0.02 nm/s; the acceleration within 30 %.
 */
/* Block registration measures where a block of lines sat on average: when
 * the drift sweeps more than a few pixels during one block (4 s), the block
 * is smeared and its shift is no measurement of the trajectory (seed 235
 * case 14: 30 nm at 25.7 s sweeps 3.7 px per block and was missed).  So an
 * oscillation's peak speed is kept to 2.5 px per block, which still leaves
 * 15 nm (2 px) at the shortest period. */
static gdouble
oscillation_max_amplitude(gdouble period)
{
    gdouble block_time = FRAME_TIME/16.0, pixel = FIELD/RES;
    gdouble max_speed = 2.5*pixel/block_time;

    return MIN(30e-9, max_speed*period/(2.0*G_PI));
}

static gdouble
uniform(SimRandom *rng, gdouble lo, gdouble hi)
{
    return lo + (hi - lo)*sim_random_uniform(rng);
}

static void
random_vector(SimRandom *rng, gdouble length, gdouble *v)
{
    gdouble angle = uniform(rng, 0.0, 2.0*G_PI);

    v[0] = length*cos(angle);
    v[1] = length*sin(angle);
}

static const DriftModelType hidden_effects[HIDDEN_CASE_EFFECTS] = {
    DRIFT_MODEL_NONE, DRIFT_MODEL_SETTLING, DRIFT_MODEL_OSCILLATION,
    DRIFT_MODEL_JUMP, DRIFT_MODEL_ACCELERATION,
};

DriftModelType
hidden_case_effect(gint i)
{
    return hidden_effects[i % HIDDEN_CASE_EFFECTS];
}

gint
hidden_case_effect_index(DriftModelType type)
{
    gint e;

    for (e = 0; e < HIDDEN_CASE_EFFECTS; e++) {
        if (hidden_effects[e] == type)
            return e;
    }
    return HIDDEN_CASE_EFFECTS;
}

void
hidden_case_draw(guint32 base_seed, gint i, DriftModel *model)
{
    SimRandom rng;
    DriftModelType type = hidden_case_effect(i);
    gdouble span = HIDDEN_CASE_FRAMES*FRAME_TIME;
    gdouble cycles;

    sim_random_init(&rng, base_seed, 100 + i);
    drift_model_init(model, type);
    random_vector(&rng, uniform(&rng, 0.0, 0.1e-9), model->v);
    switch (type) {
        case DRIFT_MODEL_SETTLING:
        model->tau = uniform(&rng, 20.0, 60.0);
        random_vector(&rng, uniform(&rng, 30e-9, 60e-9)/model->tau, model->u);
        break;

        case DRIFT_MODEL_OSCILLATION:
        /* A period that divides the frame time puts the same distortion
         * into every frame: it cancels between frames and no frame series
         * can see it.  Such periods are not drawn. */
        do {
            model->period = uniform(&rng, 20.0, 60.0);
            cycles = FRAME_TIME/model->period;
        } while (fabs(cycles - floor(cycles + 0.5)) < 0.15);
        model->phase = uniform(&rng, 0.0, 2.0*G_PI);
        random_vector(&rng, uniform(&rng, 15e-9, oscillation_max_amplitude(model->period)),
                      model->a);
        break;

        case DRIFT_MODEL_JUMP:
        model->t_jump = uniform(&rng, 30.0, 230.0);
        random_vector(&rng, uniform(&rng, 25e-9, 50e-9), model->step);
        break;

        case DRIFT_MODEL_ACCELERATION:
        random_vector(&rng, 2.0*uniform(&rng, 20e-9, 50e-9)/(span*span),
                      model->accel);
        break;

        default:
        break;
    }
}

/* Scans the frames and saves them as .gwy files (no timing inside: the
 * fit gets the timing from options, as a user would give it). */
gchar**
hidden_case_make_frames(guint32 base_seed, gint i, const DriftModel *model,
                        const gchar *dir)
{
    SimParticleParams pp;
    SimScanParams sp;
    SimSample *sample;
    gchar **files = g_new0(gchar*, N_FRAMES + 1);
    GError *error = NULL;
    gint k;

    sim_particle_params_init(&pp);
    pp.xreal = pp.yreal = FIELD + 2.0*MARGIN;
    pp.radius = 20e-9;
    pp.count = 90;
    if (!(sample = sim_sample_new_particles(&pp, base_seed + 1000*i))) {
        g_free(files);
        return NULL;
    }
    for (k = 0; k < N_FRAMES; k++) {
        GwyContainer *data = gwy_container_new();
        GwyDataField *field;

        sim_scan_params_init(&sp, sample, RES, RES);
        sp.xreal = sp.yreal = FIELD;
        sp.xoff = sp.yoff = MARGIN;
        sp.line_time = LINE_TIME;
        sp.frame_start = k*FRAME_TIME;
        sp.noise_rms = 0.2e-9;
        sp.noise_seed = base_seed + 1000*i + k;
        field = sim_scan_frame(sample, model, &sp);
        gwy_container_set_object_by_name(data, "/0/data", field);
        files[k] = g_strdup_printf("%s/frame%d.gwy", dir, k);
        if (!gwy_file_save(data, files[k], GWY_RUN_NONINTERACTIVE, &error)) {
            g_printerr("cannot save %s: %s\n", files[k], error->message);
            g_clear_error(&error);
        }
        g_object_unref(field);
        g_object_unref(data);
    }
    sim_sample_free(sample);
    return files;
}

JsonObject*
hidden_case_fit(gchar **files, const gchar *dir, JsonParser *parser)
{
    gchar *json = g_build_filename(dir, "fit.json", NULL);
    gchar *times = g_strdup_printf("%g,%g,%g,%g", 0.0, FRAME_TIME,
                                   2*FRAME_TIME, 3*FRAME_TIME);
    gchar *argv[16] = {
        "fit", "--json", json, "--line-time", "0.5", "--frame-times", times,
        "--direction", "down", NULL,
    };
    gint argc = 9, k, status;
    gboolean ok;
    GError *error = NULL;

    for (k = 0; k < N_FRAMES; k++)
        argv[argc++] = files[k];
    argv[argc] = NULL;
    status = simscan_fit_main(argc, argv);
    ok = (status == 0 && json_parser_load_from_file(parser, json, &error));
    g_clear_error(&error);
    g_free(times);
    g_unlink(json);
    g_free(json);
    return ok ? json_node_get_object(json_parser_get_root(parser)) : NULL;
}

gdouble
hidden_case_pair(JsonObject *obj, const gchar *name, gint i)
{
    JsonArray *a = json_object_get_array_member(obj, name);

    return json_array_get_double_element(a, i);
}

gchar*
hidden_case_check(gint i, const DriftModel *m, JsonObject *result)
{
    JsonObject *p = json_object_get_object_member(result, "parameters");
    gdouble err, len;

    switch (m->type) {
        case DRIFT_MODEL_NONE:
        err = hypot(hidden_case_pair(result, "velocity_nm_per_s", 0) - 1e9*m->v[0],
                    hidden_case_pair(result, "velocity_nm_per_s", 1) - 1e9*m->v[1]);
        if (!(err < 0.02))
            return g_strdup_printf("case %d: velocity off by %g nm/s", i, err);
        break;

        case DRIFT_MODEL_SETTLING:
        err = json_object_get_double_member(p, "tau_s")/m->tau - 1.0;
        if (!(fabs(err) < 0.4))
            return g_strdup_printf("case %d: tau %g s, true %g s", i,
                      json_object_get_double_member(p, "tau_s"), m->tau);
        break;

        case DRIFT_MODEL_OSCILLATION:
        err = json_object_get_double_member(p, "period_s")/m->period - 1.0;
        if (!(fabs(err) < 0.1))
            return g_strdup_printf("case %d: period %g s, true %g s", i,
                      json_object_get_double_member(p, "period_s"), m->period);
        len = hypot(hidden_case_pair(p, "amplitude_nm", 0),
                    hidden_case_pair(p, "amplitude_nm", 1));
        if (!(fabs(len/(1e9*hypot(m->a[0], m->a[1])) - 1.0) < 0.35))
            return g_strdup_printf("case %d: |a| %g nm, true %g nm", i, len,
                      1e9*hypot(m->a[0], m->a[1]));
        break;

        case DRIFT_MODEL_JUMP:
        err = json_object_get_double_member(p, "t_s") - m->t_jump;
        if (!(fabs(err) < 8.0))
            return g_strdup_printf("case %d: t_s %g s, true %g s", i,
                      json_object_get_double_member(p, "t_s"), m->t_jump);
        err = hypot(hidden_case_pair(p, "step_nm", 0) - 1e9*m->step[0],
                    hidden_case_pair(p, "step_nm", 1) - 1e9*m->step[1]);
        len = 1e9*hypot(m->step[0], m->step[1]);
        if (!(err < 0.3*len + 4.0))
            return g_strdup_printf("case %d: step off by %g nm of %g",
                      i, err, len);
        break;

        case DRIFT_MODEL_ACCELERATION:
        err = hypot(hidden_case_pair(p, "accel_nm_per_s2", 0) - 1e9*m->accel[0],
                    hidden_case_pair(p, "accel_nm_per_s2", 1) - 1e9*m->accel[1]);
        len = 1e9*hypot(m->accel[0], m->accel[1]);
        if (!(err < 0.3*len))
            return g_strdup_printf("case %d: acceleration off by %g nm/s^2 "
                                   "of %g", i, err, len);
        break;

        default:
        break;
    }
    return NULL;
}

