/*
 *  One simulated experiment: the scene (sample, drift, contaminated image,
 *  truth) and the local-scan measurement on it with N stripes, its paper-mode
 *  compensation and the particle-centre errors before and after.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef SIMSCAN_RUN_H
#define SIMSCAN_RUN_H

#include <glib.h>
#include <libprocess/datafield.h>
#include "drift-table.h"
#include "scanner.h"
#include "local-scan.h"
#include "centre-error.h"
#include "simscan-config.h"

G_BEGIN_DECLS

typedef struct {
    const SimscanConfig *config;
    SimSample *sample;
    DriftModel drift;          /* prepared; no drift at all for Figure 6 */
    SimScanParams scan;
    ScanTiming timing;
    GwyDataField *image;       /* drift-contaminated */
    GwyDataField *truth;       /* drift-free, noise-free */
    gint shift_n;              /* Figure 6: stripes of the contamination */
    gdouble *shift_dx;         /* px, shift_n each; NULL without */
    gdouble *shift_dy;
    ParticleDetectParams detect;
    GArray *particles;         /* DetectedParticle found in image */
    gdouble substrate;
} SimscanScene;

typedef struct {
    gint n_stripes;
    DriftTable *table;         /* what the local scans measured, px */
    LocalScanParticle *scans;  /* n_stripes */
    gdouble *true_dx;          /* px: what a perfect local scan would measure */
    gdouble *true_dy;
    gdouble t_start, t_end;    /* the local scans, s */
    gint lines;                /* local-scan lines in all */
    gdouble ref_drift[2];      /* p(t_start), m: the compensated image shows
                                  the sample displaced by this */
    GwyDataField *compensated; /* paper mode with the measured table */
    gboolean have_errors;      /* synthetic particles: errors known */
    gint n_particles;
    gdouble *truth_px;         /* 2 n_particles: where each belongs after a
                                  perfect compensation (col, row) */
    gdouble *shown_px;         /* 2 n_particles: where the image shows it */
    CentreError before;
    CentreError after;
} SimscanMeasurement;

/* sample_field (may be NULL) is the measured image to use as the sample when
 * config->sample_file is set; the caller loads it. */
SimscanScene*        simscan_scene_new          (const SimscanConfig *config,
                                                 GwyDataField *sample_field,
                                                 GError **error);
void                 simscan_scene_free         (SimscanScene *scene);
/* Pixel column and row (centres at whole numbers) of scan position x, y
 * (m) in the scene's image. */
gdouble              simscan_scene_column       (const SimscanScene *scene,
                                                 gdouble x);
gdouble              simscan_scene_row          (const SimscanScene *scene,
                                                 gdouble y);

/* Fails (with a message) only when no stripe got a particle measured. */
SimscanMeasurement*  simscan_measure            (SimscanScene *scene,
                                                 gint n_stripes,
                                                 GError **error);
void                 simscan_measurement_free   (SimscanMeasurement *m);

G_END_DECLS

#endif
