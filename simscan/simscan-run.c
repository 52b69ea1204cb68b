/*
 *  One simulated experiment: scene, local-scan measurement, compensation,
 *  errors.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <math.h>
#include "stripe-geometry.h"
#include "paper-compensate.h"
#include "simscan-presets.h"
#include "simscan-run.h"
#include "simscan-i18n.h"

#define SIMSCAN_ERROR simscan_error_quark()

/* The noise must not repeat the sample's random numbers. */
#define NOISE_SEED_SALT 0x9e3779b9u

typedef struct {
    const SimSample *sample;
    const DriftModel *drift;
    gdouble tip_radius;
} SimProbe;

static G_DEFINE_QUARK(simscan-error-quark, simscan_error)

static gdouble
sim_probe(gpointer user_data, gdouble x, gdouble y, gdouble t)
{
    const SimProbe *probe = user_data;

    return sim_probe_height(probe->sample, probe->drift, probe->tip_radius,
                            x, y, t);
}

/* Longest the local scans can take, with every line of every search. */
static gdouble
local_scan_time_bound(const SimscanConfig *config, gint n_stripes)
{
    const LocalScanParams *lp = &config->local;
    gint lines = 4 + 2*(gint)ceil((lp->r_max + lp->radius)/(1.5*lp->radius));

    return config->local_delay
           + n_stripes*lines*local_scan_line_time(lp);
}

/* FALSE when the sample cannot be made from the configuration. */
static gboolean
make_sample_and_scan(SimscanScene *scene, GwyDataField *sample_field)
{
    const SimscanConfig *config = scene->config;

    if (sample_field)
        scene->sample = sim_sample_new_from_field(sample_field);
    else
        scene->sample = sim_sample_new_particles(&config->particles,
                                                 config->seed);
    if (!scene->sample)
        return FALSE;
    sim_scan_params_init(&scene->scan, scene->sample,
                         config->xres, config->yres);
    if (!sample_field) {
        scene->scan.xreal = config->xreal;
        scene->scan.yreal = config->yreal;
    }
    scene->scan.line_time = config->line_time;
    scene->scan.direction = config->direction;
    scene->scan.frame_start = 0.0;
    scene->scan.noise_rms = config->noise_rms;
    scene->scan.tip_radius = config->tip_radius;
    scene->scan.noise_seed = config->seed ^ NOISE_SEED_SALT;
    sim_scan_params_timing(&scene->scan, &scene->timing);
    return TRUE;
}

SimscanScene*
simscan_scene_new(const SimscanConfig *config, GwyDataField *sample_field,
                  GError **error)
{
    SimscanScene *scene = g_new0(SimscanScene, 1);

    scene->config = config;
    if (!make_sample_and_scan(scene,
                              config->sample_file ? sample_field : NULL)) {
        g_set_error(error, SIMSCAN_ERROR, 0,
                    _("cannot make the sample from these parameters"));
        simscan_scene_free(scene);
        return NULL;
    }
    if (config->figure6) {
        drift_model_init(&scene->drift, DRIFT_MODEL_NONE);
        scene->shift_n = config->n_stripes;
        scene->shift_dx = g_new(gdouble, scene->shift_n);
        scene->shift_dy = g_new(gdouble, scene->shift_n);
        simscan_figure6_drift(scene->shift_n, scene->shift_dx,
                              scene->shift_dy);
        scene->image = sim_scan_frame_stripes(scene->sample, &scene->scan,
                                              scene->shift_n, scene->shift_dx,
                                              scene->shift_dy);
    }
    else {
        drift_model_copy(&scene->drift, &config->drift);
        drift_model_prepare(&scene->drift,
                            scan_timing_frame_end(&scene->timing)
                            + local_scan_time_bound(config, config->yres));
        scene->image = sim_scan_frame(scene->sample, &scene->drift,
                                      &scene->scan);
    }
    scene->truth = sim_scan_truth(scene->sample, &scene->scan);
    if (!scene->image || !scene->truth) {
        g_set_error(error, SIMSCAN_ERROR, 0,
                    _("cannot scan the sample with these parameters"));
        simscan_scene_free(scene);
        return NULL;
    }
    particle_detect_params_init(&scene->detect);
    /* Half the height of a particle; a measured sample: half its range. */
    if (!config->sample_file)
        scene->detect.height = config->particles.radius;
    scene->particles = particle_detect(scene->image, &scene->detect,
                                       &scene->substrate, NULL);
    return scene;
}

