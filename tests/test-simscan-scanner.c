/*
 *  Tests of the simulated sample and scanner: drift shows where p(t) says,
 *  whole-pixel shifts are exact, seeds reproduce, measured samples survive.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <stdlib.h>
#include <string.h>
#include <math.h>
#include <check.h>
#include <glib.h>
#include <libprocess/stats.h>
#include <libprocess/arithmetic.h>
#include "stripe-geometry.h"
#include "sample.h"
#include "scanner.h"
#include "test-common.h"

static guint32 test_seed;
static gint warnings_seen;

static void
count_warning(G_GNUC_UNUSED const gchar *domain,
              G_GNUC_UNUSED GLogLevelFlags level,
              G_GNUC_UNUSED const gchar *message,
              G_GNUC_UNUSED gpointer user_data)
{
    warnings_seen++;
}

/* 1 um field with a few particles, 5 nm pixels at 200 x 200. */
static SimSample*
small_particle_sample(guint32 seed, gint count, gdouble roughness)
{
    SimParticleParams pp;
    SimSample *sample;

    sim_particle_params_init(&pp);
    pp.xreal = pp.yreal = 1e-6;
    pp.count = count;
    pp.roughness_rms = roughness;
    sample = sim_sample_new_particles(&pp, seed);
    ck_assert(sample);
    return sample;
}

static gdouble
field_range(GwyDataField *field)
{
    gdouble min, max;

    gwy_data_field_get_min_max(field, &min, &max);
    return max - min;
}

static void
assert_same_bytes(GwyDataField *a, GwyDataField *b)
{
    gint n = gwy_data_field_get_xres(a)*gwy_data_field_get_yres(a);

    ck_assert_int_eq(gwy_data_field_get_xres(a), gwy_data_field_get_xres(b));
    ck_assert_int_eq(gwy_data_field_get_yres(a), gwy_data_field_get_yres(b));
    ck_assert(memcmp(gwy_data_field_get_data_const(a),
                     gwy_data_field_get_data_const(b),
                     n*sizeof(gdouble)) == 0);
}

/* frame[r][c] against truth[r - dy][c - dx] wherever both exist, at least
 * `margin` pixels from the frame's edges; returns the largest difference. */
static gdouble
max_shifted_difference(GwyDataField *frame, GwyDataField *truth,
                       gint dx, gint dy, gint margin)
{
    gint xres = gwy_data_field_get_xres(frame), yres = gwy_data_field_get_yres(frame);
    const gdouble *f = gwy_data_field_get_data_const(frame);
    const gdouble *t = gwy_data_field_get_data_const(truth);
    gdouble worst = 0.0;
    gint r, c, n = 0;

    for (r = margin; r < yres - margin; r++) {
        for (c = margin; c < xres - margin; c++) {
            if (r - dy < 0 || r - dy >= yres || c - dx < 0 || c - dx >= xres)
                continue;
            worst = MAX(worst, fabs(f[r*xres + c] - t[(r - dy)*xres + c - dx]));
            n++;
        }
    }
    ck_assert_int_gt(n, xres*yres/4);
    return worst;
}

START_TEST(test_zero_drift_is_truth)
{
    SimSample *sample = small_particle_sample(test_seed, 12, 0.5e-9);
    SimScanParams sp;
    DriftModel still;
    GwyDataField *frame, *framed, *truth;

    sim_scan_params_init(&sp, sample, 200, 160);
    sp.tip_radius = 8e-9;
    sp.direction = SCAN_DIRECTION_UP;
    truth = sim_scan_truth(sample, &sp);
    frame = sim_scan_frame(sample, NULL, &sp);
    drift_model_init(&still, DRIFT_MODEL_OSCILLATION);
    framed = sim_scan_frame(sample, &still, &sp);
    assert_same_bytes(frame, truth);
    assert_same_bytes(framed, truth);
    /* The particles are there: 2R = 50 nm above the substrate. */
    ck_assert_msg(field_range(truth) > 45e-9 && field_range(truth) < 56e-9,
                  "height range %g", field_range(truth));
    ck_assert_double_eq(gwy_data_field_get_xreal(frame), 1e-6);
    ck_assert_double_eq(gwy_data_field_get_yreal(frame), 1e-6);
    g_object_unref(frame);
    g_object_unref(framed);
    g_object_unref(truth);
    drift_model_clear(&still);
    sim_sample_free(sample);
}
END_TEST

