/*
 *  Raw-channel artefacts for simulated frames.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef SIMSCAN_RAW_ARTEFACTS_H
#define SIMSCAN_RAW_ARTEFACTS_H

#include <glib.h>

G_BEGIN_DECLS

/* A standard normal deviate drawn from rng (two draws). */
gdouble  sim_raw_gaussian        (GRand *rng);
/* What raw instrument channels carry on top of the sample, drawn from rng:
 * a plane, an offset on every scan line, a bow along x and 1/f noise in
 * scan time (line offsets wandering from line to line), of about the given
 * size (the data's own unit). */
void     sim_raw_artefacts_add   (gdouble *data, gint xres, gint yres,
                                  gdouble size, GRand *rng);
/* A separable 1/f pattern fixed to the frame, over every octave (rms about
 * 0.3 size): frame-fixed texture no conditioning can tell from the
 * sample's. */
void     sim_raw_undulation_add  (gdouble *data, gint xres, gint yres,
                                  gdouble size, GRand *rng);

G_END_DECLS

#endif
