/*
 *  Drift measured from the data: each stripe of an image registered against
 *  a reference frame of the same area (FFT cross-correlation, FFTW).
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <math.h>
#include <string.h>
#include <libgwyddion/gwymacros.h>
#include "stripe-registration.h"
#include "stripe-geometry.h"
#include "fft-correlation.h"
#include "stripe-subpixel.h"
#include "localscan-intl.h"

/*
 * How it works.
 *
 * Every stripe (a template of h rows by xres columns) is matched against the
 * whole reference, not against the same stripe of the reference: a stripe
 * drifted in y shares only part of its rows with the reference stripe, the
 * reference frame around it holds all of them.  The match measure is the
 * zero-mean normalised cross-correlation (ZNCC) with a Tukey window in x as
 * weights, computed over the part of the template that overlaps the reference
 * at each shift (masked ZNCC).  The local mean and energy of the reference
 * under the template normalise each shift, so a bright or rough region of the
 * reference cannot win over the matching one, and shifts that move the
 * template partly off the reference are judged on the shared part only.
 *
 * Only the cross term needs a 2D FFT per stripe (template against the slab of
 * reference rows the search can reach).  The other sums are separable: the
 * window is constant along y, so the reference's windowed row sums are 1D
 * correlations done once per frame and summed over rows by prefix sums, and
 * the template's sums over its overlap are prefix sums too.
 *
 * The best peak is located to a fraction of a pixel by a quadratic fitted to
 * its 3x3 neighbourhood, which is enough to judge it and to predict the
 * neighbours; the shift reported is then refined by matching the stripe
 * against the reference interpolated at fractional shifts, with the shift
 * free to change linearly over the stripe's rows and taken at its centre row
 * (stripe-subpixel.c says why the map alone cannot give it without bias).
 * Confidence comes from the peak height and from how far the best competing
 * peak stays below it, so periodic textures and featureless stripes score low.
 * Drift varies smoothly from stripe to stripe: a stripe whose best peak lies
 * far from the median of its confident neighbours is searched again in a
 * small window around that prediction.
 */

/* Competing peaks closer than this (px, in both axes) are the main peak's. */
#define RIVAL_EXCLUSION 3
/* Half-size of the window searched around the neighbours' prediction (px). */
#define CONSISTENCY_RADIUS 3
/* Neighbours on each side whose median predicts a stripe; the far reach is
 * used where the near one has too few confident stripes. */
#define NEAR_REACH 2
#define FAR_REACH 4
/* Fraction of the width tapered by the Tukey window at each side. */
#define WINDOW_TAPER 0.1
/* Shifts that leave less than this fraction of the stripe on the reference
 * are not considered: a tiny overlap can correlate by chance. */
#define MIN_OVERLAP 0.5
/* Correlation peaks below this are hardly above chance for a stripe. */
#define LOW_PEAK 0.3
/* Stripes this confident predict their neighbours. */
#define RELIABLE_SCORE 0.3
/* Correlation maps are kept for the consistency step up to this size;
 * above it they are computed again. */
#define MAP_CACHE_BYTES (256*1024*1024)
/* How far (px) the match may move a peak that lies on the edge of the
 * shifts with enough overlap; a peak inside them moves at most 1 px.  On
 * the edge row itself only dx = 0 may be kept (off it the window loses a
 * little weight), so the true peak may lie a few px along x. */
#define EDGE_POLISH_REACH 3
/* Marks shifts that are not considered. */
#define NO_MATCH -2.0

typedef struct {
    gint iy, ix;          /* map indices of the peak */
    gdouble dy, dx;       /* refined shift, px */
    gdouble value;        /* ZNCC at the peak */
    gdouble rival;        /* best competing local maximum, >= 0 */
    gboolean trusted;     /* found, inside the search area, refinable */
    gboolean polished;    /* dy, dx refined by stripe_subpixel_refine() */
} Peak;

