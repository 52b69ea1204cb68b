/*
 *  What one simscan run simulates and writes: sample, scanner, drift, local
 *  scans and outputs in SI units, filled from the command line and presets.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef SIMSCAN_CONFIG_H
#define SIMSCAN_CONFIG_H

#include <glib.h>
#include <libprocess/datafield.h>
#include "scan-timing.h"
#include "drift-model.h"
#include "sample.h"
#include "local-scan.h"

G_BEGIN_DECLS

typedef enum {
    SIMSCAN_PRESET_NONE = 0,
    SIMSCAN_PRESET_PAPER,      /* Section IV: linear drift, 300 s per image */
    SIMSCAN_PRESET_FIGURE6,    /* the paper's Figure 6 per-stripe shifts */
} SimscanPreset;

typedef struct {
    SimscanPreset preset;
    /* Sample: synthetic particles, or a measured image when sample_file. */
    SimParticleParams particles;
    gchar *sample_file;
    gint sample_channel;       /* -1: the first channel */
    /* Scanner. */
    gint xres, yres;
    gdouble xreal, yreal;      /* m */
    gdouble line_time;         /* s */
    ScanDirection direction;
    gdouble noise_rms;         /* m */
    gdouble tip_radius;        /* m */
    /* Drift: a time model, or the Figure 6 stripe shifts. */
    DriftModel drift;
    gboolean figure6;
    /* Local scans. */
    gint n_stripes;
    LocalScanParams local;
    gdouble local_delay;       /* s from the end of the image to the first scan */
    guint32 seed;
    /* Outputs; NULL: not written. */
    gchar *output;
    gchar *table;
    gchar *json;
    gboolean quiet;
} SimscanConfig;

/* Options the user gave, which a measured sample's defaults leave alone. */
typedef enum {
    SIMSCAN_GIVEN_RADIUS     = 1 << 0,     /* --radius */
    SIMSCAN_GIVEN_RESOLUTION = 1 << 1,     /* --xres or --yres */
    SIMSCAN_GIVEN_VELOCITY   = 1 << 2,     /* --velocity */
    SIMSCAN_GIVEN_RMAX       = 1 << 3,     /* --ls-rmax */
} SimscanGiven;

/* The paper's setting (Section IV): 256 x 256 px over 5 um, 50 nm latex
 * particles, 300 s per image scanning down, v = (0.08, 0.02) nm/s, 16
 * stripes, seed 1. */
void         simscan_config_init          (SimscanConfig *config);
void         simscan_config_clear         (SimscanConfig *config);

/* Defaults taken from a measured sample for what the user did not give
 * (given: SimscanGiven flags): the scan covers the sample's own size at its
 * own resolution; the local scans' particle radius is the typical radius of
 * the particles found on the levelled sample (particle_typical_radius); the
 * drift velocity and the largest drift expected are the paper's (Section
 * IV) scaled by the ratio of pixel sizes, so the image is contaminated by as
 * many pixels as in the paper.  Fails when the sample shows no particle. */
gboolean     simscan_config_adopt_sample  (SimscanConfig *config,
                                           GwyDataField *sample,
                                           guint given,
                                           GError **error);

G_END_DECLS

#endif
