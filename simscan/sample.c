/*
 *  The simulated sample: synthetic spherical particles on a rough substrate,
 *  or a measured image.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <string.h>
#include <math.h>
#include <fftw3.h>
#include <libprocess/inttrans.h>
#include "sample.h"
#include "spline-grid.h"
#include "sim-random.h"

enum {
    SUBSTRATE_MAX_NODES = 2048,
    SUBSTRATE_MIN_NODES = 16,
    PARTICLE_GRID_MAX_CELLS = 1024,
    PLACEMENT_TRIES_PER_PARTICLE = 200,
    PLACEMENT_MAX_FAILURES_IN_ROW = 20000,
};

/* Buckets of particles by position, as linked lists, so a height needs only
 * the particles of the few cells around it.  Cells are at least as wide as
 * any particle's diameter and the minimum spacing. */
typedef struct {
    gint nx, ny;
    gdouble cell_w, cell_h;
    gint *head;
    gint *next;
} ParticleGrid;

/* A measured surface dilated by one tip radius; entries are never changed
 * once added, so a scan may keep using one while others are added. */
typedef struct {
    gdouble tip_radius;
    SplineGrid *surface;
} DilatedSurface;

struct _SimSample {
    gdouble xreal, yreal;
    /* synthetic */
    SplineGrid *substrate;     /* NULL: flat at zero */
    gint n_particles;
    gdouble *px, *py, *pr, *pz;
    gdouble max_radius;
    ParticleGrid grid;
    /* measured */
    gint mxres, myres;
    gdouble *measured;
    SplineGrid *measured_surface;
    GMutex dilated_lock;
    GPtrArray *dilated;
};

void
sim_particle_params_init(SimParticleParams *params)
{
    params->xreal = params->yreal = 5e-6;
    params->radius = 25e-9;
    params->radius_spread = 0.0;
    params->count = 0;
    params->density = 4e12;
    params->min_spacing = 4.0*params->radius;
    params->roughness_rms = 0.3e-9;
    params->roughness_corr = 50e-9;
}

static SimSample*
sample_alloc(gdouble xreal, gdouble yreal)
{
    SimSample *sample = g_new0(SimSample, 1);

    sample->xreal = xreal;
    sample->yreal = yreal;
    g_mutex_init(&sample->dilated_lock);
    return sample;
}

/* ---- Substrate ---------------------------------------------------------- */

static void
fft_grid_forward(gdouble *values, fftw_complex *spectrum, gint nx, gint ny)
{
    fftw_plan plan = fftw_plan_dft_r2c_2d(ny, nx, values, spectrum,
                                          FFTW_ESTIMATE);
    fftw_execute(plan);
    fftw_destroy_plan(plan);
}

static void
fft_grid_backward(fftw_complex *spectrum, gdouble *values, gint nx, gint ny)
{
    fftw_plan plan = fftw_plan_dft_c2r_2d(ny, nx, spectrum, values,
                                          FFTW_ESTIMATE);
    gsize k, n = (gsize)nx*ny;

    fftw_execute(plan);
    fftw_destroy_plan(plan);
    for (k = 0; k < n; k++)
        values[k] /= n;
}

/* Signed frequency of index m of n, in cycles per period. */
static inline gint
signed_frequency(gint m, gint n)
{
    return m <= n/2 ? m : m - n;
}

/* White noise filtered to the Gaussian ACF rms^2 exp(-r^2/T^2), whose
 * amplitude spectrum is exp(-k^2 T^2/8). */
static void
substrate_fill_gaussian(gdouble *values, fftw_complex *spectrum,
                        gint nx, gint ny, gdouble xreal, gdouble yreal,
                        gdouble corr, gdouble rms, SimRandom *rng)
{
    gint hx = nx/2 + 1, i, j;
    gsize k, n = (gsize)nx*ny;
    gdouble kx, ky, f, mean = 0.0, var = 0.0;

    for (k = 0; k < n; k++)
        values[k] = sim_random_gaussian(rng);
    fft_grid_forward(values, spectrum, nx, ny);
    for (i = 0; i < ny; i++) {
        ky = 2.0*G_PI*signed_frequency(i, ny)/yreal;
        for (j = 0; j < hx; j++) {
            kx = 2.0*G_PI*j/xreal;
            f = exp(-(kx*kx + ky*ky)*corr*corr/8.0);
            spectrum[i*hx + j][0] *= f;
            spectrum[i*hx + j][1] *= f;
        }
    }
    fft_grid_backward(spectrum, values, nx, ny);
    for (k = 0; k < n; k++)
        mean += values[k];
    mean /= n;
    for (k = 0; k < n; k++)
        var += (values[k] - mean)*(values[k] - mean);
    f = var > 0.0 ? rms/sqrt(var/n) : 0.0;
    for (k = 0; k < n; k++)
        values[k] = (values[k] - mean)*f;
}

