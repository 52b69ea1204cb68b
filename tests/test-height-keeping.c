/*
 *  Continuous compensation with the default interpolation keeps particle
 *  heights: every particle's peak (its highest pixel above the image's
 *  median) stays within 2 % of the original and never rises above it.
 *  Built twice: on simulated particles (simscan's sample, drift-free scan)
 *  and, with -DHEIGHT_MEASURED, on the particles-film sample
 *  ($LOCALSCAN_MEASURED_DIR/particles-film, SKIPPED when absent).  Every
 *  kernel's figures are printed for docs/heights.md; only the default's
 *  are asserted.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <stdio.h>
#include <stdlib.h>
#include <math.h>
#include <check.h>
#include <libgwyddion/gwyddion.h>
#include <libprocess/gwyprocess.h>
#include <libgwymodule/gwymodule-file.h>
#include <app/gwyapp.h>
#include "localscan-channel.h"
#include "localscan-params.h"
#include "sample.h"
#include "scanner.h"
#include "test-common.h"
#include "continuous-fixtures.h"
#include "run-description.h"

#ifdef HEIGHT_MEASURED
#define PROGRAM "test-height-keeping-measured"
#else
#define PROGRAM "test-height-keeping"
#endif
#define SAMPLE_PATH "particles-film/PTO_110_Virgin0001.gwy"
#define N_STRIPES 16
/* Stripe drifts stay within this (px), so a particle's peak is found
 * within MATCH_RADIUS of where it was. */
#define MAX_DRIFT 1.5
#define MATCH_RADIUS 3
/* A peak is the highest pixel within ISOLATION px, at least PEAK_FRACTION
 * of the image's highest point above the median. */
#define ISOLATION 6
#define PEAK_FRACTION 0.3
#define HEIGHT_TOLERANCE 0.02

static guint32 seed;
static GwyDataField *image;

typedef struct {
    gint n_peaks;
    gdouble worst_rise;    /* relative, >= 0 */
    gdouble worst_loss;    /* relative, <= 0 */
} HeightChange;

/* A table of fractional drifts growing down the image, as slow thermal
 * drift does, with a random start and rate. */
static DriftTable*
make_table(GRand *rng)
{
    DriftTable *table = drift_table_new(N_STRIPES, DRIFT_UNIT_PX);
    gdouble x0 = g_rand_double_range(rng, -0.5, 0.5), y0 = g_rand_double_range(rng, -0.5, 0.5);
    gdouble vx = g_rand_double_range(rng, -1.0, 1.0)/N_STRIPES;
    gdouble vy = g_rand_double_range(rng, -1.0, 1.0)/N_STRIPES;
    gint s;

    for (s = 0; s < N_STRIPES; s++) {
        table->rows[s].has_drift = TRUE;
        table->rows[s].dx = CLAMP(x0 + vx*s, -MAX_DRIFT, MAX_DRIFT);
        table->rows[s].dy = CLAMP(y0 + vy*s, -MAX_DRIFT, MAX_DRIFT);
    }
    return table;
}

static gboolean
is_peak(const gdouble *a, gint xres, gint i, gint j)
{
    gdouble v = a[i*xres + j];
    gint k, l;

    for (k = -ISOLATION; k <= ISOLATION; k++) {
        for (l = -ISOLATION; l <= ISOLATION; l++) {
            if ((k || l) && a[(i + k)*xres + j + l] >= v)
                return FALSE;
        }
    }
    return TRUE;
}

static gdouble
window_max(const gdouble *b, gint xres, gint i, gint j)
{
    gdouble m = -G_MAXDOUBLE;
    gint k, l;

    for (k = -MATCH_RADIUS; k <= MATCH_RADIUS; k++) {
        for (l = -MATCH_RADIUS; l <= MATCH_RADIUS; l++)
            m = fmax(m, b[(i + k)*xres + j + l]);
    }
    return m;
}

/* Every isolated peak of the source against the highest pixel near it in
 * the result, both above the source's median (the substrate). */
static HeightChange
compare_peaks(GwyDataField *source, GwyDataField *result)
{
    gint xres = gwy_data_field_get_xres(source), yres = gwy_data_field_get_yres(source);
    const gdouble *a = gwy_data_field_get_data_const(source);
    const gdouble *b = gwy_data_field_get_data_const(result);
    gdouble base = gwy_data_field_get_median(source), top = gwy_data_field_get_max(source);
    gint margin = ISOLATION + 2, i, j;
    HeightChange change = { 0, 0.0, 0.0 };
    gdouble h, rel;

    for (i = margin; i < yres - margin; i++) {
        for (j = margin; j < xres - margin; j++) {
            h = a[i*xres + j] - base;
            if (h < PEAK_FRACTION*(top - base) || !is_peak(a, xres, i, j))
                continue;
            rel = (window_max(b, xres, i, j) - base)/h - 1.0;
            change.worst_rise = fmax(change.worst_rise, rel);
            change.worst_loss = fmin(change.worst_loss, rel);
            change.n_peaks++;
        }
    }
    return change;
}

