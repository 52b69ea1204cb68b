/*
 *  Tests of simscan on a measured sample: particle detection on a real
 *  particle film (also when tilted), the sample's defaults, and the local
 *  scans and paper-mode compensation on its drifting scan.
 *  Needs shared/data/measured/particles-film/PTO_110_Virgin0001.gwy
 *  ($LOCALSCAN_MEASURED_DIR); prints SKIPPED and exits 77 without it.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <stdlib.h>
#include <stdio.h>
#include <math.h>
#include <check.h>
#include <libgwyddion/gwyddion.h>
#include <libgwymodule/gwymodule-file.h>
#include <libprocess/level.h>
#include <app/gwyapp.h>
#include "particle-detect.h"
#include "centre-error.h"
#include "simscan-config.h"
#include "simscan-run.h"
#include "test-common.h"

#define SAMPLE_PATH "particles-film/PTO_110_Virgin0001.gwy"
/* Particles are farther apart than this (px), drifts are smaller. */
#define MATCH_RADIUS 6.0
/* Drifts reach 4.3 px and the particles' radius is 1.7 px: a particle whose
 * true place lies closer to the border than that can be pushed out of the
 * image, where no detector finds it. */
#define BORDER_MARGIN 6.0

static guint32 test_seed;
static gchar *sample_file;
static GwyDataField *sample_field;

static GwyDataField*
load_sample(const gchar *filename)
{
    GwyContainer *data;
    GwyDataField *field = NULL;

    gwy_app_init_nongui("enable-threads", FALSE, NULL);
    if (!(data = gwy_file_load(filename, GWY_RUN_NONINTERACTIVE, NULL)))
        return NULL;
    if (gwy_container_gis_object_by_name(data, "/0/data", &field))
        g_object_ref(field);
    g_object_unref(data);
    return field;
}

static GArray*
detect(GwyDataField *field)
{
    ParticleDetectParams params;

    particle_detect_params_init(&params);
    return particle_detect(field, &params, NULL, NULL);
}

/* Index of the particle nearest to (x, y) within radius px, or -1. */
static gint
nearest(const GArray *particles, gdouble x, gdouble y, gdouble radius)
{
    gdouble best = radius;
    gint found = -1;
    guint k;

    for (k = 0; k < particles->len; k++) {
        const DetectedParticle *p = &g_array_index(particles,
                                                   DetectedParticle, k);
        gdouble d = hypot(p->x - x, p->y - y);

        if (d <= best) {
            best = d;
            found = (gint)k;
        }
    }
    return found;
}

/* The film's particles: the clear ones, from 12 nm to 110 nm high (the
 * dimmest real particles are about 10 nm, noise 0.5 nm); nothing on the
 * line-levelling streaks.  The local scans' radius, from the particles'
 * tops, is about 68 nm (1.7 px), not the latex default of 25 nm. */
START_TEST(test_detect_film)
{
    GArray *particles = detect(sample_field);
    gdouble dx = gwy_data_field_get_dx(sample_field);
    gdouble dy = gwy_data_field_get_dy(sample_field);
    gdouble radius = particle_typical_radius(particles, dx, dy);
    gdouble lowest = G_MAXDOUBLE, highest = 0.0;
    guint k;

    for (k = 0; k < particles->len; k++) {
        const DetectedParticle *p = &g_array_index(particles,
                                                   DetectedParticle, k);

        lowest = fmin(lowest, p->peak);
        highest = fmax(highest, p->peak);
    }
    g_printerr("film: %u particles, %.1f to %.1f nm high, typical radius "
               "%.1f nm\n", particles->len, 1e9*lowest, 1e9*highest,
               1e9*radius);
    ck_assert_int_ge(particles->len, 17);
    ck_assert_int_le(particles->len, 24);
    ck_assert(lowest > 10e-9);
    ck_assert(fabs(highest - 109.6e-9) < 1e-9);
    ck_assert(radius > 55e-9 && radius < 80e-9);
    /* Two well-known particles: the highest and a low one near it. */
    ck_assert_int_ge(nearest(particles, 242.8, 105.1, 0.5), 0);
    ck_assert_int_ge(nearest(particles, 125.9, 104.1, 0.5), 0);
    g_array_free(particles, TRUE);
}
END_TEST

/* Tilted by a plane rising up to 300 nm across the image (three times the
 * highest particle) in a random direction, the film shows the same
 * particles at the same places: detection levels its own copy.  Without
 * levelling the threshold cuts the plane instead. */