void
simscan_scene_free(SimscanScene *scene)
{
    if (!scene)
        return;
    if (scene->sample)
        sim_sample_free(scene->sample);
    drift_model_clear(&scene->drift);
    g_clear_object(&scene->image);
    g_clear_object(&scene->truth);
    g_free(scene->shift_dx);
    g_free(scene->shift_dy);
    if (scene->particles)
        g_array_free(scene->particles, TRUE);
    g_free(scene);
}

gdouble
simscan_scene_column(const SimscanScene *scene, gdouble x)
{
    return (x - scene->scan.xoff)*scene->scan.xres/scene->scan.xreal - 0.5;
}

gdouble
simscan_scene_row(const SimscanScene *scene, gdouble y)
{
    return (y - scene->scan.yoff)*scene->scan.yres/scene->scan.yreal - 0.5;
}

/* Figure 6 shift of the contamination stripe holding (fractional) row. */
static void
stripe_shift_at(const SimscanScene *scene, gdouble row,
                gdouble *dx, gdouble *dy)
{
    gint yres = scene->scan.yres;
    gint r = CLAMP((gint)floor(row + 0.5), 0, yres-1);
    gint s = stripe_of_row(r, scene->shift_n, yres);

    *dx = scene->shift_dx[s];
    *dy = scene->shift_dy[s];
}

/* Where a particle truly at (x, y) metres shows in the image, px: the
 * displacement depends on when (or in which stripe) it is shown, so a few
 * fixed-point steps. */
static void
displayed_position(const SimscanScene *scene, gdouble x, gdouble y,
                   gdouble *col, gdouble *row)
{
    gdouble c0 = simscan_scene_column(scene, x);
    gdouble r0 = simscan_scene_row(scene, y);
    gdouble c = c0, r = r0, px, py;
    gint iter;

    for (iter = 0; iter < 4; iter++) {
        if (scene->shift_dx) {
            stripe_shift_at(scene, r, &px, &py);
            c = c0 + px;
            r = r0 + py;
        }
        else {
            gdouble t = scan_timing_pixel_time(&scene->timing,
                                               CLAMP(r, 0, scene->scan.yres-1),
                                               CLAMP(c, 0, scene->scan.xres-1));

            drift_model_eval(&scene->drift, t, &px, &py);
            c = simscan_scene_column(scene, x + px);
            r = simscan_scene_row(scene, y + py);
        }
    }
    *col = c;
    *row = r;
}

static void
drift_px(const SimscanScene *scene, gdouble t, gdouble *dx, gdouble *dy)
{
    gdouble px, py;

    drift_model_eval(&scene->drift, t, &px, &py);
    *dx = px*scene->scan.xres/scene->scan.xreal;
    *dy = py*scene->scan.yres/scene->scan.yreal;
}

/* A perfect local scan measures p(t_image) - p(t_local); a stripe without
 * a particle is judged at its centre line against the scans' start. */
static void
fill_true_drift(const SimscanScene *scene, SimscanMeasurement *m)
{
    gint yres = scene->scan.yres, s;

    for (s = 0; s < m->n_stripes; s++) {
        const LocalScanParticle *r = m->scans + s;
        gdouble row = stripe_centre_row(s, m->n_stripes, yres);
        gdouble ax, ay, bx, by;

        if (scene->shift_dx) {
            stripe_shift_at(scene, r->lines ? r->y_disp : row,
                            m->true_dx + s, m->true_dy + s);
            continue;
        }
        if (r->lines && r->found) {
            drift_px(scene, r->t_image, &ax, &ay);
            drift_px(scene, r->t_local, &bx, &by);
        }
        else {
            drift_px(scene, scan_timing_pixel_time(&scene->timing, row,
                                                   0.5*(scene->scan.xres - 1)),
                     &ax, &ay);
            drift_px(scene, m->t_start, &bx, &by);
        }
        m->true_dx[s] = ax - bx;
        m->true_dy[s] = ay - by;
    }
}

