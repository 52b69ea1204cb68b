/*
 *  Synthetic frame pairs for the stripe registration: one analytic surface
 *  sampled as a drift-free reference and as a drifting image.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include "raw-artefacts.h"
#include "registration-frames.h"

enum {
    ROUGHNESS_MODES = 64,
    /* Particles lie this far outside the frame too, so that content drifting
     * into the image is as rich as the rest. */
    PARTICLE_MARGIN = 12,
};

typedef struct {
    gdouble x, y, sigma, height;
} Particle;

/* The surface is analytic, so the drifting image can be sampled at exact
 * sub-pixel positions. */
typedef struct {
    const FramePairSpec *spec;
    gint nparticles;
    Particle *particles;
    gdouble amplitude;                /* of each roughness mode */
    gdouble kx[ROUGHNESS_MODES], ky[ROUGHNESS_MODES], phase[ROUGHNESS_MODES];
    gdouble *cos_kx, *sin_kx;         /* ROUGHNESS_MODES x xres */
} Surface;

typedef struct {
    gdouble offset, velocity, settle, tau;
} DriftAxis;

void
frame_pair_spec_init(FramePairSpec *spec)
{
    spec->xres = spec->yres = 256;
    spec->noise = 0.05;
    spec->particle_density = 1.0/1200.0;
    spec->roughness = 0.15;
    spec->lattice = 0.0;
    spec->grating = 0.0;
    spec->lattice_period = 12.0;
    spec->flat_from = spec->flat_to = 0;
    spec->drift = TRUE;
    spec->drift_scale = 1.0;
    spec->shift_x = spec->shift_y = 0.0;
    spec->velocity_x = spec->velocity_y = 0.0;
    spec->jump_row = -1;
    spec->jump_x = spec->jump_y = 0.0;
}

static void
surface_init(Surface *surface, const FramePairSpec *spec, GRand *rng)
{
    gint xres = spec->xres, k, c;

    surface->spec = spec;
    surface->nparticles = (gint)((spec->xres + 2*PARTICLE_MARGIN)*(gdouble)(spec->yres + 2*PARTICLE_MARGIN)
                                  *spec->particle_density);
    surface->particles = g_new(Particle, surface->nparticles);
    for (k = 0; k < surface->nparticles; k++) {
        Particle *p = surface->particles + k;

        p->x = g_rand_double_range(rng, -PARTICLE_MARGIN, xres + PARTICLE_MARGIN);
        p->y = g_rand_double_range(rng, -PARTICLE_MARGIN, spec->yres + PARTICLE_MARGIN);
        p->sigma = g_rand_double_range(rng, 2.0, 5.0);
        p->height = g_rand_double_range(rng, 0.5, 1.5);
    }
    surface->amplitude = spec->roughness*sqrt(2.0/ROUGHNESS_MODES);
    surface->cos_kx = g_new(gdouble, ROUGHNESS_MODES*xres);
    surface->sin_kx = g_new(gdouble, ROUGHNESS_MODES*xres);
    for (k = 0; k < ROUGHNESS_MODES; k++) {
        gdouble wavelength = 6.0*exp(g_rand_double(rng)*log(64.0/6.0));
        gdouble angle = g_rand_double_range(rng, 0.0, 2.0*G_PI);

        surface->kx[k] = 2.0*G_PI/wavelength*cos(angle);
        surface->ky[k] = 2.0*G_PI/wavelength*sin(angle);
        surface->phase[k] = g_rand_double_range(rng, 0.0, 2.0*G_PI);
        for (c = 0; c < xres; c++) {
            surface->cos_kx[k*xres + c] = cos(surface->kx[k]*c);
            surface->sin_kx[k*xres + c] = sin(surface->kx[k]*c);
        }
    }
}

static void
surface_free(Surface *surface)
{
    g_free(surface->particles);
    g_free(surface->cos_kx);
    g_free(surface->sin_kx);
}

