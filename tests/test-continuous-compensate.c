/*
 *  Tests of continuous (sub-pixel, line-by-line) drift compensation.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <check.h>
#include "test-common.h"
#include "continuous-fixtures.h"
#include "settling-motion.h"
#include <glib.h>
#include <libprocess/interpolation.h>
#include "continuous-compensate.h"
#include "paper-compensate.h"
#include "stripe-geometry.h"

#define PARTICLE_SIGMA 2.5

static guint32 test_seed;

/* Gaussian particles at true positions (px). */
typedef struct {
    gint n;
    gdouble *x;
    gdouble *y;
} Particles;

/* A jittered grid of particles 24 px apart, well inside the image. */
static void
particles_init(Particles *particles, gint xres, gint yres, GRand *rng)
{
    gint nx = (xres - 24)/24, ny = (yres - 24)/24, i, j, k = 0;

    particles->n = nx*ny;
    particles->x = g_new(gdouble, 2*particles->n);
    particles->y = particles->x + particles->n;
    for (i = 0; i < ny; i++) {
        for (j = 0; j < nx; j++, k++) {
            particles->x[k] = 24.0*(j + 1) + g_rand_double_range(rng, -4.0, 4.0);
            particles->y[k] = 24.0*(i + 1) + g_rand_double_range(rng, -4.0, 4.0);
        }
    }
}

static gdouble
sample_height(const Particles *particles, gdouble x, gdouble y)
{
    gdouble z = 0.0, d2;
    gint k;

    for (k = 0; k < particles->n; k++) {
        d2 = (x - particles->x[k])*(x - particles->x[k])
             + (y - particles->y[k])*(y - particles->y[k]);
        if (d2 < 100.0)
            z += exp(-d2/(2.0*PARTICLE_SIGMA*PARTICLE_SIGMA));
    }
    return z;
}

/* The drifting scan: pixel (i, j) scanned at t shows the sample at
 * (j, i) - p(t). */
static gdouble*
render_scan(const Particles *particles, const Motion *motion,
            const ScanTiming *timing)
{
    gint xres = timing->xres, yres = timing->yres, i, j;
    gdouble *a = g_new(gdouble, xres*yres), p[2];

    for (i = 0; i < yres; i++) {
        for (j = 0; j < xres; j++) {
            motion_eval(motion, scan_timing_pixel_time(timing, i, j), p);
            a[i*xres + j] = sample_height(particles, j - p[0], i - p[1]);
        }
    }
    return a;
}

/* The sample as it was at t: what compensation should give back. */
static gdouble*
render_at(const Particles *particles, const Motion *motion, gdouble t,
          gint xres, gint yres)
{
    gdouble *a = g_new(gdouble, xres*yres), p[2];
    gint i, j;

    motion_eval(motion, t, p);
    for (i = 0; i < yres; i++) {
        for (j = 0; j < xres; j++)
            a[i*xres + j] = sample_height(particles, j - p[0], i - p[1]);
    }
    return a;
}

/* The paper's local scans: stripe s imaged at its centre time, scanned
 * locally at frame end + gap + s step.  dx, dy rounded (paper mode),
 * exact values and both times in extra columns. */
static DriftTable*
measure_table(const Motion *motion, const ScanTiming *timing, gint n,
              gdouble gap, gdouble step, const gboolean *blank)
{
    DriftTable *table = drift_table_new(n, DRIFT_UNIT_PX);
    gdouble ti, tl, pi[2], pl[2];
    gint s, yres = timing->yres;

    for (s = 0; s < n; s++) {
        if (blank && blank[s])
            continue;
        ti = scan_timing_rows_time(timing, stripe_first_row(s, n, yres),
                                   stripe_end_row(s, n, yres));
        tl = scan_timing_frame_end(timing) + gap + s*step;
        motion_eval(motion, ti, pi);
        motion_eval(motion, tl, pl);
        table->rows[s].has_drift = TRUE;
        table->rows[s].dx = floor(pi[0] - pl[0] + 0.5);
        table->rows[s].dy = floor(pi[1] - pl[1] + 0.5);
        drift_table_set_extra(table, s, "dx_exact", pi[0] - pl[0]);
        drift_table_set_extra(table, s, "dy_exact", pi[1] - pl[1]);
        drift_table_set_extra(table, s, "t_image", ti);
        drift_table_set_extra(table, s, "t_local", tl);
    }
    return table;
}

