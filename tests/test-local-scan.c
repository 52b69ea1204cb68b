/*
 *  Tests of particle detection and the paper's local-scan procedure, on an
 *  ideal analytic sample and on the simulator's Figure 6 scan.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <stdlib.h>
#include <math.h>
#include <check.h>
#include <glib.h>
#include <string.h>
#include <libprocess/stats.h>
#include "stripe-geometry.h"
#include "paper-compensate.h"
#include "drift-table.h"
#include "particle-detect.h"
#include "local-scan.h"
#include "sample.h"
#include "scanner.h"

#define MAX_SPHERES 16

/* Spheres resting on a flat substrate at z = 0, drifting as p(t) = v t. */
typedef struct {
    gint n;
    gdouble x[MAX_SPHERES], y[MAX_SPHERES], r[MAX_SPHERES];
    gdouble vx, vy;                /* m/s */
    gdouble px0, py0;              /* m, drift at t = 0 */
} IdealSample;

static guint32 test_seed;

static gdouble
ideal_probe(gpointer user_data, gdouble x, gdouble y, gdouble t)
{
    const IdealSample *sample = user_data;
    gdouble z = 0.0;
    gint i;

    x -= sample->px0 + sample->vx*t;
    y -= sample->py0 + sample->vy*t;
    for (i = 0; i < sample->n; i++) {
        gdouble ex = x - sample->x[i], ey = y - sample->y[i];
        gdouble rho2 = ex*ex + ey*ey, r = sample->r[i];

        if (rho2 < r*r)
            z = fmax(z, r + sqrt(r*r - rho2));
    }
    return z;
}

/* 128 x 128 px over 2.5 um: the paper's pixel size, 19.5 nm. */
static GwyDataField*
make_field(gint res)
{
    return gwy_data_field_new(res, res, res*2.5e-6/128, res*2.5e-6/128, TRUE);
}

static gdouble
px_to_m(GwyDataField *field, gdouble px)
{
    return (px + 0.5)*gwy_data_field_get_dx(field);
}

/* An ideal particle whose displayed centre is off by up to half a pixel (the
 * image's own pixel grid) is found within 0.1 px with no noise. */
START_TEST(test_ideal_centre)
{
    GwyDataField *field = make_field(128);
    LocalScanParams params;
    IdealSample sample = { 0 };
    GRand *rng = g_rand_new_with_seed(test_seed);
    gdouble worst = 0.0;
    gint k;

    local_scan_params_init(&params);
    sample.n = 1;
    sample.r[0] = params.radius;
    for (k = 0; k < 50; k++) {
        LocalScanParticle res;
        gdouble cx = g_rand_double_range(rng, 40.0, 88.0);
        gdouble cy = g_rand_double_range(rng, 40.0, 88.0);
        gdouble xd = cx + g_rand_double_range(rng, -0.5, 0.5);
        gdouble yd = cy + g_rand_double_range(rng, -0.5, 0.5);

        sample.x[0] = px_to_m(field, cx);
        sample.y[0] = px_to_m(field, cy);
        local_scan_particle(field, &params, ideal_probe, &sample, xd, yd,
                            1.5*params.radius, 10.0, &res);
        ck_assert_msg(res.found, "case %d: particle at (%g, %g) not found",
                      k, cx, cy);
        worst = fmax(worst, fmax(fabs(res.x_act - cx), fabs(res.y_act - cy)));
        ck_assert_msg(fabs(res.x_act - cx) < 0.1 && fabs(res.y_act - cy) < 0.1,
                      "case %d: found (%g, %g), true (%g, %g)",
                      k, res.x_act, res.y_act, cx, cy);
        ck_assert(fabs(res.dx - (xd - res.x_act)) < 1e-12);
        ck_assert(res.t_start == 10.0);
        ck_assert(fabs(res.t_end - 10.0
                       - res.lines*local_scan_line_time(&params)) < 1e-9);
    }
    g_printerr("ideal centre: worst error %.4f px over 50 cases\n", worst);
    g_rand_free(rng);
    g_object_unref(field);
}
END_TEST

/* Displaced by up to r_max in any direction, the particle is still found:
 * when it lies more than R off L0 only the up/down search can reach it. */