START_TEST(test_detect_tilted_film)
{
    GRand *rng = g_rand_new_with_seed(test_seed);
    GwyDataField *tilted = gwy_data_field_duplicate(sample_field);
    GArray *flat = detect(sample_field), *found, *unlevelled;
    ParticleDetectParams params;
    gdouble phi = g_rand_double_range(rng, 0.0, 2.0*G_PI);
    gdouble rise = 300e-9/256, worst = 0.0;
    gint n_same = 0, n_unlevelled = 0;
    guint k;

    /* plane_level subtracts a + bx j + by i. */
    gwy_data_field_plane_level(tilted, 0.0, -rise*cos(phi)/sqrt(2.0),
                               -rise*sin(phi)/sqrt(2.0));
    found = detect(tilted);
    particle_detect_params_init(&params);
    params.level = FALSE;
    unlevelled = particle_detect(tilted, &params, NULL, NULL);
    for (k = 0; k < flat->len; k++) {
        const DetectedParticle *p = &g_array_index(flat, DetectedParticle, k);
        gint i = nearest(found, p->x, p->y, 1.0);

        if (i >= 0) {
            const DetectedParticle *q = &g_array_index(found,
                                                       DetectedParticle, i);

            n_same++;
            worst = fmax(worst, hypot(q->x - p->x, q->y - p->y));
        }
        if (nearest(unlevelled, p->x, p->y, 1.0) >= 0)
            n_unlevelled++;
    }
    g_printerr("tilted film (direction %.0f deg): %d of %u particles found "
               "again, %u in all, worst shift %.3f px; unlevelled: %d of "
               "them, %u in all\n", phi*180.0/G_PI, n_same, flat->len,
               found->len, worst, n_unlevelled, unlevelled->len);
    ck_assert_int_ge(n_same, (gint)flat->len - 1);
    ck_assert_int_le(abs((gint)found->len - (gint)flat->len), 1);
    ck_assert(worst < 0.1);
    ck_assert(n_unlevelled < n_same - 3
              || abs((gint)unlevelled->len - (gint)flat->len) > 3);
    g_array_free(unlevelled, TRUE);
    g_array_free(found, TRUE);
    g_array_free(flat, TRUE);
    g_object_unref(tilted);
    g_rand_free(rng);
}
END_TEST

/* simscan --sample FILE without other options: scanned at the sample's own
 * 256 x 256 over its 10 um, local-scan radius from its particles, the
 * paper's drift scaled by the pixel size (39.2 nm against 19.5 nm). */
START_TEST(test_sample_defaults)
{
    SimscanConfig config;
    GError *error = NULL;
    gdouble scale = (10.0392e-6/256)/(5e-6/256);

    simscan_config_init(&config);
    config.sample_file = g_strdup(sample_file);
    ck_assert(simscan_config_adopt_sample(&config, sample_field, 0, &error));
    ck_assert_int_eq(config.xres, 256);
    ck_assert_int_eq(config.yres, 256);
    ck_assert(fabs(config.xreal - 10.0392e-6) < 1e-9);
    ck_assert(config.local.radius > 55e-9 && config.local.radius < 80e-9);
    ck_assert(fabs(config.drift.v[0]/DRIFT_MODEL_PAPER_VX - scale) < 0.01);
    ck_assert(fabs(config.drift.v[1]/DRIFT_MODEL_PAPER_VY - scale) < 0.01);
    ck_assert(fabs(config.local.r_max - 100e-9*scale) < 1e-9);
    simscan_config_clear(&config);

    /* What the user gives stays. */
    simscan_config_init(&config);
    config.sample_file = g_strdup(sample_file);
    config.xres = config.yres = 128;
    config.local.radius = 40e-9;
    config.drift.v[0] = 1e-9;
    ck_assert(simscan_config_adopt_sample(&config, sample_field,
                                          SIMSCAN_GIVEN_RADIUS
                                          | SIMSCAN_GIVEN_RESOLUTION
                                          | SIMSCAN_GIVEN_VELOCITY, &error));
    ck_assert_int_eq(config.xres, 128);
    ck_assert(config.local.radius == 40e-9);
    ck_assert(config.drift.v[0] == 1e-9);
    simscan_config_clear(&config);
}
END_TEST