/* A constant drift of a whole number of pixels moves every feature by that
 * many pixels: feature truly at (r, c) appears at (r + dy, c + dx). */
START_TEST(test_whole_pixel_drift_shifts)
{
    GRand *rng = g_rand_new_with_seed(test_seed + 10);
    SimSample *sample = small_particle_sample(test_seed, 15, 0.5e-9);
    SimScanParams sp;
    DriftModel drift;
    GwyDataField *frame, *truth;
    gint dx = g_rand_int_range(rng, -6, 7), dy = g_rand_int_range(rng, -6, 7);
    gdouble diff, range;

    if (dx == 0 && dy == 0)
        dx = 3;
    sim_scan_params_init(&sp, sample, 200, 200);
    sp.xoff = 0.1e-6;
    sp.yoff = 0.05e-6;
    sp.xreal = sp.yreal = 0.8e-6;
    sp.tip_radius = 5e-9;
    drift_model_init(&drift, DRIFT_MODEL_NONE);
    drift.p0[0] = dx*sp.xreal/sp.xres;
    drift.p0[1] = dy*sp.yreal/sp.yres;
    frame = sim_scan_frame(sample, &drift, &sp);
    truth = sim_scan_truth(sample, &sp);
    range = field_range(truth);
    diff = max_shifted_difference(frame, truth, dx, dy, 0);
    ck_assert_msg(diff <= 1e-9*range,
                  "shift (%d, %d) px: frame differs from shifted truth by %g "
                  "(range %g)", dx, dy, diff, range);
    /* And it is really shifted: unshifted comparison fails. */
    ck_assert(max_shifted_difference(frame, truth, 0, 0, 0) > 0.1*range);
    g_object_unref(frame);
    g_object_unref(truth);
    drift_model_clear(&drift);
    sim_sample_free(sample);
    g_rand_free(rng);
}
END_TEST

/* Centroid, in pixels, of the window around (col, row), weighted by the
 * height above floor (a floor at the particle's equator makes the weight
 * continuous at its rim, so sampling hardly biases the centroid). */
static void
weighted_centroid(GwyDataField *field, gdouble col, gdouble row, gint half,
                  gdouble floor_z, gdouble *cc, gdouble *cr)
{
    gint xres = gwy_data_field_get_xres(field), yres = gwy_data_field_get_yres(field);
    const gdouble *d = gwy_data_field_get_data_const(field);
    gdouble sw = 0.0, sc = 0.0, sr = 0.0, wt;
    gint r, c;

    for (r = MAX((gint)row - half, 0); r <= MIN((gint)row + half, yres - 1); r++) {
        for (c = MAX((gint)col - half, 0); c <= MIN((gint)col + half, xres - 1); c++) {
            wt = MAX(d[r*xres + c] - floor_z, 0.0);
            sw += wt;
            sc += c*wt;
            sr += r*wt;
        }
    }
    ck_assert(sw > 0.0);
    *cc = sc/sw;
    *cr = sr/sw;
}

/* Where a feature truly at (x, y) appears: solve Y = X + p(t(Y)) with t the
 * scan time of the pixel at Y (a contraction: drift per line << pixel). */
static void
predicted_apparent_pixel(const SimScanParams *sp, const DriftModel *drift,
                         gdouble x, gdouble y, gdouble *col, gdouble *row)
{
    ScanTiming timing;
    gdouble w = sp->xreal/sp->xres, h = sp->yreal/sp->yres, px, py;
    gint k;

    sim_scan_params_timing(sp, &timing);
    *col = (x - sp->xoff)/w - 0.5;
    *row = (y - sp->yoff)/h - 0.5;
    for (k = 0; k < 50; k++) {
        drift_model_eval(drift, scan_timing_pixel_time(&timing, *row, *col),
                         &px, &py);
        *col = (x + px - sp->xoff)/w - 0.5;
        *row = (y + py - sp->yoff)/h - 0.5;
    }
}

/* Constant velocity maps the sample affinely into the image (heights kept),
 * so a single particle's height-weighted centroid lands at X + p(t_centre)
 * exactly, up to sampling. */