/* Periodic interpolating B-spline: coefficients are the values divided, in
 * Fourier space, by the kernel's transfer function (4 + 2 cos w)/6. */
static void
periodic_bspline_coefficients(gdouble *values, fftw_complex *spectrum,
                              gint nx, gint ny)
{
    gint hx = nx/2 + 1, i, j;
    gdouble by, f;

    fft_grid_forward(values, spectrum, nx, ny);
    for (i = 0; i < ny; i++) {
        by = (4.0 + 2.0*cos(2.0*G_PI*i/ny))/6.0;
        for (j = 0; j < hx; j++) {
            f = 1.0/(by*(4.0 + 2.0*cos(2.0*G_PI*j/nx))/6.0);
            spectrum[i*hx + j][0] *= f;
            spectrum[i*hx + j][1] *= f;
        }
    }
    fft_grid_backward(spectrum, values, nx, ny);
}

static gint
substrate_nodes(gdouble extent, gdouble spacing)
{
    gdouble n = ceil(extent/spacing);

    n = CLAMP(n, SUBSTRATE_MIN_NODES, SUBSTRATE_MAX_NODES);
    return gwy_fft_find_nice_size((gint)n);
}

/* Nodes are spaced at most a quarter of the correlation length, so the
 * spline follows the roughness closely; the grid is periodic over the
 * field so drift across the edge shows no seam. */
static SplineGrid*
substrate_new(const SimParticleParams *params, SimRandom *rng)
{
    gdouble spacing = 0.25*params->roughness_corr;
    gint nx, ny;
    SplineGrid *grid;
    fftw_complex *spectrum;
    gdouble *values;

    if (params->roughness_rms <= 0.0 || params->roughness_corr <= 0.0)
        return NULL;
    nx = substrate_nodes(params->xreal, spacing);
    ny = substrate_nodes(params->yreal, spacing);
    grid = spline_grid_new(nx, ny, 0.0, 0.0,
                           params->xreal/nx, params->yreal/ny,
                           SPLINE_GRID_PERIODIC);
    values = fftw_malloc((gsize)nx*ny*sizeof(gdouble));
    spectrum = fftw_malloc((gsize)ny*(nx/2 + 1)*sizeof(fftw_complex));
    substrate_fill_gaussian(values, spectrum, nx, ny,
                            params->xreal, params->yreal,
                            params->roughness_corr, params->roughness_rms, rng);
    periodic_bspline_coefficients(values, spectrum, nx, ny);
    memcpy(grid->coeff, values, (gsize)nx*ny*sizeof(gdouble));
    fftw_free(values);
    fftw_free(spectrum);
    return grid;
}

static inline gdouble
substrate_height(const SimSample *sample, gdouble x, gdouble y)
{
    return sample->substrate ? spline_grid_eval(sample->substrate, x, y) : 0.0;
}

/* ---- Particles ---------------------------------------------------------- */

static void
particle_grid_init(ParticleGrid *grid, gdouble xreal, gdouble yreal,
                   gdouble min_cell, gint capacity)
{
    grid->nx = (gint)CLAMP(floor(xreal/min_cell), 1, PARTICLE_GRID_MAX_CELLS);
    grid->ny = (gint)CLAMP(floor(yreal/min_cell), 1, PARTICLE_GRID_MAX_CELLS);
    grid->cell_w = xreal/grid->nx;
    grid->cell_h = yreal/grid->ny;
    grid->head = g_new(gint, grid->nx*grid->ny);
    memset(grid->head, 0xff, grid->nx*grid->ny*sizeof(gint));
    grid->next = g_new(gint, MAX(capacity, 1));
}

static inline gint
particle_grid_cell(gdouble pos, gdouble cell, gint n)
{
    gdouble c = floor(pos/cell);

    return (gint)CLAMP(c, 0, n - 1);
}

static void
particle_grid_insert(ParticleGrid *grid, gint i, gdouble x, gdouble y)
{
    gint cell = (particle_grid_cell(y, grid->cell_h, grid->ny)*grid->nx
                 + particle_grid_cell(x, grid->cell_w, grid->nx));

    grid->next[i] = grid->head[cell];
    grid->head[cell] = i;
}

