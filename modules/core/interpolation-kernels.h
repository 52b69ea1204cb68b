/*
 *  Tap weights of Gwyddion's interpolation kernels (GwyInterpolationType),
 *  for resampling loops that compute them inline.  Internal to the core.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_INTERPOLATION_KERNELS_H
#define LOCALSCAN_INTERPOLATION_KERNELS_H

#include <glib.h>
#include <libprocess/gwyprocessenums.h>

G_BEGIN_DECLS

/*
 * The weights are Gwyddion's (libprocess/interpolation.c), and so is the
 * edge rule: values are extended by mirroring with the border value
 * repeated, which gwy_interpolation_resolve_coeffs_1d() also assumes for
 * B-spline and o-MOMS.  They are written out here, not taken from
 * gwy_interpolation_get_dval(), so that a row's weights are computed inline
 * in loops specialised per kernel, without a call per pixel.
 */

/* Forced inlining: the switch on the kernel type folds away only where a
 * weight function is inlined into the loop specialised for one kernel,
 * which is too important for speed to leave to GCC's size heuristics. */
#if defined(__GNUC__)
#define KERNEL_INLINE static inline __attribute__((always_inline))
#else
#define KERNEL_INLINE static inline
#endif

/* Every kernel reads at most four taps, i-1 .. i+2 around x = i + frac. */
enum { KERNEL_TAPS = 4 };

gboolean kernel_needs_prefilter(GwyInterpolationType type,
                                gdouble *centre,
                                gdouble *side);

static inline gdouble
keys_inner(gdouble d)
{
    return (1.5*d - 2.5)*d*d + 1.0;
}

static inline gdouble
keys_outer(gdouble d)
{
    return d*(-0.5 + d*(1.0 - 0.5*d));
}

static inline gdouble
omoms_inner(gdouble d)
{
    return 13.0/21.0 + d*(1.0/14.0 + d*(-1.0 + 0.5*d));
}

static inline gdouble
omoms_outer(gdouble d)
{
    return 4.0/21.0 + d*(-11.0/21.0 + d*(0.5 - d*(1.0/6.0)));
}

/* Exactly half way Gwyddion takes both neighbours by half. */
KERNEL_INLINE void
round_weights(gdouble x, gdouble *w)
{
    w[0] = w[3] = 0.0;
    w[1] = (x < 0.5) ? 1.0 : (x > 0.5 ? 0.0 : 0.5);
    w[2] = 1.0 - w[1];
}

KERNEL_INLINE void
linear_weights(gdouble x, gdouble y, gdouble *w)
{
    w[0] = w[3] = 0.0;
    w[1] = y;
    w[2] = x;
}

KERNEL_INLINE void
keys_weights(gdouble x, gdouble y, gdouble *w)
{
    w[0] = keys_outer(x);
    w[1] = keys_inner(x);
    w[2] = keys_inner(y);
    w[3] = keys_outer(y);
}

/* Cubic Lagrange polynomials through the nodes -1, 0, 1, 2. */
KERNEL_INLINE void
schaum_weights(gdouble x, gdouble y, gdouble *w)
{
    w[0] = x*y*(x - 2.0)*(1.0/6.0);
    w[1] = (x + 1.0)*y*(2.0 - x)*0.5;
    w[2] = (x + 1.0)*x*(2.0 - x)*0.5;
    w[3] = -(x + 1.0)*x*y*(1.0/6.0);
}

KERNEL_INLINE void
bspline_weights(gdouble x, gdouble y, gdouble *w)
{
    w[0] = y*y*y*(1.0/6.0);
    w[1] = 2.0/3.0 - x*x*(1.0 - 0.5*x);
    w[2] = 2.0/3.0 - y*y*(1.0 - 0.5*y);
    w[3] = x*x*x*(1.0/6.0);
}

KERNEL_INLINE void
omoms_weights(gdouble x, gdouble y, gdouble *w)
{
    w[0] = omoms_outer(x);
    w[1] = omoms_inner(x);
    w[2] = omoms_inner(y);
    w[3] = omoms_outer(y);
}

/* Inverse fourth powers of the distances 1+x, x, y, 1+y, each multiplied
 * by the product of all four fourth powers: one division, and x = 0 needs
 * no branch (only w[1] is nonzero). */
KERNEL_INLINE void
nna_weights(gdouble x, gdouble y, gdouble *w)
{
    gdouble s, d0, d1, d2, d3;

    d0 = (1.0 + x)*(1.0 + x);
    d1 = x*x;
    d2 = y*y;
    d3 = (1.0 + y)*(1.0 + y);
    d0 *= d0;
    d1 *= d1;
    d2 *= d2;
    d3 *= d3;
    w[0] = d1*d2*d3;
    w[1] = d0*d2*d3;
    w[2] = d0*d1*d3;
    w[3] = d0*d1*d2;
    s = 1.0/(w[0] + w[1] + w[2] + w[3]);
    w[0] *= s;
    w[1] *= s;
    w[2] *= s;
    w[3] *= s;
}

/* Weights of the taps at i-1, i, i+1, i+2 for the position i + x,
 * 0 <= x < 1.  Two-point kernels leave the outer taps at zero. */
KERNEL_INLINE void
kernel_weights(GwyInterpolationType type, gdouble x, gdouble *w)
{
    gdouble y = 1.0 - x;

    switch (type) {
        case GWY_INTERPOLATION_ROUND:
        round_weights(x, w);
        break;

        case GWY_INTERPOLATION_LINEAR:
        linear_weights(x, y, w);
        break;

        case GWY_INTERPOLATION_KEY:
        keys_weights(x, y, w);
        break;

        case GWY_INTERPOLATION_SCHAUM:
        schaum_weights(x, y, w);
        break;

        case GWY_INTERPOLATION_BSPLINE:
        bspline_weights(x, y, w);
        break;

        case GWY_INTERPOLATION_OMOMS:
        omoms_weights(x, y, w);
        break;

        case GWY_INTERPOLATION_NNA:
        nna_weights(x, y, w);
        break;

        default:
        g_assert_not_reached();
        break;
    }
}

static inline gboolean
kernel_has_two_taps(GwyInterpolationType type)
{
    return type == GWY_INTERPOLATION_ROUND || type == GWY_INTERPOLATION_LINEAR;
}

/* The value from taps s[-1] .. s[2] with weights w; two-tap kernels read
 * only s[0] and s[1]. */
KERNEL_INLINE gdouble
kernel_apply(GwyInterpolationType type, const gdouble *s, const gdouble *w)
{
    if (kernel_has_two_taps(type))
        return w[1]*s[0] + w[2]*s[1];
    return w[0]*s[-1] + w[1]*s[0] + w[2]*s[1] + w[3]*s[2];
}

/* The tap i at or below position x (x > -1) and the offset x - i.  Not a
 * plain cast, which would take -0.5 to tap 0. */
static inline gint
kernel_tap_below(gdouble x, gdouble *frac)
{
    gint i = (gint)(x + 1.0) - 1;

    *frac = x - i;
    return i;
}

/* Index into n values extended by mirroring with the border value
 * repeated: -1 -> 0, -2 -> 1, n -> n-1. */
static inline gint
kernel_mirror_index(gint i, gint n)
{
    while (i < 0 || i >= n) {
        if (i < 0)
            i = -1 - i;
        else
            i = 2*n - 1 - i;
    }
    return i;
}

G_END_DECLS

#endif