static void
check_velocity_centroid(ScanDirection direction, guint32 seed)
{
    GRand *rng = g_rand_new_with_seed(seed);
    SimSample *sample = NULL;
    SimScanParams sp;
    DriftModel drift;
    GwyDataField *frame;
    gdouble x, y, pc = -1.0, pr = -1.0, cc, cr, still_c, still_r;
    gdouble frame_start;
    gint attempt;

    drift_model_init(&drift, DRIFT_MODEL_NONE);
    /* Up to 0.4 nm/s: some 90 nm (18 px) over the 234 s frame; p0 of the
     * same sign, at least 6 nm, so the particle surely moves. */
    drift.v[0] = g_rand_double_range(rng, -0.4e-9, 0.4e-9);
    drift.v[1] = g_rand_double_range(rng, -0.4e-9, 0.4e-9);
    drift.p0[0] = copysign(g_rand_double_range(rng, 6e-9, 20e-9), drift.v[0]);
    drift.p0[1] = copysign(g_rand_double_range(rng, 6e-9, 20e-9), drift.v[1]);
    /* The frame starts up to 100 s late: p reaches 154 nm (31 px) at most,
     * so most particles, placed at random, stay inside. */
    frame_start = g_rand_double_range(rng, 0.0, 100.0);
    /* A particle the drift keeps well inside the frame.  Every attempt is an
     * independent sample with the same drift and timing: seeds in a plain
     * progression (seed + 1000 k) start the simulator's PCG streams so close
     * that the first particle's x hardly moves (3 px per attempt), and a
     * frame start growing with the attempt let the drift outrun it. */
    for (attempt = 0; attempt < 50; attempt++) {
        sim_sample_free(sample);
        sample = small_particle_sample(g_rand_int(rng), 1, 0.0);
        sim_scan_params_init(&sp, sample, 200, 200);
        sp.direction = direction;
        sp.frame_start = frame_start;
        sim_sample_particle(sample, 0, &x, &y, NULL);
        predicted_apparent_pixel(&sp, &drift, x, y, &pc, &pr);
        if (pc > 15.0 && pc < 184.0 && pr > 15.0 && pr < 184.0)
            break;
    }
    ck_assert(attempt < 50);
    frame = sim_scan_frame(sample, &drift, &sp);
    weighted_centroid(frame, pc, pr, 12, sim_sample_particle_centre_z(sample, 0),
                      &cc, &cr);
    ck_assert_msg(fabs(cc - pc) < 0.1 && fabs(cr - pr) < 0.1,
                  "direction %d v=(%g, %g) nm/s: centroid (%.3f, %.3f) px, "
                  "predicted (%.3f, %.3f)", direction, drift.v[0]*1e9,
                  drift.v[1]*1e9, cc, cr, pc, pr);
    /* The drift moved it measurably from where it truly is. */
    still_c = x/(sp.xreal/sp.xres) - 0.5;
    still_r = y/(sp.yreal/sp.yres) - 0.5;
    ck_assert(hypot(pc - still_c, pr - still_r) > 1.0);
    g_object_unref(frame);
    drift_model_clear(&drift);
    sim_sample_free(sample);
    g_rand_free(rng);
}

START_TEST(test_velocity_centroid_down)
{
    gint k;

    for (k = 0; k < 5; k++)
        check_velocity_centroid(SCAN_DIRECTION_DOWN, test_seed + 20 + k);
}
END_TEST

START_TEST(test_velocity_centroid_up)
{
    gint k;

    for (k = 0; k < 5; k++)
        check_velocity_centroid(SCAN_DIRECTION_UP, test_seed + 30 + k);
}
END_TEST

/* A pixel of a frame is exactly what the probe records at that pixel's
 * nominal position and scan time: the local-scan procedure and the frame
 * see the same instrument. */
