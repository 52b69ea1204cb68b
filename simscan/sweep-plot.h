/*
 *  The N sweep drawn as a PNG (cairo): error against stripes.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef SIMSCAN_SWEEP_PLOT_H
#define SIMSCAN_SWEEP_PLOT_H

#include <glib.h>
#include "n-sweep.h"

G_BEGIN_DECLS

/* Writes the plot atomically (temporary file, rename). */
gboolean  sweep_plot_write_png  (const SweepPoint *points,
                                 gint n_points,
                                 const gchar *title,
                                 const gchar *filename,
                                 GError **error);

G_END_DECLS

#endif
