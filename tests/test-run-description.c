/*
 *  A run's settings in words (modules/core/run-description.c): names, not
 *  numbers; only what the run used; the mode read back from a description
 *  and from Gwyddion's own log entries of older files.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <string.h>
#include <check.h>
#include "run-description.h"
#include "test-common.h"

START_TEST(test_format)
{
    RunDescription run = { LOCALSCAN_SOURCE_REFERENCE, NULL, "a.gwy \342\200\224 Height", 16,
                           GWY_MASK_EXCLUDE, LOCALSCAN_MODE_CONTINUOUS, GWY_INTERPOLATION_ROUND,
                           LOCALSCAN_FILL_MEAN };
    gchar *text = run_description_format(&run);

    ck_assert_str_eq(text, "source=reference, reference=a.gwy \342\200\224 Height, stripes=16, "
                           "masking=exclude, mode=continuous, interpolation=round, fill=mean");
    g_free(text);
    run.source = LOCALSCAN_SOURCE_FILE;
    run.table_file = "/tmp/t.csv";
    run.mode = LOCALSCAN_MODE_PAPER;
    run.fill = LOCALSCAN_FILL_MAXIMUM;
    text = run_description_format(&run);
    ck_assert_str_eq(text, "source=table file, table=/tmp/t.csv, mode=paper, fill=maximum");
    g_free(text);
}
END_TEST

/* The masking names gwy-localscan --masking takes, both ways. */
START_TEST(test_masking_names)
{
    ck_assert_str_eq(run_description_masking_name(GWY_MASK_EXCLUDE), "exclude");
    ck_assert_str_eq(run_description_masking_name(GWY_MASK_INCLUDE), "include");
    ck_assert_str_eq(run_description_masking_name(GWY_MASK_IGNORE), "ignore");
    ck_assert_int_eq(run_description_masking_from_name("exclude"), GWY_MASK_EXCLUDE);
    ck_assert_int_eq(run_description_masking_from_name("include"), GWY_MASK_INCLUDE);
    ck_assert_int_eq(run_description_masking_from_name("ignore"), GWY_MASK_IGNORE);
    ck_assert_int_eq(run_description_masking_from_name("Exclude"), -1);
    ck_assert_int_eq(run_description_masking_from_name(NULL), -1);
}
END_TEST

START_TEST(test_names)
{
    static const GwyInterpolationType kernels[] = {
        GWY_INTERPOLATION_ROUND, GWY_INTERPOLATION_LINEAR, GWY_INTERPOLATION_KEY,
        GWY_INTERPOLATION_BSPLINE, GWY_INTERPOLATION_OMOMS, GWY_INTERPOLATION_NNA,
        GWY_INTERPOLATION_SCHAUM,
    };
    gchar *names = run_description_interpolation_names();
    guint i;

    for (i = 0; i < G_N_ELEMENTS(kernels); i++) {
        const gchar *name = run_description_interpolation_name(kernels[i]);

        ck_assert_int_eq(run_description_interpolation_from_name(name), kernels[i]);
        ck_assert(strstr(names, name));
    }
    ck_assert_int_eq(run_description_interpolation_from_name("none"), -1);
    ck_assert_int_eq(run_description_interpolation_from_name("cubic"), -1);
    ck_assert_str_eq(names, "round, linear, key, bspline, omoms, nna, schaum");
    g_free(names);
}
END_TEST

START_TEST(test_parse_mode)
{
    ck_assert_int_eq(run_description_parse_mode("source=stored table, mode=paper, fill=mean"),
                     LOCALSCAN_MODE_PAPER);
    ck_assert_int_eq(run_description_parse_mode("mode=continuous, interpolation=round"),
                     LOCALSCAN_MODE_CONTINUOUS);
    /* Gwyddion's own log entries list the settings as numbers. */
    ck_assert_int_eq(run_description_parse_mode("add-mask=True, fill=0, mode=1, source=0)"), 1);
    ck_assert_int_eq(run_description_parse_mode("fill=0, submode=1"), -1);
    ck_assert_int_eq(run_description_parse_mode("fill=0"), -1);
}
END_TEST

int
main(void)
{
    TCase *tc;
    Suite *suite = test_suite_new("run-description", "description", &tc);

    tcase_add_test(tc, test_format);
    tcase_add_test(tc, test_masking_names);
    tcase_add_test(tc, test_names);
    tcase_add_test(tc, test_parse_mode);
    return test_run_suite(suite);
}
