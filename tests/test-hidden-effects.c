/*
 *  Tests that hide a drift effect in simulated frame series: simscan draws
 *  one effect (none, settling, oscillation, jump) with random parameters,
 *  scans a particle sample into frames, and `simscan fit` must name the
 *  effect and its parameters from the frames alone.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <stdlib.h>
#include <string.h>
#include <math.h>
#include <check.h>
#include <glib/gstdio.h>
#include <json-glib/json-glib.h>
#include <libgwyddion/gwyddion.h>
#include <libgwymodule/gwymodule.h>
#include <app/gwyapp.h>
#include "hidden-effect-cases.h"
#include "test-common.h"

#define N_CASES 20
static guint32 base_seed;

static void
print_models(JsonObject *result)
{
    JsonArray *models = json_object_get_array_member(result, "models");
    guint i;

    for (i = 0; i < json_array_get_length(models); i++) {
        JsonObject *m = json_array_get_object_element(models, i);

        JsonObject *p = json_object_get_object_member(m, "parameters");

        printf("    %-11s rms %6.3f nm  cv %6.3f nm  BIC %8.1f",
               json_object_get_string_member(m, "name"),
               json_object_get_double_member(m, "rms_nm"),
               json_object_get_double_member(m, "cv_rms_nm"),
               json_object_get_double_member(m, "score"));
        if (json_object_has_member(p, "tau_s"))
            printf("  tau %.1f s", json_object_get_double_member(p, "tau_s"));
        if (json_object_has_member(p, "period_s"))
            printf("  period %.1f s", json_object_get_double_member(p, "period_s"));
        if (json_object_has_member(p, "t_s"))
            printf("  t_s %.1f s", json_object_get_double_member(p, "t_s"));
        printf("\n");
    }
}

/* Draws case i of seed, fits it and asserts the effect and its
 * parameters. */
static void
check_hidden_case(guint32 seed, gint i)
{
    gchar *dir = g_dir_make_tmp("hidden-effects-XXXXXX", NULL);
    JsonParser *parser = json_parser_new();
    DriftModel model;
    JsonObject *result;
    const gchar *effect;
    gchar **files, *why;
    gint k;

    ck_assert(dir != NULL);
    hidden_case_draw(seed, i, &model);
    files = hidden_case_make_frames(seed, i, &model, dir);
    ck_assert(files != NULL);
    result = hidden_case_fit(files, dir, parser);
    ck_assert_msg(result != NULL, "simscan fit failed");
    effect = json_object_get_string_member(result, "effect");
    printf("case %2d: hidden %-11s found %-11s (v %.3f, %.3f nm/s)\n", i,
           drift_model_type_name(model.type), effect,
           hidden_case_pair(result, "velocity_nm_per_s", 0),
           hidden_case_pair(result, "velocity_nm_per_s", 1));
    printf("    truth: tau %.1f s, u %.3f %.3f nm/s; period %.1f s, a %.1f %.1f nm; "
           "t_s %.1f s, step %.1f %.1f nm\n", model.tau, 1e9*model.u[0],
           1e9*model.u[1], model.period, 1e9*model.a[0], 1e9*model.a[1],
           model.t_jump, 1e9*model.step[0], 1e9*model.step[1]);
    print_models(result);
    fflush(stdout);
    ck_assert_msg(strcmp(effect, drift_model_type_name(model.type)) == 0,
                  "case %d (seed %u): hidden %s, found %s", i, seed,
                  drift_model_type_name(model.type), effect);
    why = hidden_case_check(i, &model, result);
    ck_assert_msg(why == NULL, "%s", why);
    for (k = 0; k < HIDDEN_CASE_FRAMES; k++)
        g_unlink(files[k]);
    g_rmdir(dir);
    g_strfreev(files);
    g_free(dir);
    g_object_unref(parser);
}

START_TEST(test_hidden_effect)
{
    check_hidden_case(base_seed, _i);
}
END_TEST

/* Cases soaks found wrong, fixed in the product, kept as they were drawn:
 * seed 103000176 case 4, an acceleration read as settling with tau 183 s
 * over the 256 s series (drift_fit_select_kept: a long settling must beat
 * the acceleration like any effect beats constant drift); seed 104000114
 * case 3, an 8 px jump read as none after the outlier rounds cut good
 * blocks at a 0.05 nm scale (the outlier floor). */
static const struct {
    guint32 seed;
    gint i;
} known_cases[] = {
    { 103000176u, 4 },
    { 104000114u, 3 },
};

START_TEST(test_known_case)
{
    check_hidden_case(known_cases[_i].seed, known_cases[_i].i);
}
END_TEST

int
main(void)
{
    TCase *tc;
    Suite *s = test_suite_new("hidden-effects", "blind", &tc);

    base_seed = test_seed_from_env("test-hidden-effects");
    gwy_app_init_nongui("enable-threads", FALSE, NULL);
    tcase_add_loop_test(tc, test_hidden_effect, 0, N_CASES);
    tcase_add_loop_test(tc, test_known_case, 0, G_N_ELEMENTS(known_cases));
    tcase_set_timeout(tc, 60);
    return test_run_suite(s);
}