typedef struct {
    const gdouble *image;
    const gdouble *reference;
    gint xres;
    gint yres;
    gint n;
    gint m;                   /* largest shift searched, px */
    gint span;                /* 2m + 1 shifts per axis */
    gint max_height;          /* rows in the tallest stripe */
    gdouble reference_mean;
    gdouble *window;          /* xres weights */
    gdouble *window_overlap;  /* span: window sum over columns with
                                 reference data, per dx */
    gdouble *ref_cum;         /* (yres+1) x span: prefix sums over rows of
                                 the windowed reference row sums, per dx */
    gdouble *ref_sq_cum;      /* the same for squares */
    gdouble *tmpl_cum;        /* (max_height+1) x span: prefix sums over
                                 template rows of their overlap sums */
    gdouble *tmpl_sq_cum;
    gdouble *row_prefix;      /* xres + 1 */
    gdouble *row_sq_prefix;
    FFTCorrelation *stripe_fc;
    gdouble *map;             /* span x span scratch */
    StripeSubpixel *subpixel;
    gdouble **cached_maps;    /* n, NULL where not kept */
} Registration;

G_DEFINE_QUARK(stripe-registration-error-quark, stripe_registration_error)

static gint
map_index(const Registration *reg, gint dy, gint dx)
{
    return (dy + reg->m)*reg->span + (dx + reg->m);
}

static void
make_tukey_window(gdouble *window, gint res)
{
    gint taper = (gint)ceil(WINDOW_TAPER*res), j;

    for (j = 0; j < res; j++) {
        gint edge = MIN(j, res-1 - j);

        if (edge >= taper)
            window[j] = 1.0;
        else
            window[j] = 0.5*(1.0 - cos(G_PI*(edge + 0.5)/taper));
    }
}

/* Columns j of the template meet reference column j - dx; those with
 * reference data form [lo, hi). */
static void
overlap_columns(gint xres, gint dx, gint *lo, gint *hi)
{
    *lo = MAX(0, dx);
    *hi = MIN(xres, xres + dx);
}

static void
compute_window_overlap(Registration *reg)
{
    gint dx, j, lo, hi;

    for (dx = -reg->m; dx <= reg->m; dx++) {
        gdouble s = 0.0;

        overlap_columns(reg->xres, dx, &lo, &hi);
        for (j = lo; j < hi; j++)
            s += reg->window[j];
        reg->window_overlap[dx + reg->m] = s;
    }
}

/* Windowed sums of every reference row (and of its squares) at every dx, as
 * 1D correlations, accumulated over rows: any stripe's reference sums at any
 * shift are then a difference of two entries. */
static void
compute_reference_sums(Registration *reg)
{
    gint xres = reg->xres, m = reg->m, span = reg->span;
    FFTCorrelation *fc;
    gdouble *field;
    const gdouble *corr;
    gint r, j, dx, pass;

    fc = fft_correlation_new(1, fft_correlation_nice_size(xres + 2*m));
    memcpy(fft_correlation_template(fc), reg->window, xres*sizeof(gdouble));
    fft_correlation_set_template(fc);
    field = fft_correlation_field(fc);
    memset(reg->ref_cum, 0, span*sizeof(gdouble));
    memset(reg->ref_sq_cum, 0, span*sizeof(gdouble));
    for (r = 0; r < reg->yres; r++) {
        const gdouble *row = reg->reference + (gsize)r*xres;

        for (pass = 0; pass < 2; pass++) {
            gdouble *cum = pass ? reg->ref_sq_cum : reg->ref_cum;

            for (j = 0; j < xres; j++) {
                gdouble v = row[j] - reg->reference_mean;
                field[m + j] = pass ? v*v : v;
            }
            corr = fft_correlation_run(fc);
            /* corr[b] = sum_j w[j] field[j + b] = sum_j w[j] R[j + b - m]. */
            for (dx = -m; dx <= m; dx++)
                cum[(r + 1)*span + dx + m] = cum[r*span + dx + m] + corr[m - dx];
        }
    }
    fft_correlation_free(fc);
}