START_TEST(test_displaced_found)
{
    GwyDataField *field = make_field(128);
    LocalScanParams params;
    IdealSample sample = { 0 };
    GRand *rng = g_rand_new_with_seed(test_seed + 1);
    gint k, n_searched = 0, most_lines = 0;

    local_scan_params_init(&params);
    sample.n = 1;
    sample.r[0] = params.radius;
    for (k = 0; k < 100; k++) {
        LocalScanParticle res;
        gdouble cx = g_rand_double_range(rng, 40.0, 88.0);
        gdouble cy = g_rand_double_range(rng, 40.0, 88.0);
        gdouble phi = g_rand_double_range(rng, 0.0, 2.0*G_PI);
        gdouble d = params.r_max*sqrt(g_rand_double(rng));
        gdouble dy_m = d*sin(phi);
        gdouble pxs = gwy_data_field_get_dx(field);

        sample.x[0] = px_to_m(field, cx);
        sample.y[0] = px_to_m(field, cy);
        local_scan_particle(field, &params, ideal_probe, &sample,
                            cx + d*cos(phi)/pxs, cy + dy_m/pxs,
                            1.5*params.radius, 0.0, &res);
        ck_assert_msg(res.found, "case %d: displaced by %g nm not found",
                      k, d*1e9);
        ck_assert_msg(fabs(res.x_act - cx) < 0.1 && fabs(res.y_act - cy) < 0.1,
                      "case %d: found (%g, %g), true (%g, %g)",
                      k, res.x_act, res.y_act, cx, cy);
        if (fabs(dy_m) > params.radius) {
            ck_assert_int_gt(res.lines, 2);
            n_searched++;
        }
        most_lines = MAX(most_lines, res.lines);
    }
    g_printerr("displaced: %d of 100 needed the search, at most %d lines\n",
               n_searched, most_lines);
    ck_assert_int_gt(n_searched, 10);
    g_rand_free(rng);
    g_object_unref(field);
}
END_TEST

/* Beyond the search's reach the particle is reported as not found. */
START_TEST(test_beyond_reach)
{
    GwyDataField *field = make_field(128);
    LocalScanParams params;
    IdealSample sample = { 0 };
    LocalScanParticle res;

    local_scan_params_init(&params);
    sample.n = 1;
    sample.r[0] = params.radius;
    sample.x[0] = px_to_m(field, 64.0);
    sample.y[0] = px_to_m(field, 64.0) + 3.0*params.r_max;
    local_scan_particle(field, &params, ideal_probe, &sample, 64.0, 64.0,
                        1.5*params.radius, 0.0, &res);
    ck_assert(!res.found);
    ck_assert(isnan(res.dx));
    ck_assert_int_gt(res.lines, 2);
    g_object_unref(field);
}
END_TEST

static void
render_ideal(GwyDataField *field, IdealSample *sample)
{
    gint xres = gwy_data_field_get_xres(field), i, j;
    gdouble *d = gwy_data_field_get_data(field);

    for (i = 0; i < xres; i++)
        for (j = 0; j < xres; j++)
            d[i*xres + j] = ideal_probe(sample, px_to_m(field, j),
                                        px_to_m(field, i), 0.0);
}

/* Particles in stripes 1, 2 and 6 of 8 only; drift grows fast during the
 * local scans so the three measured stripes differ.  Every other stripe
 * is blank in the table and takes the nearest stripe's drift. */
START_TEST(test_empty_stripes_filled)
{
    static const gint particle_stripe[3] = { 1, 2, 6 };
    static const gint source[8] = { 1, 1, 2, 2, 2, 6, 6, 6 };
    GwyDataField *field = make_field(64);
    LocalScanParams params;
    IdealSample sample = { 0 };
    LocalScanParticle res[8];
    ScanTiming timing;
    DriftTable *table;
    GArray *particles;
    GRand *rng = g_rand_new_with_seed(test_seed + 2);
    gdouble dx[8], dy[8], pxs, substrate, ex;
    GError *error = NULL;
    gchar *text;
    gint k, s;

    local_scan_params_init(&params);
    params.r_max = 200e-9;
    pxs = gwy_data_field_get_dx(field);
    sample.n = 3;
    for (k = 0; k < 3; k++) {
        sample.r[k] = params.radius;
        sample.x[k] = px_to_m(field, g_rand_double_range(rng, 12.0, 52.0));
        sample.y[k] = px_to_m(field, 8*particle_stripe[k] + 3.5
                              + g_rand_double_range(rng, -1.0, 1.0));
    }
    render_ideal(field, &sample);
    sample.vx = 4.0*pxs;
    scan_timing_init(&timing, 64, 64, 0.0, 0.1, SCAN_DIRECTION_DOWN);

    particles = particle_detect(field, &(ParticleDetectParams){ 0, 1, 0 },
                                &substrate, NULL);
    ck_assert_int_eq(particles->len, 3);
    table = local_scan_run(field, &timing, particles, substrate, 8, &params,
                           ideal_probe, &sample, 0.0, res, NULL);
    text = drift_table_to_string(table);
    for (s = 0; s < 8; s++) {
        gboolean has = (source[s] == s);

        ck_assert_msg(table->rows[s].has_drift == has, "stripe %d", s);
        ck_assert_int_eq(res[s].lines > 0, has);
        if (has) {
            /* The x chord is measured on L0, in the first half of the scan. */
            ex = -sample.vx*(res[s].t_start + 0.5*(res[s].t_local
                                                   - res[s].t_start))/pxs;
            ck_assert_msg(fabs(res[s].dx - ex) < 0.4,
                          "stripe %d: dx %g, expected %g", s, res[s].dx, ex);
        }
    }
    ck_assert(table->rows[1].dx != table->rows[2].dx);
    ck_assert(table->rows[2].dx != table->rows[6].dx);

    ck_assert(strstr(text, "\n0,,,,,,,,,\n"));
    g_free(text);

    ck_assert(drift_table_to_pixels(table, 64, pxs, pxs, TRUE, dx, dy,
                                    &error));
    for (s = 0; s < 8; s++) {
        ck_assert_msg(dx[s] == table->rows[source[s]].dx,
                      "stripe %d: %g, expected stripe %d's %g",
                      s, dx[s], source[s], table->rows[source[s]].dx);
        ck_assert(dy[s] == table->rows[source[s]].dy);
    }
    drift_table_free(table);
    g_array_free(particles, TRUE);
    g_rand_free(rng);
    g_object_unref(field);
}
END_TEST

