/*
 *  Gwyddion's own "Compensate Drift" (process function drift) run headlessly
 *  on an image, as the baseline the benchmarks compare against.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <stdio.h>
#include <string.h>
#include <libgwyddion/gwyddion.h>
#include <libprocess/gwyprocess.h>
#include <libgwymodule/gwymodule.h>
#include <libdraw/gwydraw.h>
#include <libgwydgets/gwydgets.h>
#include <app/gwyapp.h>
#include "gwyddion-drift-baseline.h"

gboolean
gwyddion_drift_init(void)
{
    GwyContainer *settings;

    gwy_app_init_nongui("enable-threads", FALSE, NULL);
    if (!gwy_process_func_exists("drift")) {
        fprintf(stderr, "Gwyddion's process function drift is not available.\n");
        return FALSE;
    }
    /* drift.c's settings keys; only the graph is wanted. */
    settings = gwy_app_settings_get();
    gwy_container_set_int32_by_name(settings, "/module/drift/range", 12);
    gwy_container_set_enum_by_name(settings, "/module/drift/interp", GWY_INTERPOLATION_BSPLINE);
    gwy_container_set_boolean_by_name(settings, "/module/drift/do-correct", FALSE);
    gwy_container_set_boolean_by_name(settings, "/module/drift/do-plot", TRUE);
    gwy_container_set_boolean_by_name(settings, "/module/drift/new-image", TRUE);
    gwy_container_set_boolean_by_name(settings, "/module/drift/distribute", FALSE);
    gwy_container_set_boolean_by_name(settings, "/module/drift/exclude-linear", FALSE);
    return TRUE;
}

static gboolean
read_drift_graph(GwyContainer *data, gint yres, gdouble *row_drift)
{
    gint *ids = gwy_app_data_browser_get_graph_ids(data);
    GwyGraphModel *gmodel;
    GwyGraphCurveModel *gcmodel;
    gboolean ok = FALSE;

    if (ids[0] != -1) {
        gmodel = gwy_container_get_object(data, gwy_app_get_graph_key_for_id(ids[0]));
        if (gwy_graph_model_get_n_curves(gmodel) >= 1) {
            gcmodel = gwy_graph_model_get_curve(gmodel, 0);
            if (gwy_graph_curve_model_get_ndata(gcmodel) == yres) {
                memcpy(row_drift, gwy_graph_curve_model_get_ydata(gcmodel), yres*sizeof(gdouble));
                ok = TRUE;
            }
        }
    }
    g_free(ids);
    return ok;
}

gboolean
gwyddion_drift_estimate(const gdouble *image, gint xres, gint yres, gdouble *row_drift, gdouble *seconds)
{
    GwyContainer *data = gwy_container_new();
    GwyDataField *field = gwy_data_field_new(xres, yres, xres, yres, FALSE);
    gint64 start;
    gboolean ok;

    memcpy(gwy_data_field_get_data(field), image, (gsize)xres*yres*sizeof(gdouble));
    gwy_container_set_object(data, gwy_app_get_data_key_for_id(0), field);
    g_object_unref(field);
    gwy_app_data_browser_add(data);
    gwy_app_data_browser_select_data_field(data, 0);
    start = g_get_monotonic_time();
    gwy_process_func_run("drift", data, GWY_RUN_IMMEDIATE);
    *seconds = (g_get_monotonic_time() - start)/1e6;
    ok = read_drift_graph(data, yres, row_drift);
    gwy_app_data_browser_remove(data);
    g_object_unref(data);
    return ok;
}

void
gwyddion_drift_finish(void)
{
    gwy_app_data_browser_shut_down();
}
