/*
 *  Tests of simscan fit's JSON (fit_report_to_json): valid JSON whatever
 *  the fits hold, a number not known written as null.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <stdlib.h>
#include <string.h>
#include <math.h>
#include <check.h>
#include <json-glib/json-glib.h>
#include "fit-report.h"
#include "test-common.h"

/* Three fitted models, every number of the first one not finite. */
static void
make_report(FitReport *report, gdouble bad)
{
    static const DriftModelType types[] = {
        DRIFT_MODEL_NONE, DRIFT_MODEL_SETTLING, DRIFT_MODEL_JUMP,
    };
    gint i, k;

    memset(report, 0, sizeof(FitReport));
    drift_fit_options_init(&report->fit_options);
    report->n_fits = G_N_ELEMENTS(types);
    for (i = 0; i < report->n_fits; i++) {
        DriftFit *fit = report->fits + i;

        fit->type = types[i];
        fit->ok = TRUE;
        fit->n_basis = (i == 0) ? 1 : 2;
        fit->n_params = 2*fit->n_basis + (i > 0);
        for (k = 0; k < 4; k++) {
            fit->coef[0][k] = 0.1*(k + 1);
            fit->coef[1][k] = -0.2*(k + 1);
        }
        fit->nonlinear = 30.0;
        fit->rms_nm = 1.5;
        fit->cv_rms_nm = 1.7;
        fit->bic = 12.0 + i;
    }
    report->fits[0].coef[0][0] = bad;
    report->fits[0].coef[1][0] = -bad;
    report->fits[0].rms_nm = bad;
    report->fits[0].cv_rms_nm = bad;
    report->fits[0].bic = bad;
    report->fits[1].nonlinear = bad;
    report->chosen = 0;
}

static JsonObject*
parse(const gchar *text, JsonParser *parser)
{
    GError *error = NULL;

    ck_assert_msg(json_parser_load_from_data(parser, text, -1, &error),
                  "invalid JSON (%s):\n%s", error ? error->message : "",
                  text);
    return json_node_get_object(json_parser_get_root(parser));
}

static void
assert_null_member(JsonObject *object, const gchar *name)
{
    ck_assert_msg(json_object_has_member(object, name), "no %s", name);
    ck_assert_msg(json_object_get_null_member(object, name),
                  "%s is not null", name);
}

static void
assert_null_pair(JsonObject *object, const gchar *name)
{
    JsonArray *pair = json_object_get_array_member(object, name);

    ck_assert_ptr_nonnull(pair);
    ck_assert_int_eq(json_array_get_length(pair), 2);
    ck_assert(json_array_get_null_element(pair, 0));
    ck_assert(json_array_get_null_element(pair, 1));
}

static void
check_not_finite(gdouble bad)
{
    JsonParser *parser = json_parser_new();
    FitReport report;
    JsonObject *root, *none, *settling;
    JsonArray *models;
    gchar *text;

    make_report(&report, bad);
    text = fit_report_to_json(&report, NULL);
    root = parse(text, parser);
    ck_assert_str_eq(json_object_get_string_member(root, "effect"), "none");
    assert_null_pair(root, "velocity_nm_per_s");
    models = json_object_get_array_member(root, "models");
    ck_assert_int_eq(json_array_get_length(models), 3);
    none = json_array_get_object_element(models, 0);
    assert_null_member(none, "rms_nm");
    assert_null_member(none, "score");
    assert_null_member(none, "cv_rms_nm");
    assert_null_pair(none, "velocity_nm_per_s");
    settling = json_array_get_object_element(models, 1);
    assert_null_member(json_object_get_object_member(settling, "parameters"),
                       "tau_s");
    /* Finite numbers are kept. */
    ck_assert(json_object_get_double_member(settling, "rms_nm") == 1.5);
    ck_assert(json_object_get_double_member(settling, "score") == 13.0);
    g_free(text);
    g_object_unref(parser);
}

START_TEST(test_nan_is_null)
{
    check_not_finite(NAN);
    check_not_finite(-NAN);
}
END_TEST

START_TEST(test_infinity_is_null)
{
    check_not_finite(INFINITY);
}
END_TEST

int
main(void)
{
    TCase *tc;
    Suite *suite = test_suite_new("fit-report-json", "core", &tc);

    tcase_add_test(tc, test_nan_is_null);
    tcase_add_test(tc, test_infinity_is_null);
    return test_run_suite(suite);
}