/* The paper's Figure 6 drift, stripe s (1-based) dx = -s, dy by fours. */
static void
figure6_drift(gdouble *dx, gdouble *dy)
{
    gint s;

    for (s = 0; s < 16; s++) {
        dx[s] = -(s + 1);
        dy[s] = -(s/4);
    }
}

typedef struct {
    SimSample *sample;
    gdouble tip_radius;
} SimProbe;

static gdouble
sim_probe(gpointer user_data, gdouble x, gdouble y, gdouble t)
{
    const SimProbe *probe = user_data;

    return sim_probe_height(probe->sample, NULL, probe->tip_radius, x, y, t);
}

static SimSample*
figure6_sample(SimScanParams *sp)
{
    SimParticleParams pp;
    SimSample *sample;

    sim_particle_params_init(&pp);
    /* Neighbours farther apart than twice the largest drift (16 px, 312 nm),
     * so the nearest chord is always the right particle, as in the preset. */
    pp.min_spacing = 700e-9;
    pp.count = 60;
    sample = sim_sample_new_particles(&pp, test_seed);
    sim_scan_params_init(sp, sample, 256, 256);
    return sample;
}

/* The local scans on the simulated Figure 6 frame measure exactly the
 * figure's drift in every stripe that has a particle. */
START_TEST(test_figure6_measured)
{
    gdouble fdx[16], fdy[16];
    LocalScanParams params;
    SimScanParams sp;
    SimProbe probe;
    ScanTiming timing;
    GwyDataField *frame;
    DriftTable *table;
    GArray *particles;
    gdouble substrate, worst = 0.0;
    gint chosen[16];
    gint s, n_measured = 0, n_cut = 0;

    figure6_drift(fdx, fdy);
    probe.sample = figure6_sample(&sp);
    probe.tip_radius = 0.0;
    frame = sim_scan_frame_stripes(probe.sample, &sp, 16, fdx, fdy);
    sim_scan_params_timing(&sp, &timing);
    local_scan_params_init(&params);
    /* Stripe 16 is 16 px = 312 nm off. */
    params.r_max = 400e-9;
    particles = particle_detect(frame, &(ParticleDetectParams){ 0, 1, 0 },
                                &substrate, NULL);
    table = local_scan_run(frame, &timing, particles, substrate, 16, &params,
                           sim_probe, &probe, 300.0, NULL, NULL);
    if (g_getenv("TEST_DEBUG")) {
        gchar *text = drift_table_to_string(table);
        g_printerr("%s", text);
        g_free(text);
    }
    particle_choose_for_stripes(particles, 16, 256, 256, chosen);
    for (s = 0; s < 16; s++) {
        const DetectedParticle *p;
        gdouble ex, ey;

        if (!table->rows[s].has_drift)
            continue;
        /* A particle cut by a stripe boundary is sheared by the figure's
         * stripe shifts: its displayed centre is not a particle's centre. */
        p = &g_array_index(particles, DetectedParticle, chosen[s]);
        if (p->row_min <= stripe_first_row(s, 16, 256)
            || p->row_max >= stripe_end_row(s, 16, 256) - 1) {
            n_cut++;
            continue;
        }
        n_measured++;
        ck_assert_msg(table->rows[s].dx == fdx[s] && table->rows[s].dy == fdy[s],
                      "stripe %d: measured (%g, %g), true (%g, %g)", s,
                      table->rows[s].dx, table->rows[s].dy, fdx[s], fdy[s]);
        ck_assert(drift_table_get_extra(table, s, "dx_exact", &ex));
        ck_assert(drift_table_get_extra(table, s, "dy_exact", &ey));
        worst = fmax(worst, fmax(fabs(ex - fdx[s]), fabs(ey - fdy[s])));
    }
    g_printerr("figure 6: %d of 16 stripes measured on whole particles "
               "(%d on cut ones), worst exact error %.3f px\n",
               n_measured, n_cut, worst);
    ck_assert_int_ge(n_measured, 8);
    drift_table_free(table);
    g_array_free(particles, TRUE);
    g_object_unref(frame);
    sim_sample_free(probe.sample);
}
END_TEST