START_TEST(test_probe_matches_frame)
{
    GRand *rng = g_rand_new_with_seed(test_seed + 40);
    SimSample *sample = small_particle_sample(test_seed, 10, 0.4e-9);
    SimScanParams sp;
    ScanTiming timing;
    DriftModel drift;
    GwyDataField *frame;
    gdouble x, y, z;
    gint k, r, c;

    sim_scan_params_init(&sp, sample, 128, 96);
    sp.tip_radius = 6e-9;
    sp.frame_start = 77.0;
    drift_model_init(&drift, DRIFT_MODEL_SETTLING);
    drift.v[0] = DRIFT_MODEL_PAPER_VX;
    drift.v[1] = DRIFT_MODEL_PAPER_VY;
    drift.u[0] = 1e-9;
    drift.u[1] = -0.5e-9;
    drift.tau = 60.0;
    frame = sim_scan_frame(sample, &drift, &sp);
    sim_scan_params_timing(&sp, &timing);
    for (k = 0; k < 500; k++) {
        r = g_rand_int_range(rng, 0, sp.yres);
        c = g_rand_int_range(rng, 0, sp.xres);
        sim_scan_pixel_position(&sp, r, c, &x, &y);
        z = sim_probe_height(sample, &drift, sp.tip_radius, x, y,
                             scan_timing_pixel_time(&timing, r, c));
        ck_assert_msg(z == gwy_data_field_get_val(frame, c, r),
                      "pixel (%d, %d): probe %g, frame %g", r, c, z,
                      gwy_data_field_get_val(frame, c, r));
    }
    g_object_unref(frame);
    drift_model_clear(&drift);
    sim_sample_free(sample);
    g_rand_free(rng);
}
END_TEST

START_TEST(test_seeds_reproduce)
{
    SimSample *a = small_particle_sample(test_seed, 20, 0.5e-9);
    SimSample *b = small_particle_sample(test_seed, 20, 0.5e-9);
    SimSample *other = small_particle_sample(test_seed + 1, 20, 0.5e-9);
    SimScanParams sp;
    DriftModel drift;
    GwyDataField *fa, *fb, *fnoise, *fother;
    gdouble diff;

    drift_model_init(&drift, DRIFT_MODEL_RANDOM_WALK);
    drift.v[0] = DRIFT_MODEL_PAPER_VX;
    drift.walk_sigma = 0.01e-9;
    drift.walk_seed = test_seed;
    drift_model_prepare(&drift, 300.0);
    sim_scan_params_init(&sp, a, 128, 128);
    sp.noise_rms = 0.2e-9;
    sp.noise_seed = test_seed;
    fa = sim_scan_frame(a, &drift, &sp);
    fb = sim_scan_frame(b, &drift, &sp);
    assert_same_bytes(fa, fb);

    sp.noise_seed = test_seed + 1;
    fnoise = sim_scan_frame(a, &drift, &sp);
    gwy_data_field_subtract_fields(fnoise, fnoise, fa);
    /* Two independent noises of 0.2 nm differ by 0.2 sqrt(2) nm RMS. */
    diff = gwy_data_field_get_rms(fnoise);
    ck_assert_msg(fabs(diff/(0.2e-9*G_SQRT2) - 1.0) < 0.05,
                  "noise difference RMS %g", diff);

    sp.noise_seed = test_seed;
    fother = sim_scan_frame(other, &drift, &sp);
    gwy_data_field_subtract_fields(fother, fother, fa);
    ck_assert(gwy_data_field_get_rms(fother) > 1e-9);

    g_object_unref(fa);
    g_object_unref(fb);
    g_object_unref(fnoise);
    g_object_unref(fother);
    drift_model_clear(&drift);
    sim_sample_free(a);
    sim_sample_free(b);
    sim_sample_free(other);
}
END_TEST

/* A small random image with unequal pixel sizes, so x and y cannot be
 * swapped unnoticed. */
static GwyDataField*
random_image(guint32 seed, gint xres, gint yres)
{
    GRand *rng = g_rand_new_with_seed(seed);
    GwyDataField *field = gwy_data_field_new(xres, yres, xres*7e-9, yres*5e-9,
                                             FALSE);
    gdouble *d = gwy_data_field_get_data(field);
    gint k;

    for (k = 0; k < xres*yres; k++)
        d[k] = g_rand_double_range(rng, -3e-9, 3e-9);
    g_rand_free(rng);
    return field;
}

