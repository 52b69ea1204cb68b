/*
 *  The graph of a series' drift trajectory, for the module and the series
 *  command alike.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <libgwyddion/gwyddion.h>
#include <libgwydgets/gwydgets.h>
#include "series-graph.h"
#include "localscan-intl.h"

static GwyGraphCurveModel*
new_curve(const gchar *title, GwyGraphCurveType type, gint colour,
          const gdouble *t, const gdouble *v, gint n)
{
    GwyGraphCurveModel *curve = gwy_graph_curve_model_new();

    g_object_set(curve, "description", title, "mode", type,
                 "color", gwy_graph_get_preset_color(colour), NULL);
    gwy_graph_curve_model_set_data(curve, t, v, n);
    return curve;
}

GwyGraphModel*
series_graph_new(const SeriesCorrection *c, const FrameSeries *series)
{
    GwyGraphModel *graph = gwy_graph_model_new();
    GArray *t = g_array_new(FALSE, FALSE, sizeof(gdouble));
    GArray *x = g_array_new(FALSE, FALSE, sizeof(gdouble));
    GArray *y = g_array_new(FALSE, FALSE, sizeof(gdouble));
    GwyGraphCurveModel *curve;
    GwySIUnit *unit;
    gdouble when, px, py, bx, by;
    gint k, r, i, m;

    for (m = 0; m < 2; m++) {
        g_array_set_size(t, 0);
        g_array_set_size(x, 0);
        g_array_set_size(y, 0);
        if (m == 0) {
            for (k = 0; k < series->n_frames; k++) {
                const ScanTiming *timing = &series->frames[k].timing;

                for (r = 0; r < timing->yres; r++) {
                    when = scan_timing_rows_time(timing, r, r+1);
                    series_correction_eval(c, when, &px, &py);
                    px *= c->xstep;
                    py *= c->ystep;
                    g_array_append_val(t, when);
                    g_array_append_val(x, px);
                    g_array_append_val(y, py);
                }
            }
        }
        else {
            for (i = 0; i < c->fit.n_meas; i++) {
                const DriftMeasurement *mm = c->fit.meas + i;

                if (mm->weight <= 0.0)
                    continue;
                series_correction_eval(c, mm->t_b, &bx, &by);
                bx *= c->xstep;
                by *= c->ystep;
                px = bx + mm->dx;
                py = by + mm->dy;
                g_array_append_val(t, mm->t_a);
                g_array_append_val(x, px);
                g_array_append_val(y, py);
            }
        }
        curve = new_curve(m ? _("dx measured") : _("dx fitted"),
                          m ? GWY_GRAPH_CURVE_POINTS : GWY_GRAPH_CURVE_LINE,
                          0, (gdouble*)t->data, (gdouble*)x->data, t->len);
        gwy_graph_model_add_curve(graph, curve);
        g_object_unref(curve);
        curve = new_curve(m ? _("dy measured") : _("dy fitted"),
                          m ? GWY_GRAPH_CURVE_POINTS : GWY_GRAPH_CURVE_LINE,
                          1, (gdouble*)t->data, (gdouble*)y->data, t->len);
        gwy_graph_model_add_curve(graph, curve);
        g_object_unref(curve);
    }
    g_object_set(graph, "title", _("Drift trajectory"),
                 "axis-label-bottom", "t", "axis-label-left", _("drift"),
                 NULL);
    unit = gwy_si_unit_new("s");
    g_object_set(graph, "si-unit-x", unit, NULL);
    g_object_unref(unit);
    unit = gwy_si_unit_new("m");
    g_object_set(graph, "si-unit-y", unit, NULL);
    g_object_unref(unit);
    g_array_free(t, TRUE);
    g_array_free(x, TRUE);
    g_array_free(y, TRUE);
    return graph;
}

