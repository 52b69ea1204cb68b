/*
 *  Drift measured from the data: each stripe of an image registered against
 *  a reference frame of the same area, coarse to fine.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <math.h>
#include <string.h>
#include <libgwyddion/gwymacros.h>
#include <libgwyddion/gwymath.h>
#include "stripe-registration.h"
#include "parallel-run.h"
#include "stripe-correlation.h"
#include "stripe-geometry.h"
#include "stripe-fringe.h"
#include "stripe-subpixel.h"
#include "registration-binning.h"
#include "localscan-intl.h"
#include "median.h"
#include "missing-data.h"

/*
 * How it works (docs/registration.md tells it with figures).
 *
 * Both frames are conditioned first (frame-conditioning.c): raw channels'
 * line offsets, bows and 1/f noise would otherwise decide the match.
 *
 * Then coarse to fine, because a frame may be offset by a third of its size
 * and a full-resolution search over such shifts costs far too much:
 *
 * 1. The whole frame's shift, at a resolution of about COARSE_SIZE px,
 *    searched over every shift that keeps half of the frame on the
 *    reference (or what the caller bounds).
 * 2. Bands of rows at that resolution, each searched around the whole
 *    frame's shift within BAND_REACH of the frame: the drift changes while
 *    the frame is scanned.  A band whose own peak is not clearly the best
 *    takes the best peak near its confident neighbours' median.
 * 3. Every stripe at full resolution, around its band's shift (interpolated
 *    between band centres) within the coarse stage's uncertainty plus room
 *    for a jump.  Each stripe is judged on its own there: a jump of a few
 *    pixels between two stripes is measured, not smoothed away.
 *
 * A stripe's shift is located to a fraction of a pixel by matching it
 * against the interpolated reference (stripe-subpixel.c), which also gives
 * its uncertainty.  Confidence comes from the peak height and from how far
 * the best competing peak in the stripe's window stays below it, so
 * periodic textures and featureless stripes score low and are left empty
 * (the nearest-stripe rule fills them).
 */

/* Competing peaks closer than this (px, in both axes) are the main peak's. */
#define RIVAL_EXCLUSION 3
/* Half-size of the window searched around the neighbours' prediction (px). */
#define CONSISTENCY_RADIUS 3
/* Neighbours on each side whose median predicts a band; the far reach is
 * used where the near one has too few confident bands. */
#define NEAR_REACH 2
#define FAR_REACH 4
/* Fraction of the width tapered by the Tukey window of the sub-pixel match
 * at each side. */
#define WINDOW_TAPER 0.1
/* Correlation peaks below this are hardly above chance for a stripe. */
#define LOW_PEAK 0.3
/* The whole frame at coarse resolution is trusted from this score: its
 * peak stands out of far more pixels than a stripe's, so a lower margin
 * over its rival is already decisive. */
#define GLOBAL_MIN_SCORE 0.1
/* Bands this confident keep their own peak and predict their neighbours. */
#define RELIABLE_SCORE 0.3
/* How far (px) the match may move a peak that lies on the edge of the
 * shifts with enough overlap; a peak inside them moves at most 1 px.  On
 * the edge row itself the true peak may lie a few px along x. */
#define EDGE_POLISH_REACH 3
/* How far (px) the sub-pixel match may move a stripe from its map peak:
 * where the frames correlate weakly the map's peak and the match's optimum
 * can lie more than a pixel apart. */
#define POLISH_REACH 3
/* A fine match is accepted only with a standard uncertainty below this
 * fraction of its search radius. */
#define LOCATED_FRACTION 0.25
/* The least fraction of a stripe, or of the whole frame, that must lie on
 * the reference at a shift considered. */
#define STRIPE_MIN_OVERLAP 0.5
#define WHOLE_FRAME_MIN_OVERLAP 0.25
/* The coarse stage works at about this many px along the longer side. */
#define COARSE_SIZE 160
/* Coarse bands have about this many rows. */
#define BAND_ROWS 12
/* How far (fraction of the frame) a band's shift may differ from the
 * whole frame's. */
#define BAND_REACH 0.12
/* The fine search reaches this far (px) beyond the coarse stage's
 * resolution around a stripe's predicted shift: room for a jump between
 * stripes that a band straddles. */
#define FINE_MIN_RADIUS 10
/* A stripe lies in the reference when at least this fraction of it is on
 * the reference at its predicted shift. */
#define IN_REFERENCE_FRACTION 0.5

typedef struct {
    gint ky, kx;          /* whole-pixel shift of the peak */
    gdouble dy, dx;       /* refined shift, px */
    gdouble value;        /* ZNCC at the peak */
    gdouble rival;        /* best competing local maximum, >= 0 */
    gdouble sigma;        /* px, from the sub-pixel match; 0 without */
    gdouble row;          /* the image row whose shift dy, dx are (the
                             stripe's centre row unless the match says
                             otherwise) */
    gboolean trusted;     /* found, inside the search area, refinable */
    gboolean polished;    /* dy, dx refined by stripe_subpixel_refine() */
    gint ylo, yhi;        /* the shifts searched */
    gint xlo, xhi;
} Peak;

/* One resolution: n stripes (or bands) of the frames, with their maps. */
typedef struct {
    const ConditionedFrame *image;
    const ConditionedFrame *reference;
    gint n;
    StripeCorrelation *correlation;
    StripeCorrelationMap *maps;   /* n */
    gdouble *window;              /* xres, for the sub-pixel match */
    StripeSubpixel *subpixel;     /* NULL: no sub-pixel match */
    StripeSubpixel *subpixel_band;/* the same on the band-passed frames */
    gboolean uncertainty;         /* the sub-pixel match's sigma wanted */
} Level;

/* How far a stripe's shift is refined beyond its map's whole-pixel peak:
 * by a quadratic through the map, or by matching the stripe against the
 * interpolated reference, with or without the match's uncertainty (which
 * costs more than the match: a series that weighs its blocks by their
 * correlation has no use for it). */
typedef enum {
    REFINE_QUADRATIC,
    REFINE_MATCH,
    REFINE_MATCH_SIGMA,
} Refinement;

G_DEFINE_QUARK(stripe-registration-error-quark, stripe_registration_error)

void
stripe_registration_options_init(StripeRegistrationOptions *options)
{
    options->search_x = options->search_y = 0.0;
    options->min_score = STRIPE_REGISTRATION_DEFAULT_MIN_SCORE;
    options->pixel_aspect = 1.0;
    options->image_mask = options->reference_mask = NULL;
    options->masking = GWY_MASK_IGNORE;
}

static gint
nearest_int(gdouble x)
{
    return (gint)floor(x + 0.5);
}

static void
make_tukey_window(gdouble *window, gint res)
{
    gint taper = (gint)ceil(WINDOW_TAPER*res), j;

    for (j = 0; j < res; j++) {
        gint edge = MIN(j, res-1 - j);

        window[j] = (edge >= taper) ? 1.0 : 0.5*(1.0 - cos(G_PI*(edge + 0.5)/taper));
    }
}

static gint
level_max_height(gint n, gint yres)
{
    gint s, h = 1;

    for (s = 0; s < n; s++)
        h = MAX(h, stripe_end_row(s, n, yres) - stripe_first_row(s, n, yres));
    return h;
}

/* The reference's validity for the sub-pixel match; NULL when every
 * pixel is valid (no check needed). */
static const gdouble*
reference_validity(const ConditionedFrame *reference)
{
    return (reference->valid_fraction >= 1.0) ? NULL : reference->weight;
}

static gint
edge_margin(const ConditionedFrame *frame)
{
    return (gint)ceil(2.0*frame->narrow_sigma);
}

/* Maps of image against reference; with sub_image and sub_reference (may
 * be NULL) a sub-pixel match on their levelled frames, and failing that on
 * their band-passed ones. */