START_TEST(test_measured_reproduced_on_own_grid)
{
    GwyDataField *image = random_image(test_seed + 50, 37, 29), *scan, *shifted;
    SimSample *sample = sim_sample_new_from_field(image);
    SimScanParams sp;
    DriftModel drift;
    gdouble range = field_range(image), diff;
    gint xres = 37, yres = 29, k;

    ck_assert(sample);
    ck_assert_int_eq(sim_sample_n_particles(sample), 0);
    sim_scan_params_init(&sp, sample, xres, yres);
    scan = sim_scan_frame(sample, NULL, &sp);
    gwy_data_field_subtract_fields(scan, scan, image);
    for (k = 0, diff = 0.0; k < xres*yres; k++)
        diff = MAX(diff, fabs(gwy_data_field_get_data_const(scan)[k]));
    ck_assert_msg(diff <= 1e-9*range, "own-grid scan differs by %g", diff);

    /* A whole-pixel drift reproduces the shifted image, edges included
     * where the source pixel exists. */
    drift_model_init(&drift, DRIFT_MODEL_NONE);
    drift.p0[0] = -2*sp.xreal/xres;
    drift.p0[1] = 3*sp.yreal/yres;
    shifted = sim_scan_frame(sample, &drift, &sp);
    diff = max_shifted_difference(shifted, image, -2, 3, 0);
    ck_assert_msg(diff <= 1e-9*range, "shifted scan differs by %g", diff);
    g_object_unref(shifted);
    g_object_unref(scan);
    g_object_unref(image);
    drift_model_clear(&drift);
    sim_sample_free(sample);
}
END_TEST

/* Between pixels a measured sample is a smooth spline, never the nearest
 * pixel: a linear ramp is reproduced exactly at half-pixel offsets. */
START_TEST(test_measured_interpolates)
{
    GwyDataField *ramp = gwy_data_field_new(64, 48, 64e-9, 48e-9, FALSE), *scan;
    SimSample *sample;
    SimScanParams sp;
    DriftModel drift;
    gdouble *d = gwy_data_field_get_data(ramp), expected, diff = 0.0;
    gint r, c;

    for (r = 0; r < 48; r++)
        for (c = 0; c < 64; c++)
            d[r*64 + c] = (2.0*c - 0.5*r)*1e-9;
    sample = sim_sample_new_from_field(ramp);
    sim_scan_params_init(&sp, sample, 64, 48);
    drift_model_init(&drift, DRIFT_MODEL_NONE);
    drift.p0[0] = 0.5e-9;
    drift.p0[1] = 0.25e-9;
    scan = sim_scan_frame(sample, &drift, &sp);
    /* Pixel (r, c) sees the sample at (c - 0.5, r - 0.25) pixels.  The
     * mirrored edges bend a ramp; their effect decays as 0.27^distance, so
     * 16 pixels in it is below 1e-18 m.  The nearest pixel would be 1 nm off. */
    for (r = 16; r < 32; r++) {
        for (c = 16; c < 48; c++) {
            expected = (2.0*(c - 0.5) - 0.5*(r - 0.25))*1e-9;
            diff = MAX(diff, fabs(gwy_data_field_get_val(scan, c, r) - expected));
        }
    }
    ck_assert_msg(diff < 1e-15, "ramp error %g m", diff);
    g_object_unref(scan);
    g_object_unref(ramp);
    drift_model_clear(&drift);
    sim_sample_free(sample);
}
END_TEST

/* A single spike dilated by a spherical tip becomes the tip's own shape. */
START_TEST(test_measured_tip_dilation)
{
    GwyDataField *spike = gwy_data_field_new(31, 31, 31e-9, 31e-9, TRUE), *scan;
    SimSample *sample;
    SimScanParams sp;
    gdouble rt = 6e-9, rho2, expected, got;
    gint r, c;

    gwy_data_field_set_val(spike, 15, 15, 10e-9);
    sample = sim_sample_new_from_field(spike);
    sim_scan_params_init(&sp, sample, 31, 31);
    sp.tip_radius = rt;
    scan = sim_scan_truth(sample, &sp);
    for (r = 0; r < 31; r++) {
        for (c = 0; c < 31; c++) {
            rho2 = ((r - 15)*(r - 15) + (c - 15)*(c - 15))*1e-18;
            expected = rho2 <= rt*rt ? 10e-9 + sqrt(rt*rt - rho2) - rt : 0.0;
            expected = MAX(expected, 0.0);
            got = gwy_data_field_get_val(scan, c, r);
            ck_assert_msg(fabs(got - expected) < 1e-15,
                          "dilated spike at (%d, %d): %g, expected %g",
                          r, c, got, expected);
        }
    }
    g_object_unref(scan);
    g_object_unref(spike);
    sim_sample_free(sample);
}
END_TEST

