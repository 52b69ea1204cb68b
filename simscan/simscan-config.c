/*
 *  simscan's run configuration: defaults and the Figure 6 drift.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <string.h>
#include "simscan-config.h"

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

void
simscan_figure6_drift(gint n, gdouble *dx, gdouble *dy)
{
    gint s;

    for (s = 0; s < n; s++) {
        dx[s] = -(s + 1);
        dy[s] = -((4*s)/n);
    }
}

const gchar*
simscan_preset_name(SimscanPreset preset)
{
    static const gchar *const names[] = { "none", "paper", "figure6" };

    g_return_val_if_fail(preset <= SIMSCAN_PRESET_FIGURE6, NULL);
    return names[preset];
}
