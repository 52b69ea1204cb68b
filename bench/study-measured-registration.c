/*
 *  The registration on measured raw frames, run as a user runs it: the
 *  FastScan pairs (three channels recorded on the same lines, so sharing
 *  one drift) and the HS-AFM movies of ../shared/data/measured, through
 *  the product's stripe_registration_table_for_fields().  Prints, per pair
 *  and stripe count, the stripes measured of those whose content lies in
 *  the reference, the median score, the agreement between channels and the
 *  closure of the FastScan pairs: the figures of docs/registration.md.
 *
 *    bench/study-measured-registration [MEASURED_DIR]
 *
 *  MEASURED_DIR defaults to $LOCALSCAN_MEASURED_DIR, else
 *  ../shared/data/measured beside the source tree.  Not a test.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <libgwyddion/gwyddion.h>
#include <libprocess/gwyprocess.h>
#include <libgwymodule/gwymodule.h>
#include <libdraw/gwydraw.h>
#include <libgwydgets/gwydgets.h>
#include <app/gwyapp.h>
#include "stripe-registration.h"
#include "drift-table.h"
#include "median.h"

enum { FASTSCAN_CHANNELS = 3, MAX_STRIPES = 16 };

static const gchar *const fastscan_files[] = { "09261606.001", "09261609.001", "09261616.001" };
static const gchar *const channel_names[FASTSCAN_CHANNELS] = { "ZSensor", "AmplitudeActual", "Phase" };

typedef struct {
    gboolean measured[MAX_STRIPES];
    gdouble dx[MAX_STRIPES], dy[MAX_STRIPES], sigma[MAX_STRIPES];
    StripeRegistrationSupport support;
} PairResult;

static GwyContainer*
load_file(const gchar *path)
{
    GError *error = NULL;
    GwyContainer *data = gwy_file_load(path, GWY_RUN_NONINTERACTIVE, &error);

    if (!data) {
        fprintf(stderr, "study-measured-registration: %s: %s\n", path, error ? error->message : "unreadable");
        exit(1);
    }
    return data;
}

static GwyDataField*
channel(GwyContainer *data, gint id)
{
    return gwy_container_get_object(data, gwy_app_get_data_key_for_id(id));
}

/* One registration; nothing measured when it found nothing. */
static void
register_pair(GwyDataField *image, GwyDataField *reference, gint n, PairResult *result)
{
    GError *error = NULL;
    DriftTable *table;
    gdouble value;
    gint s;

    gwy_clear(result, 1);
    table = stripe_registration_table_for_fields(image, reference, n, NULL, FALSE, &result->support, &error);
    g_clear_error(&error);
    if (!table)
        return;
    for (s = 0; s < n; s++) {
        if (!table->rows[s].has_drift)
            continue;
        result->measured[s] = TRUE;
        result->dx[s] = drift_table_get_extra(table, s, "dx_exact", &value) ? value : table->rows[s].dx;
        result->dy[s] = drift_table_get_extra(table, s, "dy_exact", &value) ? value : table->rows[s].dy;
        result->sigma[s] = drift_table_get_extra(table, s, "sigma_px", &value) ? value : 0.0;
    }
    drift_table_free(table);
}

static void
print_pair(const gchar *what, gint n, const PairResult *r)
{
    gint s;

    printf("%-34s N=%2d  %2d/%-2d measured, median score %.2f:", what, n, r->support.measured,
           r->support.in_reference, r->support.median_score);
    for (s = 0; s < n; s++) {
        if (r->measured[s])
            printf(" %d(%.1f,%.1f±%.1f)", s, r->dx[s], r->dy[s], r->sigma[s]);
    }
    printf("\n");
}

/* Median of the measured stripes' shifts. */
static gboolean
median_shift(const PairResult *r, gint n, gdouble *dx, gdouble *dy)
{
    gdouble xs[MAX_STRIPES], ys[MAX_STRIPES];
    gint s, m = 0;

    for (s = 0; s < n; s++) {
        if (r->measured[s]) {
            xs[m] = r->dx[s];
            ys[m++] = r->dy[s];
        }
    }
    if (!m)
        return FALSE;
    *dx = median_in_place(xs, m);
    *dy = median_in_place(ys, m);
    return TRUE;
}

/* The shift of a pair at image row y, interpolated linearly between the
 * centre rows of the measured stripes (the nearest one's beyond them). */