static void
run_paper_mode(const gdouble *a, gint xres, gint yres,
               const DriftTable *table, gdouble *result, gdouble *mask)
{
    gint n = table->n_stripes, s;
    gdouble *dx = g_new(gdouble, 2*n), *dy = dx + n;
    gint *idx = g_new(gint, 2*n), *idy = idx + n;

    ck_assert(drift_table_to_pixels(table, yres, 1.0, 1.0, TRUE, dx, dy, NULL));
    for (s = 0; s < n; s++) {
        idx[s] = (gint)dx[s];
        idy[s] = (gint)dy[s];
    }
    paper_compensate(a, xres, yres, n, idx, idy,
                     paper_image_mean(a, xres, yres), result, mask);
    g_free(dx);
    g_free(idx);
}

/* RMS difference over pixels at least margin from every border and not
 * filled in either mask. */
static gdouble
interior_rms(const gdouble *got, const gdouble *truth, const gdouble *mask1,
             const gdouble *mask2, gint xres, gint yres, gint margin)
{
    gdouble sum = 0.0;
    gint i, j, k, count = 0;

    for (i = margin; i < yres - margin; i++) {
        for (j = margin; j < xres - margin; j++) {
            k = i*xres + j;
            if (mask1[k] != 0.0 || mask2[k] != 0.0)
                continue;
            sum += (got[k] - truth[k])*(got[k] - truth[k]);
            count++;
        }
    }
    ck_assert_int_gt(count, xres*yres/3);
    return sqrt(sum/count);
}

/* Centroid of the image within 6 px of (x, y). */
static void
local_centroid(const gdouble *a, gint xres, gint yres, gdouble x, gdouble y,
               gdouble *cx, gdouble *cy)
{
    gdouble sw = 0.0, sx = 0.0, sy = 0.0, w;
    gint i, j;

    for (i = MAX((gint)floor(y - 6.0), 0); i <= MIN((gint)ceil(y + 6.0), yres-1); i++) {
        for (j = MAX((gint)floor(x - 6.0), 0); j <= MIN((gint)ceil(x + 6.0), xres-1); j++) {
            if ((i - y)*(i - y) + (j - x)*(j - x) > 36.0)
                continue;
            w = a[i*xres + j];
            sw += w;
            sx += w*j;
            sy += w*i;
        }
    }
    *cx = sx/sw;
    *cy = sy/sw;
}

/* Largest distance between particle centroids in got and in truth, over the
 * particles whose neighbourhood has a source in got. */
static gdouble
max_particle_error(const gdouble *got, const gdouble *mask,
                   const gdouble *truth, const Particles *particles,
                   const gdouble *offset, gint xres, gint yres)
{
    gdouble x, y, gx, gy, tx, ty, err = 0.0;
    gint k, counted = 0;

    for (k = 0; k < particles->n; k++) {
        x = particles->x[k] + offset[0];
        y = particles->y[k] + offset[1];
        if (x < 12.0 || y < 12.0 || x > xres - 13.0 || y > yres - 13.0
            || mask[(gint)(y + 0.5)*xres + (gint)(x + 0.5)] != 0.0)
            continue;
        local_centroid(got, xres, yres, x, y, &gx, &gy);
        local_centroid(truth, xres, yres, x, y, &tx, &ty);
        err = MAX(err, hypot(gx - tx, gy - ty));
        counted++;
    }
    ck_assert_int_gt(counted, particles->n/2);
    return err;
}

typedef struct {
    gdouble rms_continuous;
    gdouble rms_paper;
    gdouble particle_continuous;
    gdouble particle_paper;
} Accuracy;

/* Scans the particles under motion, measures the stripes the paper's way,
 * compensates in both modes and compares with the sample at t_ref. */