/* Particles: count, spacing, inside the field, and the sphere heights,
 * sharp and with a tip. */
START_TEST(test_particle_geometry)
{
    SimParticleParams pp;
    SimSample *sample;
    gdouble x, y, r, xj, yj, rj, zc, rt = 10e-9, d, z, sub;
    gint i, j, n;

    sim_particle_params_init(&pp);
    pp.count = 60;
    pp.min_spacing = 150e-9;
    pp.radius_spread = 0.1;
    sample = sim_sample_new_particles(&pp, test_seed + 60);
    n = sim_sample_n_particles(sample);
    ck_assert_int_eq(n, 60);
    for (i = 0; i < n; i++) {
        sim_sample_particle(sample, i, &x, &y, &r);
        ck_assert(x >= r && x <= pp.xreal - r && y >= r && y <= pp.yreal - r);
        for (j = 0; j < i; j++) {
            sim_sample_particle(sample, j, &xj, &yj, &rj);
            ck_assert(hypot(x - xj, y - yj) >= pp.min_spacing);
        }
        zc = sim_sample_particle_centre_z(sample, i);
        ck_assert(fabs(zc - r) < 5.0*pp.roughness_rms);
        /* Top of the sphere; the tip touches the top just the same. */
        ck_assert(fabs(sim_sample_height(sample, x, y) - (zc + r)) < 1e-18);
        ck_assert(fabs(sim_sample_height_tip(sample, rt, x, y) - (zc + r))
                  < 1e-18);
        /* Halfway out: sphere for a sharp tip. */
        d = 0.5*r;
        z = sim_sample_height(sample, x + d, y);
        ck_assert(fabs(z - (zc + sqrt(r*r - d*d))) < 1e-18);
        /* Just beyond the sphere the sharp tip sees substrate, the round
         * tip still rides on the particle. */
        d = r + 0.5*rt;
        sub = sim_sample_height(sample, x, y + d);
        ck_assert(fabs(sub - zc + r) < 5.0*pp.roughness_rms);
        z = sim_sample_height_tip(sample, rt, x, y + d);
        ck_assert(fabs(z - (zc + sqrt((r + rt)*(r + rt) - d*d) - rt)) < 1e-18);
    }
    sim_sample_free(sample);

    /* Too many for the spacing (at most some 800 fit): fewer are placed. */
    pp.count = 100000;
    sample = sim_sample_new_particles(&pp, test_seed + 61);
    ck_assert_int_gt(sim_sample_n_particles(sample), 100);
    ck_assert_int_lt(sim_sample_n_particles(sample), 100000);
    sim_sample_free(sample);
}
END_TEST

/* The substrate has the RMS asked for and is smooth: it changes gradually
 * under sub-pixel drift instead of jumping. */
START_TEST(test_substrate_roughness)
{
    SimParticleParams pp;
    SimSample *sample;
    SimScanParams sp;
    DriftModel drift;
    GwyDataField *truth, *sub_px;
    gdouble rms, step;

    sim_particle_params_init(&pp);
    pp.count = 0;
    pp.density = 0.0;
    pp.roughness_rms = 1e-9;
    pp.roughness_corr = 40e-9;
    sample = sim_sample_new_particles(&pp, test_seed + 70);
    ck_assert_int_eq(sim_sample_n_particles(sample), 0);
    sim_scan_params_init(&sp, sample, 256, 256);
    truth = sim_scan_truth(sample, &sp);
    rms = gwy_data_field_get_rms(truth);
    ck_assert_msg(fabs(rms/pp.roughness_rms - 1.0) < 0.1, "substrate RMS %g", rms);
    /* A hundredth of a pixel of drift changes heights by a hundredth of the
     * local slope times the pixel, far less than the RMS. */
    drift_model_init(&drift, DRIFT_MODEL_NONE);
    drift.p0[0] = 0.01*sp.xreal/sp.xres;
    sub_px = sim_scan_frame(sample, &drift, &sp);
    gwy_data_field_subtract_fields(sub_px, sub_px, truth);
    step = gwy_data_field_get_rms(sub_px);
    ck_assert_msg(step > 0.0 && step < 0.01*rms, "sub-pixel change %g", step);
    g_object_unref(truth);
    g_object_unref(sub_px);
    drift_model_clear(&drift);
    sim_sample_free(sample);
}
END_TEST

