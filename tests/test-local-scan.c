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
#include "test-common.h"

#define MAX_SPHERES 16

/* Spheres resting on a flat substrate at z = 0, drifting as p(t) = v t. */
typedef struct {
    gint n;
    gdouble x[MAX_SPHERES], y[MAX_SPHERES], r[MAX_SPHERES];
    gdouble vx, vy;                /* m/s */
    gdouble px0, py0;              /* m, drift at t = 0 */
} IdealSample;

static guint32 test_seed;

/* Detection as the simulator's scenes on flat substrates had it: no
 * levelling, threshold half way up to the highest particle. */
static const ParticleDetectParams half_way_detect = {
    .height = 0.0, .min_area = 1, .max_area = 0, .level = FALSE,
};

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

/* The default parameters and n ideal particles of their radius, to be
 * placed by the test; returns the field of res x res px they sit in. */
static GwyDataField*
ideal_setup(gint res, gint n, LocalScanParams *params, IdealSample *sample)
{
    gint i;

    local_scan_params_init(params);
    memset(sample, 0, sizeof(IdealSample));
    sample->n = n;
    for (i = 0; i < n; i++)
        sample->r[i] = params->radius;
    return make_field(res);
}

/* An ideal particle whose displayed centre is off by up to half a pixel (the
 * image's own pixel grid) is found within 0.1 px with no noise. */
