/*
 *  The simulated sample: a height z(x, y) defined everywhere, either
 *  synthetic spherical particles on a rough substrate or a measured image.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef SIMSCAN_SAMPLE_H
#define SIMSCAN_SAMPLE_H

#include <glib.h>
#include <libprocess/datafield.h>

G_BEGIN_DECLS

/*
 * Sample coordinates: metres, origin at the top left corner of the sample,
 * x to the right, y downward (the direction of growing row index, as in a
 * Gwyddion data field).  The sample spans [0, xreal] x [0, yreal]; heights
 * are defined outside it too (the synthetic substrate repeats periodically and
 * has no particles there; a measured image is mirrored at its edges).
 */
typedef struct _SimSample SimSample;

typedef struct {
    gdouble xreal;             /* field width, m (default 5e-6) */
    gdouble yreal;             /* field height, m (default 5e-6) */
    gdouble radius;            /* particle radius, m (default 25e-9: 50 nm latex) */
    gdouble radius_spread;     /* relative RMS spread of radii (default 0) */
    gint count;                /* number of particles; <= 0: use density */
    gdouble density;           /* particles per m^2 when count <= 0 (default 4e12) */
    gdouble min_spacing;       /* minimum centre distance, m (default 4*radius);
                                  never less than the sum of the two radii */
    gdouble roughness_rms;     /* substrate RMS roughness, m (default 0.3e-9) */
    gdouble roughness_corr;    /* substrate Gaussian correlation length T, m,
                                  ACF = rms^2 exp(-r^2/T^2) (default 50e-9) */
} SimParticleParams;

/* Fills params with the defaults above. */
void        sim_particle_params_init     (SimParticleParams *params);

/* Particles are placed by random sequential addition, centres at least one
 * radius from the field edges.  When the field cannot hold `count` particles
 * with the spacing asked for, fewer are placed (sim_sample_n_particles says
 * how many).  A particle rests on the substrate: its centre lies at height
 * radius + substrate(centre).  Same params and seed, same sample.  Returns
 * NULL (with a g_warning) for non-positive sizes or radius. */
SimSample*  sim_sample_new_particles     (const SimParticleParams *params,
                                          guint32 seed);

/* A measured image used as the sample.  The data are copied (field may be
 * freed afterwards); pixel (row i, col j) is the height at
 * ((j + 0.5) dx, (i + 0.5) dy); the field's offsets are ignored.  Heights
 * between pixels come from an interpolating cubic B-spline. */
SimSample*  sim_sample_new_from_field    (GwyDataField *field);

void        sim_sample_free              (SimSample *sample);

/* Height at (x, y), metres, as a perfectly sharp tip would see it. */
gdouble     sim_sample_height            (const SimSample *sample,
                                          gdouble x_m,
                                          gdouble y_m);

/* Height at (x, y) recorded by a spherical tip of radius tip_radius (the
 * position of the tip apex; tip_radius <= 0 is the sharp tip).  Spheres are
 * dilated analytically; the synthetic substrate is taken as undilated, its
 * curvature radius being far larger than any tip's.  A measured sample is
 * grey-scale dilated on its pixel grid (cached for the last tip radius). */
gdouble     sim_sample_height_tip        (const SimSample *sample,
                                          gdouble tip_radius,
                                          gdouble x_m,
                                          gdouble y_m);

/* The same for n points at once (x[k], y[k]) -> z[k]: what a scan uses. */
void        sim_sample_heights_tip       (const SimSample *sample,
                                          gdouble tip_radius,
                                          gint n,
                                          const gdouble *x_m,
                                          const gdouble *y_m,
                                          gdouble *z);

/* Synthetic particles; 0 for a measured sample. */
gint        sim_sample_n_particles       (const SimSample *sample);
/* Centre (x, y) and radius r of particle i, metres; any pointer may be NULL. */
void        sim_sample_particle          (const SimSample *sample,
                                          gint i,
                                          gdouble *x,
                                          gdouble *y,
                                          gdouble *r);
/* Height of particle i's centre (its radius + the substrate below it). */
gdouble     sim_sample_particle_centre_z (const SimSample *sample,
                                          gint i);

void        sim_sample_get_extent        (const SimSample *sample,
                                          gdouble *xreal,
                                          gdouble *yreal);

G_END_DECLS

#endif