static void
measure_accuracy(const Motion *motion, ScanDirection direction, gint n,
                 const gboolean *blank, guint32 seed, guint32 salt,
                 Accuracy *acc)
{
    GRand *rng = test_rand_salted(seed, salt);
    gint xres = 192, yres = 160, margin, size = xres*yres, k;
    ScanTiming timing;
    Particles particles;
    DriftTable *table;
    DriftTrajectory *trajectory;
    GError *error = NULL;
    gdouble *a, *truth, *cont, *cont_mask, *paper, *paper_mask;
    gdouble pref[2], t_ref, maxdrift = 0.0, p[2];

    scan_timing_init(&timing, xres, yres, 0.0, 1.0, direction);
    particles_init(&particles, xres, yres, rng);
    a = render_scan(&particles, motion, &timing);
    table = measure_table(motion, &timing, n, 1.0, 0.1, blank);
    trajectory = drift_trajectory_new_from_table(table, 1.0, 1.0, &timing,
                                                 NULL);
    t_ref = drift_trajectory_reference_time(trajectory);
    drift_trajectory_free(trajectory);
    motion_eval(motion, t_ref, pref);
    truth = render_at(&particles, motion, t_ref, xres, yres);

    cont = g_new(gdouble, 4*size);
    cont_mask = cont + size;
    paper = cont_mask + size;
    paper_mask = paper + size;
    ck_assert_msg(continuous_compensate_table(a, xres, yres, table, 1.0, 1.0,
                                              &timing, GWY_INTERPOLATION_BSPLINE,
                                              -1.0, cont, cont_mask, &error),
                  "%s", error ? error->message : "");
    run_paper_mode(a, xres, yres, table, paper, paper_mask);

    for (k = 0; k <= 100; k++) {
        motion_eval(motion, scan_timing_frame_end(&timing)*k/100.0, p);
        maxdrift = MAX(maxdrift, MAX(fabs(p[0] - pref[0]), fabs(p[1] - pref[1])));
    }
    margin = (gint)ceil(maxdrift) + 4;
    acc->rms_continuous = interior_rms(cont, truth, cont_mask, paper_mask,
                                       xres, yres, margin);
    acc->rms_paper = interior_rms(paper, truth, cont_mask, paper_mask,
                                  xres, yres, margin);
    acc->particle_continuous = max_particle_error(cont, cont_mask, truth,
                                                  &particles, pref, xres, yres);
    acc->particle_paper = max_particle_error(paper, paper_mask, truth,
                                             &particles, pref, xres, yres);
    printf("%s scan, %d stripes: interior RMS continuous %.5f, paper %.5f "
           "(ratio %.4f); particle centres continuous %.4f px, paper %.3f px\n",
           direction == SCAN_DIRECTION_UP ? "up" : "down", n,
           acc->rms_continuous, acc->rms_paper,
           acc->rms_continuous/acc->rms_paper,
           acc->particle_continuous, acc->particle_paper);
    fflush(stdout);

    g_free(cont);
    g_free(truth);
    g_free(a);
    g_free(particles.x);
    drift_table_free(table);
    g_rand_free(rng);
}

static void
random_motion(Motion *motion, gboolean settling, GRand *rng)
{
    gdouble frame = 160.0, total;
    gint k;

    memset(motion, 0, sizeof(Motion));
    for (k = 0; k < 2; k++) {
        motion->p0[k] = g_rand_double_range(rng, -3.0, 3.0);
        /* 4-10 px over the frame, either sign. */
        total = g_rand_double_range(rng, 4.0, 10.0);
        motion->v[k] = (g_rand_boolean(rng) ? total : -total)/frame;
    }
    if (settling) {
        motion->tau = frame*g_rand_double_range(rng, 0.2, 0.4);
        for (k = 0; k < 2; k++) {
            total = g_rand_double_range(rng, 4.0, 8.0);
            motion->u[k] = (g_rand_boolean(rng) ? total : -total)/motion->tau;
            motion->v[k] *= 0.3;
        }
    }
}

/* Constant velocity and settling drift, scanning down and up (loop index
 * bit 0: direction, bit 1: settling).  Continuous mode brings the interior
 * RMS error to under 5 % of paper mode's and every particle centre within
 * 0.05 px of the truth (paper mode: whole pixels and sheared stripes). */
START_TEST(test_accuracy_against_paper_mode)
{
    GRand *rng = test_rand_salted(test_seed, 10 + _i);
    Motion motion;
    Accuracy acc;

    random_motion(&motion, _i & 2, rng);
    measure_accuracy(&motion, (_i & 1) ? SCAN_DIRECTION_UP : SCAN_DIRECTION_DOWN,
                     10, NULL, test_seed, 20 + _i, &acc);
    ck_assert_msg(acc.rms_continuous < 0.05*acc.rms_paper,
                  "RMS continuous %g, paper %g",
                  acc.rms_continuous, acc.rms_paper);
    ck_assert_msg(acc.particle_continuous < 0.05,
                  "particle centre error %g px", acc.particle_continuous);
    ck_assert_msg(acc.particle_paper > 0.15,
                  "paper mode unexpectedly good: %g px", acc.particle_paper);
    g_rand_free(rng);
}
END_TEST

/* Three random stripes without a particle, on settling drift: they are
 * interpolated over.  Loop 0: isolated inner stripes (neighbours measured):
 * an order of magnitude better than paper mode, particles within the
 * issue's 0.15 px.  The bound is relative to paper mode, whose error
 * depends on how the stripes' rounding happens to fall (it varies by a
 * factor of three between draws) while the error of bridging a blank
 * stripe does not: over 300 seeds the ratio had p99 0.044 and max 0.055,
 * the particle error max 0.107 px, so 0.05 and 0.1 failed about one seed
 * in a hundred without anything being wrong.  Loop 1: anywhere, also the
 * first or the second stripe, which leaves the top of the frame, where
 * settling bends most, to extrapolation: still far better than paper mode.
 * Not both: a settling drift bends mostly within its first 20-40 % of the
 * frame (tau), and with no measurement before 25 % of it no method knows
 * how (soaks of 500 and 400 seeds drew stripes 0, 1 and 2 three times and
 * 0, 1 and 6 once: particles 0.41-0.58 px off, paper mode 1.8-2.6 px);
 * that is an extrapolation of unobserved drift, not the bridging of blank
 * stripes this test is about. */