static void
level_init(Level *level, const ConditionedFrame *image, const ConditionedFrame *reference,
           const ConditionedFrame *sub_image, const ConditionedFrame *sub_reference, gint n,
           gint max_ry, gint max_rx)
{
    gint s, h = level_max_height(n, image->yres);

    gwy_clear(level, 1);
    level->image = image;
    level->reference = reference;
    level->n = n;
    /* The whole frame holds so much more than a stripe that a third of it
     * on the reference still matches surely: frames offset by a third
     * of their size in both axes overlap by less than half. */
    level->correlation = stripe_correlation_new(image, reference, h, max_ry, max_rx,
                                                (n == 1) ? WHOLE_FRAME_MIN_OVERLAP : STRIPE_MIN_OVERLAP);
    level->maps = g_new0(StripeCorrelationMap, n);
    for (s = 0; s < n; s++)
        level->maps[s].values = g_new(gdouble, (gsize)(2*max_ry + 1)*(2*max_rx + 1));
    if (sub_image && sub_reference) {
        image = sub_image;
        reference = sub_reference;
        level->window = g_new(gdouble, image->xres);
        make_tukey_window(level->window, image->xres);
        /* The levelled frames keep exact shifts exact up to the frames'
         * edges, where the band-pass cannot. */
        level->subpixel = stripe_subpixel_new(image->levelled ? image->levelled : image->data,
                                              reference->levelled ? reference->levelled : reference->data,
                                              image->weight, reference_validity(reference),
                                              image->xres, image->yres, level->window, h,
                                              edge_margin(image));
        /* Where pixel noise or what differs between the frames beyond the
         * sample outweighs the features, only the band-passed frames
         * match. */
        if (image->levelled && reference->levelled)
            level->subpixel_band = stripe_subpixel_new(image->data, reference->data, image->weight,
                                                       reference_validity(reference),
                                                       image->xres, image->yres, level->window, h,
                                                       edge_margin(image));
    }
}

static void
level_free(Level *level)
{
    gint s;

    for (s = 0; s < level->n; s++)
        g_free(level->maps[s].values);
    g_free(level->maps);
    stripe_subpixel_free(level->subpixel);
    stripe_subpixel_free(level->subpixel_band);
    g_free(level->window);
    stripe_correlation_free(level->correlation);
}

static void
level_compute_map(Level *level, gint s, gint cy, gint cx, gint ry, gint rx)
{
    StripeCorrelationMap *map = level->maps + s;
    gint yres = level->image->yres;

    map->cy = cy;
    map->cx = cx;
    map->ry = ry;
    map->rx = rx;
    stripe_correlation_map(level->correlation, stripe_first_row(s, level->n, yres),
                           stripe_end_row(s, level->n, yres), map);
}

static gboolean
is_local_maximum(const StripeCorrelationMap *map, gint ky, gint kx)
{
    gdouble v = stripe_correlation_map_at(map, ky, kx), u;
    gint i, j;

    if (v <= STRIPE_CORRELATION_NONE)
        return FALSE;
    for (i = ky - 1; i <= ky + 1; i++) {
        for (j = kx - 1; j <= kx + 1; j++) {
            /* Next to the shifts left out (too little overlap, or outside
             * the window), a maximum is as likely the cut slope of a peak
             * beyond them as a peak of its own. */
            u = stripe_correlation_map_at(map, i, j);
            if (u > v || u <= STRIPE_CORRELATION_NONE)
                return FALSE;
        }
    }
    return TRUE;
}

static gboolean
neighbourhood_matched(const StripeCorrelationMap *map, gint ky, gint kx)
{
    gint i, j;

    for (i = -1; i <= 1; i++) {
        for (j = -1; j <= 1; j++) {
            if (stripe_correlation_map_at(map, ky + i, kx + j) <= STRIPE_CORRELATION_NONE)
                return FALSE;
        }
    }
    return TRUE;
}

/* Least-squares quadratic through the 3x3 neighbourhood; its maximum, when
 * it has one near the centre, else a parabola along each axis. */
static void
refine_peak(const StripeCorrelationMap *map, gint ky, gint kx, gdouble *oy, gdouble *ox)
{
    gdouble sx = 0.0, sy = 0.0, sxy = 0.0, sxx = 0.0, syy = 0.0;
    gdouble f, det, x, y, fm, fp, f0, denom;
    gint i, j;

    for (i = -1; i <= 1; i++) {
        for (j = -1; j <= 1; j++) {
            f = stripe_correlation_map_at(map, ky + i, kx + j);
            sx += j*f;
            sy += i*f;
            sxy += i*j*f;
            sxx += (3*j*j - 2)*f;
            syy += (3*i*i - 2)*f;
        }
    }
    sx /= 6.0;
    sy /= 6.0;
    sxy /= 4.0;
    sxx /= 6.0;
    syy /= 6.0;
    det = 4.0*sxx*syy - sxy*sxy;
    if (sxx < 0.0 && syy < 0.0 && det > 0.0) {
        x = (sxy*sy - 2.0*syy*sx)/det;
        y = (sxy*sx - 2.0*sxx*sy)/det;
        if (fabs(x) <= 1.0 && fabs(y) <= 1.0) {
            *ox = x;
            *oy = y;
            return;
        }
    }
    f0 = stripe_correlation_map_at(map, ky, kx);
    fm = stripe_correlation_map_at(map, ky, kx - 1);
    fp = stripe_correlation_map_at(map, ky, kx + 1);
    denom = fm - 2.0*f0 + fp;
    *ox = (denom < 0.0) ? CLAMP(0.5*(fm - fp)/denom, -0.5, 0.5) : 0.0;
    fm = stripe_correlation_map_at(map, ky - 1, kx);
    fp = stripe_correlation_map_at(map, ky + 1, kx);
    denom = fm - 2.0*f0 + fp;
    *oy = (denom < 0.0) ? CLAMP(0.5*(fm - fp)/denom, -0.5, 0.5) : 0.0;
}

/* The shift of a trusted peak refined by matching the stripe against the
 * interpolated reference, within reach px of the peak, once per peak; where
 * the match fails to converge the quadratic's estimate stays.  TRUE if the
 * peak is polished. */
static gboolean
polish_peak(Level *level, gint s, gint reach, Peak *peak)
{
    gint yres = level->image->yres;

    gint first = stripe_first_row(s, level->n, yres), end = stripe_end_row(s, level->n, yres);

    if (level->subpixel && peak->trusted && !peak->polished) {
        gint ky = peak->ky, kx = peak->kx;

        gdouble *sigma = level->uncertainty ? &peak->sigma : NULL;

        peak->sigma = 0.0;

        peak->polished = stripe_subpixel_refine(level->subpixel, first, end, peak->ky, peak->kx,
                                                reach, &peak->dy, &peak->dx, sigma, &peak->row);
        if (!peak->polished && level->subpixel_band) {
            peak->polished = stripe_subpixel_refine(level->subpixel_band, first, end, peak->ky, peak->kx,
                                                    reach, &peak->dy, &peak->dx, sigma, &peak->row);
        }
        /* The match must not carry the stripe out of its searched window,
         * whose border a peak of its own could not cross. */
        if (peak->polished && !(peak->dy >= peak->ylo && peak->dy <= peak->yhi
                                && peak->dx >= peak->xlo && peak->dx <= peak->xhi)) {
            peak->polished = peak->trusted = FALSE;
            peak->dy = ky;
            peak->dx = kx;
            peak->row = 0.5*(first + end - 1);
        }
        if (!peak->polished)
            g_debug("registration: stripe %d: no sub-pixel match at (%d, %d)", s, peak->ky, peak->kx);
    }
    return peak->polished;
}

/* How far the sub-pixel match may move a stripe from its map peak: the
 * map of frames blurred against pixel noise is as broad as the blur, and
 * its peak as uncertain (FastScan, blurred by 10 px: matches 3.4 px from
 * the peak). */
static gint
polish_reach(const Level *level)
{
    return MAX(POLISH_REACH, (gint)ceil(0.5*level->image->narrow_sigma));
}

/* The best shift within (ry, rx) of (cy, cx) in the map of stripe s, and
 * the best local maximum that is not part of it.  A peak on the border of
 * the searched area may be the slope of a better one outside, so it is
 * not trusted.  With known > 0, the prediction (cy, cx) is known to within
 * known px already (a coarser stage with more content resolved what lies
 * beyond, such as the aliases of a periodic background): a peak within it
 * competes only with the maxima within it; a peak beyond it (a jump away
 * from the prediction) competes with the whole window. */
