/*
 *  Stripes matched on the fringe of a feature beyond them
 *  (stripe-fringe.h).
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <math.h>
#include "stripe-fringe.h"
#include "stripe-geometry.h"

/* A stripe's lines show little of their own where their texture stays
 * below this many times the pixel noise (featureless lines of the
 * simulator's series read 3 to 4 times it: the noise estimate from
 * neighbouring pixels reads noise correlated along the lines low) ... */
#define WEAK_TEXTURE 8.0
/* ... and what they show comes from beyond them where a line within the
 * filters' reach beyond them stands this many times above them (200 to
 * 300 times for the particle's fringe of seed 20000037 below; lines of
 * one fine texture differ by a few times at most).  Not against the
 * noise: a fine texture raises the noise estimate too. */
#define FRINGE_CONTRAST 16.0

void
line_textures_init(LineTextures *textures, const ConditionedFrame *levelled)
{
    textures->variance = conditioned_frame_line_variances(levelled);
    textures->yres = levelled->yres;
    textures->noise_var = conditioned_frame_pixel_noise(levelled);
}

void
line_textures_clear(LineTextures *textures)
{
    g_free(textures->variance);
    textures->variance = NULL;
}

/* The largest texture of lines lo .. hi-1 within the frame. */
static gdouble
largest_texture(const LineTextures *textures, gint lo, gint hi)
{
    gdouble largest = 0.0;
    gint r;

    for (r = MAX(lo, 0); r < MIN(hi, textures->yres); r++) {
        if (textures->variance[r] > largest)
            largest = textures->variance[r];
    }
    return largest;
}

/* Stripes whose lines that take part in the match (those beyond the
 * filters' reach of the frame's edge) show nothing, while a line within
 * that reach beyond them shows a feature: the narrow blur carries the
 * feature's fringe into the stripe, and a fringe matches its counterpart
 * with a high correlation but a poorly held shift across the lines (an
 * exponential tail shifted is the same tail scaled).  Such a stripe is not
 * measured.  A series' frame whose first lines were featureless but for a
 * particle just below, and for one cut by the frame's edge, read the
 * start of a fast settling 0.4 px off in every pair alike, with
 * correlations of 0.99 (test-series-correction seed 20000037, case 11).
 * Featureless lines beside featureless lines are left to the correlation
 * (white noise scores low), and so are fine textures whose lines all look
 * alike, which the pixel noise estimate takes for noise.
 *
 * Whether lines lo .. hi-1 of frame (those beyond reach of its edge) show
 * nothing while a line within reach beyond them shows a feature. */
static gboolean
lines_on_fringe(const LineTextures *frame, gint lo, gint hi, gint reach)
{
    gint yres = frame->yres;
    gdouble own, near;

    lo = MAX(lo, reach);
    hi = MIN(hi, yres - reach);
    /* Lines within the reach of the frame's edge have no lines of their
     * own to judge by. */
    if (lo >= hi)
        return FALSE;
    own = largest_texture(frame, lo, hi);
    near = MAX(largest_texture(frame, lo - reach, lo), largest_texture(frame, hi, hi + reach));
    return own <= WEAK_TEXTURE*frame->noise_var && near > FRINGE_CONTRAST*own;
}

/* Either frame of the pair: the stripe matched on the fringe of one
 * frame reads the shift as poorly as on both.  A series' frame 0 whose
 * first lines showed a particle cut by the frame's edge, and whose third
 * line missed its rim by a few hundredths of a pixel where the other
 * frames' caught it, read 0.5 px off as the reference of every pair
 * (test-series-correction seed 62000021, case 10). */
void
stripe_fringe_reject(const LineTextures *image, const LineTextures *reference, gint n, gint reach,
                     StripeShift *shifts)
{
    gint yres = image->yres, s, lo, hi, rlo, rhi, widened;
    gdouble dy;

    for (s = 0; s < n; s++) {
        if (!shifts[s].accepted)
            continue;
        lo = stripe_first_row(s, n, yres);
        hi = stripe_end_row(s, n, yres);
        /* The reference's own lines are those wholly under the stripe's
         * lines shifted back (a line partly under them lends the stripe
         * its content through the interpolation, as one beside does
         * through the blur), for any shift within half a pixel of the
         * one measured where that leaves more than half of the stripe's
         * lines, a line more then being within reach beside them: a
         * match on a fringe misreads its shift (0.4 px in a synthetic
         * draw, test-stripe-registration seed 69000268, which brought a
         * line of the feature among those judged).  Blocks of four
         * lines keep the measured shift: judged on two lines, three
         * frames of 64 lines with sparse particles used 26 of their 48
         * blocks instead of 35. */
        dy = shifts[s].dy;
        if (!isfinite(dy))
            continue;
        rlo = (gint)ceil(lo - dy + 0.5);
        rhi = (gint)floor(hi - 1 - dy - 0.5) + 1;
        widened = reach + 1;
        if (2*(rhi - rlo) <= hi - lo) {
            rlo = (gint)ceil(lo - dy);
            rhi = (gint)floor(hi - 1 - dy) + 1;
            widened = reach;
        }
        if (lines_on_fringe(image, lo, hi, reach) || lines_on_fringe(reference, rlo, rhi, widened)) {
            shifts[s].accepted = FALSE;
            g_debug("registration: stripe %d: matched on a fringe only", s);
        }
    }
}
