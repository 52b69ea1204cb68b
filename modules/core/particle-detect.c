/*
 *  Finding particles in a (drift-contaminated) image and choosing one per
 *  stripe.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <stdlib.h>
#include <math.h>
#include <libgwyddion/gwymath.h>
#include <libprocess/stats.h>
#include <libprocess/level.h>
#include <libprocess/grains.h>
#include "stripe-geometry.h"
#include "particle-detect.h"
#include "median.h"

/* Automatic threshold on a levelled image: this many noise sigmas ... */
#define AUTO_NOISE_SIGMAS 10.0
/* ... and at least this fraction of the highest particle. */
#define AUTO_RANGE_FRACTION 0.1
/* Pixels this many noise sigmas above the substrate are left out of the
 * levelling fits as (parts of) particles. */
#define LEVEL_MASK_SIGMAS 3.0
/* A particle's top: above this fraction of its height (the local scan's
 * default chord threshold).  A sphere of radius R is cut there in a disc of
 * radius sqrt(1 - (2 TOP_FRACTION - 1)^2) R. */
#define TOP_FRACTION 0.75
#define TOP_CUT_RADIUS 0.8660254037844386
/* The refined centre weighs the pixels within this many equivalent radii
 * of the grain (the radius of a disc of its area) ... */
#define WINDOW_RADII 2.0
/* ... moving the window to the new centre this many times. */
#define WINDOW_ITERATIONS 5

typedef struct {
    gdouble sw, swx, swy;
    gint area;
    gdouble peak;          /* in the field's own values */
    gdouble level_peak;    /* in the values grains were found on */
    gboolean on_edge;
    gint row_min, row_max;
    gint top_area;
} GrainSums;

void
particle_detect_params_init(ParticleDetectParams *params)
{
    params->height = 0.0;
    params->min_area = 1;
    params->max_area = 0;
    params->level = TRUE;
}

gdouble
particle_detect_substrate(GwyDataField *field)
{
    return gwy_data_field_get_median(field);
}

gdouble
particle_detect_noise(GwyDataField *field, gdouble median)
{
    gint n = gwy_data_field_get_xres(field)*gwy_data_field_get_yres(field);
    const gdouble *d = gwy_data_field_get_data_const(field);
    gdouble *dev = g_new(gdouble, n), mad;
    gint k;

    for (k = 0; k < n; k++)
        dev[k] = fabs(d[k] - median);
    mad = median_in_place(dev, n);
    g_free(dev);
    /* The MAD of a Gaussian is 0.6745 sigma. */
    return mad/0.6745;
}

/* Pixels clearly above the substrate of a roughly levelled field. */
static GwyDataField*
particle_mask(GwyDataField *field)
{
    GwyDataField *mask = gwy_data_field_new_alike(field, FALSE);
    gdouble median = gwy_data_field_get_median(field);
    gdouble above = median + LEVEL_MASK_SIGMAS*particle_detect_noise(field,
                                                                     median);
    const gdouble *d = gwy_data_field_get_data_const(field);
    gdouble *m = gwy_data_field_get_data(mask);
    gint k, n = gwy_data_field_get_xres(field)*gwy_data_field_get_yres(field);

    for (k = 0; k < n; k++)
        m[k] = (d[k] > above) ? 1.0 : 0.0;
    return mask;
}

static void
subtract_row_medians(GwyDataField *field, GwyDataField *mask)
{
    gint xres = gwy_data_field_get_xres(field);
    gint yres = gwy_data_field_get_yres(field);
    GwyDataLine *medians = gwy_data_line_new(yres, yres, FALSE);
    gdouble *d = gwy_data_field_get_data(field);
    const gdouble *m;
    gint i, j;

    /* A row that is all particle keeps its plain median. */
    gwy_data_field_get_line_stats_mask(field, mask, GWY_MASK_EXCLUDE, medians,
                                       NULL, 0, 0, xres, yres,
                                       GWY_LINE_STAT_MEDIAN,
                                       GWY_ORIENTATION_HORIZONTAL);
    m = gwy_data_line_get_data_const(medians);
    for (i = 0; i < yres; i++) {
        gdouble z = isfinite(m[i]) ? m[i]
                    : gwy_data_field_area_get_median(field, NULL, 0, i,
                                                     xres, 1);

        for (j = 0; j < xres; j++)
            d[i*xres + j] -= z;
    }
    g_object_unref(medians);
}

GwyDataField*
particle_detect_level(GwyDataField *field)
{
    GwyDataField *levelled = gwy_data_field_duplicate(field), *mask;
    gint xres = gwy_data_field_get_xres(field);
    gint yres = gwy_data_field_get_yres(field);
    gdouble a, bx, by;

    /* A plain plane first, so particles stand out for the mask; then the
     * plane of the substrate alone, fitted to the original values. */
    gwy_data_field_fit_plane(levelled, &a, &bx, &by);
    gwy_data_field_plane_level(levelled, a, bx, by);
    mask = particle_mask(levelled);
    gwy_data_field_copy(field, levelled, FALSE);
    gwy_data_field_area_fit_plane_mask(levelled, mask, GWY_MASK_EXCLUDE,
                                       0, 0, xres, yres, &a, &bx, &by);
    gwy_data_field_plane_level(levelled, a, bx, by);
    /* Median line correction: the offsets a measured image's lines have. */
    subtract_row_medians(levelled, mask);
    g_object_unref(mask);
    gwy_data_field_add(levelled, -gwy_data_field_get_median(levelled));
    return levelled;
}