static void
find_peak(Level *level, gint s, gint cy, gint cx, gint ry, gint rx, gint known, Peak *peak)
{
    const StripeCorrelationMap *map = level->maps + s;
    gint ylo = MAX(cy - ry, map->cy - map->ry), yhi = MIN(cy + ry, map->cy + map->ry);
    gint xlo = MAX(cx - rx, map->cx - map->rx), xhi = MIN(cx + rx, map->cx + map->rx);
    gdouble best = STRIPE_CORRELATION_NONE, rival = 0.0, oy, ox, v;
    gint i, j;

    gwy_clear(peak, 1);
    peak->row = 0.5*(stripe_first_row(s, level->n, level->image->yres)
                     + stripe_end_row(s, level->n, level->image->yres) - 1);
    peak->ylo = ylo;
    peak->yhi = yhi;
    peak->xlo = xlo;
    peak->xhi = xhi;
    peak->ky = cy;
    peak->kx = cx;
    for (i = ylo; i <= yhi; i++) {
        for (j = xlo; j <= xhi; j++) {
            if ((v = stripe_correlation_map_at(map, i, j)) > best) {
                best = v;
                peak->ky = i;
                peak->kx = j;
            }
        }
    }
    peak->value = best;
    peak->dy = peak->ky;
    peak->dx = peak->kx;
    peak->trusted = (best > STRIPE_CORRELATION_NONE
                     && peak->ky > ylo && peak->ky < yhi && peak->kx > xlo && peak->kx < xhi);
    if (known > 0 && ABS(peak->ky - cy) <= known && ABS(peak->kx - cx) <= known) {
        ylo = MAX(ylo, cy - known);
        yhi = MIN(yhi, cy + known);
        xlo = MAX(xlo, cx - known);
        xhi = MIN(xhi, cx + known);
    }
    for (i = ylo; i <= yhi; i++) {
        for (j = xlo; j <= xhi; j++) {
            if (ABS(i - peak->ky) < RIVAL_EXCLUSION && ABS(j - peak->kx) < RIVAL_EXCLUSION)
                continue;
            if ((v = stripe_correlation_map_at(map, i, j)) > rival && is_local_maximum(map, i, j))
                rival = v;
        }
    }
    peak->rival = rival;
    if (!peak->trusted)
        return;
    if (neighbourhood_matched(map, peak->ky, peak->kx)) {
        refine_peak(map, peak->ky, peak->kx, &oy, &ox);
        peak->dy += oy;
        peak->dx += ox;
    }
    else if (!level->subpixel) {
        /* On the edge of the shifts that keep enough of the stripe on the
         * reference the map cannot tell a peak from the slope of a better
         * one beyond (on a lattice the edge is where the highest values
         * lie), and there is no match to tell. */
        peak->trusted = FALSE;
    }
    else {
        /* The match can tell, and says where the peak lies, which must
         * still be within the searched area. */
        peak->trusted = (polish_peak(level, s, EDGE_POLISH_REACH, peak)
                         && peak->dy >= ylo && peak->dy <= yhi && peak->dx >= xlo && peak->dx <= xhi);
        if (!peak->trusted) {
            peak->dy = peak->ky;
            peak->dx = peak->kx;
        }
    }
}

/* How far the peak stands above its best rival, as a fraction of the way
 * from the rival to a perfect match: a periodic texture (rival as high as
 * the peak) scores near zero, and a peak of 0.99 over a rival of 0.8 is as
 * sure as one of 0.6 over 0.2, noise lowering both.  Peaks too low to stand
 * out of the noise of the correlation itself (featureless stripes) are
 * scaled down further. */
static gdouble
peak_score(const Peak *peak)
{
    gdouble p = peak->value, q = MAX(peak->rival, 0.0);

    if (!peak->trusted || p <= 0.0 || q >= p)
        return 0.0;
    return CLAMP((p - q)/(1.0 - q)*MIN(1.0, p/LOW_PEAK), 0.0, 1.0);
}

/* The coarse stages decide which of a periodic background's aliases the
 * fine windows (narrower than many periods) will see at all, so there a
 * peak must also stand out relative to its own height: on a lattice with a
 * little roughness, 0.95 over 0.93 is a coin toss, however high both are. */
static gdouble
coarse_peak_score(const Peak *peak)
{
    gdouble p = peak->value, q = MAX(peak->rival, 0.0);

    return (p > 0.0) ? MIN(peak_score(peak), 1.0 - q/p) : 0.0;
}

static gdouble
level_peak_score(const Level *level, const Peak *peak)
{
    return level->subpixel ? peak_score(peak) : coarse_peak_score(peak);
}

/* The median shift of the confident bands around s (not s itself), from
 * the near neighbours if there are two or more, else from farther ones.  On a
 * linear drift the median of symmetric neighbours is exact. */
static gboolean
predict_from_neighbours(const Peak *peaks, const gboolean *reliable, gint n, gint s,
                        gdouble *dy, gdouble *dx)
{
    gdouble ys[2*FAR_REACH], xs[2*FAR_REACH];
    gint reach, t, count = 0;

    for (reach = NEAR_REACH; reach <= FAR_REACH && count < 2; reach += FAR_REACH - NEAR_REACH) {
        count = 0;
        for (t = MAX(0, s - reach); t <= MIN(n-1, s + reach); t++) {
            if (t == s || !reliable[t])
                continue;
            ys[count] = peaks[t].dy;
            xs[count] = peaks[t].dx;
            count++;
        }
    }
    if (count < 2)
        return FALSE;
    *dy = median_in_place(ys, count);
    *dx = median_in_place(xs, count);
    return TRUE;
}

/* At full resolution a stripe is accepted only with a sub-pixel match,
 * which also gives its uncertainty: no value is given without one. */
static void
set_shift(StripeShift *shift, const Peak *peak, gdouble score, gboolean resolved, gdouble min_score,
          gboolean need_polish)
{
    shift->dx = peak->dx;
    shift->dy = peak->dy;
    shift->score = score;
    shift->sigma = peak->polished ? peak->sigma : 0.0;
    shift->row = peak->row;
    shift->accepted = (peak->trusted && score >= min_score && score > 0.0
                       && (peak->polished || !need_polish));
    shift->peak = MAX(peak->value, -1.0);
    shift->rival = peak->rival;
    shift->resolved = resolved;
    shift->in_reference = TRUE;
}

/* A band whose own peak is not clearly the best is judged within a small
 * window around its confident neighbours' median: there, a peak is either
 * the neighbours' peak or a rival the neighbours rule out.  It takes the
 * best peak inside, at a score scaled down by how much lower that peak is
 * than its own.  Confident bands keep their own peak, so that a jump of
 * the drift between bands stays. */
static void
choose_consistent_shifts(Level *level, const Peak *own, gdouble min_score, StripeShift *shifts)
{
    gint n = level->n, s;
    gboolean *reliable = g_new(gboolean, MAX(n, 1));
    gdouble py, px, score;
    Peak local;

    for (s = 0; s < n; s++)
        reliable[s] = (level_peak_score(level, own + s) >= MAX(min_score, RELIABLE_SCORE));
    for (s = 0; s < n; s++) {
        if (reliable[s] || !predict_from_neighbours(own, reliable, n, s, &py, &px)) {
            set_shift(shifts + s, own + s, level_peak_score(level, own + s), FALSE, min_score, level->subpixel != NULL);
            continue;
        }
        find_peak(level, s, nearest_int(py), nearest_int(px), CONSISTENCY_RADIUS, CONSISTENCY_RADIUS,
                  0, &local);
        score = level_peak_score(level, &local);
        if ((local.ky != own[s].ky || local.kx != own[s].kx) && own[s].value > 0.0)
            score *= CLAMP(local.value/own[s].value, 0.0, 1.0);
        set_shift(shifts + s, &local, score, local.ky != own[s].ky || local.kx != own[s].kx,
                  min_score, level->subpixel != NULL);
    }
    g_free(reliable);
}

/* The peak of stripe s searched within (ry, rx) of its predicted shift (0
 * where predicted is NULL), polished where the level has a sub-pixel
 * match. */
static void
measure_stripe_peak(Level *level, gint s, const gdouble *pdy, const gdouble *pdx, gint ry, gint rx,
                    gint known, Peak *peak)
{
    gint cy = pdy ? nearest_int(pdy[s]) : 0, cx = pdx ? nearest_int(pdx[s]) : 0;

    level_compute_map(level, s, cy, cx, ry, rx);
    find_peak(level, s, cy, cx, ry, rx, known, peak);
    polish_peak(level, s, polish_reach(level), peak);
}