START_TEST(test_ideal_centre)
{
    LocalScanParams params;
    IdealSample sample;
    GwyDataField *field = ideal_setup(128, 1, &params, &sample);
    GRand *rng = g_rand_new_with_seed(test_seed);
    gdouble worst = 0.0;
    gint k;

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
    LocalScanParams params;
    IdealSample sample;
    GwyDataField *field = ideal_setup(128, 1, &params, &sample);
    GRand *rng = g_rand_new_with_seed(test_seed + 1);
    gint k, n_searched = 0, most_lines = 0;

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

/* A neighbour that the search lines reach before the particle, but whose
 * centre lies farther than r_max from the displayed centre, is passed over:
 * by the definition of r_max it cannot be the particle.  The neighbour sits
 * on the search's fourth line (two steps up, the lines go 0, -1, +1, -2, +2
 * steps of 1.5 R), within r_max in x, so its chord is taken and measured,
 * with its centre 10 nm or more beyond r_max (the lines resolve 4 nm); the
 * particle is first cut by the fifth line (two steps down). */
START_TEST(test_neighbour_beyond_rmax_passed)
{
    LocalScanParams params;
    IdealSample sample;
    GwyDataField *field = ideal_setup(128, 2, &params, &sample);
    GRand *rng = g_rand_new_with_seed(test_seed + 5);
    gdouble pxs = gwy_data_field_get_dx(field);
    gint k;

    for (k = 0; k < 50; k++) {
        LocalScanParticle res;
        gdouble r = params.radius, step = 1.5*r, r_max = params.r_max;
        gdouble cx = g_rand_double_range(rng, 40.0, 88.0);
        gdouble cy = g_rand_double_range(rng, 40.0, 88.0);
        gdouble ny = -2.0*step + 0.3*g_rand_double_range(rng, -r, r);
        gdouble py = 2.0*step + 0.3*g_rand_double_range(rng, -r, r);
        gdouble nx_min = sqrt((r_max + 10e-9)*(r_max + 10e-9) - ny*ny);
        gdouble nx = g_rand_double_range(rng, nx_min, r_max);
        gdouble px_max = sqrt((r_max - 5e-9)*(r_max - 5e-9) - py*py);
        gdouble px = g_rand_double_range(rng, -px_max, px_max);

        if (g_rand_boolean(rng))
            nx = -nx;
        sample.x[0] = px_to_m(field, cx) + px;
        sample.y[0] = px_to_m(field, cy) + py;
        sample.x[1] = px_to_m(field, cx) + nx;
        sample.y[1] = px_to_m(field, cy) + ny;
        local_scan_particle(field, &params, ideal_probe, &sample, cx, cy,
                            1.5*params.radius, 0.0, &res);
        ck_assert_msg(res.found, "case %d: particle at (%g, %g) nm not found",
                      k, px*1e9, py*1e9);
        ck_assert_msg(fabs(res.x_act - (cx + px/pxs)) < 0.1
                      && fabs(res.y_act - (cy + py/pxs)) < 0.1,
                      "case %d: found (%g, %g), particle at (%g, %g), "
                      "neighbour at (%g, %g)", k, res.x_act, res.y_act,
                      cx + px/pxs, cy + py/pxs, cx + nx/pxs, cy + ny/pxs);
        /* Five search lines, the neighbour's V and the particle's. */
        ck_assert_int_eq(res.lines, 7);
    }
    g_rand_free(rng);
    g_object_unref(field);
}
END_TEST

/* Beyond the search's reach the particle is reported as not found. */
START_TEST(test_beyond_reach)
{
    LocalScanParams params;
    IdealSample sample;
    GwyDataField *field = ideal_setup(128, 1, &params, &sample);
    LocalScanParticle res;

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
 * is blank in the table and takes the nearest stripe's drift.
 *
 * The rounded drifts of stripes 1 and 2 differ by construction: each
 * measured stripe takes 2 lines (L0 and V; vy = 0, so L0 always hits), so
 * stripe 2's L0 comes 2 line times after stripe 1's and its exact dx is
 * 2 vx T_line = 1.44 px lower; the displayed centres' errors (the grains'
 * centroids) are asserted below 0.2 px, which leaves the difference above
 * 1 px, and rounding keeps a difference of 1 px or more.  Between L0 and V
 * the particle moves vx T_line = 14 nm, well inside the 35 nm half-width
 * of the band where V still cuts a 40 nm sphere above the threshold. */
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
    params.radius = 40e-9;
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
    sample.vx = 6.0*pxs;
    scan_timing_init(&timing, 64, 64, 0.0, 0.1, SCAN_DIRECTION_DOWN);

    particles = particle_detect(field, &half_way_detect,
                                &substrate, NULL);
    ck_assert_int_eq(particles->len, 3);
    /* Grains come top to bottom, so in the order of particle_stripe. */
    for (k = 0; k < 3; k++) {
        const DetectedParticle *p = &g_array_index(particles,
                                                   DetectedParticle, k);

        ck_assert_msg(fabs(p->x - (sample.x[k]/pxs - 0.5)) < 0.2,
                      "particle %d: displayed x %g, true %g",
                      k, p->x, sample.x[k]/pxs - 0.5);
    }
    table = local_scan_run(field, &timing, particles, substrate, 8, &params,
                           ideal_probe, &sample, 0.0, res, NULL);
    text = drift_table_to_string(table);
    if (g_getenv("TEST_DEBUG"))
        g_printerr("%s", text);
    for (s = 0; s < 8; s++) {
        gboolean has = (source[s] == s);

        ck_assert_msg(table->rows[s].has_drift == has, "stripe %d", s);
        ck_assert_int_eq(res[s].lines, has ? 2 : 0);
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

/* The spec's rule written out plainly, stripe by stripe: among the
 * particles off the border whose rounded centre row lies in the stripe, the
 * lowest index at the least Euclidean distance from the stripe's centre
 * point; with prefer_whole, among those clear of the boundary rows if any. */
static gint
reference_choice(const GArray *particles, gint s, gint n, gint xres,
                 gint yres, gboolean prefer_whole)
{
    gint first = s*yres/n, last = (s + 1)*yres/n - 1, pass, best_k = -1;
    gdouble cx = (xres - 1)/2.0, cy = (first + last)/2.0, best = INFINITY;
    guint k;

    for (pass = prefer_whole ? 0 : 1; pass < 2 && best_k < 0; pass++) {
        for (k = 0; k < particles->len; k++) {
            const DetectedParticle *p = &g_array_index(particles,
                                                       DetectedParticle, k);
            gint row = (gint)floor(p->y + 0.5);
            gdouble d = hypot(p->x - cx, p->y - cy);

            if (p->on_edge || row < first || row > last)
                continue;
            if (pass == 0 && (p->row_min <= first || p->row_max >= last))
                continue;
            if (d < best) {
                best = d;
                best_k = (gint)k;
            }
        }
    }
    return best_k;
}

/* Random particles on a quarter-pixel grid (distances are exact, so mirror
 * images and repeats make true ties); grains extend a few rows either way,
 * so many touch a stripe's first or last row. */
static GArray*
random_particles(GRand *rng, gint count, gint xres, gint yres)
{
    GArray *particles = g_array_new(FALSE, TRUE, sizeof(DetectedParticle));
    gint k;

    for (k = 0; k < count; k++) {
        DetectedParticle p = { 0 };

        if (k && g_rand_int_range(rng, 0, 4) == 0) {
            /* A tie: the mirror image of an earlier particle through the
             * centre column, or the same place again. */
            p = g_array_index(particles, DetectedParticle,
                              g_rand_int_range(rng, 0, k));
            if (g_rand_boolean(rng))
                p.x = (xres - 1) - p.x;
        }
        else {
            p.x = 0.25*g_rand_int_range(rng, 0, 4*(xres - 1) + 1);
            p.y = 0.25*g_rand_int_range(rng, 0, 4*(yres - 1) + 1);
            p.row_min = (gint)floor(p.y) - g_rand_int_range(rng, 0, 4);
            p.row_max = (gint)ceil(p.y) + g_rand_int_range(rng, 0, 4);
            p.on_edge = (g_rand_int_range(rng, 0, 10) == 0);
            p.area = 1;
        }
        g_array_append_val(particles, p);
    }
    return particles;
}

/* The default choice is exactly the spec's: the particle closest to the
 * stripe's centre point, ties to the earlier one; particle_choose_for_stripes
 * and the CLOSEST choice agree.  500 seeded random sets of particles over
 * random image sizes and stripe counts. */
START_TEST(test_choice_closest_is_spec)
{
    GRand *rng = g_rand_new_with_seed(test_seed + 3);
    gint trial, n_cut_chosen = 0, n_ties = 0, n_checked = 0;

    for (trial = 0; trial < 500; trial++) {
        gint xres = g_rand_int_range(rng, 8, 300);
        gint yres = g_rand_int_range(rng, 8, 300);
        gint n = g_rand_int_range(rng, 1, MIN(yres, 40) + 1);
        GArray *particles = random_particles(rng, g_rand_int_range(rng, 0, 60),
                                             xres, yres);
        gint *chosen = g_new(gint, n), *chosen_by = g_new(gint, n);
        gint s;

        particle_choose_for_stripes(particles, n, xres, yres, chosen);
        particle_choose_for_stripes_by(particles, n, xres, yres,
                                       PARTICLE_CHOICE_CLOSEST, chosen_by);
        for (s = 0; s < n; s++) {
            gint expected = reference_choice(particles, s, n, xres, yres,
                                             FALSE);
            const DetectedParticle *p;
            guint k;

            ck_assert_msg(chosen[s] == expected,
                          "trial %d (%d x %d, %d stripes) stripe %d: chose %d, "
                          "the spec's rule gives %d", trial, xres, yres, n, s,
                          chosen[s], expected);
            ck_assert_int_eq(chosen_by[s], chosen[s]);
            n_checked++;
            if (expected < 0)
                continue;
            p = &g_array_index(particles, DetectedParticle, expected);
            if (p->row_min <= stripe_first_row(s, n, yres)
                || p->row_max >= stripe_end_row(s, n, yres) - 1)
                n_cut_chosen++;
            for (k = expected + 1; k < particles->len; k++) {
                const DetectedParticle *q = &g_array_index(particles,
                                                           DetectedParticle,
                                                           k);
                gdouble ey = stripe_centre_row(s, n, yres);

                if (!q->on_edge && (gint)floor(q->y + 0.5) >= 0
                    && stripe_of_row((gint)floor(q->y + 0.5), n, yres) == s
                    && hypot(q->x - 0.5*(xres - 1), q->y - ey)
                       == hypot(p->x - 0.5*(xres - 1), p->y - ey))
                    n_ties++;
            }
        }
        g_free(chosen);
        g_free(chosen_by);
        g_array_free(particles, TRUE);
    }
    g_printerr("closest choice: %d stripes agree with the spec's rule, %d "
               "chosen grains touch a boundary row, %d ties resolved\n",
               n_checked, n_cut_chosen, n_ties);
    /* The sets must exercise what distinguishes the rules. */
    ck_assert_int_gt(n_cut_chosen, 100);
    ck_assert_int_gt(n_ties, 20);
    g_rand_free(rng);
}
END_TEST

/* The opt-in choice agrees with its own plain reference on the same random
 * sets, and differs from the spec's rule in some stripes. */
START_TEST(test_choice_prefer_whole_random)
{
    GRand *rng = g_rand_new_with_seed(test_seed + 4);
    gint trial, n_differ = 0;

    for (trial = 0; trial < 500; trial++) {
        gint xres = g_rand_int_range(rng, 8, 300);
        gint yres = g_rand_int_range(rng, 8, 300);
        gint n = g_rand_int_range(rng, 1, MIN(yres, 40) + 1);
        GArray *particles = random_particles(rng, g_rand_int_range(rng, 0, 60),
                                             xres, yres);
        gint *whole = g_new(gint, n), *closest = g_new(gint, n);
        gint s;

        particle_choose_for_stripes_by(particles, n, xres, yres,
                                       PARTICLE_CHOICE_PREFER_WHOLE, whole);
        particle_choose_for_stripes(particles, n, xres, yres, closest);
        for (s = 0; s < n; s++) {
            ck_assert_int_eq(whole[s], reference_choice(particles, s, n, xres,
                                                        yres, TRUE));
            if (whole[s] != closest[s])
                n_differ++;
        }
        g_free(whole);
        g_free(closest);
        g_array_free(particles, TRUE);
    }
    g_printerr("prefer-whole choice: differs from the spec's rule in %d "
               "stripes\n", n_differ);
    ck_assert_int_gt(n_differ, 50);
    g_rand_free(rng);
}
END_TEST

/* One stripe (rows 16-31 of 64, 4 stripes): a grain touching row 16 lies
 * nearer the centre point (31.5, 23.5) than a whole one.  The spec's rule
 * takes the cut grain, the opt-in the whole one; alone, the cut grain is
 * taken by both. */
START_TEST(test_choice_boundary_grain)
{
    DetectedParticle cut = { .x = 31.5, .y = 19.0, .area = 12, .peak = 1.0,
                             .row_min = 16, .row_max = 22 };
    DetectedParticle whole = { .x = 40.0, .y = 24.0, .area = 12, .peak = 1.0,
                               .row_min = 21, .row_max = 27 };
    GArray *particles = g_array_new(FALSE, TRUE, sizeof(DetectedParticle));
    gint chosen[4];

    g_array_append_val(particles, whole);
    g_array_append_val(particles, cut);
    particle_choose_for_stripes(particles, 4, 64, 64, chosen);
    ck_assert_int_eq(chosen[1], 1);
    ck_assert_int_eq(chosen[0], -1);
    ck_assert_int_eq(chosen[2], -1);
    particle_choose_for_stripes_by(particles, 4, 64, 64,
                                   PARTICLE_CHOICE_PREFER_WHOLE, chosen);
    ck_assert_int_eq(chosen[1], 0);
    /* Touching the last row (31) counts as cut too. */
    g_array_index(particles, DetectedParticle, 1).row_min = 17;
    g_array_index(particles, DetectedParticle, 1).row_max = 31;
    particle_choose_for_stripes_by(particles, 4, 64, 64,
                                   PARTICLE_CHOICE_PREFER_WHOLE, chosen);
    ck_assert_int_eq(chosen[1], 0);
    g_array_remove_index(particles, 0);
    particle_choose_for_stripes_by(particles, 4, 64, 64,
                                   PARTICLE_CHOICE_PREFER_WHOLE, chosen);
    ck_assert_int_eq(chosen[1], 0);
    g_array_free(particles, TRUE);
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
    /* Neighbours farther apart than twice the largest drift ((16, 3) px,
     * 318 nm), so some r_max reaches the particle and no neighbour. */
    pp.min_spacing = 700e-9;
    pp.count = 60;
    sample = sim_sample_new_particles(&pp, test_seed);
    sim_scan_params_init(sp, sample, 256, 256);
    return sample;
}

/* The local scans on the simulated Figure 6 frame measure exactly the
 * figure's drift in every stripe that has a whole particle.  The stripes
 * are measured on whole particles wherever the stripe has one (the opt-in
 * choice): with the spec's closest particle, a quarter of the stripes fall
 * on cut grains, and in 2 of 300 seeded frames fewer than 8 of 16 stripes
 * were left to check. */
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
    /* Stripe 16 is (16, 3) px = 318 nm off, so r_max must exceed that; a
     * neighbour, 700 nm or more from the particle, is at least 382 nm from
     * its displayed centre, so r_max below that keeps neighbours out of
     * reach.  Half way between, with 30 nm to spare either side for the
     * displayed centres' errors: */
    params.r_max = 350e-9;
    /* The default lines' sample spacing, 4 nm, on these 3 times longer
     * lines: the centre is measured to 0.1 px on it, and the displayed
     * centres of these 2.5 px grains are off by up to 0.3 px, together
     * safely under the half pixel the rounding allows.  With 64 points (12
     * nm) a grazing chord of the search put some stripes 0.45 px off. */
    params.points = 192;
    params.choice = PARTICLE_CHOICE_PREFER_WHOLE;
    particles = particle_detect(frame, &half_way_detect,
                                &substrate, NULL);
    table = local_scan_run(frame, &timing, particles, substrate, 16, &params,
                           sim_probe, &probe, 300.0, NULL, NULL);
    if (g_getenv("TEST_DEBUG")) {
        gchar *text = drift_table_to_string(table);
        g_printerr("%s", text);
        g_free(text);
    }
    particle_choose_for_stripes_by(particles, 16, 256, 256, params.choice,
                                   chosen);
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
    TCase *tc;
    Suite *suite = test_suite_new("local-scan", "core", &tc);

    tcase_add_test(tc, test_ideal_centre);
    tcase_add_test(tc, test_displaced_found);
    tcase_add_test(tc, test_beyond_reach);
    tcase_add_test(tc, test_neighbour_beyond_rmax_passed);
    tcase_add_test(tc, test_empty_stripes_filled);
    tcase_add_test(tc, test_choice_closest_is_spec);
    tcase_add_test(tc, test_choice_prefer_whole_random);
    tcase_add_test(tc, test_choice_boundary_grain);
    tcase_add_test(tc, test_figure6_measured);
    tcase_add_test(tc, test_true_drift_recovers_truth);
    return suite;
}

int
main(void)
{
    test_seed = test_seed_from_env("test-local-scan");
    return test_run_suite(local_scan_suite());
}
