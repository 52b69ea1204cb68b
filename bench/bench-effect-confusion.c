/*
 *  Benchmark of `simscan fit` on effects hidden in simulated series: 200
 *  random draws, the confusion matrix of the named effect and the errors of
 *  the fitted parameters (a benchmark: it prints, it never asserts).
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <math.h>
#include <glib/gstdio.h>
#include <libgwyddion/gwyddion.h>
#include <libgwymodule/gwymodule.h>
#include <app/gwyapp.h>
#include "hidden-effect-cases.h"
#include "median.h"

#define N_TYPES HIDDEN_CASE_EFFECTS

typedef struct {
    gint confusion[N_TYPES][N_TYPES + 1];   /* last column: fit failed */
    gint within[N_TYPES];                   /* named right and in tolerance */
    GArray *errors[N_TYPES];                /* relative parameter errors */
} Tally;

static gint
type_index(const gchar *name)
{
    DriftModelType type;

    if (name && drift_model_type_from_name(name, &type))
        return hidden_case_effect_index(type);
    return N_TYPES;
}

/* The main parameter's relative error (velocity: absolute, nm/s). */
static gdouble
parameter_error(const DriftModel *m, JsonObject *result)
{
    JsonObject *p = json_object_get_object_member(result, "parameters");

    switch (m->type) {
        case DRIFT_MODEL_SETTLING:
        return fabs(json_object_get_double_member(p, "tau_s")/m->tau - 1.0);
        case DRIFT_MODEL_OSCILLATION:
        return fabs(json_object_get_double_member(p, "period_s")/m->period
                    - 1.0);
        case DRIFT_MODEL_JUMP:
        return fabs(json_object_get_double_member(p, "t_s") - m->t_jump);
        case DRIFT_MODEL_ACCELERATION:
        return fabs(hypot(hidden_case_pair(p, "accel_nm_per_s2", 0),
                          hidden_case_pair(p, "accel_nm_per_s2", 1))
                    /(1e9*hypot(m->accel[0], m->accel[1])) - 1.0);
        default:
        return hypot(hidden_case_pair(result, "velocity_nm_per_s", 0)
                     - 1e9*m->v[0],
                     hidden_case_pair(result, "velocity_nm_per_s", 1)
                     - 1e9*m->v[1]);
    }
}

static gdouble
median(GArray *a)
{
    gdouble *v = (gdouble*)a->data;

    if (!a->len)
        return NAN;
    return median_in_place(v, a->len);
}

static void
print_table(const Tally *t, gint n, guint32 seed, gboolean markdown)
{
    static const gchar *what[N_TYPES] = {
        "velocity error (nm/s)", "tau relative error", "period relative error",
        "t_s error (s)", "acceleration relative error",
    };
    gint i, j;

    printf("%s%d draws, seed %u (128 x 128 frames, 4 frames of 64 s; "
           "drawn: |v| <= 0.1 nm/s; settling tau 20..60 s; oscillation "
           "period 20..60 s, 4 to 12 cycles over the series, inside the "
           "observable 12..167 s, amplitude 15..30 nm sweeping at most "
           "2.5 px per 4 s block; jump t_s 30..230 s; acceleration 20..50 nm "
           "over the series; details in "
           "tests/hidden-effect-cases.c)\n\n", markdown ? "" : "# ",
           n, seed);
    printf("| hidden \\ named | none | settling | oscillation | jump | "
           "acceleration | failed | named right | within tolerance | median %s |\n",
           "main parameter error");
    printf("|---|---|---|---|---|---|---|---|---|---|\n");
    for (i = 0; i < N_TYPES; i++) {
        gint total = 0;

        for (j = 0; j <= N_TYPES; j++)
            total += t->confusion[i][j];
        printf("| %s |", drift_model_type_name(hidden_case_effect(i)));
        for (j = 0; j <= N_TYPES; j++)
            printf(" %d |", t->confusion[i][j]);
        printf(" %d/%d | %d/%d | %.3g (%s) |\n", t->confusion[i][i], total,
               t->within[i], total, median(t->errors[i]), what[i]);
    }
}

int
main(int argc, char **argv)
{
    const gchar *env = g_getenv("LOCALSCAN_TEST_SEED");
    guint32 seed = env ? (guint32)strtoul(env, NULL, 10) : 20260101u;
    gint n = 200, i, k;
    gboolean markdown = (argc > 1 && strcmp(argv[1], "--markdown") == 0);
    Tally tally;

    if (g_getenv("BENCH_EFFECT_DRAWS"))
        n = MAX(atoi(g_getenv("BENCH_EFFECT_DRAWS")), 4);
    memset(&tally, 0, sizeof(tally));
    for (i = 0; i < N_TYPES; i++)
        tally.errors[i] = g_array_new(FALSE, FALSE, sizeof(gdouble));
    gwy_app_init_nongui("enable-threads", FALSE, NULL);
    for (i = 0; i < n; i++) {
        gchar *dir = g_dir_make_tmp("bench-effects-XXXXXX", NULL);
        JsonParser *parser = json_parser_new();
        DriftModel model;
        JsonObject *result = NULL;
        gchar **files, *why;
        gint named;

        hidden_case_draw(seed, i, &model);
        if ((files = hidden_case_make_frames(seed, i, &model, dir)))
            result = hidden_case_fit(files, dir, parser);
        named = result ? type_index(json_object_get_string_member(result,
                                                                  "effect"))
                       : N_TYPES;
        tally.confusion[hidden_case_effect_index(model.type)][named]++;
        if (named == hidden_case_effect_index(model.type)) {
            gdouble e = parameter_error(&model, result);

            g_array_append_val(tally.errors[named], e);
            if (!(why = hidden_case_check(i, &model, result)))
                tally.within[named]++;
            g_free(why);
        }
        for (k = 0; files && k < HIDDEN_CASE_FRAMES; k++)
            g_unlink(files[k]);
        g_rmdir(dir);
        g_strfreev(files);
        g_free(dir);
        g_object_unref(parser);
        if (!markdown && (i + 1) % 20 == 0)
            fprintf(stderr, "%d/%d\n", i + 1, n);
    }
    print_table(&tally, n, seed, markdown);
    for (i = 0; i < N_TYPES; i++)
        g_array_free(tally.errors[i], TRUE);
    return 0;
}