/* The stripes' shifts from their own peaks; matched says whether they
 * were polished by a sub-pixel match (the fine level). */
static void
set_own_shifts(const Peak *own, gint n, gboolean matched, gint ry, gint rx, gdouble min_score,
               StripeShift *shifts)
{
    gint s;

    for (s = 0; s < n; s++) {
        set_shift(shifts + s, own + s, matched ? peak_score(own + s) : coarse_peak_score(own + s), FALSE,
                  min_score, matched);
        /* A match as uncertain as this has not located the stripe
         * within its window: a chance peak of the texture, typically
         * (the window's own peak has no rival when it is smooth). */
        if (matched && shifts[s].sigma > LOCATED_FRACTION*MIN(rx, ry))
            shifts[s].accepted = FALSE;
    }
}

/* Each stripe of the level searched within (ry, rx) of its predicted shift
 * (0 where predicted is NULL); polished with reach px where the level has
 * a sub-pixel match. */
static void
measure_level(Level *level, const gdouble *pdy, const gdouble *pdx, gint ry, gint rx, gint known,
              gboolean consistency, gdouble min_score, StripeShift *shifts)
{
    Peak *own = g_new(Peak, MAX(level->n, 1));
    gint s;

    for (s = 0; s < level->n; s++)
        measure_stripe_peak(level, s, pdy, pdx, ry, rx, known, own + s);
    if (consistency)
        choose_consistent_shifts(level, own, min_score, shifts);
    else
        set_own_shifts(own, level->n, level->subpixel != NULL, ry, rx, min_score, shifts);
    g_free(own);
}

/* Search half-widths (px) from the options: the whole frame unless bounded. */
static void
search_radii(const StripeRegistrationOptions *options, gint xres, gint yres, gint *ry, gint *rx)
{
    gdouble sy = options->search_y, sx = options->search_x;

    if (!(sy > 0.0))
        sy = STRIPE_REGISTRATION_WHOLE_FRAME*yres;
    if (!(sx > 0.0))
        sx = STRIPE_REGISTRATION_WHOLE_FRAME*xres;
    *ry = (gint)CLAMP(ceil(sy), 1, MAX(1, yres/2));
    *rx = (gint)CLAMP(ceil(sx), 1, MAX(1, xres/2));
}

/* Linear interpolation of the accepted bands' shifts at row y (band rows),
 * the nearest band's beyond the outer ones.  FALSE when none is accepted. */
static gboolean
interpolate_bands(const StripeShift *bands, gint nb, gint yres, gdouble y, gdouble *dy, gdouble *dx)
{
    gint b, below = -1, above = -1;
    gdouble yb, ya, t;

    for (b = 0; b < nb; b++) {
        if (!bands[b].accepted)
            continue;
        yb = 0.5*(stripe_first_row(b, nb, yres) + stripe_end_row(b, nb, yres) - 1);
        if (yb <= y)
            below = b;
        else if (above < 0)
            above = b;
    }
    if (below < 0 && above < 0)
        return FALSE;
    if (below < 0 || above < 0) {
        b = (below < 0) ? above : below;
        *dy = bands[b].dy;
        *dx = bands[b].dx;
        return TRUE;
    }
    yb = 0.5*(stripe_first_row(below, nb, yres) + stripe_end_row(below, nb, yres) - 1);
    ya = 0.5*(stripe_first_row(above, nb, yres) + stripe_end_row(above, nb, yres) - 1);
    t = (y - yb)/(ya - yb);
    *dy = (1.0 - t)*bands[below].dy + t*bands[above].dy;
    *dx = (1.0 - t)*bands[below].dx + t*bands[above].dx;
    return TRUE;
}

/* The fine search's reach (px) around a stripe's predicted shift: the
 * coarse stage is good to about a coarse pixel, and a stripe may have
 * jumped away from its band's shift. */
static gint
fine_radius(gint factor)
{
    return MAX(FINE_MIN_RADIUS, 2*factor + 4);
}

/* Whether at least IN_REFERENCE_FRACTION of stripe s lies on the reference
 * at the shift (dy, dx). */
static gboolean
stripe_in_reference(gint s, gint n, gint xres, gint yres, gdouble dy, gdouble dx)
{
    gint first = stripe_first_row(s, n, yres), end = stripe_end_row(s, n, yres);
    gdouble rows = MIN(end, yres + dy) - MAX(first, dy), cols = xres - fabs(dx);

    return (rows > 0.0 && cols > 0.0
            && rows*cols >= IN_REFERENCE_FRACTION*(end - first)*(gdouble)xres);
}

/* A band mostly off the reference at the whole frame's shift has little
 * of its content to match there, and its best peak is often a shift that
 * brings more of it onto the reference, matched on texture alone (a band
 * 28 px from both the whole frame and its neighbours at score 0.34 led
 * two stripes 26 and 31 px astray).  Such a band is believed only within
 * the fine search's reach of the whole frame's shift; beyond it, its
 * stripes are predicted from the other bands. */
static void
reject_bands_gaining_overlap(StripeShift *bands, gint nb, gint xres, gint yres, gdouble gy, gdouble gx,
                             gdouble reach)
{
    gint b;

    for (b = 0; b < nb; b++) {
        if (bands[b].accepted && !stripe_in_reference(b, nb, xres, yres, gy, gx)
            && (fabs(bands[b].dy - gy) > reach || fabs(bands[b].dx - gx) > reach)) {
            g_debug("registration: band %d/%d off the reference at the whole frame's shift and "
                    "(%.1f, %.1f) coarse px from it: rejected", b, nb, bands[b].dx - gx, bands[b].dy - gy);
            bands[b].accepted = FALSE;
        }
    }
}

/* Bands searched blind (the whole frame gave no shift) are believed only
 * when another accepted band agrees within the reach a band may differ by:
 * one band's peak over a blind search of a third of the frame is too
 * often a coincidence of texture that nothing else confirms. */
static void
reject_uncorroborated_bands(StripeShift *bands, gint nb, gint ry, gint rx)
{
    gboolean *corroborated = g_new0(gboolean, MAX(nb, 1));
    gint a, b;

    for (a = 0; a < nb; a++) {
        for (b = 0; b < nb && bands[a].accepted; b++) {
            if (b != a && bands[b].accepted
                && fabs(bands[a].dy - bands[b].dy) <= ry && fabs(bands[a].dx - bands[b].dx) <= rx)
                corroborated[a] = TRUE;
        }
    }
    for (a = 0; a < nb; a++)
        bands[a].accepted = bands[a].accepted && corroborated[a];
    g_free(corroborated);
}

/* nb bands of the coarse frames, each searched within (by, bx) of (gy, gx),
 * a band that is not clearly the best taking the best peak near its
 * confident neighbours'. */
static void
measure_bands(const ConditionedFrame *small_image, const ConditionedFrame *small_reference, gint nb,
              gdouble gy, gdouble gx, gint by, gint bx, gdouble min_score, StripeShift *bands)
{
    gdouble *cdy = g_new(gdouble, nb), *cdx = g_new(gdouble, nb);
    Level level;
    gint b;

    for (b = 0; b < nb; b++) {
        cdy[b] = gy;
        cdx[b] = gx;
    }
    level_init(&level, small_image, small_reference, NULL, NULL, nb, by, bx);
    measure_level(&level, cdy, cdx, by, bx, 0, TRUE, min_score, bands);
    level_free(&level);
    g_free(cdy);
    g_free(cdx);
}

/* Stages 1 and 2 at reduced resolution: the predicted shift (full-resolution
 * px) of each of n stripes.  FALSE when the coarse stage found nothing. */
