/*
 *  Synthetic frame pairs for the stripe registration: one analytic surface
 *  sampled as a drift-free reference and as a drifting image.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_REGISTRATION_FRAMES_H
#define LOCALSCAN_REGISTRATION_FRAMES_H

#include <glib.h>

G_BEGIN_DECLS

typedef struct {
    gint xres;
    gint yres;
    gdouble noise;            /* white noise rms per frame (particle height ~1) */
    gdouble particle_density; /* Gaussian bumps per px^2 */
    gdouble roughness;        /* rms of the correlated roughness */
    gdouble lattice;          /* amplitude of a periodic lattice, 0 for none */
    gdouble lattice_period;   /* px */
    gdouble grating;          /* amplitude of lines along y (varying along
                                 x only, lattice_period apart), 0: none */
    gint flat_from;           /* rows [flat_from, flat_to) of the surface are */
    gint flat_to;             /* flat (only noise); flat_to <= flat_from: none */
    gboolean drift;           /* random smooth drift; FALSE: linear drift */
    gdouble drift_scale;      /* multiplies the random drift (1: up to ~10 px) */
    gdouble shift_x;          /* the linear drift when !drift: */
    gdouble shift_y;          /* shift + velocity*row */
    gdouble velocity_x;       /* px per row */
    gdouble velocity_y;
    gint jump_row;            /* with the linear drift, rows from this one on */
    gdouble jump_x;           /* are moved by (jump_x, jump_y) more; */
    gdouble jump_y;           /* jump_row < 0: no jump */
} FramePairSpec;

typedef struct {
    gint xres;
    gint yres;
    gdouble *reference;       /* yres x xres, row-major */
    gdouble *image;
    gdouble *row_dx;          /* yres: the true drift of each image row */
    gdouble *row_dy;
} FramePair;

/* Defaults: 256 x 256, noise 0.05, roughness 0.15, random drift of scale 1. */
void        frame_pair_spec_init   (FramePairSpec *spec);

/* The reference is the surface z(x, y) at pixel (r, c) = z(c, r); the image
 * row r is scanned with the drift p(r) and shows z(c - dx(r), r - dy(r)), so
 * reference content at (r, c) appears in the image at (r + dy, c + dx). */
FramePair*  frame_pair_generate    (const FramePairSpec *spec, guint32 seed);
void        frame_pair_free        (FramePair *pair);

/* What raw instrument channels carry on top of the sample, drawn anew for
 * each frame: a plane, an offset on every scan line, a bow along x and 1/f
 * noise in scan time (line offsets wandering from line to line), of the
 * given size relative to the particles' heights (~1). */
void        frame_pair_add_raw_artefacts(FramePair *pair, gdouble size,
                                         guint32 seed);
/* The same artefacts on one frame (size in the data's own unit). */
void        frame_add_raw_artefacts(gdouble *data, gint xres, gint yres,
                                    gdouble size, guint32 seed);
/* A separable 1/f pattern fixed to each frame, over every octave (rms
 * about 0.3 size): frame-fixed texture no conditioning can tell from the
 * sample's. */
void        frame_pair_add_undulation(FramePair *pair, gdouble size,
                                      guint32 seed);

/* The true drift of each of n stripes: the mean over its rows. */
void        frame_pair_stripe_truth(const FramePair *pair, gint n,
                                    gdouble *dx, gdouble *dy);

/* The true drift at each of n stripes' centre rows, (first + last)/2,
 * between two rows for an even height: what a registered stripe's shift
 * stands for (StripeShift), the mean only where the drift changes
 * linearly over the stripe. */
void        frame_pair_stripe_centre_truth(const FramePair *pair, gint n,
                                           gdouble *dx, gdouble *dy);

/* The seed of a test: LOCALSCAN_TEST_SEED if set, else a fresh one; printed. */
guint32     frame_pair_test_seed   (const gchar *program);

G_END_DECLS

#endif