static gboolean
shift_at_row(const PairResult *r, gint n, gint yres, gdouble y, gdouble *dx, gdouble *dy)
{
    gint s, below = -1, above = -1;
    gdouble yb, ya, t;

    for (s = 0; s < n; s++) {
        if (!r->measured[s])
            continue;
        if ((s + 0.5)*yres/n <= y)
            below = s;
        else if (above < 0)
            above = s;
    }
    if (below < 0 && above < 0)
        return FALSE;
    if (below < 0 || above < 0) {
        s = (below < 0) ? above : below;
        *dx = r->dx[s];
        *dy = r->dy[s];
        return TRUE;
    }
    yb = (below + 0.5)*yres/n;
    ya = (above + 0.5)*yres/n;
    t = (y - yb)/(ya - yb);
    *dx = (1.0 - t)*r->dx[below] + t*r->dx[above];
    *dy = (1.0 - t)*r->dy[below] + t*r->dy[above];
    return TRUE;
}

/* Closure stripe by stripe: the content of 16's stripe s was in 09 at its
 * centre row minus the 09->16 shift, and in 06 a further 06->09 shift
 * (at that row of 09) away, so 06->16 = 09->16 + 06->09 there.  The
 * frames drift by up to 10 px between stripes, so the medians of the
 * pairs' stripes do not close (they are taken over other stripes). */
static void
print_stripe_closure(const gchar *name, gint n, gint yres, const PairResult *r0609,
                     const PairResult *r0916, const PairResult *r0616)
{
    gdouble misses[MAX_STRIPES], ax, ay;
    gint s, m = 0;

    printf("N=%d %s closure per stripe (06->16 - 09->16 - 06->09 at the content's row):", n, name);
    for (s = 0; s < n; s++) {
        if (!r0616->measured[s] || !r0916->measured[s]
            || !shift_at_row(r0609, n, yres, (s + 0.5)*yres/n - r0916->dy[s], &ax, &ay))
            continue;
        ax = r0616->dx[s] - r0916->dx[s] - ax;
        ay = r0616->dy[s] - r0916->dy[s] - ay;
        printf(" %d(%.1f,%.1f)", s, ax, ay);
        misses[m++] = hypot(ax, ay);
    }
    if (m)
        printf("; median %.1f px\n", median_in_place(misses, m));
    else
        printf(" no stripe measured in both\n");
}

static void
fastscan(const gchar *dir)
{
    static const gint pairs[3][2] = { { 0, 1 }, { 1, 2 }, { 0, 2 } };
    static const gint stripe_counts[2] = { 8, 16 };
    GwyContainer *files[3];
    GwyDataField *fields[3][FASTSCAN_CHANNELS];
    PairResult results[3][FASTSCAN_CHANNELS];
    gint f, ch, p, k, s, a, b, n, agree, both, total_measured, total_in;
    gdouble diffs[3*MAX_STRIPES*3], ratio;

    for (f = 0; f < 3; f++) {
        gchar *path = g_build_filename(dir, "fastscan-series", fastscan_files[f], NULL);

        files[f] = load_file(path);
        for (ch = 0; ch < FASTSCAN_CHANNELS; ch++)
            fields[f][ch] = channel(files[f], ch);
        g_free(path);
    }
    printf("== FastScan raw channels (dx, dy ± sigma_px per measured stripe)\n");
    for (k = 0; k < 2; k++) {
        gdouble mx[3][FASTSCAN_CHANNELS], my[3][FASTSCAN_CHANNELS];
        gboolean have[3][FASTSCAN_CHANNELS];
        gint m = 0;

        n = stripe_counts[k];
        total_measured = total_in = agree = both = 0;
        for (p = 0; p < 3; p++) {
            for (ch = 0; ch < FASTSCAN_CHANNELS; ch++) {
                gchar *what = g_strdup_printf("%s %s->%s", channel_names[ch],
                                              fastscan_files[pairs[p][0]] + 6, fastscan_files[pairs[p][1]] + 6);

                register_pair(fields[pairs[p][1]][ch], fields[pairs[p][0]][ch], n, &results[p][ch]);
                print_pair(what, n, &results[p][ch]);
                total_measured += results[p][ch].support.measured;
                total_in += results[p][ch].support.in_reference;
                have[p][ch] = median_shift(&results[p][ch], n, &mx[p][ch], &my[p][ch]);
                g_free(what);
            }
            /* Channels recorded on the same lines share the drift. */
            for (a = 0; a < FASTSCAN_CHANNELS; a++) {
                for (b = a + 1; b < FASTSCAN_CHANNELS; b++) {
                    for (s = 0; s < n; s++) {
                        const PairResult *ra = &results[p][a], *rb = &results[p][b];
                        gdouble d, sig;

                        if (!ra->measured[s] || !rb->measured[s])
                            continue;
                        d = hypot(ra->dx[s] - rb->dx[s], ra->dy[s] - rb->dy[s]);
                        sig = sqrt(ra->sigma[s]*ra->sigma[s] + rb->sigma[s]*rb->sigma[s]);
                        both++;
                        agree += (d <= 3.0*sig);
                        diffs[m++] = d;
                    }
                }
            }
        }
        ratio = total_in ? (gdouble)total_measured/total_in : 0.0;
        printf("N=%d: %d of %d stripes in the reference measured (%.0f %%); channels measuring the same "
               "stripe: %d pairs, %d within 3 combined sigma, median disagreement %.2f px\n",
               n, total_measured, total_in, 100.0*ratio, both, agree, m ? median_in_place(diffs, m) : 0.0);
        for (ch = 0; ch < FASTSCAN_CHANNELS; ch++) {
            print_stripe_closure(channel_names[ch], n, gwy_data_field_get_yres(fields[0][ch]),
                                 &results[0][ch], &results[1][ch], &results[2][ch]);
            if (have[0][ch] && have[1][ch] && have[2][ch]) {
                printf("N=%d %s closure: 06->09 + 09->16 - 06->16 = (%.1f, %.1f) px (median shifts)\n", n,
                       channel_names[ch], mx[0][ch] + mx[1][ch] - mx[2][ch], my[0][ch] + my[1][ch] - my[2][ch]);
            }
            else
                printf("N=%d %s closure: not every pair measured\n", n, channel_names[ch]);
        }
    }
    for (f = 0; f < 3; f++)
        g_object_unref(files[f]);
}

