/*
 *  simscan's presets: the paper's Section IV setting and its Figure 6.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef SIMSCAN_PRESETS_H
#define SIMSCAN_PRESETS_H

#include <glib.h>
#include "simscan-config.h"

G_BEGIN_DECLS

gboolean     simscan_preset_from_name  (const gchar *name,
                                        SimscanPreset *preset);
const gchar* simscan_preset_name       (SimscanPreset preset);
/* Sets the preset's values in config; options given afterwards override
 * them. */
void         simscan_preset_apply      (SimscanConfig *config,
                                        SimscanPreset preset);

/* The Figure 6 stripe drift in px: stripe s (0-based) dx = -(s+1), dy =
 * -(s/4), for n = 16; other n repeat the pattern by stripe groups of n/4. */
void         simscan_figure6_drift     (gint n,
                                        gdouble *dx,
                                        gdouble *dy);

G_END_DECLS

#endif
