/*
 *  The graph of a series' drift trajectory, for the module and the series
 *  command alike.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <string.h>
#include <math.h>
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

/* The share of each axis a legend of four curves covers in the dialog's
 * graph, about; each corner's box is this large. */
#define LEGEND_FRACTION 0.35

/* Every curve's points, one after another (g_free x); their number. */
static gint
curve_points(GwyGraphModel *graph, gdouble **x, gdouble **y)
{
    gint i, n, total = 0, nc = gwy_graph_model_get_n_curves(graph);

    for (i = 0; i < nc; i++)
        total += gwy_graph_curve_model_get_ndata(gwy_graph_model_get_curve(graph, i));
    *x = g_new(gdouble, 2*MAX(total, 1));
    *y = *x + MAX(total, 1);
    total = 0;
    for (i = 0; i < nc; i++) {
        GwyGraphCurveModel *curve = gwy_graph_model_get_curve(graph, i);

        n = gwy_graph_curve_model_get_ndata(curve);
        memcpy(*x + total, gwy_graph_curve_model_get_xdata(curve), n*sizeof(gdouble));
        memcpy(*y + total, gwy_graph_curve_model_get_ydata(curve), n*sizeof(gdouble));
        total += n;
    }
    return total;
}

/* The range of the finite values; FALSE when there are none. */
static gboolean
value_range(const gdouble *v, gint n, gdouble *lo, gdouble *hi)
{
    gint i;

    *lo = G_MAXDOUBLE;
    *hi = -G_MAXDOUBLE;
    for (i = 0; i < n; i++) {
        if (isfinite(v[i])) {
            *lo = MIN(*lo, v[i]);
            *hi = MAX(*hi, v[i]);
        }
    }
    return *lo <= *hi;
}

void
series_graph_place_legend(GwyGraphModel *graph)
{
    /* In GwyGraphLabelPosition's order: NE, NW, SE, SW. */
    static const gboolean east[4] = { TRUE, FALSE, TRUE, FALSE };
    static const gboolean north[4] = { TRUE, TRUE, FALSE, FALSE };
    gdouble *x, *y, xmin, xmax, ymin, ymax, wx, wy;
    gint j, c, n = curve_points(graph, &x, &y), count[4] = { 0, 0, 0, 0 };
    gint best = GWY_GRAPH_LABEL_NORTHEAST;

    /* Points with a non-finite coordinate are drawn nowhere. */
    if (value_range(x, n, &xmin, &xmax) && value_range(y, n, &ymin, &ymax)) {
        wx = LEGEND_FRACTION*(xmax - xmin);
        wy = LEGEND_FRACTION*(ymax - ymin);
        for (j = 0; j < n; j++) {
            for (c = 0; c < 4; c++) {
                if ((east[c] ? x[j] >= xmax - wx : x[j] <= xmin + wx)
                    && (north[c] ? y[j] >= ymax - wy : y[j] <= ymin + wy))
                    count[c]++;
            }
        }
        for (c = 1; c < 4; c++) {
            if (count[c] < count[best])
                best = c;
        }
        g_object_set(graph, "label-position", best, NULL);
    }
    g_free(x);
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
    series_graph_place_legend(graph);
    return graph;
}