static void
hsafm_movie(const gchar *dir, const gchar *file)
{
    static const gint pairs[4][2] = { { 0, 1 }, { 1, 2 }, { 0, 3 }, { 3, 6 } };
    gchar *path = g_build_filename(dir, "hsafm-minicircles", file, NULL);
    GwyContainer *data = load_file(path);
    PairResult result;
    gint p;

    printf("== HS-AFM %s, 8 stripes, frame j against frame i\n", file);
    for (p = 0; p < 4; p++) {
        gchar *what = g_strdup_printf("frames %d->%d", pairs[p][0], pairs[p][1]);

        register_pair(channel(data, pairs[p][1]), channel(data, pairs[p][0]), 8, &result);
        print_pair(what, 8, &result);
        g_free(what);
    }
    g_object_unref(data);
    g_free(path);
}

/* The AFM-IR film's channels of one stage position that are distinct
 * recordings (the file holds duplicates too; ../shared/data/measured/
 * MANIFEST.md): Height 9, 10, 11, 12 and 16, recorded at 15:16, 17:42,
 * 17:51, 18:18 and 18:29. */
static void
afmir_film(const gchar *dir)
{
    static const gint pairs[5][2] = { { 9, 10 }, { 10, 11 }, { 11, 12 }, { 12, 16 }, { 9, 16 } };
    gchar *path = g_build_filename(dir, "afmir-film", "PEA_BDA_film.axz", NULL);
    GwyContainer *data = load_file(path);
    PairResult result;
    gint p;

    printf("== AFM-IR PEA_BDA_film.axz, channels Height i -> Height j, 8 stripes\n");
    for (p = 0; p < 5; p++) {
        gchar *what = g_strdup_printf("Height %d->%d", pairs[p][0], pairs[p][1]);

        register_pair(channel(data, pairs[p][1]), channel(data, pairs[p][0]), 8, &result);
        print_pair(what, 8, &result);
        g_free(what);
    }
    g_object_unref(data);
    g_free(path);
}

int
main(int argc, char *argv[])
{
    const gchar *env = g_getenv("LOCALSCAN_MEASURED_DIR");
    const gchar *dir = (argc > 1) ? argv[1] : (env && *env) ? env : TOP_SRCDIR "/../shared/data/measured";
    gchar *probe = g_build_filename(dir, "fastscan-series", fastscan_files[0], NULL);

    if (!g_file_test(probe, G_FILE_TEST_IS_REGULAR)) {
        fprintf(stderr, "study-measured-registration: measured data absent (%s)\n", probe);
        return 77;
    }
    g_free(probe);
    gwy_app_init_nongui("enable-threads", FALSE, NULL);
    fastscan(dir);
    hsafm_movie(dir, "hsafm_sample0_frames50-140.gwy");
    hsafm_movie(dir, "hsafm_extra_frames14-62.gwy");
    afmir_film(dir);
    return 0;
}