/* out[c] = z(c - shift_x, y) for one row. */
static void
surface_sample_row(const Surface *surface, gdouble y, gdouble shift_x, gdouble *out)
{
    const FramePairSpec *spec = surface->spec;
    gint xres = spec->xres, k, c;

    for (c = 0; c < xres; c++)
        out[c] = 0.0;
    if (y >= spec->flat_from && y < spec->flat_to)
        return;
    for (k = 0; k < ROUGHNESS_MODES; k++) {
        gdouble theta = surface->ky[k]*y - surface->kx[k]*shift_x + surface->phase[k];
        gdouble a = surface->amplitude*cos(theta), b = surface->amplitude*sin(theta);
        const gdouble *ck = surface->cos_kx + k*xres, *sk = surface->sin_kx + k*xres;

        for (c = 0; c < xres; c++)
            out[c] += a*ck[c] - b*sk[c];
    }
    if (spec->lattice != 0.0) {
        gdouble q = 2.0*G_PI/spec->lattice_period, cy = cos(q*y);

        for (c = 0; c < xres; c++)
            out[c] += spec->lattice*(cos(q*(c - shift_x)) + cy);
    }
    if (spec->grating != 0.0) {
        gdouble q = 2.0*G_PI/spec->lattice_period;

        for (c = 0; c < xres; c++)
            out[c] += spec->grating*cos(q*(c - shift_x));
    }
    for (k = 0; k < surface->nparticles; k++) {
        const Particle *p = surface->particles + k;
        gdouble reach = 4.0*p->sigma, ey, x;
        gint cfrom, cto;

        if (fabs(y - p->y) > reach)
            continue;
        ey = p->height*exp(-0.5*(y - p->y)*(y - p->y)/(p->sigma*p->sigma));
        cfrom = MAX(0, (gint)floor(p->x + shift_x - reach));
        cto = MIN(xres - 1, (gint)ceil(p->x + shift_x + reach));
        for (c = cfrom; c <= cto; c++) {
            x = c - shift_x - p->x;
            out[c] += ey*exp(-0.5*x*x/(p->sigma*p->sigma));
        }
    }
}

/* Constant velocity plus exponential settling, as a drifting scanner does
 * after a move: p(r) = offset + v r + settle (1 - exp(-r/tau)). */
static void
drift_axis_init(DriftAxis *axis, gint yres, GRand *rng)
{
    axis->offset = g_rand_double_range(rng, -3.0, 3.0);
    axis->velocity = g_rand_double_range(rng, -4.0, 4.0)/yres;
    axis->settle = g_rand_double_range(rng, -3.0, 3.0);
    axis->tau = g_rand_double_range(rng, 0.05, 0.3)*yres;
}

static gdouble
drift_axis_at(const DriftAxis *axis, gint row)
{
    return axis->offset + axis->velocity*row + axis->settle*(1.0 - exp(-row/axis->tau));
}

static void
add_noise(gdouble *data, gsize count, gdouble rms, GRand *rng)
{
    gsize k;

    for (k = 0; k < count; k++)
        data[k] += rms*sim_raw_gaussian(rng);
}

FramePair*
frame_pair_generate(const FramePairSpec *spec, guint32 seed)
{
    GRand *rng = g_rand_new_with_seed(seed);
    FramePair *pair = g_new0(FramePair, 1);
    gint xres = spec->xres, yres = spec->yres, r;
    gsize count = (gsize)xres*yres;
    DriftAxis ax, ay;
    Surface surface;

    pair->xres = xres;
    pair->yres = yres;
    pair->reference = g_new(gdouble, count);
    pair->image = g_new(gdouble, count);
    pair->row_dx = g_new(gdouble, yres);
    pair->row_dy = g_new(gdouble, yres);
    surface_init(&surface, spec, rng);
    drift_axis_init(&ax, yres, rng);
    drift_axis_init(&ay, yres, rng);
    for (r = 0; r < yres; r++) {
        if (spec->drift) {
            pair->row_dx[r] = spec->drift_scale*drift_axis_at(&ax, r);
            pair->row_dy[r] = spec->drift_scale*drift_axis_at(&ay, r);
        }
        else {
            gboolean jumped = (spec->jump_row >= 0 && r >= spec->jump_row);

            pair->row_dx[r] = spec->shift_x + spec->velocity_x*r + (jumped ? spec->jump_x : 0.0);
            pair->row_dy[r] = spec->shift_y + spec->velocity_y*r + (jumped ? spec->jump_y : 0.0);
        }
        surface_sample_row(&surface, r, 0.0, pair->reference + (gsize)r*xres);
        surface_sample_row(&surface, r - pair->row_dy[r], pair->row_dx[r], pair->image + (gsize)r*xres);
    }
    add_noise(pair->reference, count, spec->noise, rng);
    add_noise(pair->image, count, spec->noise, rng);
    surface_free(&surface);
    g_rand_free(rng);
    return pair;
}