/* A flat field without particles is refused with a message. */
START_TEST(test_sample_without_particles)
{
    GwyDataField *flat = gwy_data_field_new(64, 64, 1e-6, 1e-6, TRUE);
    SimscanConfig config;
    GError *error = NULL;

    simscan_config_init(&config);
    config.sample_file = g_strdup("flat.gwy");
    ck_assert(!simscan_config_adopt_sample(&config, flat, 0, &error));
    ck_assert_str_eq(error->message, "no particles found on the sample flat.gwy");
    g_clear_error(&error);
    simscan_config_clear(&config);
    g_object_unref(flat);
}
END_TEST

typedef struct {
    gint with_particle;    /* stripes that had a particle to scan */
    gint found;            /* of them, found by the local scan */
    gdouble worst_dx;      /* px: measured exact minus true drift */
    CentreError before, after;
} SampleRun;

/* The particle-centre errors: true places are the particles found on the
 * drift-free truth, displaced by the drift at the local scans (which the
 * compensated image shows); before is the contaminated image, after the
 * paper-mode compensated one. */
static void
measure_centres(const SimscanScene *scene, const SimscanMeasurement *m,
                SampleRun *run)
{
    GArray *truth = detect(scene->truth), *before = detect(scene->image);
    GArray *after = detect(m->compensated);
    gdouble dx = gwy_data_field_get_dx(scene->image);
    gdouble dy = gwy_data_field_get_dy(scene->image);
    gint xres = gwy_data_field_get_xres(scene->image);
    gint yres = gwy_data_field_get_yres(scene->image);
    gdouble *places = g_new(gdouble, 2*truth->len);
    guint k;

    for (k = 0; k < truth->len; k++) {
        const DetectedParticle *p = &g_array_index(truth, DetectedParticle, k);

        places[2*k] = p->x + m->ref_drift[0]/dx;
        places[2*k + 1] = p->y + m->ref_drift[1]/dy;
    }
    centre_error_measure(before, places, places, truth->len, xres, yres,
                         BORDER_MARGIN, MATCH_RADIUS, dx, dy, &run->before);
    centre_error_measure(after, places, places, truth->len, xres, yres,
                         BORDER_MARGIN, MATCH_RADIUS, dx, dy, &run->after);
    g_free(places);
    g_array_free(truth, TRUE);
    g_array_free(before, TRUE);
    g_array_free(after, TRUE);
}

static void
run_sample(SimscanConfig *config, SampleRun *run)
{
    SimscanScene *scene;
    SimscanMeasurement *m;
    GError *error = NULL;
    gint s;

    scene = simscan_scene_new(config, sample_field, &error);
    ck_assert_msg(scene, "%s", error ? error->message : "");
    m = simscan_measure(scene, config->n_stripes, &error);
    ck_assert_msg(m, "%s", error ? error->message : "");
    run->with_particle = run->found = 0;
    run->worst_dx = 0.0;
    for (s = 0; s < m->n_stripes; s++) {
        if (!m->scans[s].lines)
            continue;
        run->with_particle++;
        if (!m->scans[s].found)
            continue;
        run->found++;
        run->worst_dx = fmax(run->worst_dx,
                             fmax(fabs(m->scans[s].dx - m->true_dx[s]),
                                  fabs(m->scans[s].dy - m->true_dy[s])));
    }
    measure_centres(scene, m, run);
    simscan_measurement_free(m);
    simscan_scene_free(scene);
}

static void
print_run(const gchar *what, const SimscanConfig *config, const SampleRun *r)
{
    g_printerr("%s: v = (%.3f, %.3f) nm/s, radius %.1f nm; %d of %d stripes "
               "had a particle, %d found, worst drift error %.3f px\n"
               "  before: RMS %.3f px (%.1f nm), max %.3f px, %d of %d "
               "matched\n  after:  RMS %.3f px (%.1f nm), max %.3f px, %d of "
               "%d matched\n", what, 1e9*config->drift.v[0],
               1e9*config->drift.v[1], 1e9*config->local.radius,
               r->with_particle, config->n_stripes, r->found, r->worst_dx,
               r->before.rms_px, r->before.rms_nm, r->before.max_px,
               r->before.n_matched, r->before.n_expected, r->after.rms_px,
               r->after.rms_nm, r->after.max_px, r->after.n_matched,
               r->after.n_expected);
}