static gboolean
predict_coarsely(const ConditionedFrame *image, const ConditionedFrame *reference, gint n,
                 const StripeRegistrationOptions *options, gint *factor, gboolean *known,
                 gdouble *pdy, gdouble *pdx)
{
    ConditionedFrame *small_image, *small_reference;
    StripeShift whole, *bands;
    Level level;
    gint f, nb, ry, rx, reach_y, reach_x, s, yres = image->yres;
    gdouble y;
    StripeRegistrationOptions coarse = *options;
    gboolean found = TRUE, global_ok;

    f = MAX(1, (MAX(image->xres, image->yres) + COARSE_SIZE - 1)/COARSE_SIZE);
    *factor = f;
    *known = FALSE;
    small_image = conditioned_frame_downsample(image, f);
    small_reference = conditioned_frame_downsample(reference, f);
    coarse.search_x = (options->search_x > 0.0) ? options->search_x/f : 0.0;
    coarse.search_y = (options->search_y > 0.0) ? options->search_y/f : 0.0;
    search_radii(&coarse, small_image->xres, small_image->yres, &ry, &rx);
    reach_y = MIN(ry, MAX(3, (gint)ceil(BAND_REACH*small_image->yres)));
    reach_x = MIN(rx, MAX(3, (gint)ceil(BAND_REACH*small_image->xres)));

    level_init(&level, small_image, small_reference, NULL, NULL, 1, ry, rx);
    measure_level(&level, NULL, NULL, ry, rx, 0, FALSE, MIN(options->min_score, GLOBAL_MIN_SCORE), &whole);
    level_free(&level);
    global_ok = whole.accepted;

    nb = CLAMP(small_image->yres/BAND_ROWS, 1, n);
    bands = g_new(StripeShift, nb);
    if (!global_ok)
        measure_bands(small_image, small_reference, nb, 0.0, 0.0, ry, rx, options->min_score, bands);
    g_debug("registration: coarse factor %d, whole frame (%.2f, %.2f) coarse px, peak %.3f, "
            "rival %.3f, score %.3f", f, whole.dx, whole.dy, whole.peak, whole.rival, whole.score);
    if (global_ok) {
        measure_bands(small_image, small_reference, nb, whole.dy, whole.dx, reach_y, reach_x,
                      options->min_score, bands);
        reject_bands_gaining_overlap(bands, nb, small_image->xres, small_image->yres, whole.dy, whole.dx,
                                     fine_radius(f)/(gdouble)f);
    }
    else
        reject_uncorroborated_bands(bands, nb, reach_y, reach_x);
    for (s = 0; s < nb; s++) {
        g_debug("registration: band %d/%d (%.2f, %.2f) coarse px, peak %.3f, rival %.3f, "
                "score %.3f%s", s, nb, bands[s].dx, bands[s].dy, bands[s].peak, bands[s].rival,
                bands[s].score, bands[s].accepted ? "" : ", rejected");
    }
    for (s = 0; s < n && found; s++) {
        y = (0.5*(stripe_first_row(s, n, yres) + stripe_end_row(s, n, yres) - 1) + 0.5)/f - 0.5;
        if (interpolate_bands(bands, nb, small_image->yres, y, pdy + s, pdx + s))
            *known = TRUE;
        else {
            if (!global_ok)
                found = FALSE;
            pdy[s] = global_ok ? whole.dy : 0.0;
            pdx[s] = global_ok ? whole.dx : 0.0;
        }
        pdy[s] *= f;
        pdx[s] *= f;
    }
    g_free(bands);
    conditioned_frame_free(small_image);
    conditioned_frame_free(small_reference);
    return found;
}

/* A view of the frame's levelled data, without the wide cut. */
static ConditionedFrame
levelled_view(const ConditionedFrame *frame)
{
    ConditionedFrame view = *frame;

    if (frame->levelled)
        view.data = frame->levelled;
    view.levelled = NULL;
    return view;
}

/* Stripes of the fine level shared among threads, each with a level of
 * its own (a level's correlation and match hold scratch space). */
typedef struct {
    const ConditionedFrame *image, *reference;   /* levelled views */
    const ConditionedFrame *sub_image, *sub_reference;
    gboolean uncertainty;
    gint n, ry, rx, workers;
    const gdouble *pdy, *pdx;
    Peak *own;
} FineStripes;

static void
measure_fine_share(gpointer user_data, gint worker)
{
    FineStripes *fs = user_data;
    Level level;
    gint s;

    level_init(&level, fs->image, fs->reference, fs->sub_image, fs->sub_reference, fs->n,
               fs->ry, fs->rx);
    level.uncertainty = fs->uncertainty;
    for (s = worker; s < fs->n; s += fs->workers)
        measure_stripe_peak(&level, s, fs->pdy, fs->pdx, fs->ry, fs->rx, 0, fs->own + s);
    level_free(&level);
}

/* Every stripe at full resolution within ry rows and rx columns of its
 * predicted shift.
 * Its map comes from the levelled frames: within a small window the
 * correlation's own mean removal over each shift's overlap takes what
 * stays of slow variations, and the wide cut, which a search over large
 * shifts needs, paints the smoothed texture around a featureless region
 * into it, with structure both frames share, so that a featureless stripe
 * matched on it (scores up to 0.6 in the tests).  With parallel, the
 * stripes are shared among the processor's cores (a single pair; a series
 * runs its pairs in parallel already). */
static void
measure_fine(const ConditionedFrame *image, const ConditionedFrame *reference, gint n,
             const gdouble *pdy, const gdouble *pdx, gint ry, gint rx, gdouble min_score,
             Refinement refine, gboolean parallel, StripeShift *shifts)
{
    ConditionedFrame image_view = levelled_view(image), reference_view = levelled_view(reference);
    gboolean match = (refine != REFINE_QUADRATIC);
    FineStripes fs = {
        &image_view, &reference_view, match ? image : NULL, match ? reference : NULL,
        refine == REFINE_MATCH_SIGMA,
        n, ry, rx, parallel ? CLAMP((gint)g_get_num_processors(), 1, n) : 1, pdy, pdx,
        g_new(Peak, MAX(n, 1)),
    };

    parallel_run(0, fs.workers, measure_fine_share, &fs);
    set_own_shifts(fs.own, n, match, ry, rx, min_score, shifts);
    g_free(fs.own);
}

static gboolean
check_frames(const ConditionedFrame *image, const ConditionedFrame *reference, gint n, GError **error)
{
    if (image->xres < 4 || image->yres < 4) {
        g_set_error(error, STRIPE_REGISTRATION_ERROR, STRIPE_REGISTRATION_ERROR_SIZE,
                    _("The image (%d x %d px) is too small to register: it needs at least 4 x 4 px."),
                    image->xres, image->yres);
        return FALSE;
    }
    if (reference->xres != image->xres || reference->yres != image->yres) {
        g_set_error(error, STRIPE_REGISTRATION_ERROR, STRIPE_REGISTRATION_ERROR_SIZE,
                    _("The reference (%d x %d px) does not have the image's size (%d x %d px)."),
                    reference->xres, reference->yres, image->xres, image->yres);
        return FALSE;
    }
    if (n < 1 || n > image->yres) {
        g_set_error(error, STRIPE_REGISTRATION_ERROR, STRIPE_REGISTRATION_ERROR_STRIPES,
                    _("The number of stripes (%d) must be between 1 and the image's %d rows."),
                    n, image->yres);
        return FALSE;
    }
    return TRUE;
}

/* The fine search reaches past the coarse stage's peak by room for a jump,
 * so a stripe could be given a shift beyond the bounds the user set
 * (--search): such a stripe is left empty.  Half a pixel is the sub-pixel
 * match's room at the bound. */
static void
reject_beyond_search(const StripeRegistrationOptions *options, StripeShift *shifts, gint n)
{
    gint s;

    for (s = 0; s < n; s++) {
        if (shifts[s].accepted
            && ((options->search_x > 0.0 && fabs(shifts[s].dx) > options->search_x + 0.5)
                || (options->search_y > 0.0 && fabs(shifts[s].dy) > options->search_y + 0.5))) {
            g_debug("registration: stripe %d/%d at (%.2f, %.2f) px, beyond the search bounds: rejected",
                    s, n, shifts[s].dx, shifts[s].dy);
            shifts[s].accepted = FALSE;
        }
    }
}

/* stripe_registration_measure() for frames conditioned already. */
static gboolean
measure_conditioned(const ConditionedFrame *image, const ConditionedFrame *reference, gint n,
                    const StripeRegistrationOptions *options, StripeShift *shifts, GError **error)
{
    StripeRegistrationOptions defaults;
    gdouble *pdy, *pdx;
    gint factor, radius, s;
    gboolean known;

    g_return_val_if_fail(image && reference && shifts, FALSE);
    if (!options) {
        stripe_registration_options_init(&defaults);
        options = &defaults;
    }
    if (!check_frames(image, reference, n, error))
        return FALSE;
    pdy = g_new(gdouble, n);
    pdx = g_new(gdouble, n);
    if (!predict_coarsely(image, reference, n, options, &factor, &known, pdy, pdx)) {
        for (s = 0; s < n; s++) {
            gwy_clear(shifts + s, 1);
            shifts[s].in_reference = TRUE;
        }
    }
    else {
        radius = MIN(fine_radius(factor), MIN(image->xres, image->yres)/2);
        measure_fine(image, reference, n, pdy, pdx, radius, radius, options->min_score,
                     REFINE_MATCH_SIGMA, TRUE, shifts);
        reject_beyond_search(options, shifts, n);
        for (s = 0; s < n; s++)
            shifts[s].in_reference = stripe_in_reference(s, n, image->xres, image->yres, pdy[s], pdx[s]);
    }
    g_free(pdy);
    g_free(pdx);
    return TRUE;
}

