/*
 *  Finding particles in a (drift-contaminated) image and choosing one per
 *  stripe.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <math.h>
#include <libprocess/stats.h>
#include <libprocess/grains.h>
#include "stripe-geometry.h"
#include "particle-detect.h"

typedef struct {
    gdouble sw, swx, swy;
    gint area;
    gdouble peak;
    gboolean on_edge;
    gint row_min, row_max;
} GrainSums;

void
particle_detect_params_init(ParticleDetectParams *params)
{
    params->height = 0.0;
    params->min_area = 1;
    params->max_area = 0;
}

gdouble
particle_detect_substrate(GwyDataField *field)
{
    return gwy_data_field_get_median(field);
}

static void
sum_grains(GwyDataField *field, const gint *grains, gdouble threshold,
           GrainSums *sums)
{
    gint xres = gwy_data_field_get_xres(field);
    gint yres = gwy_data_field_get_yres(field);
    const gdouble *d = gwy_data_field_get_data_const(field);
    gint i, j, g;

    for (i = 0; i < yres; i++) {
        for (j = 0; j < xres; j++) {
            gdouble z = d[i*xres + j], w;
            GrainSums *s;

            if (!(g = grains[i*xres + j]))
                continue;
            s = sums + g;
            /* A tiny floor keeps a grain of pixels exactly at the threshold
             * (flat tops) from having zero total weight. */
            w = fmax(z - threshold, 1e-30);
            s->sw += w;
            s->swx += w*j;
            s->swy += w*i;
            s->area++;
            if (s->area == 1) {
                s->peak = z;
                s->row_min = i;
            }
            s->peak = fmax(s->peak, z);
            s->row_max = i;
            if (i == 0 || j == 0 || i == yres-1 || j == xres-1)
                s->on_edge = TRUE;
        }
    }
}

GArray*
particle_detect(GwyDataField *field, const ParticleDetectParams *params,
                gdouble *substrate, gdouble *threshold)
{
    GwyDataField *mask;
    GArray *particles;
    GrainSums *sums;
    gint *grains;
    gdouble base, thr, height;
    gint xres, yres, ngrains, g, k;
    const gdouble *d;
    gdouble *m;

    xres = gwy_data_field_get_xres(field);
    yres = gwy_data_field_get_yres(field);
    base = particle_detect_substrate(field);
    height = params->height;
    if (height <= 0.0)
        height = 0.5*(gwy_data_field_get_max(field) - base);
    thr = base + height;

    mask = gwy_data_field_new_alike(field, FALSE);
    d = gwy_data_field_get_data_const(field);
    m = gwy_data_field_get_data(mask);
    for (k = 0; k < xres*yres; k++)
        m[k] = (d[k] > thr) ? 1.0 : 0.0;

    grains = g_new0(gint, xres*yres);
    ngrains = gwy_data_field_number_grains(mask, grains);
    sums = g_new0(GrainSums, ngrains + 1);
    sum_grains(field, grains, thr, sums);

    particles = g_array_new(FALSE, FALSE, sizeof(DetectedParticle));
    for (g = 1; g <= ngrains; g++) {
        DetectedParticle p;

        if (sums[g].area < params->min_area
            || (params->max_area > 0 && sums[g].area > params->max_area))
            continue;
        p.x = sums[g].swx/sums[g].sw;
        p.y = sums[g].swy/sums[g].sw;
        p.area = sums[g].area;
        p.peak = sums[g].peak;
        p.on_edge = sums[g].on_edge;
        p.row_min = sums[g].row_min;
        p.row_max = sums[g].row_max;
        g_array_append_val(particles, p);
    }

    g_free(sums);
    g_free(grains);
    g_object_unref(mask);
    if (substrate)
        *substrate = base;
    if (threshold)
        *threshold = thr;
    return particles;
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
