/*
 *  Finding particles in a (drift-contaminated) image: a levelled copy,
 *  threshold above the substrate, grain numbering, weighted centres, typical
 *  size; and choosing one particle per stripe by the paper's rule
 *  (docs/paper-mode.md).
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_PARTICLE_DETECT_H
#define LOCALSCAN_PARTICLE_DETECT_H

#include <glib.h>
#include <libprocess/datafield.h>

G_BEGIN_DECLS

/* Pixel coordinates: column x, row y, pixel centres at whole numbers. */
typedef struct {
    gdouble x;             /* centre column, px */
    gdouble y;             /* centre row, px */
    gint area;             /* pixels above the threshold */
    gdouble peak;          /* highest value in the grain, z units */
    gboolean on_edge;      /* the grain touches the image border */
    gint row_min;          /* first and last row of the grain */
    gint row_max;
    gint top_area;         /* pixels above three quarters of its height
                              over the substrate, where the local scan cuts
                              it by default */
} DetectedParticle;

typedef struct {
    gdouble height;        /* threshold above the substrate, z units; <= 0:
                              automatic (see particle_detect_auto_height) */
    gint min_area;         /* smaller grains are dropped (px) */
    gint max_area;         /* larger grains are dropped (px); <= 0: no limit */
    gboolean level;        /* find grains on a levelled copy (a measured
                              image's tilt and line offsets) */
} ParticleDetectParams;

/* Automatic threshold, levelling on, no area limits. */
void        particle_detect_params_init  (ParticleDetectParams *params);

/* A copy of field with a plane and then each row's median subtracted, both
 * fitted to the pixels off the particles, so the substrate lies at 0. */
GwyDataField* particle_detect_level      (GwyDataField *field);

/* The substrate's noise: the median absolute deviation of field from
 * median, scaled to a Gaussian's standard deviation. */
gdouble     particle_detect_noise        (GwyDataField *field,
                                          gdouble median);

/* The automatic threshold above the substrate.  On a levelled field: ten
 * times the noise and at least a tenth of the highest particle, so a film of
 * real particles of mixed heights is found whole, not only its tallest
 * ones.  Without levelling (the old rule): half way from the substrate to
 * the maximum. */
gdouble     particle_detect_auto_height  (GwyDataField *field,
                                          gdouble substrate,
                                          gboolean levelled);

/* The substrate level: the median of the image (particles cover little). */
gdouble     particle_detect_substrate    (GwyDataField *field);

/* Returns a GArray of DetectedParticle, in grain-number order (top to
 * bottom, left to right).  The centre: starting from the centroid of the
 * grain's pixels weighted by their height above the threshold, the centroid
 * of the pixels within two equivalent radii (sqrt(area/pi)) of it, weighted
 * by their height above the substrate, with the window moved to it five
 * times.  The thresholded centroid alone snaps towards pixel centres.  With
 * params->level the grains are found on particle_detect_level()'s copy;
 * substrate, threshold and each peak are in field's own z values all the
 * same (the levelled substrate put at field's median). */
GArray*     particle_detect              (GwyDataField *field,
                                          const ParticleDetectParams *params,
                                          gdouble *substrate,
                                          gdouble *threshold);

/* The typical particle radius for the local scans, m: the lower quartile
 * over the particles of the radius of the sphere whose cut at three
 * quarters of its height is as large as the particle's top_area (pixel size
 * dx by dy); 0 without particles.  For equal spheres it is their radius.  A
 * real particle is more peaked than a sphere: measured by its top it comes
 * out smaller than its half-height width, so the local scans' search, which
 * moves its line by 1.5 radii, does not step over the top that its chords
 * need, on the smaller particles either. */
gdouble     particle_typical_radius      (const GArray *particles,
                                          gdouble dx,
                                          gdouble dy);

/* How a stripe with several particles picks the one to local-scan. */
typedef enum {
    /* The paper's rule (docs/paper-mode.md): the particle whose
     * centre lies closest to the stripe's centre point
     * ((xres-1)/2, (first_row+last_row)/2), Euclidean distance in px. */
    PARTICLE_CHOICE_CLOSEST = 0,
    /* A deviation from the paper, opt-in: particles clear of the stripe's
     * first and last rows go first, closest to the centre among them.  A
     * grain cut by a stripe boundary may be a fragment sheared by the two
     * stripes' different shifts, whose centre is then off by a pixel. */
    PARTICLE_CHOICE_PREFER_WHOLE,
} ParticleChoice;

/* For each of the n stripes, the index of the particle (not touching the
 * image border) whose rounded centre row lies in the stripe, chosen by
 * choice; -1 for a stripe without one.  On equal distances the particle
 * earlier in the array wins.  chosen gets n values. */
void        particle_choose_for_stripes_by (const GArray *particles,
                                            gint n,
                                            gint xres,
                                            gint yres,
                                            ParticleChoice choice,
                                            gint *chosen);

/* Whether the grain reaches stripe s's first or last row, so that a stripe
 * boundary may have cut it. */
gboolean    particle_touches_stripe_boundary (const DetectedParticle *particle,
                                              gint s,
                                              gint n,
                                              gint yres);

/* The paper's rule: particle_choose_for_stripes_by() with
 * PARTICLE_CHOICE_CLOSEST. */
void        particle_choose_for_stripes  (const GArray *particles,
                                          gint n,
                                          gint xres,
                                          gint yres,
                                          gint *chosen);

G_END_DECLS

#endif
