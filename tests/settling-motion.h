/*
 *  A known drift for the continuous-mode tests: p(t) = p0 + v t
 *  + u tau (1 - exp(-t/tau)), constant velocity plus settling
 *  (docs/conventions.md), in px and s.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_SETTLING_MOTION_H
#define LOCALSCAN_SETTLING_MOTION_H

#include <math.h>
#include <glib.h>

typedef struct {
    gdouble p0[2];
    gdouble v[2];
    gdouble u[2];
    gdouble tau;            /* no settling when 0 */
} Motion;

static inline void
motion_eval(const Motion *motion, gdouble t, gdouble *p)
{
    gint k;

    for (k = 0; k < 2; k++) {
        p[k] = motion->p0[k] + motion->v[k]*t;
        if (motion->tau > 0.0)
            p[k] += motion->u[k]*motion->tau*(1.0 - exp(-t/motion->tau));
    }
}

#endif
