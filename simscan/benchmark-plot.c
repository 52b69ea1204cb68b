/*
 *  The benchmark's figure as SVG, written by hand so that the benchmark
 *  needs no plotting tool: trajectory RMS per case and method, bars on a
 *  log axis (errors span 0.001 to tens of pixels).
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <math.h>
#include "benchmark-plot.h"

#define LABEL_WIDTH 170
#define PLOT_WIDTH 480
#define BAR_HEIGHT 7
#define GROUP_GAP 6
#define LEGEND_PER_ROW 4
#define LEGEND_ROW 12
/* The axis: 10^LOG_MIN to 10^LOG_MAX px. */
#define LOG_MIN -3
#define LOG_MAX 2

static const gchar *const colours[] = {
    "#1b6ca8", "#d95f02", "#7570b3", "#1b9e77", "#e7298a", "#66a61e",
};

static gdouble
axis_x(gdouble value)
{
    gdouble l = log10(CLAMP(value, pow(10.0, LOG_MIN), pow(10.0, LOG_MAX)));

    return LABEL_WIDTH + PLOT_WIDTH*(l - LOG_MIN)/(LOG_MAX - LOG_MIN);
}

static void
draw_axis(GString *svg, gint top, gint height)
{
    gint e;

    for (e = LOG_MIN; e <= LOG_MAX; e++) {
        gdouble x = axis_x(pow(10.0, e));

        g_string_append_printf(svg, "<line x1='%.1f' y1='%d' x2='%.1f' y2='%d' "
                               "stroke='#ccc'/>\n", x, top - 5, x, height - 20);
        g_string_append_printf(svg, "<text x='%.1f' y='%d' font-size='10' "
                               "text-anchor='middle'>%g</text>\n", x,
                               height - 6, pow(10.0, e));
    }
    g_string_append_printf(svg, "<text x='%d' y='14' font-size='12'>Trajectory "
                           "RMS per case (px, log scale)</text>\n", LABEL_WIDTH);
}

/* Four methods to a row of the legend, above the plot. */
static void
draw_legend(GString *svg, gchar **methods)
{
    gchar *name;
    gint j, x, y;

    for (j = 0; methods[j]; j++) {
        x = LABEL_WIDTH + 120*(j % LEGEND_PER_ROW);
        y = 22 + LEGEND_ROW*(j/LEGEND_PER_ROW);
        name = g_markup_escape_text(methods[j], -1);
        g_string_append_printf(svg, "<rect x='%d' y='%d' width='10' height='8' "
                               "fill='%s'/><text x='%d' y='%d' font-size='10'>"
                               "%s</text>\n", x, y,
                               colours[j % G_N_ELEMENTS(colours)], x + 14,
                               y + 8, name);
        g_free(name);
    }
}

gchar*
benchmark_plot_svg(gchar **cases, gchar **methods, const BenchmarkScore *scores)
{
    gint nc = g_strv_length(cases), nm = g_strv_length(methods), i, j, y;
    gint top = 34 + LEGEND_ROW*((nm + LEGEND_PER_ROW - 1)/LEGEND_PER_ROW);
    gint height = top + nc*(nm*BAR_HEIGHT + GROUP_GAP) + 30;
    GString *svg = g_string_new(NULL);
    const BenchmarkScore *s;
    gchar *name;

    g_string_append_printf(svg, "<svg xmlns='http://www.w3.org/2000/svg' "
                           "width='%d' height='%d' font-family='sans-serif'>\n",
                           LABEL_WIDTH + PLOT_WIDTH + 20, height);
    g_string_append(svg, "<rect width='100%' height='100%' fill='white'/>\n");
    draw_axis(svg, top, height);
    draw_legend(svg, methods);
    for (i = 0; i < nc; i++) {
        y = top + i*(nm*BAR_HEIGHT + GROUP_GAP);
        name = g_markup_escape_text(cases[i], -1);
        g_string_append_printf(svg, "<text x='%d' y='%d' font-size='10' "
                               "text-anchor='end'>%s</text>\n", LABEL_WIDTH - 6,
                               y + nm*BAR_HEIGHT/2 + 4, name);
        g_free(name);
        for (j = 0; j < nm; j++) {
            s = scores + i*nm + j;
            if (s->failure || !isfinite(s->trajectory_rms_px)) {
                g_string_append_printf(svg, "<text x='%d' y='%d' font-size='8' "
                                       "fill='#b00'>failed</text>\n",
                                       LABEL_WIDTH + 2, y + (j + 1)*BAR_HEIGHT);
                continue;
            }
            /* At least a pixel: a perfect method is not a missing one. */
            g_string_append_printf(svg, "<rect x='%d' y='%d' width='%.1f' "
                                   "height='%d' fill='%s'/>\n", LABEL_WIDTH,
                                   y + j*BAR_HEIGHT,
                                   MAX(axis_x(s->trajectory_rms_px) - LABEL_WIDTH, 1.0),
                                   BAR_HEIGHT - 1,
                                   colours[j % G_N_ELEMENTS(colours)]);
        }
    }
    g_string_append(svg, "</svg>\n");
    return g_string_free(svg, FALSE);
}