static gdouble
stripe_weighted_mean(const Registration *reg, gint first, gint end)
{
    gdouble s = 0.0, w = 0.0;
    gint r, j;

    for (r = first; r < end; r++) {
        const gdouble *row = reg->image + (gsize)r*reg->xres;

        for (j = 0; j < reg->xres; j++) {
            s += reg->window[j]*row[j];
            w += reg->window[j];
        }
    }
    return s/w;
}

/* Puts the windowed, zero-mean template into the FFT buffer and accumulates
 * its overlap sums (of values and squares) over rows, per dx. */
static void
prepare_template(Registration *reg, gint first, gint end)
{
    gint xres = reg->xres, m = reg->m, span = reg->span;
    gint cols = fft_correlation_cols(reg->stripe_fc);
    gdouble *tmpl = fft_correlation_template(reg->stripe_fc);
    gdouble mean = stripe_weighted_mean(reg, first, end);
    gint i, j, dx, lo, hi;

    memset(reg->tmpl_cum, 0, span*sizeof(gdouble));
    memset(reg->tmpl_sq_cum, 0, span*sizeof(gdouble));
    for (i = 0; i < end - first; i++) {
        const gdouble *row = reg->image + (gsize)(first + i)*xres;
        gdouble *trow = tmpl + (gsize)i*cols;

        reg->row_prefix[0] = reg->row_sq_prefix[0] = 0.0;
        for (j = 0; j < xres; j++) {
            gdouble v = row[j] - mean;

            trow[j] = reg->window[j]*v;
            reg->row_prefix[j+1] = reg->row_prefix[j] + trow[j];
            reg->row_sq_prefix[j+1] = reg->row_sq_prefix[j] + trow[j]*v;
        }
        for (dx = -m; dx <= m; dx++) {
            gint k = (i + 1)*span + dx + m;

            overlap_columns(xres, dx, &lo, &hi);
            reg->tmpl_cum[k] = reg->tmpl_cum[k - span] + reg->row_prefix[hi] - reg->row_prefix[lo];
            reg->tmpl_sq_cum[k] = (reg->tmpl_sq_cum[k - span]
                                   + reg->row_sq_prefix[hi] - reg->row_sq_prefix[lo]);
        }
    }
    fft_correlation_set_template(reg->stripe_fc);
}

/* The reference rows the search can reach, first - m .. end - 1 + m, with m
 * columns of zeros each side; zero outside the frame. */
static void
prepare_slab(Registration *reg, gint first, gint end)
{
    gint xres = reg->xres, m = reg->m;
    gint cols = fft_correlation_cols(reg->stripe_fc);
    gdouble *field = fft_correlation_field(reg->stripe_fc);
    gint k, j, r;

    for (k = 0; k < end - first + 2*m; k++) {
        gdouble *frow = field + (gsize)k*cols + m;
        const gdouble *row;

        r = first - m + k;
        if (r < 0 || r >= reg->yres) {
            memset(frow, 0, xres*sizeof(gdouble));
            continue;
        }
        row = reg->reference + (gsize)r*xres;
        for (j = 0; j < xres; j++)
            frow[j] = row[j] - reg->reference_mean;
    }
}