/* The paper's Figure 6 contamination: stripe s (1-based) has dx = -s,
 * dy = 0, -1, -2, -3 for stripes 1-4, 5-8, 9-12, 13-16. */
START_TEST(test_stripes_figure6)
{
    SimSample *sample = small_particle_sample(test_seed + 80, 40, 0.3e-9);
    SimScanParams sp;
    GwyDataField *frame, *truth;
    gdouble dx[16], dy[16], worst = 0.0, range;
    const gdouble *f, *t;
    gint s, r, c, yres = 256, xres = 256, sr, sc, compared = 0;

    for (s = 0; s < 16; s++) {
        dx[s] = -(s + 1);
        dy[s] = -(s/4);
    }
    sim_scan_params_init(&sp, sample, xres, yres);
    frame = sim_scan_frame_stripes(sample, &sp, 16, dx, dy);
    truth = sim_scan_truth(sample, &sp);
    f = gwy_data_field_get_data_const(frame);
    t = gwy_data_field_get_data_const(truth);
    range = field_range(truth);
    for (r = 0; r < yres; r++) {
        s = stripe_of_row(r, 16, yres);
        sr = r - (gint)dy[s];
        for (c = 0; c < xres; c++) {
            sc = c - (gint)dx[s];
            if (sr < 0 || sr >= yres || sc < 0 || sc >= xres)
                continue;
            worst = MAX(worst, fabs(f[r*xres + c] - t[sr*xres + sc]));
            compared++;
        }
    }
    ck_assert_int_gt(compared, xres*yres/2);
    ck_assert_msg(worst <= 1e-9*range, "stripe frame differs by %g", worst);
    g_object_unref(frame);
    g_object_unref(truth);
    sim_sample_free(sample);
}
END_TEST

START_TEST(test_bad_input_refused)
{
    SimSample *sample = small_particle_sample(test_seed, 3, 0.0);
    SimParticleParams pp;
    SimScanParams sp;
    gdouble dx[2] = { 0.0, 0.0 }, dy[2] = { 0.0, NAN };
    guint handler;

    handler = g_log_set_handler(NULL, G_LOG_LEVEL_WARNING, count_warning, NULL);
    warnings_seen = 0;
    sim_scan_params_init(&sp, sample, 0, 10);
    ck_assert(!sim_scan_frame(sample, NULL, &sp));
    sim_scan_params_init(&sp, sample, 10, 10);
    sp.line_time = 0.0;
    ck_assert(!sim_scan_frame(sample, NULL, &sp));
    sp.line_time = 1.0;
    sp.noise_rms = -1.0;
    ck_assert(!sim_scan_frame(sample, NULL, &sp));
    sp.noise_rms = 0.0;
    ck_assert(!sim_scan_frame_stripes(sample, &sp, 11, dx, dy));
    ck_assert(!sim_scan_frame_stripes(sample, &sp, 2, dx, dy));
    sim_particle_params_init(&pp);
    pp.radius = -1.0;
    ck_assert(!sim_sample_new_particles(&pp, 1));
    ck_assert_int_eq(warnings_seen, 6);
    g_log_remove_handler(NULL, handler);
    sim_sample_free(sample);
}
END_TEST

static Suite*
scanner_suite(void)
{
    TCase *tc;
    Suite *s = test_suite_new("simscan-scanner", "core", &tc);

    tcase_add_test(tc, test_zero_drift_is_truth);
    tcase_add_test(tc, test_whole_pixel_drift_shifts);
    tcase_add_test(tc, test_velocity_centroid_down);
    tcase_add_test(tc, test_velocity_centroid_up);
    tcase_add_test(tc, test_probe_matches_frame);
    tcase_add_test(tc, test_seeds_reproduce);
    tcase_add_test(tc, test_measured_reproduced_on_own_grid);
    tcase_add_test(tc, test_measured_interpolates);
    tcase_add_test(tc, test_measured_tip_dilation);
    tcase_add_test(tc, test_particle_geometry);
    tcase_add_test(tc, test_substrate_roughness);
    tcase_add_test(tc, test_stripes_figure6);
    tcase_add_test(tc, test_bad_input_refused);
    return s;
}

int
main(void)
{
    test_seed = test_seed_from_env("test-simscan-scanner");
    return test_run_suite(scanner_suite());
}