/* stripe_registration_measure_around() for frames conditioned already,
 * searched within radius_px[0] columns and radius_px[1] rows, the shifts
 * refined as refine says. */
static gboolean
measure_around(const ConditionedFrame *image, const ConditionedFrame *reference, gint n,
               const gdouble *predicted_dx, const gdouble *predicted_dy, const gdouble *radius_px,
               gdouble min_score, Refinement refine, StripeShift *shifts, GError **error)
{
    gint s, rx, ry;

    if (!check_frames(image, reference, n, error))
        return FALSE;
    for (s = 0; s < n; s++) {
        if (!isfinite(predicted_dx[s]) || !isfinite(predicted_dy[s])
            || fabs(predicted_dx[s]) > image->xres || fabs(predicted_dy[s]) > image->yres) {
            g_set_error(error, STRIPE_REGISTRATION_ERROR, STRIPE_REGISTRATION_ERROR_VALUE,
                        _("The predicted shift of stripe %d is not a finite number within the frame."),
                        s);
            return FALSE;
        }
    }
    rx = (gint)CLAMP(ceil(radius_px[0]), 1, image->xres/2);
    ry = (gint)CLAMP(ceil(radius_px[1]), 1, image->yres/2);
    measure_fine(image, reference, n, predicted_dy, predicted_dx, ry, rx, min_score, refine, FALSE,
                 shifts);
    for (s = 0; s < n; s++) {
        shifts[s].in_reference = stripe_in_reference(s, n, image->xres, image->yres,
                                                     predicted_dy[s], predicted_dx[s]);
    }
    return TRUE;
}

/* The two frames of a pair, conditioned at once on two cores: each
 * frame's steps are its own, only the band-pass's narrow blur is shared. */
typedef struct {
    const gdouble *data[2];
    ConditionedFrame *frame[2];
    LineTextures *textures;     /* two, of the levelled frames */
    gint xres, yres;
    gdouble aspect, narrow;
} PairConditioning;

static void
level_one_of_pair(gpointer user_data, gint i)
{
    PairConditioning *pc = user_data;

    pc->frame[i] = frame_condition_level(pc->data[i], NULL, pc->xres, pc->yres);
    if (pc->frame[i])
        line_textures_init(pc->textures + i, pc->frame[i]);
}

static void
band_pass_one_of_pair(gpointer user_data, gint i)
{
    PairConditioning *pc = user_data;

    conditioned_frame_band_pass(pc->frame[i], pc->aspect, pc->narrow);
}

/* The two frames conditioned, and textures[2] the lines of each levelled
 * one (cleared by the caller after a success). */
static gboolean
condition_pair(const gdouble *image, const gdouble *reference, gint xres, gint yres, gdouble aspect,
               ConditionedFrame **cimage, ConditionedFrame **creference, LineTextures *textures,
               GError **error)
{
    PairConditioning pc = { { image, reference }, { NULL, NULL }, textures, xres, yres, aspect, 0.0 };

    *cimage = *creference = NULL;
    gwy_clear(textures, 2);
    if (xres < 4 || yres < 4) {
        g_set_error(error, STRIPE_REGISTRATION_ERROR, STRIPE_REGISTRATION_ERROR_SIZE,
                    _("The image (%d x %d px) is too small to register: it needs at least 4 x 4 px."),
                    xres, yres);
        return FALSE;
    }
    parallel_run(0, 2, level_one_of_pair, &pc);
    if (!pc.frame[0] || !pc.frame[1]) {
        g_set_error(error, STRIPE_REGISTRATION_ERROR, STRIPE_REGISTRATION_ERROR_VALUE,
                    pc.frame[0]
                    ? _("The reference has no valid pixel (all are NaN or infinite).")
                    : _("The image has no valid pixel (all are NaN or infinite)."));
        conditioned_frame_free(pc.frame[0]);
        conditioned_frame_free(pc.frame[1]);
        line_textures_clear(textures);
        line_textures_clear(textures + 1);
        return FALSE;
    }
    /* One band for both frames: the noisier one decides. */
    pc.narrow = MAX(conditioned_frame_noise_scale(pc.frame[0], aspect),
                    conditioned_frame_noise_scale(pc.frame[1], aspect));
    parallel_run(0, 2, band_pass_one_of_pair, &pc);
    *cimage = pc.frame[0];
    *creference = pc.frame[1];
    return TRUE;
}

static gboolean
measure_at_resolution(const gdouble *image, const gdouble *reference, gint xres, gint yres, gint n,
                      const StripeRegistrationOptions *options, StripeShift *shifts, GError **error)
{
    ConditionedFrame *cimage, *creference;
    LineTextures textures[2];
    gboolean ok;

    if (!condition_pair(image, reference, xres, yres, options ? options->pixel_aspect : 1.0,
                        &cimage, &creference, textures, error))
        return FALSE;
    ok = measure_conditioned(cimage, creference, n, options, shifts, error);
    if (ok)
        stripe_fringe_reject(textures, textures + 1, n, edge_margin(cimage), shifts);
    conditioned_frame_free(cimage);
    conditioned_frame_free(creference);
    line_textures_clear(textures);
    line_textures_clear(textures + 1);
    return ok;
}

/* The registration of both frames binned by factor, its shifts in px of
 * the frames as given.  A stripe's rows in the binned frames are its rows
 * here to within a block. */
static gboolean
measure_binned(const gdouble *image, const gdouble *reference, gint xres, gint yres, gint n, gint factor,
               const StripeRegistrationOptions *options, StripeShift *shifts, GError **error)
{
    StripeRegistrationOptions binned_options;
    gdouble *binned_image = registration_bin_frame(image, xres, yres, factor);
    gdouble *binned_reference = registration_bin_frame(reference, xres, yres, factor);
    gboolean ok;
    gint s;

    if (options)
        binned_options = *options;
    else
        stripe_registration_options_init(&binned_options);
    if (binned_options.search_x > 0.0)
        binned_options.search_x /= factor;
    if (binned_options.search_y > 0.0)
        binned_options.search_y /= factor;
    ok = measure_at_resolution(binned_image, binned_reference, xres/factor, yres/factor, n, &binned_options,
                               shifts, error);
    for (s = 0; ok && s < n; s++) {
        shifts[s].dx *= factor;
        shifts[s].dy *= factor;
        shifts[s].sigma *= factor;
        /* Binned row i holds rows factor i .. factor i + factor - 1. */
        shifts[s].row = factor*shifts[s].row + 0.5*(factor - 1);
    }
    /* The bounds' half-pixel room was a binned pixel's. */
    if (ok && options)
        reject_beyond_search(options, shifts, n);
    g_free(binned_image);
    g_free(binned_reference);
    return ok;
}

gboolean
stripe_registration_measure(const gdouble *image, const gdouble *reference, gint xres, gint yres, gint n,
                            const StripeRegistrationOptions *options, StripeShift *shifts, GError **error)
{
    gint factor;

    g_return_val_if_fail(image && reference && shifts, FALSE);
    /* Sizes and counts are checked at full resolution, so that a refusal
     * names the frames as given. */
    if (xres >= 4 && yres >= 4 && n >= 1 && n <= yres
        && (factor = registration_binning_factor(image, reference, xres, yres, n)) > 1) {
        g_debug("registration: %d x %d px binned by %d", xres, yres, factor);
        return measure_binned(image, reference, xres, yres, n, factor, options, shifts, error);
    }
    return measure_at_resolution(image, reference, xres, yres, n, options, shifts, error);
}