gdouble
particle_detect_auto_height(GwyDataField *field, gdouble substrate,
                            gboolean levelled)
{
    gdouble range = gwy_data_field_get_max(field) - substrate;

    if (!levelled)
        return 0.5*range;
    return fmax(AUTO_NOISE_SIGMAS*particle_detect_noise(field, substrate),
                AUTO_RANGE_FRACTION*range);
}

/* Grains are numbered on work (the levelled copy or field itself); centres
 * and areas come from work, peaks from field. */
static void
sum_grains(GwyDataField *field, GwyDataField *work, const gint *grains,
           gdouble threshold, GrainSums *sums)
{
    gint xres = gwy_data_field_get_xres(field);
    gint yres = gwy_data_field_get_yres(field);
    const gdouble *d = gwy_data_field_get_data_const(field);
    const gdouble *w = gwy_data_field_get_data_const(work);
    gint i, j, g;

    for (i = 0; i < yres; i++) {
        for (j = 0; j < xres; j++) {
            gdouble z = w[i*xres + j], weight;
            GrainSums *s;

            if (!(g = grains[i*xres + j]))
                continue;
            s = sums + g;
            /* A tiny floor keeps a grain of pixels exactly at the threshold
             * (flat tops) from having zero total weight. */
            weight = fmax(z - threshold, 1e-30);
            s->sw += weight;
            s->swx += weight*j;
            s->swy += weight*i;
            s->area++;
            if (s->area == 1) {
                s->peak = d[i*xres + j];
                s->level_peak = z;
                s->row_min = i;
            }
            s->peak = fmax(s->peak, d[i*xres + j]);
            s->level_peak = fmax(s->level_peak, z);
            s->row_max = i;
            if (i == 0 || j == 0 || i == yres-1 || j == xres-1)
                s->on_edge = TRUE;
        }
    }
}

static void
count_top_areas(GwyDataField *work, const gint *grains, gdouble base,
                GrainSums *sums)
{
    gint k, n = gwy_data_field_get_xres(work)*gwy_data_field_get_yres(work);
    const gdouble *w = gwy_data_field_get_data_const(work);

    for (k = 0; k < n; k++) {
        GrainSums *s;

        if (!grains[k])
            continue;
        s = sums + grains[k];
        if (w[k] - base > TOP_FRACTION*(s->level_peak - base))
            s->top_area++;
    }
}

/* One step of the window centroid: pixels within r px of (*x, *y), weighted
 * by their height over the substrate base.  FALSE when nothing there stands
 * above it. */
static gboolean
window_centroid_step(GwyDataField *work, const gint *grains, gint g,
                     gdouble base, gdouble r, gdouble *x, gdouble *y)
{
    gint xres = gwy_data_field_get_xres(work);
    gint yres = gwy_data_field_get_yres(work);
    const gdouble *d = gwy_data_field_get_data_const(work);
    gint i, j, imin, imax, jmin, jmax;
    gdouble sw = 0.0, swx = 0.0, swy = 0.0;

    imin = MAX((gint)floor(*y - r), 0);
    imax = MIN((gint)ceil(*y + r), yres-1);
    jmin = MAX((gint)floor(*x - r), 0);
    jmax = MIN((gint)ceil(*x + r), xres-1);
    for (i = imin; i <= imax; i++) {
        for (j = jmin; j <= jmax; j++) {
            gdouble w;

            if ((i - *y)*(i - *y) + (j - *x)*(j - *x) > r*r
                || (grains[i*xres + j] && grains[i*xres + j] != g))
                continue;
            w = fmax(d[i*xres + j] - base, 0.0);
            sw += w;
            swx += w*j;
            swy += w*i;
        }
    }
    if (!(sw > 0.0))
        return FALSE;
    *x = swx/sw;
    *y = swy/sw;
    return TRUE;
}

/* The thresholded centroid sees only the few pixels of a small particle's
 * top, so it snaps towards pixel centres (0.12 px RMS on simscan's paper
 * scenario).  A window of fixed size around the particle, weighted by the
 * height over the substrate, takes in its flanks as well, whose pixels
 * balance each other as the particle moves across the grid. */
static void
refine_centre(GwyDataField *work, const gint *grains, gint g, gdouble base,
              const GrainSums *sums, DetectedParticle *p)
{
    gdouble r = WINDOW_RADII*sqrt(sums->area/G_PI);
    gdouble x = p->x, y = p->y;
    gint k;

    for (k = 0; k < WINDOW_ITERATIONS; k++) {
        if (!window_centroid_step(work, grains, g, base, r, &x, &y))
            return;
    }
    p->x = x;
    p->y = y;
}

