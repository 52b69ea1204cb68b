/*
 *  A frame series loaded from files with Gwyddion's file modules.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <libgwyddion/gwyddion.h>
#include <libgwymodule/gwymodule.h>
#include <app/gwyapp.h>
#include "frame-series-load.h"
#include "isolated-load.h"
#include "localscan-intl.h"

static void
free_datas(GwyContainer **datas, gint n)
{
    gint k;

    for (k = 0; k < n; k++) {
        if (datas[k])
            g_object_unref(datas[k]);
    }
    g_free(datas);
}

FrameSeries*
frame_series_load(gchar **filenames, gint n_files,
                  const FrameSeriesOptions *options, GError **error)
{
    GwyContainer **datas = g_new0(GwyContainer*, MAX(n_files, 1));
    FrameSeries *series = NULL;
    GError *err = NULL;
    gint k;

    for (k = 0; k < n_files; k++) {
        /* Screened, then loaded in a child process: a damaged frame gets
         * one line, not an abort or a hang inside a loader (isolated-load.h). */
        datas[k] = isolated_load(filenames[k], &err);
        if (!datas[k]) {
            g_set_error(error, FRAME_SERIES_ERROR, FRAME_SERIES_ERROR_LOAD,
                        "%s", err->message);
            g_clear_error(&err);
            free_datas(datas, n_files);
            return NULL;
        }
    }
    series = frame_series_from_files(datas, filenames, n_files, options,
                                     error);
    free_datas(datas, n_files);
    return series;
}