gboolean
stripe_registration_measure_around(const gdouble *image, const gdouble *reference, gint xres, gint yres,
                                   gint n, const gdouble *predicted_dx, const gdouble *predicted_dy,
                                   gdouble radius_px, gdouble min_score, StripeShift *shifts,
                                   GError **error)
{
    ConditionedFrame *cimage, *creference;
    LineTextures textures[2];
    gdouble radii[2] = { radius_px, radius_px };
    gboolean ok;

    g_return_val_if_fail(image && reference && predicted_dx && predicted_dy && shifts, FALSE);
    if (!condition_pair(image, reference, xres, yres, 1.0, &cimage, &creference, textures, error))
        return FALSE;
    ok = measure_around(cimage, creference, n, predicted_dx, predicted_dy, radii, min_score,
                        REFINE_MATCH_SIGMA, shifts, error);
    if (ok)
        stripe_fringe_reject(textures, textures + 1, n, edge_margin(cimage), shifts);
    conditioned_frame_free(cimage);
    conditioned_frame_free(creference);
    line_textures_clear(textures);
    line_textures_clear(textures + 1);
    return ok;
}

struct _StripeRegistrationFrame {
    ConditionedFrame *unfiltered;  /* conditioned up to the band-pass */
    gdouble noise_scale;           /* the narrow blur its own noise calls for */
    gdouble pixel_aspect;
    ConditionedFrame *passed;      /* band-passed with noise_scale */
    LineTextures textures;         /* of unfiltered's lines */
};

/* A frame band-passed with narrow. */
static ConditionedFrame*
band_pass_copy(const StripeRegistrationFrame *frame, gdouble narrow)
{
    ConditionedFrame *passed = conditioned_frame_copy(frame->unfiltered);

    conditioned_frame_band_pass(passed, frame->pixel_aspect, narrow);
    return passed;
}

StripeRegistrationFrame*
stripe_registration_frame_new(const gdouble *data, gint xres, gint yres, gdouble pixel_aspect)
{
    StripeRegistrationFrame *frame;
    ConditionedFrame *unfiltered;

    g_return_val_if_fail(data, NULL);
    if (xres < 4 || yres < 4 || !(unfiltered = frame_condition_level(data, NULL, xres, yres)))
        return NULL;
    frame = g_new0(StripeRegistrationFrame, 1);
    frame->unfiltered = unfiltered;
    frame->pixel_aspect = pixel_aspect;
    frame->noise_scale = conditioned_frame_noise_scale(unfiltered, pixel_aspect);
    /* Frames of a series have alike noise: a pair mostly asks for the
     * band each frame's own noise calls for. */
    frame->passed = band_pass_copy(frame, frame->noise_scale);
    line_textures_init(&frame->textures, unfiltered);
    return frame;
}

void
stripe_registration_frame_free(StripeRegistrationFrame *frame)
{
    if (!frame)
        return;
    conditioned_frame_free(frame->unfiltered);
    conditioned_frame_free(frame->passed);
    line_textures_clear(&frame->textures);
    g_free(frame);
}

/* The frame band-passed with narrow: its own copy when that is its band,
 * else one made for the pair in *made (freed by the caller).  The frame is
 * not changed, so pairs can be registered in parallel. */
static const ConditionedFrame*
band_passed(const StripeRegistrationFrame *frame, gdouble narrow, ConditionedFrame **made)
{
    *made = NULL;
    if (narrow == frame->noise_scale)
        return frame->passed;
    return *made = band_pass_copy(frame, narrow);
}

/* measure_around() for two registration frames, each band-passed with the
 * pair's band (its own copy where that is its band). */
static gboolean
measure_around_pair(const StripeRegistrationFrame *image,
                    const StripeRegistrationFrame *reference, gint n,
                    const gdouble *predicted_dx, const gdouble *predicted_dy,
                    const gdouble *radius_px, gdouble min_narrow, gdouble min_score,
                    Refinement refine, StripeShift *shifts, GError **error)
{
    /* The same band as condition_pair() gives the two frames, or wider. */
    gdouble narrow = MAX(MAX(image->noise_scale, reference->noise_scale), min_narrow);
    ConditionedFrame *made_image, *made_reference;
    const ConditionedFrame *cimage, *creference;
    gboolean ok;

    cimage = band_passed(image, narrow, &made_image);
    creference = band_passed(reference, narrow, &made_reference);
    ok = measure_around(cimage, creference, n, predicted_dx, predicted_dy, radius_px, min_score,
                        refine, shifts, error);
    if (ok)
        stripe_fringe_reject(&image->textures, &reference->textures, n, edge_margin(cimage), shifts);
    conditioned_frame_free(made_image);
    conditioned_frame_free(made_reference);
    return ok;
}

/* The whole frame's shift is searched at half resolution on frames this
 * large: the blocks search around it anyway, and at full resolution it cost
 * a tenth of a long series' registration. */
#define FRAME_SHIFT_HALVED_FROM 128

gboolean
stripe_registration_frame_shift(const StripeRegistrationFrame *image,
                                const StripeRegistrationFrame *reference,
                                gdouble predicted_dx, gdouble predicted_dy, gdouble radius_x_px,
                                gdouble radius_y_px, gdouble min_narrow, StripeShift *shift)
{
    gdouble narrow, pdx = 0.5*predicted_dx, pdy = 0.5*predicted_dy;
    gdouble radii[2] = { radius_x_px, radius_y_px };
    gdouble halved[2] = { MAX(0.5*radius_x_px, 1.0), MAX(0.5*radius_y_px, 1.0) };
    ConditionedFrame *made_image, *made_reference, *small_image, *small_reference;
    const ConditionedFrame *cimage, *creference;
    gboolean ok;

    g_return_val_if_fail(image && reference && shift, FALSE);
    if (MIN(image->unfiltered->xres, image->unfiltered->yres) < FRAME_SHIFT_HALVED_FROM)
        return measure_around_pair(image, reference, 1, &predicted_dx, &predicted_dy, radii, min_narrow,
                                   STRIPE_REGISTRATION_DEFAULT_MIN_SCORE, REFINE_QUADRATIC, shift, NULL);
    narrow = MAX(MAX(image->noise_scale, reference->noise_scale), min_narrow);
    cimage = band_passed(image, narrow, &made_image);
    creference = band_passed(reference, narrow, &made_reference);
    small_image = conditioned_frame_downsample(cimage, 2);
    small_reference = conditioned_frame_downsample(creference, 2);
    ok = measure_around(small_image, small_reference, 1, &pdx, &pdy, halved,
                        STRIPE_REGISTRATION_DEFAULT_MIN_SCORE, REFINE_QUADRATIC, shift, NULL);
    shift->dx *= 2.0;
    shift->dy *= 2.0;
    conditioned_frame_free(small_image);
    conditioned_frame_free(small_reference);
    conditioned_frame_free(made_image);
    conditioned_frame_free(made_reference);
    return ok;
}

gboolean
stripe_registration_measure_around_frames(const StripeRegistrationFrame *image,
                                          const StripeRegistrationFrame *reference, gint n,
                                          const gdouble *predicted_dx, const gdouble *predicted_dy,
                                          gdouble radius_px, gdouble min_narrow, gdouble min_score,
                                          gboolean uncertainty, StripeShift *shifts, GError **error)
{
    gdouble radii[2] = { radius_px, radius_px };

    g_return_val_if_fail(image && reference && predicted_dx && predicted_dy && shifts, FALSE);
    return measure_around_pair(image, reference, n, predicted_dx, predicted_dy, radii,
                               min_narrow, min_score, uncertainty ? REFINE_MATCH_SIGMA : REFINE_MATCH,
                               shifts, error);
}

/* The field's data with the pixels its mask makes missing (masking) as
 * NaN; NULL when none is: the field's own data serve. */
static gdouble*
data_without_masked(GwyDataField *field, GwyDataField *mask, GwyMaskingType masking)
{
    const gdouble *d = gwy_data_field_get_data_const(field), *m;
    gsize k, n = (gsize)gwy_data_field_get_xres(field)*gwy_data_field_get_yres(field);
    gdouble *copy;

    if (!mask || (masking != GWY_MASK_EXCLUDE && masking != GWY_MASK_INCLUDE))
        return NULL;
    m = gwy_data_field_get_data_const(mask);
    copy = g_new(gdouble, n);
    for (k = 0; k < n; k++)
        copy[k] = ((m[k] > 0.5) == (masking == GWY_MASK_EXCLUDE)) ? NAN : d[k];
    return copy;
}