/* Paper-mode compensation with the true per-stripe drift gives back the
 * truth in every pixel that is neither filled nor borrowed from a
 * neighbouring stripe (whose own shift differs: the whole-pixel method's
 * inherent seam). */
START_TEST(test_true_drift_recovers_truth)
{
    gdouble fdx[16], fdy[16];
    gint idx[16], idy[16];
    SimScanParams sp;
    SimSample *sample;
    GwyDataField *frame, *truth;
    gdouble *result, *mask;
    const gdouble *t;
    gdouble tol, d;
    gint r, c, s, n_compared = 0, n_wrong = 0;

    figure6_drift(fdx, fdy);
    for (s = 0; s < 16; s++) {
        idx[s] = (gint)fdx[s];
        idy[s] = (gint)fdy[s];
    }
    sample = figure6_sample(&sp);
    frame = sim_scan_frame_stripes(sample, &sp, 16, fdx, fdy);
    truth = sim_scan_truth(sample, &sp);
    result = g_new(gdouble, 256*256);
    mask = g_new(gdouble, 256*256);
    d = paper_image_mean(gwy_data_field_get_data_const(frame), 256, 256);
    paper_compensate(gwy_data_field_get_data_const(frame), 256, 256, 16,
                     idx, idy, d, result, mask);
    t = gwy_data_field_get_data_const(truth);
    tol = 1e-9*(gwy_data_field_get_max(truth) - gwy_data_field_get_min(truth));
    for (r = 0; r < 256; r++) {
        gint src;

        s = stripe_of_row(r, 16, 256);
        src = r + idy[s];
        if (src < 0 || src >= 256 || stripe_of_row(src, 16, 256) != s)
            continue;
        for (c = 0; c < 256; c++) {
            if (mask[r*256 + c])
                continue;
            n_compared++;
            if (fabs(result[r*256 + c] - t[r*256 + c]) > tol)
                n_wrong++;
        }
    }
    g_printerr("true drift: %d pixels compared, %d differ\n",
               n_compared, n_wrong);
    ck_assert_int_gt(n_compared, 256*200);
    ck_assert_int_eq(n_wrong, 0);
    g_free(result);
    g_free(mask);
    g_object_unref(truth);
    g_object_unref(frame);
    sim_sample_free(sample);
}
END_TEST

static Suite*
local_scan_suite(void)
{
    Suite *suite = suite_create("local-scan");
    TCase *tc = tcase_create("core");

    tcase_add_test(tc, test_ideal_centre);
    tcase_add_test(tc, test_displaced_found);
    tcase_add_test(tc, test_beyond_reach);
    tcase_add_test(tc, test_empty_stripes_filled);
    tcase_add_test(tc, test_figure6_measured);
    tcase_add_test(tc, test_true_drift_recovers_truth);
    suite_add_tcase(suite, tc);
    return suite;
}

int
main(void)
{
    const gchar *env = g_getenv("LOCALSCAN_TEST_SEED");
    SRunner *runner;
    gint failed;

    test_seed = env ? (guint32)g_ascii_strtoull(env, NULL, 10) : g_random_int();
    g_printerr("test-local-scan: seed %u (LOCALSCAN_TEST_SEED overrides)\n",
               test_seed);
    runner = srunner_create(local_scan_suite());
    srunner_run_all(runner, CK_NORMAL);
    failed = srunner_ntests_failed(runner);
    srunner_free(runner);
    return failed ? EXIT_FAILURE : EXIT_SUCCESS;
}