static gboolean
compensate(GwyDataField *field, const DriftTable *table, GwyInterpolationType interpolation,
           GwyDataField *result)
{
    LocalscanOptions options = {
        LOCALSCAN_MODE_CONTINUOUS, LOCALSCAN_FILL_MEAN, interpolation,
        1.0, SCAN_DIRECTION_DOWN, 0.0,
    };
    GError *error = NULL;
    gboolean ok = localscan_compensate_field(field, table, &options, result, NULL, NULL, &error);

    if (!ok)
        fprintf(stderr, "%s: %s\n", PROGRAM, error->message);
    g_clear_error(&error);
    return ok;
}

START_TEST(test_default_keeps_heights)
{
    GRand *rng = g_rand_new_with_seed(seed);
    DriftTable *table = make_table(rng);
    GwyDataField *result = gwy_data_field_new_alike(image, FALSE);
    HeightChange change, of_default = { -1, 0.0, 0.0 };
    guint k;

    /* Every kernel is printed for comparison; only the default is held to
     * the tolerance. */
    for (k = 0; k < G_N_ELEMENTS(all_kernels); k++) {
        ck_assert(compensate(image, table, all_kernels[k], result));
        change = compare_peaks(image, result);
        printf("%s: %-8s %d peaks: highest rise %+.2f %%, largest loss %+.2f %%%s\n",
               PROGRAM, run_description_interpolation_name(all_kernels[k]), change.n_peaks,
               100.0*change.worst_rise, 100.0*change.worst_loss,
               all_kernels[k] == LOCALSCAN_DEFAULT_INTERPOLATION ? "  (default)" : "");
        if (all_kernels[k] == LOCALSCAN_DEFAULT_INTERPOLATION)
            of_default = change;
    }
    ck_assert_msg(of_default.n_peaks >= 5, "only %d peaks found (seed %u)", of_default.n_peaks, seed);
    ck_assert_msg(of_default.worst_rise <= HEIGHT_TOLERANCE,
                  "the default interpolation raises a peak by %.2f %% (seed %u)",
                  100.0*of_default.worst_rise, seed);
    ck_assert_msg(of_default.worst_loss >= -HEIGHT_TOLERANCE,
                  "the default interpolation lowers a peak by %.2f %% (seed %u)",
                  -100.0*of_default.worst_loss, seed);

    g_object_unref(result);
    drift_table_free(table);
    g_rand_free(rng);
}
END_TEST

#ifdef HEIGHT_MEASURED
static GwyDataField*
load_image(void)
{
    gchar *filename = test_measured_file(PROGRAM, SAMPLE_PATH, "every test");
    GwyContainer *data;
    GwyDataField *field = NULL;

    if (!filename)
        exit(TEST_EXIT_SKIP);
    gwy_app_init_nongui("enable-threads", FALSE, NULL);
    if ((data = gwy_file_load(filename, GWY_RUN_NONINTERACTIVE, NULL))
        && gwy_container_gis_object_by_name(data, "/0/data", &field)) {
        /* Heights above a tilted film are measured from the levelled film. */
        field = gwy_data_field_duplicate(field);
        gwy_data_field_plane_level(field, 0.0, 0.0, 0.0);
    }
    if (!field)
        printf("%s: cannot read %s\n", PROGRAM, filename);
    if (data)
        g_object_unref(data);
    g_free(filename);
    return field;
}
#else
/* 50 nm particles on a 2.56 um frame of 256 px: about 5 px across, as
 * small particles in real scans are; a sharp tip, no noise. */
static GwyDataField*
load_image(void)
{
    SimParticleParams particles;
    SimScanParams scan;
    SimSample *sample;
    GwyDataField *field;

    sim_particle_params_init(&particles);
    particles.xreal = particles.yreal = 2.56e-6;
    particles.count = 30;
    sample = sim_sample_new_particles(&particles, seed);
    sim_scan_params_init(&scan, sample, 256, 256);
    field = sim_scan_truth(sample, &scan);
    sim_sample_free(sample);
    return field;
}
#endif

int
main(void)
{
    TCase *tc;
    Suite *suite = test_suite_new("height-keeping", "default-kernel", &tc);
    gint status;

    seed = test_seed_from_env(PROGRAM);
    if (!(image = load_image()))
        return EXIT_FAILURE;
    tcase_add_test(tc, test_default_keeps_heights);
    status = test_run_suite(suite);
    g_object_unref(image);
    return status;
}