static gdouble
draw_radius(const SimParticleParams *params, SimRandom *rng)
{
    gdouble f;

    if (params->radius_spread <= 0.0)
        return params->radius;
    f = 1.0 + params->radius_spread*sim_random_gaussian(rng);
    return params->radius*CLAMP(f, 0.2, 1.0 + 4.0*params->radius_spread);
}

static gboolean
placement_is_free(const SimSample *sample, gdouble x, gdouble y, gdouble r,
                  gdouble min_spacing)
{
    const ParticleGrid *grid = &sample->grid;
    gint ci = particle_grid_cell(y, grid->cell_h, grid->ny);
    gint cj = particle_grid_cell(x, grid->cell_w, grid->nx);
    gint i, j, k;
    gdouble d, dx, dy;

    for (i = MAX(ci - 1, 0); i <= MIN(ci + 1, grid->ny - 1); i++) {
        for (j = MAX(cj - 1, 0); j <= MIN(cj + 1, grid->nx - 1); j++) {
            for (k = grid->head[i*grid->nx + j]; k >= 0; k = grid->next[k]) {
                d = MAX(min_spacing, r + sample->pr[k]);
                dx = x - sample->px[k];
                dy = y - sample->py[k];
                if (dx*dx + dy*dy < d*d)
                    return FALSE;
            }
        }
    }
    return TRUE;
}

/* Random sequential addition: candidates uniform over the field (one radius
 * from its edges), refused when too close to a placed particle.  A long run
 * of refusals means the field is full (jammed) for this spacing. */
static void
place_particles(SimSample *sample, const SimParticleParams *params,
                gint wanted, SimRandom *rng)
{
    gdouble max_r = params->radius*(1.0 + 4.0*MAX(params->radius_spread, 0.0));
    gdouble x, y, r;
    gint tries, n = 0, failures = 0;

    particle_grid_init(&sample->grid, params->xreal, params->yreal,
                       MAX(params->min_spacing, 2.0*max_r), wanted);
    sample->px = g_new(gdouble, MAX(wanted, 1));
    sample->py = g_new(gdouble, MAX(wanted, 1));
    sample->pr = g_new(gdouble, MAX(wanted, 1));
    sample->pz = g_new(gdouble, MAX(wanted, 1));
    for (tries = 0;
         n < wanted && failures < PLACEMENT_MAX_FAILURES_IN_ROW
         && tries/PLACEMENT_TRIES_PER_PARTICLE < wanted;
         tries++) {
        r = draw_radius(params, rng);
        x = r + (params->xreal - 2.0*r)*sim_random_uniform(rng);
        y = r + (params->yreal - 2.0*r)*sim_random_uniform(rng);
        if (!placement_is_free(sample, x, y, r, params->min_spacing)) {
            failures++;
            continue;
        }
        failures = 0;
        sample->px[n] = x;
        sample->py[n] = y;
        sample->pr[n] = r;
        sample->pz[n] = r + substrate_height(sample, x, y);
        sample->max_radius = MAX(sample->max_radius, r);
        particle_grid_insert(&sample->grid, n, x, y);
        n++;
    }
    sample->n_particles = n;
}

SimSample*
sim_sample_new_particles(const SimParticleParams *params, guint32 seed)
{
    SimSample *sample;
    SimRandom rng;
    gdouble wanted;

    if (!(params->xreal > 0.0 && params->yreal > 0.0 && params->radius > 0.0
          && 2.0*params->radius < MIN(params->xreal, params->yreal))) {
        g_warning("simscan: particle sample needs positive sizes and a "
                  "radius smaller than half the field");
        return NULL;
    }
    wanted = (params->count > 0
              ? params->count
              : floor(params->density*params->xreal*params->yreal + 0.5));
    if (!(wanted >= 0.0 && wanted < 1e7)) {
        g_warning("simscan: particle count %g is out of range", wanted);
        return NULL;
    }
    sample = sample_alloc(params->xreal, params->yreal);
    /* Separate streams keep the particles where they are when only the
     * roughness changes. */
    sim_random_init(&rng, seed, 1);
    sample->substrate = substrate_new(params, &rng);
    sim_random_init(&rng, seed, 2);
    place_particles(sample, params, (gint)wanted, &rng);
    return sample;
}

/* Apex height of a spherical tip of radius rt touching particles near
 * (x, y): the tip's centre stays R + rt from the particle's centre, so the
 * apex follows zc + sqrt((R + rt)^2 - d^2) - rt within d < R + rt (rt = 0 is
 * the bare sphere).  Where that falls below the substrate the tip rests on
 * the substrate instead. */
