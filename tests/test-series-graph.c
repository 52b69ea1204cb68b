/*
 *  The series graph's legend (modules/series-graph.h) goes to the corner
 *  of the plot the curves' points crowd least: points drawn at random
 *  (seeded), one corner left empty at random, the others crowded.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <check.h>
#include <libgwyddion/gwyddion.h>
#include <libgwydgets/gwydgets.h>
#include "series-graph.h"
#include "test-common.h"

#define N_DRAWS 20
#define N_POINTS 400

static guint32 base_seed;

/* A curve of N_POINTS points over [0, 1] x [0, 1] (and the corners
 * (0, 0) and (1, 1), which fix the range) avoiding the corner box of the
 * position empty (GwyGraphLabelPosition, its box 0.4 of each axis). */
static GwyGraphCurveModel*
curve_avoiding(GRand *rng, gint empty)
{
    GwyGraphCurveModel *curve = gwy_graph_curve_model_new();
    gdouble x[N_POINTS], y[N_POINTS];
    gboolean east = (empty == GWY_GRAPH_LABEL_NORTHEAST || empty == GWY_GRAPH_LABEL_SOUTHEAST);
    gboolean north = (empty == GWY_GRAPH_LABEL_NORTHEAST || empty == GWY_GRAPH_LABEL_NORTHWEST);
    gint i = 2;

    x[0] = y[0] = 0.0;
    x[1] = y[1] = 1.0;
    while (i < N_POINTS) {
        x[i] = g_rand_double(rng);
        y[i] = g_rand_double(rng);
        if ((east ? x[i] > 0.6 : x[i] < 0.4) && (north ? y[i] > 0.6 : y[i] < 0.4))
            continue;
        i++;
    }
    /* (0, 0) or (1, 1) lies in the empty corner itself: move it to the
     * edge's middle, keeping the range. */
    for (i = 0; i < 2; i++) {
        if ((east ? x[i] > 0.6 : x[i] < 0.4) && (north ? y[i] > 0.6 : y[i] < 0.4))
            y[i] = 0.5;
    }
    gwy_graph_curve_model_set_data(curve, x, y, N_POINTS);
    return curve;
}

START_TEST(test_legend_in_the_empty_corner)
{
    GRand *rng = test_rand_salted(base_seed, 1);
    gint d, empty, position;

    for (d = 0; d < N_DRAWS; d++) {
        GwyGraphModel *graph = gwy_graph_model_new();
        GwyGraphCurveModel *curve;

        empty = g_rand_int_range(rng, GWY_GRAPH_LABEL_NORTHEAST, GWY_GRAPH_LABEL_SOUTHWEST + 1);
        curve = curve_avoiding(rng, empty);
        gwy_graph_model_add_curve(graph, curve);
        g_object_unref(curve);
        series_graph_place_legend(graph);
        g_object_get(graph, "label-position", &position, NULL);
        ck_assert_msg(position == empty, "seed %u draw %d: legend at %d, the empty corner is %d",
                      base_seed, d, position, empty);
        g_object_unref(graph);
    }
    g_rand_free(rng);
}
END_TEST

int
main(void)
{
    TCase *tc;
    Suite *s = test_suite_new("series-graph", "legend", &tc);

    base_seed = test_seed_from_env("test-series-graph");
    tcase_add_test(tc, test_legend_in_the_empty_corner);
    return test_run_suite(s);
}