/* Stripes: 11 or 12 of the 16 hold a particle clear of the border, and the
 * local scans find every one.  A real particle is no sphere: its chords'
 * midpoints miss its detected centre by up to 0.7 px, which the displayed
 * centre measured by the same chords in the image cancels; the rest, 0.04
 * px with the default drift and up to 0.51 px over random drifts (seeds
 * 1-300), comes from the drift distorting the particle in the image.  Centres: whole-pixel shifts
 * leave up to half a pixel on each axis (0.41 px RMS if uniform), more
 * where the drift changes within a stripe or a stripe without a particle
 * takes its neighbour's. */
static void
check_run(const SampleRun *r, gdouble min_before_px, gdouble max_ratio,
          gdouble max_after_px)
{
    ck_assert_int_ge(r->with_particle, 10);
    ck_assert_int_eq(r->found, r->with_particle);
    ck_assert_msg(r->worst_dx < 0.6, "worst drift error %.3f px",
                  r->worst_dx);
    ck_assert_int_ge(r->before.n_matched, r->before.n_expected - 1);
    ck_assert_int_ge(r->after.n_matched, r->after.n_expected - 1);
    ck_assert_int_ge(r->after.n_expected, 14);
    ck_assert(r->before.rms_px > min_before_px);
    ck_assert_msg(r->after.rms_px < max_ratio*r->before.rms_px
                  && r->after.rms_px < max_after_px,
                  "after %.3f px, before %.3f px", r->after.rms_px,
                  r->before.rms_px);
}

/* The defaults: the paper's drift in pixels, about 1.2 px over the frame. */
START_TEST(test_local_scans_default_drift)
{
    SimscanConfig config;
    SampleRun run;
    GError *error = NULL;

    simscan_config_init(&config);
    config.sample_file = g_strdup(sample_file);
    ck_assert(simscan_config_adopt_sample(&config, sample_field, 0, &error));
    run_sample(&config, &run);
    print_run("default drift", &config, &run);
    /* Measured: before 0.775 px RMS, after 0.349 px. */
    check_run(&run, 0.5, 0.6, 0.45);
    simscan_config_clear(&config);
}
END_TEST

/* A random drift 2 to 4 times the default, in a random direction: up to
 * 4.8 px over the frame, within the default largest drift (5.1 px). */
START_TEST(test_local_scans_random_drift)
{
    GRand *rng = g_rand_new_with_seed(test_seed + 1);
    gdouble factor = g_rand_double_range(rng, 2.0, 4.0);
    gdouble phi = g_rand_double_range(rng, 0.0, 2.0*G_PI);
    SimscanConfig config;
    SampleRun run;
    GError *error = NULL;
    gdouble speed;

    simscan_config_init(&config);
    config.sample_file = g_strdup(sample_file);
    ck_assert(simscan_config_adopt_sample(&config, sample_field, 0, &error));
    speed = factor*hypot(config.drift.v[0], config.drift.v[1]);
    config.drift.v[0] = speed*cos(phi);
    config.drift.v[1] = speed*sin(phi);
    run_sample(&config, &run);
    print_run("random drift", &config, &run);
    /* Measured over ten seeds: before 1.55 to 2.5 px RMS, after 0.32 to
     * 0.56 px. */
    check_run(&run, 1.0, 0.4, 0.65);
    simscan_config_clear(&config);
    g_rand_free(rng);
}
END_TEST

static Suite*
measured_sample_suite(void)
{
    TCase *tc;
    Suite *suite = test_suite_new("simscan-measured-sample", "particles-film", &tc);

    tcase_add_test(tc, test_detect_film);
    tcase_add_test(tc, test_detect_tilted_film);
    tcase_add_test(tc, test_sample_defaults);
    tcase_add_test(tc, test_sample_without_particles);
    tcase_add_test(tc, test_local_scans_default_drift);
    tcase_add_test(tc, test_local_scans_random_drift);
    return suite;
}

int
main(void)
{
    gint status;

    sample_file = test_measured_file("test-simscan-measured-sample",
                                     SAMPLE_PATH, "every test");
    if (!sample_file)
        return TEST_EXIT_SKIP;
    if (!(sample_field = load_sample(sample_file))) {
        printf("test-simscan-measured-sample: cannot read %s\n", sample_file);
        return EXIT_FAILURE;
    }
    test_seed = test_seed_from_env("test-simscan-measured-sample");
    status = test_run_suite(measured_sample_suite());
    g_object_unref(sample_field);
    g_free(sample_file);
    return status;
}
