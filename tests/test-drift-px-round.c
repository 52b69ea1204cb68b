/*
 *  Tests of the one rounding of drift to whole pixels (drift_px_round):
 *  halves away from zero on every path that rounds (the function itself,
 *  physical tables in paper mode, measured tables made whole, the
 *  registration's whole-pixel tables and paper compensation of a channel).
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <stdlib.h>
#include <math.h>
#include <check.h>
#include "drift-table.h"
#include "localscan-channel.h"
#include "paper-compensate.h"
#include "stripe-registration.h"
#include "test-common.h"

/* The halves that two rules (floor(v + 0.5) and round()) used to split, and
 * neighbours that must not move. */
#define N_VALUES 6
static const gdouble values[N_VALUES] = { -0.5, 0.5, -1.5, 1.5, -0.4, 2.5 };
static const gdouble rounded[N_VALUES] = { -1.0, 1.0, -2.0, 2.0, 0.0, 3.0 };

START_TEST(test_function)
{
    gint i;

    for (i = 0; i < N_VALUES; i++)
        ck_assert_msg(drift_px_round(values[i]) == rounded[i], "%g rounds to %g, not %g",
                      values[i], drift_px_round(values[i]), rounded[i]);
    ck_assert(!signbit(drift_px_round(-0.4)));
}
END_TEST

/* A nm table on a 1 nm grid: paper mode rounds the pixels. */
START_TEST(test_physical_table)
{
    DriftTable *table = drift_table_new(N_VALUES, DRIFT_UNIT_NM);
    gdouble dx[N_VALUES], dy[N_VALUES];
    gint i;

    for (i = 0; i < N_VALUES; i++)
        drift_table_set_drift(table, i, values[i], -values[i]);
    ck_assert(drift_table_to_pixels(table, 12, 1e-9, 1e-9, TRUE, dx, dy, NULL));
    for (i = 0; i < N_VALUES; i++) {
        ck_assert_msg(dx[i] == rounded[i], "dx %g nm -> %g px", values[i], dx[i]);
        ck_assert_msg(dy[i] == -rounded[i] + 0.0, "dy %g nm -> %g px", -values[i], dy[i]);
    }
    drift_table_free(table);
}
END_TEST

START_TEST(test_measured_table_made_whole)
{
    DriftTable *table = drift_table_new(N_VALUES, DRIFT_UNIT_PX), *whole;
    gint i;

    for (i = 0; i < N_VALUES; i++)
        drift_table_set_drift(table, i, values[i], -values[i]);
    whole = localscan_table_round_px(table);
    for (i = 0; i < N_VALUES; i++) {
        ck_assert(whole->rows[i].dx == rounded[i]);
        ck_assert(whole->rows[i].dy == -rounded[i] + 0.0);
    }
    drift_table_free(whole);
    drift_table_free(table);
}
END_TEST

START_TEST(test_registration_table)
{
    StripeShift shifts[N_VALUES];
    DriftTable *table;
    gint i;

    for (i = 0; i < N_VALUES; i++) {
        shifts[i] = (StripeShift){ .dx = values[i], .dy = -values[i], .score = 1.0, .accepted = TRUE };
    }
    table = stripe_registration_to_table(shifts, N_VALUES, TRUE);
    for (i = 0; i < N_VALUES; i++) {
        ck_assert_msg(table->rows[i].dx == rounded[i], "registered %g -> %g", values[i], table->rows[i].dx);
        ck_assert(table->rows[i].dy == -rounded[i] + 0.0);
    }
    drift_table_free(table);
}
END_TEST

/* Paper compensation of a channel from a nm table: the applied shifts and
 * the image are those of the rounded pixels. */
START_TEST(test_paper_channel)
{
    gint xres = 10, yres = 2*N_VALUES, i, dx[N_VALUES], dy[N_VALUES];
    GwyDataField *field = gwy_data_field_new(xres, yres, xres*1e-9, yres*1e-9, FALSE);
    GwyDataField *result = gwy_data_field_new_alike(field, FALSE), *mask = gwy_data_field_new_alike(field, FALSE);
    DriftTable *table = drift_table_new(N_VALUES, DRIFT_UNIT_NM);
    gdouble *want = g_new(gdouble, 2*xres*yres), *want_mask = want + xres*yres;
    LocalscanOptions options = { LOCALSCAN_MODE_PAPER, LOCALSCAN_FILL_ZERO, GWY_INTERPOLATION_LINEAR,
                                 1.0, SCAN_DIRECTION_DOWN, 0.0 };
    LocalscanApplied applied;

    gwy_si_unit_set_from_string(gwy_data_field_get_si_unit_xy(field), "m");
    for (i = 0; i < xres*yres; i++)
        gwy_data_field_get_data(field)[i] = i + 1;
    for (i = 0; i < N_VALUES; i++) {
        drift_table_set_drift(table, i, values[i], values[N_VALUES-1-i]);
        dx[i] = (gint)rounded[i];
        dy[i] = (gint)rounded[N_VALUES-1-i];
    }
    ck_assert(localscan_compensate_field(field, table, &options, result, mask, &applied, NULL));
    paper_compensate(gwy_data_field_get_data_const(field), xres, yres, N_VALUES, dx, dy, 0.0, want, want_mask);
    for (i = 0; i < N_VALUES; i++)
        ck_assert(applied.dx_px[i] == rounded[i] && applied.dy_px[i] == rounded[N_VALUES-1-i]);
    for (i = 0; i < xres*yres; i++) {
        ck_assert_msg(gwy_data_field_get_data_const(result)[i] == want[i], "pixel %d", i);
        ck_assert(gwy_data_field_get_data_const(mask)[i] == want_mask[i]);
    }
    localscan_applied_clear(&applied);
    drift_table_free(table);
    g_free(want);
    g_object_unref(mask);
    g_object_unref(result);
    g_object_unref(field);
}
END_TEST

int
main(void)
{
    TCase *tc;
    Suite *s = test_suite_new("drift-px-round", "halves away from zero", &tc);

    tcase_add_test(tc, test_function);
    tcase_add_test(tc, test_physical_table);
    tcase_add_test(tc, test_measured_table_made_whole);
    tcase_add_test(tc, test_registration_table);
    tcase_add_test(tc, test_paper_channel);
    return test_run_suite(s);
}
