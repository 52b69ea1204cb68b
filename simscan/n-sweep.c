/*
 *  `simscan sweep`: error against the number of stripes.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <stdlib.h>
#include <stdio.h>
#include <string.h>
#include <math.h>
#include "simscan-options.h"
#include "simscan-run.h"
#include "simscan-sample-file.h"
#include "sweep-plot.h"
#include "n-sweep.h"
#include "option-values.h"
#include "simscan-i18n.h"

#define DEFAULT_N_LIST "1,2,4,8,16,32,64"
#define MAX_N_LIST 64

static gboolean
parse_n_list(const gchar *text, gint yres, GArray *list, GError **error)
{
    gchar **parts = g_strsplit(text, ",", -1);
    gboolean ok = TRUE;
    guint i;

    for (i = 0; ok && parts[i]; i++) {
        gchar *end;
        gint64 n = g_ascii_strtoll(g_strstrip(parts[i]), &end, 10);
        gint value = (gint)n;

        ok = (*parts[i] && !*end && n >= 1 && n <= yres);
        if (ok)
            g_array_append_val(list, value);
    }
    g_strfreev(parts);
    /* Each count is a whole simulation of local scans. */
    if (list->len > MAX_N_LIST) {
        g_set_error(error, G_OPTION_ERROR, G_OPTION_ERROR_BAD_VALUE,
                    _("--n-list: %u stripe counts are too many (from 1 to %d)"),
                    list->len, MAX_N_LIST);
        return FALSE;
    }
    if (!ok || !list->len)
        g_set_error(error, G_OPTION_ERROR, G_OPTION_ERROR_BAD_VALUE,
                    _("--n-list: expected stripe counts from 1 to %d "
                      "separated by commas"), yres);
    return ok && list->len;
}

/* A stripe count whose local scans found nothing is a result too (the drift
 * outran r_max): it shows as measured 0, no errors. */
static void
sweep_point(SimscanScene *scene, gint n, SweepPoint *point)
{
    SimscanMeasurement *m = simscan_measure(scene, n, NULL);
    gint s;

    point->n = n;
    point->measured = 0;
    if (!m) {
        point->before.rms_px = point->after.rms_px = NAN;
        point->after.max_px = point->after.rms_nm = NAN;
        return;
    }
    for (s = 0; s < n; s++)
        point->measured += m->table->rows[s].has_drift;
    point->lines = m->lines;
    point->local_time = m->t_end - m->t_start;
    point->before = m->before;
    point->after = m->after;
    simscan_measurement_free(m);
}

static void
print_sweep(const SweepPoint *points, gint n_points)
{
    gint i;

    printf(_("# particle-centre error after paper-mode compensation against "
             "the number of stripes N\n"));
    printf("%4s %8s %6s %9s %10s %10s %10s %10s %8s\n",
           "N", "measured", "lines", "scan_s", "before_px", "after_px",
           "after_max", "after_nm", "matched");
    for (i = 0; i < n_points; i++) {
        const SweepPoint *p = points + i;

        printf("%4d %8d %6d %9.3f %10.3f %10.3f %10.3f %10.2f %4d/%-4d\n",
               p->n, p->measured, p->lines, p->local_time, p->before.rms_px,
               p->after.rms_px, p->after.max_px, p->after.rms_nm,
               p->after.n_matched, p->after.n_expected);
    }
}

static gboolean
check_sweep_config(const SimscanConfig *config, GError **error)
{
    if (config->output || config->table || config->json) {
        g_set_error(error, G_OPTION_ERROR, G_OPTION_ERROR_BAD_VALUE,
                    _("sweep writes no .gwy, table or JSON; use --plot"));
        return FALSE;
    }
    if (config->sample_file) {
        g_set_error(error, G_OPTION_ERROR, G_OPTION_ERROR_BAD_VALUE,
                    _("sweep needs synthetic particles, not --sample"));
        return FALSE;
    }
    return TRUE;
}

/* The plot's title names the drift as simscan's options do, except the
 * model type "none", which is no additional effect on top of the constant
 * velocity: the title says the velocity (or that there is no drift). */
static gchar*
sweep_title(const SimscanConfig *config)
{
    const DriftModel *drift = &config->drift;

    if (config->figure6)
        return g_strdup_printf(_("Figure 6 drift, seed %u"), config->seed);
    if (drift->type != DRIFT_MODEL_NONE)
        return g_strdup_printf(_("%s drift, seed %u"), drift_model_type_name(drift->type),
                               config->seed);
    if (drift->v[0] == 0.0 && drift->v[1] == 0.0)
        return g_strdup_printf(_("no drift, seed %u"), config->seed);
    return g_strdup_printf(_("constant drift %.3g, %.3g nm/s, seed %u"),
                           1e9*drift->v[0], 1e9*drift->v[1], config->seed);
}

static gboolean
run_sweep(const SimscanConfig *config, GArray *list, const gchar *plot,
          GError **error)
{
    SimscanScene *scene;
    SweepPoint *points;
    gboolean ok = TRUE;
    gchar *title;
    guint i;

    if (!(scene = simscan_scene_new(config, NULL, error)))
        return FALSE;
    points = g_new0(SweepPoint, list->len);
    for (i = 0; i < list->len; i++)
        sweep_point(scene, g_array_index(list, gint, i), points + i);
    if (plot) {
        title = sweep_title(config);
        ok = sweep_plot_write_png(points, list->len, title, plot, error);
        g_free(title);
    }
    if (ok && !config->quiet)
        print_sweep(points, list->len);
    g_free(points);
    simscan_scene_free(scene);
    return ok;
}

int
simscan_sweep_main(int argc, char **argv)
{
    gchar *n_list = NULL, *plot = NULL;
    GOptionEntry extra[] = {
        { "n-list", 0, 0, G_OPTION_ARG_STRING, &n_list,
          N_("stripe counts to try (" DEFAULT_N_LIST ")"), "N,N,..." },
        { "plot", 0, 0, G_OPTION_ARG_FILENAME, &plot,
          N_("write the error against N as a PNG plot"), "OUT.png" },
        { NULL, 0, 0, 0, NULL, NULL, NULL },
    };
    SimscanConfig config;
    GArray *list = g_array_new(FALSE, FALSE, sizeof(gint));
    GError *error = NULL;
    gboolean ok;

    simscan_config_init(&config);
    ok = simscan_options_parse(argc, argv,
                               _("- error against the number of stripes"),
                               extra, &config, &error);
    ok = ok && check_sweep_config(&config, &error);
    ok = ok && parse_n_list(n_list ? n_list : DEFAULT_N_LIST, config.yres,
                            list, &error);
    ok = ok && run_sweep(&config, list, plot, &error);
    if (!ok) {
        simscan_print_error("simscan sweep", error);
        g_error_free(error);
    }
    g_array_free(list, TRUE);
    g_free(n_list);
    g_free(plot);
    simscan_config_clear(&config);
    return ok ? EXIT_SUCCESS : EXIT_FAILURE;
}