static void
compute_stripe_map(Registration *reg, gint s, gdouble *map)
{
    gint first = stripe_first_row(s, reg->n, reg->yres);
    gint end = stripe_end_row(s, reg->n, reg->yres);
    gint h = end - first, m = reg->m, span = reg->span;
    gint cols = fft_correlation_cols(reg->stripe_fc);
    gdouble full_weight, min_weight;
    const gdouble *cross;
    gint dy, dx;

    fft_correlation_clear(reg->stripe_fc);
    prepare_template(reg, first, end);
    prepare_slab(reg, first, end);
    cross = fft_correlation_run(reg->stripe_fc);
    full_weight = h*reg->window_overlap[m];
    min_weight = MIN_OVERLAP*full_weight;

    for (dy = -m; dy <= m; dy++) {
        /* Template rows i meet reference rows first + i - dy. */
        gint ilo = MAX(0, dy - first), ihi = MIN(h, reg->yres - first + dy);
        gint rlo = first + ilo - dy, rhi = first + ihi - dy;

        for (dx = -m; dx <= m; dx++) {
            gint k = dx + m;
            gdouble w, st, stt, sr, srr, str, vt, vr;

            map[map_index(reg, dy, dx)] = NO_MATCH;
            if (ihi <= ilo)
                continue;
            w = (ihi - ilo)*reg->window_overlap[k];
            if (w < min_weight)
                continue;
            st = reg->tmpl_cum[ihi*span + k] - reg->tmpl_cum[ilo*span + k];
            stt = reg->tmpl_sq_cum[ihi*span + k] - reg->tmpl_sq_cum[ilo*span + k];
            sr = reg->ref_cum[rhi*span + k] - reg->ref_cum[rlo*span + k];
            srr = reg->ref_sq_cum[rhi*span + k] - reg->ref_sq_cum[rlo*span + k];
            str = cross[(m - dy)*cols + (m - dx)];
            vt = stt - st*st/w;
            vr = srr - sr*sr/w;
            /* A flat template or reference patch matches nothing. */
            if (vt <= 1e-12*stt || vr <= 1e-12*srr || vt <= 0.0 || vr <= 0.0) {
                map[map_index(reg, dy, dx)] = 0.0;
                continue;
            }
            map[map_index(reg, dy, dx)] = (str - st*sr/w)/sqrt(vt*vr);
        }
    }
}

static const gdouble*
stripe_map(Registration *reg, gint s)
{
    if (reg->cached_maps && reg->cached_maps[s])
        return reg->cached_maps[s];
    compute_stripe_map(reg, s, reg->map);
    if (!reg->cached_maps)
        return reg->map;
    reg->cached_maps[s] = g_memdup2(reg->map, (gsize)reg->span*reg->span*sizeof(gdouble));
    return reg->cached_maps[s];
}

static gboolean
is_local_maximum(const gdouble *map, gint span, gint iy, gint ix)
{
    gdouble v = map[iy*span + ix];
    gint i, j;

    if (v <= NO_MATCH)
        return FALSE;
    for (i = MAX(0, iy-1); i <= MIN(span-1, iy+1); i++) {
        for (j = MAX(0, ix-1); j <= MIN(span-1, ix+1); j++) {
            /* Next to the shifts left out for too little overlap, a maximum
             * is as likely the cut slope of the main peak beyond them (as
             * for a stripe half off the reference) as a peak of its own. */
            if (map[i*span + j] > v || map[i*span + j] <= NO_MATCH)
                return FALSE;
        }
    }
    return TRUE;
}

/* Least-squares quadratic through the 3x3 neighbourhood; its maximum, when
 * it has one near the centre, else a parabola along each axis. */