static void
check_blank_stripes(guint32 seed, gint loop)
{
    GRand *rng = test_rand_salted(seed, 30 + loop);
    gboolean blank[10];
    Motion motion;
    Accuracy acc;
    gint k, s;

    memset(blank, 0, sizeof(blank));
    for (k = 0; k < 3; k++) {
        do {
            s = g_rand_int_range(rng, 0, 10);
        } while (blank[s]
                 || (loop == 0 && (s == 0 || s == 9 || blank[s-1] || blank[s+1]))
                 || (s <= 1 && blank[1 - s]));
        blank[s] = TRUE;
    }
    printf("seed %u, blank stripes:", seed);
    for (s = 0; s < 10; s++) {
        if (blank[s])
            printf(" %d", s);
    }
    printf("\n");
    random_motion(&motion, TRUE, rng);
    measure_accuracy(&motion, SCAN_DIRECTION_DOWN, 10, blank, seed, 32 + loop,
                     &acc);
    ck_assert_msg(acc.rms_continuous < (loop ? 0.25 : 0.1)*acc.rms_paper,
                  "seed %u: RMS continuous %g, paper %g",
                  seed, acc.rms_continuous, acc.rms_paper);
    ck_assert_msg(acc.particle_continuous < (loop ? 0.4 : 0.15),
                  "seed %u: particle centre error %g px",
                  seed, acc.particle_continuous);
    g_rand_free(rng);
}

START_TEST(test_accuracy_blank_stripes)
{
    check_blank_stripes(test_seed, _i);
}
END_TEST

/* Draws of loop 0 with seven exact knots of a steep settling start that
 * were smoothed as if noisy (drift-trajectory.c), replayed whatever the
 * seed:
 * - 71000482 (blank stripes 2, 4 and 7): the per-axis bar of twenty
 *   missed it (the differences 14.6 times below on either axis); 0.08-0.09
 *   px off at the first knots, interior RMS 0.112 of paper mode's
 *   (FEW_KNOTS_NOISE_OVER_DIFFERENCES_MAX);
 * - 76000205 (blank stripes 3, 5 and 8): the differences 9.2 (x) and 4.8
 *   (y) times below the cross-validated noise, which preferred
 *   interpolation on both axes; interior RMS 0.106 of paper mode's
 *   (FEW_KNOTS_CV_NOISE_OVER_DIFFERENCES_MAX).  Interpolating x alone
 *   passes, so this guards a bar below 9.2, not the value four. */
static const guint32 seven_exact_knots_seeds[] = { 71000482, 76000205 };

START_TEST(test_blank_stripes_seven_exact_knots)
{
    check_blank_stripes(seven_exact_knots_seeds[_i], 0);
}
END_TEST

START_TEST(test_zero_drift_exact)
{
    GRand *rng = test_rand_salted(test_seed, 40);
    gint xres = 37, yres = 23, size = xres*yres, k;
    gdouble *a = random_image(xres, yres, 0.0, 10.0, rng);
    gdouble *result = g_new(gdouble, 2*size), *mask = result + size;
    DriftTable *table = constant_table(5, 0.0, 0.0, rng);
    ScanTiming timing;
    guint i;

    scan_timing_init(&timing, xres, yres, 0.0, 0.7, SCAN_DIRECTION_UP);
    for (i = 0; i < G_N_ELEMENTS(all_kernels); i++) {
        ck_assert(continuous_compensate_table(a, xres, yres, table, 1.0, 1.0,
                                              &timing, all_kernels[i], -1.0,
                                              result, mask, NULL));
        ck_assert(memcmp(result, a, size*sizeof(gdouble)) == 0);
        for (k = 0; k < size; k++)
            ck_assert(mask[k] == 0.0);
    }
    drift_table_free(table);
    g_free(result);
    g_free(a);
    g_rand_free(rng);
}
END_TEST

/* The same whole-pixel drift in every stripe (local scans at different
 * times): exactly paper mode's result, pixels and mask. */