static gboolean
check_mask_size(GwyDataField *field, GwyDataField *mask, gboolean is_reference, GError **error)
{
    gint xres = gwy_data_field_get_xres(field), yres = gwy_data_field_get_yres(field);

    if (!mask || (gwy_data_field_get_xres(mask) == xres && gwy_data_field_get_yres(mask) == yres))
        return TRUE;
    g_set_error(error, STRIPE_REGISTRATION_ERROR, STRIPE_REGISTRATION_ERROR_SIZE,
                is_reference
                ? _("The reference's mask (%d x %d px) does not have the reference's size (%d x %d px).")
                : _("The image's mask (%d x %d px) does not have the image's size (%d x %d px)."),
                gwy_data_field_get_xres(mask), gwy_data_field_get_yres(mask), xres, yres);
    return FALSE;
}

/* Whether data (NULL: the field's own, unmasked) keeps a pixel to register. */
static gboolean
check_mask_leaves_data(const gdouble *data, gsize n, gboolean is_reference, GwyMaskingType masking,
                       GError **error)
{
    gsize k;

    for (k = 0; data && k < n; k++) {
        if (!isnan(data[k]))
            return TRUE;
    }
    if (!data)
        return TRUE;
    if (masking == GWY_MASK_INCLUDE) {
        g_set_error(error, STRIPE_REGISTRATION_ERROR, STRIPE_REGISTRATION_ERROR_VALUE, "%s",
                    is_reference ? _("Only masked pixels are used, and the reference's mask has none.")
                    : _("Only masked pixels are used, and the image's mask has none."));
    }
    else {
        g_set_error(error, STRIPE_REGISTRATION_ERROR, STRIPE_REGISTRATION_ERROR_VALUE, "%s",
                    is_reference ? _("The reference's mask covers every pixel: with masked pixels "
                                     "excluded, nothing is left to register.")
                    : _("The image's mask covers every pixel: with masked pixels excluded, nothing "
                        "is left to register."));
    }
    return FALSE;
}

gboolean
stripe_registration_measure_fields(GwyDataField *image, GwyDataField *reference, gint n,
                                   const StripeRegistrationOptions *options, StripeShift *shifts,
                                   GError **error)
{
    StripeRegistrationOptions opts;
    gint xres, yres, rxres, ryres;
    gdouble *image_data, *reference_data;
    gboolean ok;

    g_return_val_if_fail(GWY_IS_DATA_FIELD(image) && GWY_IS_DATA_FIELD(reference), FALSE);
    xres = gwy_data_field_get_xres(image);
    yres = gwy_data_field_get_yres(image);
    rxres = gwy_data_field_get_xres(reference);
    ryres = gwy_data_field_get_yres(reference);
    if (xres != rxres || yres != ryres) {
        g_set_error(error, STRIPE_REGISTRATION_ERROR, STRIPE_REGISTRATION_ERROR_SIZE,
                    _("The reference (%d x %d px) does not have the image's size (%d x %d px)."),
                    rxres, ryres, xres, yres);
        return FALSE;
    }
    if (options)
        opts = *options;
    else
        stripe_registration_options_init(&opts);
    if (opts.masking == GWY_MASK_IGNORE)
        opts.image_mask = opts.reference_mask = NULL;
    if (!check_mask_size(image, opts.image_mask, FALSE, error)
        || !check_mask_size(reference, opts.reference_mask, TRUE, error))
        return FALSE;
    opts.pixel_aspect = gwy_data_field_get_dy(image)/gwy_data_field_get_dx(image);
    if (!missing_data_check_range(gwy_data_field_get_data_const(image), (gsize)xres*yres, _("the image"),
                                  error)
        || !missing_data_check_range(gwy_data_field_get_data_const(reference), (gsize)xres*yres,
                                     _("the reference"), error))
        return FALSE;
    image_data = data_without_masked(image, opts.image_mask, opts.masking);
    reference_data = data_without_masked(reference, opts.reference_mask, opts.masking);
    if (!check_mask_leaves_data(image_data, (gsize)xres*yres, FALSE, opts.masking, error)
        || !check_mask_leaves_data(reference_data, (gsize)xres*yres, TRUE, opts.masking, error)) {
        g_free(image_data);
        g_free(reference_data);
        return FALSE;
    }
    ok = stripe_registration_measure(image_data ? image_data : gwy_data_field_get_data_const(image),
                                     reference_data ? reference_data
                                     : gwy_data_field_get_data_const(reference),
                                     xres, yres, n, &opts, shifts, error);
    g_free(image_data);
    g_free(reference_data);
    return ok;
}

gint
stripe_registration_count_accepted(const StripeShift *shifts, gint n)
{
    gint s, count = 0;

    for (s = 0; s < n; s++)
        count += !!shifts[s].accepted;
    return count;
}

DriftTable*
stripe_registration_to_table(const StripeShift *shifts, gint n, gboolean whole_pixels)
{
    DriftTable *table;
    gint s;

    g_return_val_if_fail(shifts && n >= 1, NULL);
    table = drift_table_new(n, DRIFT_UNIT_PX);
    for (s = 0; s < n; s++) {
        DriftTableRow *row = table->rows + s;
        const StripeShift *shift = shifts + s;

        row->stripe = s;
        row->has_drift = shift->accepted;
        if (shift->accepted) {
            row->dx = whole_pixels ? drift_px_round(shift->dx) : shift->dx;
            row->dy = whole_pixels ? drift_px_round(shift->dy) : shift->dy;
        }
        else
            row->dx = row->dy = 0.0;
        drift_table_set_extra(table, s, "dx_exact", shift->accepted ? shift->dx : NAN);
        drift_table_set_extra(table, s, "dy_exact", shift->accepted ? shift->dy : NAN);
        drift_table_set_extra(table, s, "score", shift->score);
        drift_table_set_extra(table, s, "sigma_px", shift->accepted ? shift->sigma : NAN);
    }
    return table;
}

DriftTable*
stripe_registration_table_for_fields(GwyDataField *image, GwyDataField *reference, gint n,
                                     const StripeRegistrationOptions *options, gboolean whole_pixels,
                                     StripeRegistrationSupport *support, GError **error)
{
    StripeShift *shifts;
    DriftTable *table = NULL;

    g_return_val_if_fail(n >= 1, NULL);
    shifts = g_new(StripeShift, n);
    if (stripe_registration_measure_fields(image, reference, n, options, shifts, error)) {
        if (support)
            stripe_registration_support(shifts, n, support);
        if (stripe_registration_count_accepted(shifts, n))
            table = stripe_registration_to_table(shifts, n, whole_pixels);
        else {
            g_set_error(error, STRIPE_REGISTRATION_ERROR, STRIPE_REGISTRATION_ERROR_NO_MATCH,
                        _("No stripe of the image could be registered against the reference "
                        "(featureless, periodic, or not the same area)."));
        }
    }
    g_free(shifts);
    return table;
}

void
stripe_registration_support(const StripeShift *shifts, gint n, StripeRegistrationSupport *support)
{
    gdouble *scores = g_new(gdouble, MAX(n, 1));
    gint s;

    gwy_clear(support, 1);
    support->stripes = n;
    for (s = 0; s < n; s++) {
        support->in_reference += !!shifts[s].in_reference;
        if (shifts[s].accepted)
            scores[support->measured++] = shifts[s].score;
    }
    support->median_score = support->measured ? median_in_place(scores, support->measured) : 0.0;
    /* A large offset that leaves part of the image outside the reference is
     * normal; what cannot be trusted is a registration that measured few
     * of the stripes it could have measured. */
    support->supported = (support->measured >= MIN(2, n)
                          && 2*support->measured >= support->in_reference);
    g_free(scores);
}

gchar*
stripe_registration_support_message(const StripeRegistrationSupport *support)
{
    if (support->supported)
        return NULL;
    if (support->measured < MIN(2, support->stripes)) {
        return g_strdup_printf(dngettext(GETTEXT_PACKAGE, "only %d stripe of %d was measured",
                                        "only %d stripes of %d were measured", support->measured),
                               support->measured, support->stripes);
    }
    return g_strdup_printf(_("only %d of the %d stripes whose content lies in the reference "
                             "were measured"), support->measured, support->in_reference);
}
