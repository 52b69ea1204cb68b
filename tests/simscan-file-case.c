/*
 *  Files made by the built simscan for the end-to-end tests of continuous
 *  mode.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <math.h>
#include <sys/wait.h>
#include <libprocess/stats.h>
#include <libprocess/correct.h>
#include "continuous-compensate.h"
#include "paper-compensate.h"
#include "localscan-channel.h"
#include "simscan-file-case.h"

/* Edge pixels see content the truth does not have after the shift. */
#define TRUTH_MARGIN 12

static const gchar *const default_args[] = { NULL };
static const gchar *const up_args[] = {
    "--velocity", "0.3,0.15", "--line-time", "1.5", "--direction", "up",
    /* The drift reaches 115 nm by the local scans: the lines must be long
     * enough to find every particle. */
    "--ls-rmax", "200",
    NULL
};

const SimscanFileCase simscan_file_default = {
    "simscan defaults", default_args, { 0.08, 0.02 }, 300.0/256.0, SCAN_DIRECTION_DOWN,
};

const SimscanFileCase simscan_file_up = {
    "scanning up, 1.5 s per line", up_args, { 0.3, 0.15 }, 1.5, SCAN_DIRECTION_UP,
};

gboolean
simscan_file_write(const SimscanFileCase *fcase, guint32 seed, const gchar *filename, GError **error)
{
    GPtrArray *argv = g_ptr_array_new_with_free_func(g_free);
    gchar *err = NULL;
    gint status = 0, i;
    gboolean ok;

    g_ptr_array_add(argv, g_strdup(SIMSCAN_PROGRAM));
    for (i = 0; fcase->args[i]; i++)
        g_ptr_array_add(argv, g_strdup(fcase->args[i]));
    g_ptr_array_add(argv, g_strdup_printf("--seed=%u", seed));
    g_ptr_array_add(argv, g_strdup("-q"));
    g_ptr_array_add(argv, g_strdup("-o"));
    g_ptr_array_add(argv, g_strdup(filename));
    g_ptr_array_add(argv, NULL);
    ok = g_spawn_sync(NULL, (gchar**)argv->pdata, NULL, G_SPAWN_STDOUT_TO_DEV_NULL, NULL, NULL,
                      NULL, &err, &status, error);
    if (ok && !(WIFEXITED(status) && WEXITSTATUS(status) == 0)) {
        g_set_error(error, G_SPAWN_ERROR, G_SPAWN_ERROR_FAILED, "simscan failed: %s", err);
        ok = FALSE;
    }
    g_free(err);
    g_ptr_array_free(argv, TRUE);
    return ok;
}

void
simscan_file_timing(const SimscanFileCase *fcase, GwyDataField *field, ScanTiming *timing)
{
    scan_timing_init(timing, gwy_data_field_get_xres(field), gwy_data_field_get_yres(field),
                     0.0, fcase->line_time, fcase->direction);
}

gdouble
simscan_file_stripe_error_px(const SimscanFileCase *fcase, const DriftTable *table,
                             GwyDataField *field, gint s)
{
    gdouble xstep = gwy_data_field_get_dx(field)*1e9, ystep = gwy_data_field_get_dy(field)*1e9;
    gdouble dx, dy, t_image, t_local, ex, ey;

    if (!table->rows[s].has_drift)
        return NAN;
    g_assert(drift_table_get_extra(table, s, "dx_exact", &dx)
             && drift_table_get_extra(table, s, "dy_exact", &dy)
             && drift_table_get_extra(table, s, "t_image", &t_image)
             && drift_table_get_extra(table, s, "t_local", &t_local));
    ex = dx - fcase->velocity[0]*(t_image - t_local)/xstep;
    ey = dy - fcase->velocity[1]*(t_image - t_local)/ystep;
    return sqrt(ex*ex + ey*ey);
}