static gboolean
compensate(const SimscanScene *scene, SimscanMeasurement *m, GError **error)
{
    GwyDataField *image = scene->image;
    gint xres = scene->scan.xres, yres = scene->scan.yres, s;
    guint n = MAX(m->n_stripes, 1);
    gdouble *dx = g_new(gdouble, n), *dy = g_new(gdouble, n);
    gint *idx = g_new(gint, n), *idy = g_new(gint, n);
    const gdouble *a = gwy_data_field_get_data_const(image);
    gboolean ok;

    ok = drift_table_to_pixels(m->table, yres,
                               gwy_data_field_get_dx(image),
                               gwy_data_field_get_dy(image),
                               TRUE, dx, dy, error);
    if (ok) {
        for (s = 0; s < m->n_stripes; s++) {
            idx[s] = (gint)dx[s];
            idy[s] = (gint)dy[s];
        }
        m->compensated = gwy_data_field_new_alike(image, FALSE);
        paper_compensate(a, xres, yres, n, idx, idy,
                         paper_image_mean(a, xres, yres),
                         gwy_data_field_get_data(m->compensated), NULL);
    }
    g_free(dx);
    g_free(dy);
    g_free(idx);
    g_free(idy);
    return ok;
}

static void
measure_errors(const SimscanScene *scene, SimscanMeasurement *m)
{
    const SimscanConfig *config = scene->config;
    gint n = sim_sample_n_particles(scene->sample), i;
    gdouble *shown = g_new(gdouble, 2*n), *truth = g_new(gdouble, 2*n);

    gdouble dx = gwy_data_field_get_dx(scene->image);
    gdouble dy = gwy_data_field_get_dy(scene->image);
    gdouble r_px = config->particles.radius/dx;
    gdouble match = fmax(2.0, 0.45*config->particles.min_spacing/dx);
    GArray *after;

    for (i = 0; i < n; i++) {
        gdouble x, y;

        sim_sample_particle(scene->sample, i, &x, &y, NULL);
        displayed_position(scene, x, y, shown + 2*i, shown + 2*i + 1);
        truth[2*i] = simscan_scene_column(scene, x + m->ref_drift[0]);
        truth[2*i + 1] = simscan_scene_row(scene, y + m->ref_drift[1]);
    }
    centre_error_measure(scene->particles, shown, truth, n,
                         scene->scan.xres, scene->scan.yres, r_px + 2.0,
                         match, dx, dy, &m->before);
    after = particle_detect(m->compensated, &scene->detect, NULL, NULL);
    centre_error_measure(after, truth, truth, n,
                         scene->scan.xres, scene->scan.yres, r_px + 2.0,
                         match, dx, dy, &m->after);
    m->have_errors = TRUE;
    m->n_particles = n;
    m->shown_px = shown;
    m->truth_px = truth;
    g_array_free(after, TRUE);
}

SimscanMeasurement*
simscan_measure(SimscanScene *scene, gint n_stripes, GError **error)
{
    SimscanMeasurement *m = g_new0(SimscanMeasurement, 1);
    SimProbe probe;
    gint s;

    g_return_val_if_fail(n_stripes >= 1, NULL);
    m->n_stripes = n_stripes;
    m->scans = g_new0(LocalScanParticle, n_stripes);
    m->true_dx = g_new(gdouble, n_stripes);
    m->true_dy = g_new(gdouble, n_stripes);
    probe.sample = scene->sample;
    probe.drift = &scene->drift;
    probe.tip_radius = scene->scan.tip_radius;
    m->t_start = scan_timing_frame_end(&scene->timing)
                 + scene->config->local_delay;
    m->table = local_scan_run(scene->image, &scene->timing, scene->particles,
                              scene->substrate, n_stripes,
                              &scene->config->local, sim_probe, &probe,
                              m->t_start, m->scans, &m->t_end);
    for (s = 0; s < n_stripes; s++)
        m->lines += m->scans[s].lines;
    drift_model_eval(&scene->drift, m->t_start,
                     m->ref_drift, m->ref_drift + 1);
    fill_true_drift(scene, m);
    if (!compensate(scene, m, NULL)) {
        g_set_error(error, SIMSCAN_ERROR, 0,
                    _("no particle was measured in any of the %d stripes"),
                    n_stripes);
        simscan_measurement_free(m);
        return NULL;
    }
    if (sim_sample_n_particles(scene->sample) > 0)
        measure_errors(scene, m);
    return m;
}

void
simscan_measurement_free(SimscanMeasurement *m)
{
    if (!m)
        return;
    drift_table_free(m->table);
    g_free(m->scans);
    g_free(m->true_dx);
    g_free(m->true_dy);
    g_free(m->shown_px);
    g_free(m->truth_px);
    g_clear_object(&m->compensated);
    g_free(m);
}