GArray*
particle_detect(GwyDataField *field, const ParticleDetectParams *params,
                gdouble *substrate, gdouble *threshold)
{
    GwyDataField *mask, *work;
    GArray *particles;
    GrainSums *sums;
    gint *grains;
    gdouble base, work_base, thr, height;
    gint xres, yres, ngrains, g, k;
    const gdouble *d;
    gdouble *m;

    xres = gwy_data_field_get_xres(field);
    yres = gwy_data_field_get_yres(field);
    base = particle_detect_substrate(field);
    work = params->level ? particle_detect_level(field) : g_object_ref(field);
    work_base = params->level ? 0.0 : base;
    height = params->height;
    if (height <= 0.0)
        height = particle_detect_auto_height(work, work_base, params->level);
    thr = work_base + height;

    mask = gwy_data_field_new_alike(work, FALSE);
    d = gwy_data_field_get_data_const(work);
    m = gwy_data_field_get_data(mask);
    for (k = 0; k < xres*yres; k++)
        m[k] = (d[k] > thr) ? 1.0 : 0.0;

    grains = g_new0(gint, xres*yres);
    ngrains = gwy_data_field_number_grains(mask, grains);
    sums = g_new0(GrainSums, ngrains + 1);
    sum_grains(field, work, grains, thr, sums);
    count_top_areas(work, grains, work_base, sums);

    particles = g_array_new(FALSE, FALSE, sizeof(DetectedParticle));
    for (g = 1; g <= ngrains; g++) {
        DetectedParticle p;

        if (sums[g].area < params->min_area
            || (params->max_area > 0 && sums[g].area > params->max_area))
            continue;
        p.x = sums[g].swx/sums[g].sw;
        p.y = sums[g].swy/sums[g].sw;
        refine_centre(work, grains, g, work_base, sums + g, &p);
        p.area = sums[g].area;
        p.peak = sums[g].peak;
        p.on_edge = sums[g].on_edge;
        p.row_min = sums[g].row_min;
        p.row_max = sums[g].row_max;
        p.top_area = sums[g].top_area;
        g_array_append_val(particles, p);
    }

    g_free(sums);
    g_free(grains);
    g_object_unref(mask);
    g_object_unref(work);
    if (substrate)
        *substrate = base;
    if (threshold)
        *threshold = base + height;
    return particles;
}

gdouble
particle_typical_radius(const GArray *particles, gdouble dx, gdouble dy)
{
    gdouble *radii, r;
    guint k, n = particles->len;

    if (!n)
        return 0.0;
    radii = g_new(gdouble, n);
    for (k = 0; k < n; k++) {
        const DetectedParticle *p = &g_array_index(particles,
                                                   DetectedParticle, k);

        radii[k] = sqrt(p->top_area*dx*dy/G_PI)/TOP_CUT_RADIUS;
    }
    /* The lower quartile, a radius that some particle really has: the
     * search must not step over the smaller particles' tops, and a single
     * speck must not set it. */
    r = median_kth_in_place(radii, n, (n - 1)/4);
    g_free(radii);
    return r;
}

gboolean
particle_touches_stripe_boundary(const DetectedParticle *particle, gint s,
                                 gint n, gint yres)
{
    return (particle->row_min <= stripe_first_row(s, n, yres)
            || particle->row_max >= stripe_end_row(s, n, yres) - 1);
}

void
particle_choose_for_stripes_by(const GArray *particles, gint n, gint xres,
                               gint yres, ParticleChoice choice, gint *chosen)
{
    gdouble *best;
    gboolean *whole;
    guint k;
    gint s;

    best = g_new(gdouble, n);
    whole = g_new0(gboolean, n);
    for (s = 0; s < n; s++) {
        chosen[s] = -1;
        best[s] = G_MAXDOUBLE;
    }
    for (k = 0; k < particles->len; k++) {
        const DetectedParticle *p = &g_array_index(particles,
                                                   DetectedParticle, k);
        gint row = (gint)floor(p->y + 0.5);
        gdouble ex, ey, dist2;
        gboolean is_whole = FALSE, better;

        if (p->on_edge || row < 0 || row >= yres)
            continue;
        s = stripe_of_row(row, n, yres);
        if (choice == PARTICLE_CHOICE_PREFER_WHOLE) {
            is_whole = !particle_touches_stripe_boundary(p, s, n, yres);
            if (whole[s] && !is_whole)
                continue;
        }
        ex = p->x - 0.5*(xres - 1);
        ey = p->y - stripe_centre_row(s, n, yres);
        dist2 = ex*ex + ey*ey;
        /* Strictly smaller: on a tie the earlier grain wins, deterministically. */
        better = (dist2 < best[s]) || (is_whole && !whole[s]);
        if (better) {
            best[s] = dist2;
            chosen[s] = (gint)k;
            whole[s] = is_whole;
        }
    }
    g_free(whole);
    g_free(best);
}

void
particle_choose_for_stripes(const GArray *particles, gint n, gint xres,
                            gint yres, gint *chosen)
{
    particle_choose_for_stripes_by(particles, n, xres, yres,
                                   PARTICLE_CHOICE_CLOSEST, chosen);
}