START_TEST(test_whole_pixel_equals_paper_mode)
{
    GRand *rng = test_rand_salted(test_seed, 50 + _i);
    gint xres = 41, yres = 29, size = xres*yres, n = 7, s;
    gint dx = g_rand_int_range(rng, -6, 7), dy = g_rand_int_range(rng, -6, 7);
    gint idx[7], idy[7];
    gdouble *a = random_image(xres, yres, 0.0, 10.0, rng);
    gdouble *result = g_new(gdouble, 4*size), *mask = result + size;
    gdouble *paper = mask + size, *paper_mask = paper + size;
    gdouble fill = paper_image_mean(a, xres, yres);
    DriftTable *table = constant_table(n, dx, dy, rng);
    ScanTiming timing;
    guint i;

    for (s = 0; s < n; s++) {
        idx[s] = dx;
        idy[s] = dy;
    }
    paper_compensate(a, xres, yres, n, idx, idy, fill, paper, paper_mask);
    scan_timing_init(&timing, xres, yres, 0.0, 1.3,
                     _i ? SCAN_DIRECTION_UP : SCAN_DIRECTION_DOWN);
    for (i = 0; i < G_N_ELEMENTS(all_kernels); i++) {
        ck_assert(continuous_compensate_table(a, xres, yres, table, 1.0, 1.0,
                                              &timing, all_kernels[i], fill,
                                              result, mask, NULL));
        ck_assert_msg(memcmp(result, paper, size*sizeof(gdouble)) == 0,
                      "kernel %d, drift %d, %d", all_kernels[i], dx, dy);
        ck_assert(memcmp(mask, paper_mask, size*sizeof(gdouble)) == 0);
    }
    drift_table_free(table);
    g_free(result);
    g_free(a);
    g_rand_free(rng);
}
END_TEST

/* Gwyddion's own interpolation of row (or column) data at position x. */
static gdouble
gwyddion_interpolate(const gdouble *data, gint n, gdouble x,
                     GwyInterpolationType type)
{
    gdouble *coeffs = g_memdup2(data, n*sizeof(gdouble)), value;
    gint support = gwy_interpolation_get_support_size(type);
    gint i = (gint)floor(x), first = (support == 4) ? i - 1 : i;

    gwy_interpolation_resolve_coeffs_1d(n, coeffs, type);
    g_assert(first >= 0 && first + support <= n);
    value = gwy_interpolation_interpolate_1d(x - i, coeffs + first, type);
    g_free(coeffs);
    return value;
}

/* A constant fractional shift along one axis is Gwyddion's interpolation
 * of each row (column), including the B-spline/o-MOMS prefilter. */
START_TEST(test_fractional_shift_matches_gwyddion)
{
    GRand *rng = test_rand_salted(test_seed, 60);
    gint xres = 37, yres = 31, size = xres*yres, r, c, axis;
    gdouble *a = random_image(xres, yres, 0.0, 10.0, rng);
    gdouble *result = g_new(gdouble, 2*size), *mask = result + size;
    gdouble *line = g_new(gdouble, MAX(xres, yres)), shift, expected;
    DriftTable *table;
    guint i;

    for (axis = 0; axis < 2; axis++) {
        shift = g_rand_double_range(rng, -2.9, 2.9);
        table = constant_table(6, axis ? 0.0 : shift, axis ? shift : 0.0, NULL);
        for (i = 0; i < G_N_ELEMENTS(all_kernels); i++) {
            ck_assert(continuous_compensate_table(a, xres, yres, table,
                                                  1.0, 1.0, NULL,
                                                  all_kernels[i], -1.0,
                                                  result, mask, NULL));
            for (r = 4; r < yres - 4; r++) {
                for (c = 4; c < xres - 4; c++) {
                    if (axis == 0) {
                        expected = gwyddion_interpolate(a + r*xres, xres,
                                                        c + shift,
                                                        all_kernels[i]);
                    }
                    else {
                        for (gint k = 0; k < yres; k++)
                            line[k] = a[k*xres + c];
                        expected = gwyddion_interpolate(line, yres, r + shift,
                                                        all_kernels[i]);
                    }
                    ck_assert_msg(fabs(result[r*xres + c] - expected) < 1e-12,
                                  "kernel %d axis %d (%d,%d): %.15g vs %.15g",
                                  all_kernels[i], axis, r, c,
                                  result[r*xres + c], expected);
                }
            }
        }
        drift_table_free(table);
    }
    g_free(line);
    g_free(result);
    g_free(a);
    g_rand_free(rng);
}
END_TEST

/* Strong shear (x drift of 2-4 px along one trace, no y drift): every row
 * is Gwyddion's interpolation at the positions solving
 * x = c + Dx(t(row, x)), for every kernel. */