gdouble
simscan_file_worst_stripe_px(const SimscanFileCase *fcase, const DriftTable *table, GwyDataField *field)
{
    gdouble worst = 0.0, e;
    gint s;

    for (s = 0; s < table->n_stripes; s++) {
        if (!isnan(e = simscan_file_stripe_error_px(fcase, table, field, s)))
            worst = fmax(worst, e);
    }
    return worst;
}

gdouble
simscan_file_reference_time(const DriftTable *table)
{
    gdouble t_ref = G_MAXDOUBLE, t;
    gint s;

    for (s = 0; s < table->n_stripes; s++) {
        if (table->rows[s].has_drift && drift_table_get_extra(table, s, "t_local", &t))
            t_ref = fmin(t_ref, t);
    }
    return t_ref;
}

/* A feature truly at X appears at X + p: the shifted truth at x is the
 * truth at x - p. */
static void
shift_back(gdouble x, gdouble y, gdouble *sx, gdouble *sy, gpointer user_data)
{
    const gdouble *p = (const gdouble*)user_data;

    *sx = x - p[0];
    *sy = y - p[1];
}

static GwyDataField*
channel_field(GwyContainer *data, gint id, const gchar *what)
{
    GwyDataField *field = NULL;
    gchar key[32];

    g_snprintf(key, sizeof(key), "/%d/%s", id, what);
    gwy_container_gis_object_by_name(data, key, &field);
    return field;
}

gdouble
simscan_file_truth_rms(const SimscanFileCase *fcase, GwyContainer *data, gint id, gdouble t_ref)
{
    GwyDataField *truth = channel_field(data, 1, "data"), *field = channel_field(data, id, "data");
    GwyDataField *mask = channel_field(data, id, "mask"), *shifted;
    gint xres = gwy_data_field_get_xres(truth), yres = gwy_data_field_get_yres(truth), i, j, k, n = 0;
    const gdouble *a, *b, *m;
    gdouble p[2], sum = 0.0;

    g_assert(truth && field);
    p[0] = fcase->velocity[0]*1e-9*t_ref/gwy_data_field_get_dx(truth);
    p[1] = fcase->velocity[1]*1e-9*t_ref/gwy_data_field_get_dy(truth);
    shifted = gwy_data_field_new_alike(truth, FALSE);
    gwy_data_field_distort(truth, shifted, shift_back, p, GWY_INTERPOLATION_BSPLINE,
                           GWY_EXTERIOR_MIRROR_EXTEND, 0.0);
    a = gwy_data_field_get_data_const(field);
    b = gwy_data_field_get_data_const(shifted);
    m = mask ? gwy_data_field_get_data_const(mask) : NULL;
    for (i = TRUTH_MARGIN; i < yres - TRUTH_MARGIN; i++) {
        for (j = TRUTH_MARGIN; j < xres - TRUTH_MARGIN; j++) {
            k = i*xres + j;
            if (m && m[k] > 0.5)
                continue;
            sum += (a[k] - b[k])*(a[k] - b[k]);
            n++;
        }
    }
    g_object_unref(shifted);
    return n ? sqrt(sum/n) : G_MAXDOUBLE;
}

GwyDataField*
simscan_file_expected_continuous(GwyContainer *data, const ScanTiming *timing,
                                 GwyInterpolationType interpolation)
{
    GwyDataField *field = channel_field(data, 0, "data"), *result;
    gint xres = gwy_data_field_get_xres(field), yres = gwy_data_field_get_yres(field);
    const gdouble *a = gwy_data_field_get_data_const(field);
    DriftTable *table = localscan_channel_stored_table(data, 0, NULL);
    gboolean ok;

    g_assert(table);
    result = gwy_data_field_new_alike(field, FALSE);
    ok = continuous_compensate_table(a, xres, yres, table,
                                     gwy_data_field_get_dx(field), gwy_data_field_get_dy(field),
                                     timing, interpolation, paper_image_mean(a, xres, yres),
                                     gwy_data_field_get_data(result), NULL, NULL);
    drift_table_free(table);
    if (!ok)
        g_clear_object(&result);
    return result;
}
