/*
 *  simscan's presets.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include "simscan-presets.h"

const gchar*
simscan_preset_name(SimscanPreset preset)
{
    static const gchar *const names[] = { "none", "paper", "figure6" };

    g_return_val_if_fail(preset <= SIMSCAN_PRESET_FIGURE6, NULL);
    return names[preset];
}

gboolean
simscan_preset_from_name(const gchar *name, SimscanPreset *preset)
{
    if (g_str_equal(name, "paper"))
        *preset = SIMSCAN_PRESET_PAPER;
    else if (g_str_equal(name, "figure6"))
        *preset = SIMSCAN_PRESET_FIGURE6;
    else
        return FALSE;
    return TRUE;
}

void
simscan_preset_apply(SimscanConfig *config, SimscanPreset preset)
{
    config->preset = preset;
    if (preset == SIMSCAN_PRESET_PAPER) {
        /* The defaults are the paper's Section IV already: 256 x 256 over
         * 5 um, 50 nm latex spheres, 300 s, v = (0.08, 0.02) nm/s, N = 16.
         * 2 s of local scans over 16 stripes: 2 lines of 62.5 ms each. */
        config->local.r_max = 100e-9;
        config->local.tip_speed = 4e-6;
    }
    else if (preset == SIMSCAN_PRESET_FIGURE6) {
        /* Shifts up to (16, 3) px (318 nm), so r_max must exceed that; a
         * neighbour, 700 nm or more from the particle, is at least 382 nm
         * from its displayed centre, so r_max below that keeps it out of
         * reach (400 nm did not).  Half way between, 30 nm to spare either
         * side.  The lines, 2 (R + r_max) = 750 nm long, keep the default
         * lines' 4 nm sample spacing with 192 points: with 64 (12 nm) a
         * grazing chord of the search is off by up to half a pixel. */
        config->figure6 = TRUE;
        config->n_stripes = 16;
        config->particles.min_spacing = 700e-9;
        config->particles.count = 60;
        config->local.r_max = 350e-9;
        config->local.points = 192;
        /* The paper's particle choice, as the figure was made: a stripe
         * measured on a grain cut by a stripe boundary is part of the honest
         * result (simscan marks such stripes with a star). */
        config->local.choice = PARTICLE_CHOICE_CLOSEST;
    }
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