static gdouble
particles_height(const SimSample *sample, gdouble x, gdouble y, gdouble rt,
                 gdouble z)
{
    const ParticleGrid *grid = &sample->grid;
    gdouble reach = sample->max_radius + rt, dx, dy, d2, rr, zk;
    gint i0, i1, j0, j1, i, j, k;

    if (!sample->n_particles)
        return z;
    i0 = particle_grid_cell(y - reach, grid->cell_h, grid->ny);
    i1 = particle_grid_cell(y + reach, grid->cell_h, grid->ny);
    j0 = particle_grid_cell(x - reach, grid->cell_w, grid->nx);
    j1 = particle_grid_cell(x + reach, grid->cell_w, grid->nx);
    for (i = i0; i <= i1; i++) {
        for (j = j0; j <= j1; j++) {
            for (k = grid->head[i*grid->nx + j]; k >= 0; k = grid->next[k]) {
                dx = x - sample->px[k];
                dy = y - sample->py[k];
                d2 = dx*dx + dy*dy;
                rr = sample->pr[k] + rt;
                if (d2 >= rr*rr)
                    continue;
                zk = sample->pz[k] + sqrt(rr*rr - d2) - rt;
                z = MAX(z, zk);
            }
        }
    }
    return z;
}

/* ---- Measured sample ---------------------------------------------------- */

SimSample*
sim_sample_new_from_field(GwyDataField *field)
{
    SimSample *sample;
    gint xres, yres;
    gdouble dx, dy;

    g_return_val_if_fail(GWY_IS_DATA_FIELD(field), NULL);
    xres = gwy_data_field_get_xres(field);
    yres = gwy_data_field_get_yres(field);
    dx = gwy_data_field_get_dx(field);
    dy = gwy_data_field_get_dy(field);
    if (xres < 2 || yres < 2 || !(dx > 0.0 && dy > 0.0)) {
        g_warning("simscan: a measured sample needs at least 2x2 pixels "
                  "and a positive size");
        return NULL;
    }
    sample = sample_alloc(gwy_data_field_get_xreal(field),
                          gwy_data_field_get_yreal(field));
    sample->mxres = xres;
    sample->myres = yres;
    sample->measured = g_memdup2(gwy_data_field_get_data_const(field),
                                 (gsize)xres*yres*sizeof(gdouble));
    sample->measured_surface
        = spline_grid_new_interpolating(sample->measured, xres, yres,
                                        0.5*dx, 0.5*dy, dx, dy);
    return sample;
}

/* Grey-scale dilation by a spherical tip on the image's own grid: each
 * pixel takes the highest apex position over the tip's footprint (mirrored
 * at the edges, like the interpolation). */
static gdouble*
dilate_measured(const SimSample *sample, gdouble rt)
{
    gint xres = sample->mxres, yres = sample->myres, i, j, k, l, ri, rj;
    gdouble dx = sample->xreal/xres, dy = sample->yreal/yres;
    gint kmax = (gint)floor(rt/dy), lmax = (gint)floor(rt/dx);
    gint fw = 2*lmax + 1, fh = 2*kmax + 1;
    gdouble *tip = g_new(gdouble, fw*fh), *out = g_new(gdouble, xres*yres);
    gdouble rho2, z, best;

    for (k = -kmax; k <= kmax; k++) {
        for (l = -lmax; l <= lmax; l++) {
            rho2 = (k*dy)*(k*dy) + (l*dx)*(l*dx);
            tip[(k + kmax)*fw + l + lmax] = (rho2 <= rt*rt
                                             ? sqrt(rt*rt - rho2) - rt
                                             : -G_MAXDOUBLE);
        }
    }
    for (i = 0; i < yres; i++) {
        for (j = 0; j < xres; j++) {
            best = -G_MAXDOUBLE;
            for (k = -kmax; k <= kmax; k++) {
                ri = i + k;
                ri = ri < 0 ? -1 - ri : (ri >= yres ? 2*yres - 1 - ri : ri);
                ri = CLAMP(ri, 0, yres - 1);
                for (l = -lmax; l <= lmax; l++) {
                    if (tip[(k + kmax)*fw + l + lmax] == -G_MAXDOUBLE)
                        continue;
                    rj = j + l;
                    rj = rj < 0 ? -1 - rj : (rj >= xres ? 2*xres - 1 - rj : rj);
                    rj = CLAMP(rj, 0, xres - 1);
                    z = sample->measured[ri*xres + rj]
                        + tip[(k + kmax)*fw + l + lmax];
                    best = MAX(best, z);
                }
            }
            out[i*xres + j] = best;
        }
    }
    g_free(tip);
    return out;
}