void
frame_pair_free(FramePair *pair)
{
    if (!pair)
        return;
    g_free(pair->reference);
    g_free(pair->image);
    g_free(pair->row_dx);
    g_free(pair->row_dy);
    g_free(pair);
}

typedef void (*FrameArtefact)(gdouble *data, gint xres, gint yres, gdouble size, GRand *rng);

/* Each frame gets its own draw of the artefact. */
static void
add_to_both_frames(FramePair *pair, FrameArtefact add, gdouble size, guint32 seed)
{
    GRand *rng = g_rand_new_with_seed(seed);

    add(pair->reference, pair->xres, pair->yres, size, rng);
    add(pair->image, pair->xres, pair->yres, size, rng);
    g_rand_free(rng);
}

void
frame_pair_add_raw_artefacts(FramePair *pair, gdouble size, guint32 seed)
{
    add_to_both_frames(pair, sim_raw_artefacts_add, size, seed ^ 0x5eedu);
}

void
frame_add_raw_artefacts(gdouble *data, gint xres, gint yres, gdouble size,
                        guint32 seed)
{
    GRand *rng = g_rand_new_with_seed(seed ^ 0x5eedu);

    sim_raw_artefacts_add(data, xres, yres, size, rng);
    g_rand_free(rng);
}

void
frame_pair_add_undulation(FramePair *pair, gdouble size, guint32 seed)
{
    add_to_both_frames(pair, sim_raw_undulation_add, size, seed ^ 0x0dd1u);
}

void
frame_pair_stripe_truth(const FramePair *pair, gint n, gdouble *dx, gdouble *dy)
{
    gint s, r, first, end;

    for (s = 0; s < n; s++) {
        first = (gint)(((gint64)s*pair->yres)/n);
        end = (gint)(((gint64)(s + 1)*pair->yres)/n);
        dx[s] = dy[s] = 0.0;
        for (r = first; r < end; r++) {
            dx[s] += pair->row_dx[r];
            dy[s] += pair->row_dy[r];
        }
        dx[s] /= end - first;
        dy[s] /= end - first;
    }
}

void
frame_pair_stripe_centre_truth(const FramePair *pair, gint n, gdouble *dx, gdouble *dy)
{
    gint s, first, last;

    for (s = 0; s < n; s++) {
        first = (gint)(((gint64)s*pair->yres)/n);
        last = (gint)(((gint64)(s + 1)*pair->yres)/n) - 1;
        dx[s] = 0.5*(pair->row_dx[(first + last)/2] + pair->row_dx[(first + last + 1)/2]);
        dy[s] = 0.5*(pair->row_dy[(first + last)/2] + pair->row_dy[(first + last + 1)/2]);
    }
}

guint32
frame_pair_test_seed(const gchar *program)
{
    const gchar *env = g_getenv("LOCALSCAN_TEST_SEED");
    guint32 seed;

    if (env && *env)
        seed = (guint32)strtoul(env, NULL, 10);
    else
        seed = g_random_int();
    printf("%s: seed %u (set LOCALSCAN_TEST_SEED=%u to repeat)\n", program, seed, seed);
    fflush(stdout);
    return seed;
}
