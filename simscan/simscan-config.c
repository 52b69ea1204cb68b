/*
 *  simscan's run configuration: defaults and a measured sample's
 *  defaults.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <string.h>
#include <math.h>
#include "particle-detect.h"
#include "simscan-config.h"
#include "simscan-i18n.h"

/* The paper's Section IV image: 5 um over 256 px. */
#define PAPER_PIXEL_SIZE (5e-6/256)

void
simscan_config_init(SimscanConfig *config)
{
    memset(config, 0, sizeof(SimscanConfig));
    config->preset = SIMSCAN_PRESET_NONE;
    sim_particle_params_init(&config->particles);
    config->sample_channel = -1;
    config->xres = config->yres = 256;
    config->xreal = config->particles.xreal;
    config->yreal = config->particles.yreal;
    config->line_time = 300.0/256.0;
    config->direction = SCAN_DIRECTION_DOWN;
    drift_model_init(&config->drift, DRIFT_MODEL_NONE);
    config->drift.v[0] = DRIFT_MODEL_PAPER_VX;
    config->drift.v[1] = DRIFT_MODEL_PAPER_VY;
    config->n_stripes = 16;
    local_scan_params_init(&config->local);
    config->local.radius = config->particles.radius;
    config->seed = 1;
}

void
simscan_config_clear(SimscanConfig *config)
{
    drift_model_clear(&config->drift);
    g_free(config->sample_file);
    g_free(config->output);
    g_free(config->table);
    g_free(config->json);
    config->sample_file = config->output = config->table = config->json = NULL;
}

static GQuark
simscan_config_error_quark(void)
{
    return g_quark_from_static_string("simscan-config-error-quark");
}

gboolean
simscan_config_adopt_sample(SimscanConfig *config, GwyDataField *sample,
                            guint given, GError **error)
{
    ParticleDetectParams detect;
    GArray *particles;
    gdouble dx = gwy_data_field_get_dx(sample);
    gdouble dy = gwy_data_field_get_dy(sample);
    gdouble scale = sqrt(dx*dy)/PAPER_PIXEL_SIZE, radius;

    particle_detect_params_init(&detect);
    particles = particle_detect(sample, &detect, NULL, NULL);
    radius = particle_typical_radius(particles, dx, dy);
    g_array_free(particles, TRUE);
    if (!(radius > 0.0)) {
        g_set_error(error, simscan_config_error_quark(), 0,
                    _("no particles found on the sample %s"),
                    config->sample_file);
        return FALSE;
    }
    config->xreal = gwy_data_field_get_xreal(sample);
    config->yreal = gwy_data_field_get_yreal(sample);
    if (!(given & SIMSCAN_GIVEN_RESOLUTION)) {
        config->xres = gwy_data_field_get_xres(sample);
        config->yres = gwy_data_field_get_yres(sample);
        config->n_stripes = MIN(config->n_stripes, config->yres);
    }
    if (!(given & SIMSCAN_GIVEN_RADIUS))
        config->local.radius = radius;
    if (!(given & SIMSCAN_GIVEN_VELOCITY)) {
        config->drift.v[0] = DRIFT_MODEL_PAPER_VX*scale;
        config->drift.v[1] = DRIFT_MODEL_PAPER_VY*scale;
    }
    if (!(given & SIMSCAN_GIVEN_RMAX))
        config->local.r_max *= scale;
    return TRUE;
}