START_TEST(test_sheared_rows_match_gwyddion)
{
    GRand *rng = test_rand_salted(test_seed, 65);
    gint xres = 64, yres = 5, size = xres*yres, r, c, k, checked = 0;
    gdouble *a = random_image(xres, yres, 0.0, 10.0, rng);
    gdouble *result = g_new(gdouble, 2*size), *mask = result + size;
    gdouble vx = g_rand_double_range(rng, 4.0, 8.0), x, dx, dy, expected;
    DriftMeasurement meas[3];
    DriftTrajectory *trajectory;
    ScanTiming timing;
    guint i;

    if (g_rand_boolean(rng))
        vx = -vx;
    scan_timing_init(&timing, xres, yres, 0.0, 1.0, SCAN_DIRECTION_DOWN);
    for (k = 0; k < 3; k++) {
        meas[k].t_a = 2.0*k + 0.5;
        meas[k].t_b = 25.0;
        meas[k].dx = vx*(meas[k].t_a - 2.5);
        meas[k].dy = 0.0;
    }
    trajectory = drift_trajectory_new(meas, 3, NULL);
    for (i = 0; i < G_N_ELEMENTS(all_kernels); i++) {
        ck_assert(continuous_compensate_trajectory(a, xres, yres, trajectory,
                                                   &timing, all_kernels[i],
                                                   -1.0, result, mask, NULL));
        for (r = 0; r < yres; r++) {
            for (c = 0; c < xres; c++) {
                x = c;
                for (k = 0; k < 60; k++) {
                    drift_trajectory_eval(trajectory,
                                          scan_timing_pixel_time(&timing, r, x),
                                          &dx, &dy);
                    x = c + dx;
                }
                if (x < 1.0 || x > xres - 3.0)
                    continue;
                expected = gwyddion_interpolate(a + r*xres, xres, x,
                                                all_kernels[i]);
                ck_assert_msg(fabs(result[r*xres + c] - expected) < 1e-9,
                              "kernel %d (%d,%d) at x %g: %.15g vs %.15g",
                              all_kernels[i], r, c, x, result[r*xres + c],
                              expected);
                checked++;
            }
        }
    }
    ck_assert_int_gt(checked, G_N_ELEMENTS(all_kernels)*size/2);
    drift_trajectory_free(trajectory);
    g_free(result);
    g_free(a);
    g_rand_free(rng);
}
END_TEST

/* Constant fractional drift: the filled pixels are exactly those whose
 * source lies more than half a pixel beyond the outer pixel centres. */
START_TEST(test_mask_constant_drift)
{
    gint xres = 30, yres = 20, size = xres*yres, r, c;
    gdouble *a = g_new(gdouble, size), *result = g_new(gdouble, 2*size);
    gdouble *mask = result + size;
    DriftTable *table = constant_table(4, 2.3, -1.6, NULL);
    gboolean filled;

    for (r = 0; r < size; r++)
        a[r] = 1.0 + r % 7;
    ck_assert(continuous_compensate_table(a, xres, yres, table, 1.0, 1.0,
                                          NULL, GWY_INTERPOLATION_KEY, -5.0,
                                          result, mask, NULL));
    /* Row r comes from r - 1.6 (rows 0, 1 have none), column c from c + 2.3
     * (columns 28, 29 have none). */
    for (r = 0; r < yres; r++) {
        for (c = 0; c < xres; c++) {
            filled = (r < 2 || c >= xres - 2);
            ck_assert_msg(mask[r*xres + c] == (filled ? 1.0 : 0.0),
                          "mask at (%d, %d)", r, c);
            ck_assert(filled == (result[r*xres + c] == -5.0));
        }
    }
    drift_table_free(table);
    g_free(result);
    g_free(a);
}
END_TEST

/* A fast drift (settling, 5-10 px over 48 lines) shears the border of the
 * valid area: the mask follows the source position solved independently
 * from the trajectory, except within 1e-3 px of the border. */
