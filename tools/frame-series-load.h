/*
 *  A frame series loaded from files with Gwyddion's file modules, for the
 *  command-line front ends (simscan fit, the validation study, tests).  The
 *  series itself is the core's (modules/core/frame-series.h); loading lives
 *  here because Gwyddion's file loaders need its application library,
 *  which the GTK-free core does not link.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_FRAME_SERIES_LOAD_H
#define LOCALSCAN_FRAME_SERIES_LOAD_H

#include "frame-series.h"

G_BEGIN_DECLS

/* Loads every file (Gwyddion's modules must be registered, as
 * gwy_app_init_nongui() does) and returns frame_series_from_files() of
 * them; a file Gwyddion cannot read is refused as FRAME_SERIES_ERROR_LOAD. */
FrameSeries*  frame_series_load  (gchar **filenames,
                                  gint n_files,
                                  const FrameSeriesOptions *options,
                                  GError **error);

G_END_DECLS

#endif
