/*
 *  Benchmark of the simulated scanner: a drifting 1024x1024 and 256x256 scan
 *  of the default particle sample, everything included.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <stdio.h>
#include <libprocess/stats.h>
#include "sample.h"
#include "scanner.h"

/* Sample creation, the drift model and one contaminated frame (noise and a
 * 10 nm tip), as the simscan program does it; returns seconds. */
static gdouble
time_particle_scan(gint res, gdouble *checksum)
{
    GTimer *timer = g_timer_new();
    SimParticleParams pparams;
    SimScanParams sparams;
    SimSample *sample;
    DriftModel drift;
    GwyDataField *frame;
    gdouble seconds;

    sim_particle_params_init(&pparams);
    sample = sim_sample_new_particles(&pparams, 1);
    drift_model_init(&drift, DRIFT_MODEL_SETTLING);
    drift.v[0] = DRIFT_MODEL_PAPER_VX;
    drift.v[1] = DRIFT_MODEL_PAPER_VY;
    drift.u[0] = 0.5e-9;
    drift.tau = 100.0;
    sim_scan_params_init(&sparams, sample, res, res);
    sparams.noise_rms = 0.1e-9;
    sparams.tip_radius = 10e-9;
    frame = sim_scan_frame(sample, &drift, &sparams);
    seconds = g_timer_elapsed(timer, NULL);
    *checksum += gwy_data_field_get_avg(frame);
    g_object_unref(frame);
    sim_sample_free(sample);
    drift_model_clear(&drift);
    g_timer_destroy(timer);
    return seconds;
}

/* A measured image (here a 512x512 particle scan) as the sample: the same
 * scan through the B-spline surface. */
static gdouble
time_measured_scan(gint res, gdouble *checksum)
{
    GwyDataField *image, *frame;
    GTimer *timer;
    SimParticleParams pparams;
    SimScanParams sparams;
    SimSample *sample;
    DriftModel drift;
    gdouble seconds;

    sim_particle_params_init(&pparams);
    sample = sim_sample_new_particles(&pparams, 2);
    sim_scan_params_init(&sparams, sample, 512, 512);
    image = sim_scan_truth(sample, &sparams);
    sim_sample_free(sample);

    timer = g_timer_new();
    sample = sim_sample_new_from_field(image);
    drift_model_init(&drift, DRIFT_MODEL_NONE);
    drift.v[0] = DRIFT_MODEL_PAPER_VX;
    drift.v[1] = DRIFT_MODEL_PAPER_VY;
    sim_scan_params_init(&sparams, sample, res, res);
    frame = sim_scan_frame(sample, &drift, &sparams);
    seconds = g_timer_elapsed(timer, NULL);
    *checksum += gwy_data_field_get_avg(frame);
    g_object_unref(frame);
    g_object_unref(image);
    sim_sample_free(sample);
    g_timer_destroy(timer);
    return seconds;
}

int
main(void)
{
    gdouble checksum = 0.0, t1024, t256, m1024, m256;

    /* One warm-up so page faults and FFTW's first plan are not counted. */
    time_particle_scan(64, &checksum);
    t1024 = time_particle_scan(1024, &checksum);
    t256 = time_particle_scan(256, &checksum);
    m1024 = time_measured_scan(1024, &checksum);
    m256 = time_measured_scan(256, &checksum);
    printf("particle sample, 1024x1024 scan: %.3f s (%.0f ns/pixel)\n",
           t1024, 1e9*t1024/(1024.0*1024.0));
    printf("particle sample,   256x256 scan: %.3f s (%.0f ns/pixel)\n",
           t256, 1e9*t256/(256.0*256.0));
    printf("particle sample, 1024/256 time ratio: %.1f (16 = pure per-pixel cost)\n",
           t1024/t256);
    printf("measured 512x512 sample, 1024x1024 scan: %.3f s, 256x256: %.3f s\n",
           m1024, m256);
    printf("(checksum %g)\n", checksum);
    return 0;
}