static void
dilated_surface_free(gpointer p)
{
    DilatedSurface *dilated = (DilatedSurface*)p;

    spline_grid_free(dilated->surface);
    g_free(dilated);
}

/* The surface a tip of radius rt records, computed once per radius. */
static const SplineGrid*
measured_surface_for_tip(const SimSample *sample, gdouble rt)
{
    SimSample *cache = (SimSample*)sample;
    DilatedSurface *dilated = NULL;
    gdouble *values;
    guint i;

    if (rt <= 0.0)
        return sample->measured_surface;
    g_mutex_lock(&cache->dilated_lock);
    if (!cache->dilated)
        cache->dilated = g_ptr_array_new_with_free_func(dilated_surface_free);
    for (i = 0; i < cache->dilated->len; i++) {
        dilated = g_ptr_array_index(cache->dilated, i);
        if (dilated->tip_radius == rt)
            break;
        dilated = NULL;
    }
    if (!dilated) {
        values = dilate_measured(sample, rt);
        dilated = g_new(DilatedSurface, 1);
        dilated->tip_radius = rt;
        dilated->surface
            = spline_grid_new_interpolating(values, sample->mxres,
                                            sample->myres,
                                            sample->measured_surface->x0,
                                            sample->measured_surface->y0,
                                            sample->measured_surface->dx,
                                            sample->measured_surface->dy);
        g_free(values);
        g_ptr_array_add(cache->dilated, dilated);
    }
    g_mutex_unlock(&cache->dilated_lock);
    return dilated->surface;
}

/* ---- Public queries ----------------------------------------------------- */

void
sim_sample_heights_tip(const SimSample *sample, gdouble tip_radius, gint n,
                       const gdouble *x_m, const gdouble *y_m, gdouble *z)
{
    const SplineGrid *surface;
    gdouble rt = MAX(tip_radius, 0.0);
    gint k;

    if (sample->measured) {
        surface = measured_surface_for_tip(sample, rt);
        for (k = 0; k < n; k++)
            z[k] = spline_grid_eval(surface, x_m[k], y_m[k]);
        return;
    }
    for (k = 0; k < n; k++) {
        z[k] = particles_height(sample, x_m[k], y_m[k], rt,
                                substrate_height(sample, x_m[k], y_m[k]));
    }
}

gdouble
sim_sample_height_tip(const SimSample *sample, gdouble tip_radius,
                      gdouble x_m, gdouble y_m)
{
    gdouble z;

    sim_sample_heights_tip(sample, tip_radius, 1, &x_m, &y_m, &z);
    return z;
}

gdouble
sim_sample_height(const SimSample *sample, gdouble x_m, gdouble y_m)
{
    return sim_sample_height_tip(sample, 0.0, x_m, y_m);
}

gint
sim_sample_n_particles(const SimSample *sample)
{
    return sample->n_particles;
}

void
sim_sample_particle(const SimSample *sample, gint i,
                    gdouble *x, gdouble *y, gdouble *r)
{
    g_return_if_fail(i >= 0 && i < sample->n_particles);
    if (x)
        *x = sample->px[i];
    if (y)
        *y = sample->py[i];
    if (r)
        *r = sample->pr[i];
}

gdouble
sim_sample_particle_centre_z(const SimSample *sample, gint i)
{
    g_return_val_if_fail(i >= 0 && i < sample->n_particles, 0.0);
    return sample->pz[i];
}

void
sim_sample_get_extent(const SimSample *sample, gdouble *xreal, gdouble *yreal)
{
    if (xreal)
        *xreal = sample->xreal;
    if (yreal)
        *yreal = sample->yreal;
}

void
sim_sample_free(SimSample *sample)
{
    if (!sample)
        return;
    spline_grid_free(sample->substrate);
    g_free(sample->px);
    g_free(sample->py);
    g_free(sample->pr);
    g_free(sample->pz);
    g_free(sample->grid.head);
    g_free(sample->grid.next);
    g_free(sample->measured);
    spline_grid_free(sample->measured_surface);
    if (sample->dilated)
        g_ptr_array_free(sample->dilated, TRUE);
    g_mutex_clear(&sample->dilated_lock);
    g_free(sample);
}