START_TEST(test_mask_sheared)
{
    GRand *rng = test_rand_salted(test_seed, 70);
    gint xres = 64, yres = 48, size = xres*yres, r, c, k, it, checked = 0;
    gdouble *a = random_image(xres, yres, 0.0, 10.0, rng);
    gdouble *result = g_new(gdouble, 2*size), *mask = result + size;
    DriftMeasurement meas[13];
    DriftTrajectory *trajectory;
    ScanTiming timing;
    Motion motion;
    gdouble x, y, t, dx, dy, p[2], pref[2];
    gboolean outside;

    memset(&motion, 0, sizeof(motion));
    motion.tau = 15.0;
    for (k = 0; k < 2; k++) {
        motion.u[k] = g_rand_double_range(rng, 5.0, 10.0)/motion.tau;
        if (g_rand_boolean(rng))
            motion.u[k] = -motion.u[k];
        motion.v[k] = g_rand_double_range(rng, -0.05, 0.05);
    }
    scan_timing_init(&timing, xres, yres, 0.0, 1.0,
                     _i ? SCAN_DIRECTION_UP : SCAN_DIRECTION_DOWN);
    /* The trajectory sampled every 4 lines (as a fitted model would be). */
    motion_eval(&motion, 50.0, pref);
    for (k = 0; k < 13; k++) {
        meas[k].t_a = 4.0*k;
        meas[k].t_b = 50.0;
        motion_eval(&motion, meas[k].t_a, p);
        meas[k].dx = p[0] - pref[0];
        meas[k].dy = p[1] - pref[1];
    }
    trajectory = drift_trajectory_new(meas, 13, NULL);
    ck_assert(continuous_compensate_trajectory(a, xres, yres, trajectory,
                                               &timing, GWY_INTERPOLATION_LINEAR,
                                               0.0, result, mask, NULL));
    for (r = 0; r < yres; r++) {
        for (c = 0; c < xres; c++) {
            y = r;
            for (it = 0; it < 40; it++) {
                t = scan_timing_pixel_time(&timing, y, 0.5*(xres - 1));
                drift_trajectory_eval(trajectory, t, &dx, &dy);
                y = r + dy;
            }
            /* Columns come from the nearest source row. */
            k = CLAMP((gint)floor(y + 0.5), 0, yres - 1);
            x = c;
            for (it = 0; it < 40; it++) {
                t = scan_timing_pixel_time(&timing, k, x);
                drift_trajectory_eval(trajectory, t, &dx, &dy);
                x = c + dx;
            }
            if (fabs(y + 0.5) < 1e-3 || fabs(y - yres + 0.5) < 1e-3
                || fabs(x + 0.5) < 1e-3 || fabs(x - xres + 0.5) < 1e-3)
                continue;
            outside = (y < -0.5 || y > yres - 0.5 || x < -0.5 || x > xres - 0.5);
            ck_assert_msg(mask[r*xres + c] == (outside ? 1.0 : 0.0),
                          "mask %g at (%d, %d), source (%g, %g)",
                          mask[r*xres + c], r, c, y, x);
            checked++;
        }
    }
    ck_assert_int_gt(checked, size - 2*(xres + yres));
    drift_trajectory_free(trajectory);
    g_free(result);
    g_free(a);
    g_rand_free(rng);
}
END_TEST

/* One stripe: the whole image moves by its (fractional) drift. */
START_TEST(test_one_stripe)
{
    GRand *rng = test_rand_salted(test_seed, 80);
    gint xres = 96, yres = 72, size = xres*yres;
    Particles particles;
    Motion still;
    DriftTable *table;
    gdouble shift[2], *a, *truth, *result, *mask, rms;

    particles_init(&particles, xres, yres, rng);
    memset(&still, 0, sizeof(still));
    shift[0] = still.p0[0] = g_rand_double_range(rng, -3.0, 3.0);
    shift[1] = still.p0[1] = g_rand_double_range(rng, -3.0, 3.0);
    a = render_at(&particles, &still, 0.0, xres, yres);
    memset(&still, 0, sizeof(still));
    truth = render_at(&particles, &still, 0.0, xres, yres);
    table = drift_table_new(1, DRIFT_UNIT_PX);
    table->rows[0].has_drift = TRUE;
    table->rows[0].dx = floor(shift[0] + 0.5);
    table->rows[0].dy = floor(shift[1] + 0.5);
    drift_table_set_extra(table, 0, "dx_exact", shift[0]);
    drift_table_set_extra(table, 0, "dy_exact", shift[1]);
    result = g_new(gdouble, 2*size);
    mask = result + size;
    ck_assert(continuous_compensate_table(a, xres, yres, table, 1.0, 1.0,
                                          NULL, GWY_INTERPOLATION_BSPLINE,
                                          0.0, result, mask, NULL));
    rms = interior_rms(result, truth, mask, mask, xres, yres, 8);
    ck_assert_msg(rms < 2e-3, "one stripe RMS %g", rms);
    drift_table_free(table);
    g_free(result);
    g_free(truth);
    g_free(a);
    g_free(particles.x);
    g_rand_free(rng);
}
END_TEST

/* Physical units: a nm table on 2 nm x 4 nm pixels is the px table. */
START_TEST(test_physical_units)
{
    GRand *rng = test_rand_salted(test_seed, 90);
    gint xres = 33, yres = 27, size = xres*yres, s;
    gdouble *a = random_image(xres, yres, 0.0, 10.0, rng);
    gdouble *r1 = g_new(gdouble, 2*size), *r2 = r1 + size;
    DriftTable *px = drift_table_new(3, DRIFT_UNIT_PX);
    DriftTable *nm = drift_table_new(3, DRIFT_UNIT_NM);

    for (s = 0; s < 3; s++) {
        px->rows[s].has_drift = nm->rows[s].has_drift = TRUE;
        px->rows[s].dx = 0.5*s - 1.0;
        px->rows[s].dy = 0.25*s;
        nm->rows[s].dx = 2.0*px->rows[s].dx;
        nm->rows[s].dy = 4.0*px->rows[s].dy;
    }
    ck_assert(continuous_compensate_table(a, xres, yres, px, 1.0, 1.0, NULL,
                                          GWY_INTERPOLATION_KEY, 0.0, r1,
                                          NULL, NULL));
    ck_assert(continuous_compensate_table(a, xres, yres, nm, 2e-9, 4e-9, NULL,
                                          GWY_INTERPOLATION_KEY, 0.0, r2,
                                          NULL, NULL));
    for (s = 0; s < size; s++)
        ck_assert_double_eq_tol(r1[s], r2[s], 1e-12);
    drift_table_free(px);
    drift_table_free(nm);
    g_free(r1);
    g_free(a);
    g_rand_free(rng);
}
END_TEST

