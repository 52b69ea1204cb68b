/*
 *  Tap weights of Gwyddion's interpolation kernels: the parts not needed
 *  inline.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include "interpolation-kernels.h"

/* B-spline and o-MOMS interpolate coefficients, not the data: the values
 * at the nodes are centre c[i] + side (c[i-1] + c[i+1]), the kernel at 0
 * and at +-1, so the coefficients solve that tridiagonal system.  FALSE
 * for the kernels that interpolate the data directly. */
gboolean
kernel_needs_prefilter(GwyInterpolationType type, gdouble *centre,
                       gdouble *side)
{
    if (type == GWY_INTERPOLATION_BSPLINE) {
        *centre = 2.0/3.0;
        *side = 1.0/6.0;
        return TRUE;
    }
    if (type == GWY_INTERPOLATION_OMOMS) {
        *centre = 13.0/21.0;
        *side = 4.0/21.0;
        return TRUE;
    }
    return FALSE;
}
