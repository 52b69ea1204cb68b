/*
 *  One drift measurement: a displacement of the sample between two moments,
 *  the quantity every drift source gives and every drift fit consumes.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_DRIFT_MEASUREMENT_H
#define LOCALSCAN_DRIFT_MEASUREMENT_H

#include <glib.h>

G_BEGIN_DECLS

/*
 * Content seen at time t_b was seen displaced by (dx, dy) at time t_a, so
 *     (dx, dy) = p(t_a) - p(t_b)
 * for the drift trajectory p (a feature truly at X appears at X + p(t)).
 * A local scan gives t_a = when the image showed the particle and t_b =
 * when the local scan found it (drift-trajectory.h, pixels); a registered
 * block of two frames gives t_a, t_b = when the block was scanned in the
 * later and the earlier frame (drift-fit.h, metres).  The constant p0
 * cancels.  weight and group matter to the fit only; the trajectory treats
 * every measurement alike.  The field order keeps { t_a, t_b, dx, dy }
 * initialisers valid.  A block of lines registered as a whole moves by the
 * drift averaged over the time it took to scan: span says how long, and
 * the fit compares it with the model averaged alike (an oscillation read
 * at points would come out too small by the sinc of its phase over the
 * block).
 */
typedef struct {
    gdouble t_a, t_b;      /* s */
    gdouble dx, dy;        /* px or m, as the consumer states */
    gdouble weight;        /* >= 0, relative confidence (0 = ignore) */
    gint group;            /* unit held out together in cross-validation */
    gint frame_a, frame_b; /* frames the times belong to (informative) */
    gdouble span;          /* s, the measurement averages the displacement
                              over [t - span/2, t + span/2] around t_a and
                              t_b (a registered block of lines); 0: at the
                              moments themselves */
} DriftMeasurement;

G_END_DECLS

#endif