START_TEST(test_errors_leave_output_untouched)
{
    gint xres = 16, yres = 12, size = xres*yres, k;
    gdouble *a = g_new0(gdouble, size), *result = g_new(gdouble, size);
    DriftTable *table = constant_table(3, 1.0, 1.0, NULL);
    DriftTable *fast = drift_table_new(2, DRIFT_UNIT_PX);
    ScanTiming timing;
    GError *error = NULL;

    for (k = 0; k < size; k++)
        result[k] = 42.0;
    scan_timing_init(&timing, xres, yres + 1, 0.0, 1.0, SCAN_DIRECTION_DOWN);
    ck_assert(!continuous_compensate_table(a, xres, yres, table, 1.0, 1.0,
                                           &timing, GWY_INTERPOLATION_KEY,
                                           0.0, result, NULL, &error));
    ck_assert(g_error_matches(error, CONTINUOUS_COMPENSATE_ERROR,
                              CONTINUOUS_COMPENSATE_ERROR_TIMING));
    ck_assert_str_eq(error->message,
                     "scan timing (16 x 13 pixels, line time 1 s) does not "
                     "describe the 16 x 12 image");
    g_clear_error(&error);

    ck_assert(!continuous_compensate_table(a, xres, yres, table, 1.0, 1.0,
                                           NULL, GWY_INTERPOLATION_NONE,
                                           0.0, result, NULL, &error));
    ck_assert(g_error_matches(error, CONTINUOUS_COMPENSATE_ERROR,
                              CONTINUOUS_COMPENSATE_ERROR_INTERPOLATION));
    ck_assert_str_eq(error->message,
                     "interpolation type 0 cannot resample an image");
    g_clear_error(&error);

    /* 30 px of y drift between two stripes 6 lines apart folds the image. */
    fast->rows[0].has_drift = fast->rows[1].has_drift = TRUE;
    fast->rows[1].dy = 30.0;
    ck_assert(!continuous_compensate_table(a, xres, yres, fast, 1.0, 1.0,
                                           NULL, GWY_INTERPOLATION_KEY,
                                           0.0, result, NULL, &error));
    ck_assert(g_error_matches(error, CONTINUOUS_COMPENSATE_ERROR,
                              CONTINUOUS_COMPENSATE_ERROR_TOO_FAST));
    g_clear_error(&error);

    fast->rows[0].has_drift = fast->rows[1].has_drift = FALSE;
    ck_assert(!continuous_compensate_table(a, xres, yres, fast, 1.0, 1.0,
                                           NULL, GWY_INTERPOLATION_KEY,
                                           0.0, result, NULL, &error));
    ck_assert(error);
    g_clear_error(&error);

    for (k = 0; k < size; k++)
        ck_assert(result[k] == 42.0);
    drift_table_free(fast);
    drift_table_free(table);
    g_free(result);
    g_free(a);
}
END_TEST

static Suite*
continuous_compensate_suite(void)
{
    TCase *tc;
    Suite *suite = test_suite_new("continuous-compensate", "core", &tc);

    tcase_set_timeout(tc, 120);
    tcase_add_loop_test(tc, test_accuracy_against_paper_mode, 0, 4);
    tcase_add_loop_test(tc, test_accuracy_blank_stripes, 0, 2);
    tcase_add_loop_test(tc, test_blank_stripes_seven_exact_knots, 0,
                        G_N_ELEMENTS(seven_exact_knots_seeds));
    tcase_add_test(tc, test_zero_drift_exact);
    tcase_add_loop_test(tc, test_whole_pixel_equals_paper_mode, 0, 2);
    tcase_add_test(tc, test_fractional_shift_matches_gwyddion);
    tcase_add_test(tc, test_sheared_rows_match_gwyddion);
    tcase_add_test(tc, test_mask_constant_drift);
    tcase_add_loop_test(tc, test_mask_sheared, 0, 2);
    tcase_add_test(tc, test_one_stripe);
    tcase_add_test(tc, test_physical_units);
    tcase_add_test(tc, test_errors_leave_output_untouched);
    return suite;
}

int
main(void)
{
    test_seed = test_seed_from_env("test-continuous-compensate");
    return test_run_suite(continuous_compensate_suite());
}