static void
refine_peak(const gdouble *map, gint span, gint iy, gint ix, gdouble *oy, gdouble *ox)
{
    gdouble sx = 0.0, sy = 0.0, sxy = 0.0, sxx = 0.0, syy = 0.0;
    gdouble f, det, x, y, fm, fp, f0, denom;
    gint i, j;

    for (i = -1; i <= 1; i++) {
        for (j = -1; j <= 1; j++) {
            f = map[(iy + i)*span + ix + j];
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
    f0 = map[iy*span + ix];
    fm = map[iy*span + ix - 1];
    fp = map[iy*span + ix + 1];
    denom = fm - 2.0*f0 + fp;
    *ox = (denom < 0.0) ? CLAMP(0.5*(fm - fp)/denom, -0.5, 0.5) : 0.0;
    fm = map[(iy - 1)*span + ix];
    fp = map[(iy + 1)*span + ix];
    denom = fm - 2.0*f0 + fp;
    *oy = (denom < 0.0) ? CLAMP(0.5*(fm - fp)/denom, -0.5, 0.5) : 0.0;
}

static gboolean
neighbourhood_matched(const gdouble *map, gint span, gint iy, gint ix)
{
    gint k, l;

    for (k = -1; k <= 1; k++) {
        for (l = -1; l <= 1; l++) {
            if (map[(iy + k)*span + ix + l] <= NO_MATCH)
                return FALSE;
        }
    }
    return TRUE;
}

/* The shift of a trusted peak refined by matching the stripe against the
 * interpolated reference, within reach px of the peak, once per peak; where
 * the match fails to converge the quadratic's estimate stays.  TRUE if the
 * peak is polished. */
static gboolean
polish_peak(Registration *reg, gint s, gint reach, Peak *peak)
{
    gint first = stripe_first_row(s, reg->n, reg->yres), end = stripe_end_row(s, reg->n, reg->yres);

    if (peak->trusted && !peak->polished) {
        peak->polished = stripe_subpixel_refine(reg->subpixel, first, end, peak->iy - reg->m,
                                                peak->ix - reg->m, reach, &peak->dy, &peak->dx);
    }
    return peak->polished;
}

/* The best shift within radius of map indices (cy, cx) in the map of stripe
 * s, and the best local maximum that is not part of it.  A peak on the
 * border of the searched area may be the slope of a better one outside, so
 * it is not trusted. */
static void
find_peak(Registration *reg, gint s, const gdouble *map, gint cy, gint cx, gint radius, Peak *peak)
{
    gint span = reg->span, i, j;
    gint ylo = MAX(0, cy - radius), yhi = MIN(span-1, cy + radius);
    gint xlo = MAX(0, cx - radius), xhi = MIN(span-1, cx + radius);
    gdouble best = NO_MATCH, rival = 0.0, oy, ox;

    peak->iy = cy;
    peak->ix = cx;
    for (i = ylo; i <= yhi; i++) {
        for (j = xlo; j <= xhi; j++) {
            if (map[i*span + j] > best) {
                best = map[i*span + j];
                peak->iy = i;
                peak->ix = j;
            }
        }
    }
    peak->value = best;
    peak->dy = peak->iy - reg->m;
    peak->dx = peak->ix - reg->m;
    peak->polished = FALSE;
    peak->trusted = (best > NO_MATCH
                     && peak->iy > ylo && peak->iy < yhi && peak->ix > xlo && peak->ix < xhi);
    for (i = ylo; i <= yhi; i++) {
        for (j = xlo; j <= xhi; j++) {
            if (ABS(i - peak->iy) < RIVAL_EXCLUSION && ABS(j - peak->ix) < RIVAL_EXCLUSION)
                continue;
            if (map[i*span + j] > rival && is_local_maximum(map, span, i, j))
                rival = map[i*span + j];
        }
    }
    peak->rival = rival;
    if (!peak->trusted)
        return;
    if (neighbourhood_matched(map, span, peak->iy, peak->ix)) {
        refine_peak(map, span, peak->iy, peak->ix, &oy, &ox);
        peak->dy += oy;
        peak->dx += ox;
    }
    else {
        /* On the edge of the shifts that keep enough of the stripe on the
         * reference the map cannot tell a peak from the slope of a better
         * one beyond; the match can, and says where the peak lies, which
         * must still be within the searched area. */
        peak->trusted = (polish_peak(reg, s, EDGE_POLISH_REACH, peak)
                         && peak->dy >= ylo - reg->m && peak->dy <= yhi - reg->m
                         && peak->dx >= xlo - reg->m && peak->dx <= xhi - reg->m);
        if (!peak->trusted) {
            peak->dy = peak->iy - reg->m;
            peak->dx = peak->ix - reg->m;
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

static gdouble
median_of(gdouble *values, gint count)
{
    gint i, j;

    /* A handful of values: insertion sort. */
    for (i = 1; i < count; i++) {
        gdouble v = values[i];

        for (j = i; j > 0 && values[j-1] > v; j--)
            values[j] = values[j-1];
        values[j] = v;
    }
    if (count % 2)
        return values[count/2];
    return 0.5*(values[count/2 - 1] + values[count/2]);
}

/* The median shift of the confident stripes around s (not s itself), from
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
    *dy = median_of(ys, count);
    *dx = median_of(xs, count);
    return TRUE;
}

static void
set_shift(StripeShift *shift, const Peak *peak, gdouble score, gboolean resolved, gdouble min_score)
{
    shift->dx = peak->dx;
    shift->dy = peak->dy;
    shift->score = score;
    shift->accepted = peak->trusted && score >= min_score && score > 0.0;
    shift->peak = MAX(peak->value, -1.0);
    shift->rival = peak->rival;
    shift->resolved = resolved;
}

/* Every stripe with a prediction from its neighbours is judged within a small
 * window around it: there, a peak is either the neighbours' peak or a rival
 * the neighbours rule out.  A stripe whose own best peak lies outside the
 * window takes the best peak inside, at a score scaled down by how much lower
 * that peak is. */
static void
choose_consistent_shifts(Registration *reg, const Peak *global, gdouble min_score, StripeShift *shifts)
{
    gint n = reg->n, s;
    gboolean *reliable = g_new(gboolean, MAX(n, 1));
    gdouble py, px, score;
    Peak local;

    for (s = 0; s < n; s++)
        reliable[s] = (peak_score(global + s) >= MAX(min_score, RELIABLE_SCORE));
    for (s = 0; s < n; s++) {
        gboolean resolved;

        if (!predict_from_neighbours(global, reliable, n, s, &py, &px)) {
            local = global[s];
            polish_peak(reg, s, 1, &local);
            set_shift(shifts + s, &local, peak_score(&local), FALSE, min_score);
            continue;
        }
        find_peak(reg, s, stripe_map(reg, s), (gint)floor(py + 0.5) + reg->m,
                  (gint)floor(px + 0.5) + reg->m, CONSISTENCY_RADIUS, &local);
        polish_peak(reg, s, 1, &local);
        resolved = (local.iy != global[s].iy || local.ix != global[s].ix);
        score = peak_score(&local);
        if (resolved && global[s].value > 0.0)
            score *= CLAMP(local.value/global[s].value, 0.0, 1.0);
        set_shift(shifts + s, &local, score, resolved, min_score);
    }
    g_free(reliable);
}

static void
registration_setup(Registration *reg, const gdouble *image, const gdouble *reference,
                   gint xres, gint yres, gint n, gdouble max_shift_px)
{
    gint s, rows, cols;
    gsize maps_bytes;
    gdouble sum = 0.0;
    gsize k;

    gwy_clear(reg, 1);
    reg->image = image;
    reg->reference = reference;
    reg->xres = xres;
    reg->yres = yres;
    reg->n = n;
    if (max_shift_px > 0.0)
        reg->m = (gint)MIN(ceil(max_shift_px), G_MAXINT/4);
    else
        reg->m = MIN(xres, yres)/4;
    /* Beyond half the smaller side most of a stripe has left the frame. */
    reg->m = CLAMP(reg->m, 1, MIN(xres, yres)/2);
    reg->span = 2*reg->m + 1;
    for (s = 0; s < n; s++)
        reg->max_height = MAX(reg->max_height, stripe_end_row(s, n, yres) - stripe_first_row(s, n, yres));

    for (k = 0; k < (gsize)xres*yres; k++)
        sum += reference[k];
    reg->reference_mean = sum/((gdouble)xres*yres);

    reg->window = g_new(gdouble, xres);
    make_tukey_window(reg->window, xres);
    reg->window_overlap = g_new(gdouble, reg->span);
    compute_window_overlap(reg);
    reg->ref_cum = g_new(gdouble, (gsize)(yres + 1)*reg->span);
    reg->ref_sq_cum = g_new(gdouble, (gsize)(yres + 1)*reg->span);
    compute_reference_sums(reg);

    reg->tmpl_cum = g_new(gdouble, (gsize)(reg->max_height + 1)*reg->span);
    reg->tmpl_sq_cum = g_new(gdouble, (gsize)(reg->max_height + 1)*reg->span);
    reg->row_prefix = g_new(gdouble, xres + 1);
    reg->row_sq_prefix = g_new(gdouble, xres + 1);
    rows = fft_correlation_nice_size(reg->max_height + 2*reg->m);
    cols = fft_correlation_nice_size(xres + 2*reg->m);
    reg->stripe_fc = fft_correlation_new(rows, cols);
    reg->map = g_new(gdouble, (gsize)reg->span*reg->span);
    reg->subpixel = stripe_subpixel_new(image, reference, xres, yres, reg->window, reg->max_height);
    maps_bytes = (gsize)n*reg->span*reg->span*sizeof(gdouble);
    if (maps_bytes <= MAP_CACHE_BYTES)
        reg->cached_maps = g_new0(gdouble*, n);
}

static void
registration_free(Registration *reg)
{
    gint s;

    if (reg->cached_maps) {
        for (s = 0; s < reg->n; s++)
            g_free(reg->cached_maps[s]);
        g_free(reg->cached_maps);
    }
    fft_correlation_free(reg->stripe_fc);
    stripe_subpixel_free(reg->subpixel);
    g_free(reg->map);
    g_free(reg->row_sq_prefix);
    g_free(reg->row_prefix);
    g_free(reg->tmpl_sq_cum);
    g_free(reg->tmpl_cum);
    g_free(reg->ref_sq_cum);
    g_free(reg->ref_cum);
    g_free(reg->window_overlap);
    g_free(reg->window);
}

static gboolean
all_finite(const gdouble *data, gsize count)
{
    gsize k;

    for (k = 0; k < count; k++) {
        if (!isfinite(data[k]))
            return FALSE;
    }
    return TRUE;
}

static gboolean
check_arguments(const gdouble *image, const gdouble *reference, gint xres, gint yres, gint n,
                GError **error)
{
    if (xres < 4 || yres < 4) {
        g_set_error(error, STRIPE_REGISTRATION_ERROR, STRIPE_REGISTRATION_ERROR_SIZE,
                    _("The image (%d x %d px) is too small to register: it needs at least 4 x 4 px."),
                    xres, yres);
        return FALSE;
    }
    if (n < 1 || n > yres) {
        g_set_error(error, STRIPE_REGISTRATION_ERROR, STRIPE_REGISTRATION_ERROR_STRIPES,
                    _("The number of stripes (%d) must be between 1 and the image's %d rows."),
                    n, yres);
        return FALSE;
    }
    if (!all_finite(image, (gsize)xres*yres)) {
        g_set_error(error, STRIPE_REGISTRATION_ERROR, STRIPE_REGISTRATION_ERROR_VALUE,
                    _("The image contains NaN or infinite values."));
        return FALSE;
    }
    if (!all_finite(reference, (gsize)xres*yres)) {
        g_set_error(error, STRIPE_REGISTRATION_ERROR, STRIPE_REGISTRATION_ERROR_VALUE,
                    _("The reference contains NaN or infinite values."));
        return FALSE;
    }
    return TRUE;
}

static gint
nearest_int(gdouble x)
{
    return (gint)floor(x + 0.5);
}

/* Each stripe's best peak within radius of its predicted shift (0 without a
 * prediction).  A blind search (no prediction) is followed by the
 * consistency step; a predicted window already is the prior the step
 * would impose, and one wider than the step's own window is the caller's
 * statement that neighbours may differ by that much. */
static void
register_stripes(Registration *reg, const gdouble *predicted_dx, const gdouble *predicted_dy,
                 gint radius, gdouble min_score, StripeShift *shifts)
{
    Peak *global;
    gint s, cx, cy;

    g_return_if_fail(reg->n >= 1);
    global = g_new(Peak, reg->n);
    for (s = 0; s < reg->n; s++) {
        cx = predicted_dx ? nearest_int(predicted_dx[s]) : 0;
        cy = predicted_dy ? nearest_int(predicted_dy[s]) : 0;
        find_peak(reg, s, stripe_map(reg, s), cy + reg->m, cx + reg->m, radius, global + s);
        if (predicted_dx) {
            polish_peak(reg, s, 1, global + s);
            set_shift(shifts + s, global + s, peak_score(global + s), FALSE, min_score);
        }
    }
    if (!predicted_dx)
        choose_consistent_shifts(reg, global, min_score, shifts);
    g_free(global);
}

gboolean
stripe_registration_measure(const gdouble *image, const gdouble *reference, gint xres, gint yres, gint n,
                            gdouble max_shift_px, gdouble min_score, StripeShift *shifts, GError **error)
{
    Registration reg;

    g_return_val_if_fail(image && reference && shifts, FALSE);
    if (!check_arguments(image, reference, xres, yres, n, error))
        return FALSE;

    registration_setup(&reg, image, reference, xres, yres, n, max_shift_px);
    register_stripes(&reg, NULL, NULL, reg.m, min_score, shifts);
    registration_free(&reg);
    return TRUE;
}

gboolean
stripe_registration_measure_around(const gdouble *image, const gdouble *reference, gint xres, gint yres,
                                   gint n, const gdouble *predicted_dx, const gdouble *predicted_dy,
                                   gdouble radius_px, gdouble min_score, StripeShift *shifts,
                                   GError **error)
{
    Registration reg;
    gint s, radius, reach = 0;

    g_return_val_if_fail(image && reference && predicted_dx && predicted_dy && shifts, FALSE);
    if (!check_arguments(image, reference, xres, yres, n, error))
        return FALSE;
    for (s = 0; s < n; s++) {
        if (!isfinite(predicted_dx[s]) || !isfinite(predicted_dy[s])) {
            g_set_error(error, STRIPE_REGISTRATION_ERROR, STRIPE_REGISTRATION_ERROR_VALUE,
                        _("The predicted shift of stripe %d is not a finite number."), s);
            return FALSE;
        }
    }
    radius = (gint)CLAMP(ceil(radius_px), 1, MIN(xres, yres)/2);
    /* The correlation maps must reach every stripe's window. */
    for (s = 0; s < n; s++) {
        gdouble far = MAX(fabs(predicted_dx[s]), fabs(predicted_dy[s]));

        reach = MAX(reach, (gint)MIN(far + 0.5, MIN(xres, yres)) + radius);
    }
    registration_setup(&reg, image, reference, xres, yres, n, reach);
    register_stripes(&reg, predicted_dx, predicted_dy, radius, min_score, shifts);
    registration_free(&reg);
    return TRUE;
}

gboolean
stripe_registration_measure_fields(GwyDataField *image, GwyDataField *reference, gint n,
                                   gdouble max_shift_px, gdouble min_score, StripeShift *shifts,
                                   GError **error)
{
    gint xres, yres, rxres, ryres;

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
    return stripe_registration_measure(gwy_data_field_get_data_const(image),
                                       gwy_data_field_get_data_const(reference),
                                       xres, yres, n, max_shift_px, min_score, shifts, error);
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
    }
    return table;
}

DriftTable*
stripe_registration_table_for_fields(GwyDataField *image, GwyDataField *reference, gint n,
                                     gdouble max_shift_px, gboolean whole_pixels, GError **error)
{
    StripeShift *shifts;
    DriftTable *table = NULL;

    g_return_val_if_fail(n >= 1, NULL);
    shifts = g_new(StripeShift, n);
    if (stripe_registration_measure_fields(image, reference, n, max_shift_px,
                                           STRIPE_REGISTRATION_DEFAULT_MIN_SCORE, shifts, error)) {
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
