/*
 *  Finding particles in a (drift-contaminated) image: threshold above the
 *  substrate, grain numbering, weighted centres; and choosing one particle
 *  per stripe by the paper's rule (shared/spec/paper-mode.md).
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef SIMSCAN_PARTICLE_DETECT_H
#define SIMSCAN_PARTICLE_DETECT_H

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
} DetectedParticle;

typedef struct {
    gdouble height;        /* threshold above the substrate, z units;
                              <= 0: half way from substrate to image maximum */
    gint min_area;         /* smaller grains are dropped (px) */
    gint max_area;         /* larger grains are dropped (px); <= 0: no limit */
} ParticleDetectParams;

void        particle_detect_params_init  (ParticleDetectParams *params);

/* The substrate level: the median of the image (particles cover little). */
gdouble     particle_detect_substrate    (GwyDataField *field);

/* Returns a GArray of DetectedParticle, in grain-number order (top to
 * bottom, left to right).  The centre is the centroid of the grain's pixels
 * weighted by their height above the threshold, which is far less sensitive
 * to the pixel grid than the plain centroid of a small grain. */
GArray*     particle_detect              (GwyDataField *field,
                                          const ParticleDetectParams *params,
                                          gdouble *substrate,
                                          gdouble *threshold);

/* How a stripe with several particles picks the one to local-scan. */
typedef enum {
    /* The paper's rule (shared/spec/paper-mode.md): the particle whose
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
