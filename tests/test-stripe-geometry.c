/*
 *  Tests of the stripe geometry and the nearest-stripe rule.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <stdlib.h>
#include <check.h>
#include <glib.h>
#include "stripe-geometry.h"
#include "test-common.h"

START_TEST(test_bounds_multiple)
{
    gint s;

    /* 256 rows in 16 stripes: 16 rows each, as in the paper. */
    for (s = 0; s < 16; s++) {
        ck_assert_int_eq(stripe_first_row(s, 16, 256), 16*s);
        ck_assert_int_eq(stripe_end_row(s, 16, 256), 16*s + 16);
        ck_assert(stripe_centre_row(s, 16, 256) == 16*s + 7.5);
    }
    ck_assert_int_eq(stripe_of_row(0, 16, 256), 0);
    ck_assert_int_eq(stripe_of_row(15, 16, 256), 0);
    ck_assert_int_eq(stripe_of_row(16, 16, 256), 1);
    ck_assert_int_eq(stripe_of_row(255, 16, 256), 15);
}
END_TEST

START_TEST(test_bounds_not_multiple)
{
    /* 10 rows in 4 stripes: floor(s*10/4) = 0, 2, 5, 7, 10. */
    static const gint first[5] = { 0, 2, 5, 7, 10 };
    static const gint stripe[10] = { 0, 0, 1, 1, 1, 2, 2, 3, 3, 3 };
    gint s, r;

    for (s = 0; s < 4; s++) {
        ck_assert_int_eq(stripe_first_row(s, 4, 10), first[s]);
        ck_assert_int_eq(stripe_end_row(s, 4, 10), first[s + 1]);
    }
    ck_assert(stripe_centre_row(0, 4, 10) == 0.5);
    ck_assert(stripe_centre_row(1, 4, 10) == 3.0);
    ck_assert(stripe_centre_row(3, 4, 10) == 8.0);
    for (r = 0; r < 10; r++)
        ck_assert_int_eq(stripe_of_row(r, 4, 10), stripe[r]);
    /* 7 rows in 3 stripes: 0, 2, 4, 7. */
    ck_assert_int_eq(stripe_first_row(1, 3, 7), 2);
    ck_assert_int_eq(stripe_first_row(2, 3, 7), 4);
    ck_assert_int_eq(stripe_end_row(2, 3, 7), 7);
}
END_TEST

START_TEST(test_bounds_extremes)
{
    gint r;

    /* n = 1: one stripe of everything. */
    ck_assert_int_eq(stripe_first_row(0, 1, 37), 0);
    ck_assert_int_eq(stripe_end_row(0, 1, 37), 37);
    ck_assert(stripe_centre_row(0, 1, 37) == 18.0);
    for (r = 0; r < 37; r++)
        ck_assert_int_eq(stripe_of_row(r, 1, 37), 0);
    /* n = yres: one row per stripe. */
    for (r = 0; r < 37; r++) {
        ck_assert_int_eq(stripe_of_row(r, 37, 37), r);
        ck_assert_int_eq(stripe_first_row(r, 37, 37), r);
        ck_assert_int_eq(stripe_end_row(r, 37, 37), r + 1);
        ck_assert(stripe_centre_row(r, 37, 37) == r);
    }
    /* One row. */
    ck_assert_int_eq(stripe_of_row(0, 1, 1), 0);
    ck_assert_int_eq(stripe_end_row(0, 1, 1), 1);
    /* Products that overflow 32 bits. */
    ck_assert_int_eq(stripe_first_row(99999, 100000, 100000), 99999);
    ck_assert_int_eq(stripe_of_row(99999, 100000, 100000), 99999);
    ck_assert_int_eq(stripe_first_row(50000, 100000, 1000000), 500000);
}
END_TEST

/* stripe_of_row must agree with the bounds for every row; the bounds must
 * tile the rows with stripes of floor or ceil(yres/n) rows. */
START_TEST(test_of_row_consistent)
{
    gint yres, n, s, r, first, end, count;

    for (yres = 1; yres <= 70; yres++) {
        for (n = 1; n <= yres; n++) {
            count = 0;
            for (s = 0; s < n; s++) {
                first = stripe_first_row(s, n, yres);
                end = stripe_end_row(s, n, yres);
                ck_assert_int_eq(first, (gint)((gint64)s*yres/n));
                ck_assert_int_ge(end - first, yres/n);
                ck_assert_int_le(end - first, (yres + n - 1)/n);
                for (r = first; r < end; r++) {
                    ck_assert_msg(stripe_of_row(r, n, yres) == s,
                                  "yres %d n %d row %d: stripe %d, "
                                  "expected %d", yres, n, r,
                                  stripe_of_row(r, n, yres), s);
                    count++;
                }
            }
            ck_assert_int_eq(stripe_first_row(0, n, yres), 0);
            ck_assert_int_eq(stripe_end_row(n - 1, n, yres), yres);
            ck_assert_int_eq(count, yres);
        }
    }
    for (yres = 4000; yres <= 4100; yres += 7) {
        for (n = 1; n <= yres; n += 13) {
            for (r = 0; r < yres; r += 11) {
                s = stripe_of_row(r, n, yres);
                ck_assert_int_le(stripe_first_row(s, n, yres), r);
                ck_assert_int_gt(stripe_end_row(s, n, yres), r);
            }
        }
    }
}
END_TEST

START_TEST(test_nearest_rule)
{
    /* Stripes 0 and 4 have drift; 2 is a tie between them: 0 wins. */
    gboolean has[6] = { TRUE, FALSE, FALSE, FALSE, TRUE, FALSE };
    gdouble dx[6] = { 1, 99, 99, 99, 5, 99 }, dy[6] = { -1, 99, 99, 99, -5, 99 };
    static const gdouble want_dx[6] = { 1, 1, 1, 5, 5, 5 };
    static const gdouble want_dy[6] = { -1, -1, -1, -5, -5, -5 };
    static const gint source[6] = { 0, 0, 0, 4, 4, 4 };
    gint s;

    for (s = 0; s < 6; s++)
        ck_assert_int_eq(stripe_drift_nearest_source(s, 6, has), source[s]);
    ck_assert(stripe_drift_fill_missing(6, has, dx, dy));
    for (s = 0; s < 6; s++) {
        ck_assert(dx[s] == want_dx[s]);
        ck_assert(dy[s] == want_dy[s]);
    }
}
END_TEST

START_TEST(test_nearest_tie_lower_wins)
{
    /* Stripe 1 between 0 and 2, stripe 3 between 2 and 4. */
    gboolean has[5] = { TRUE, FALSE, TRUE, FALSE, TRUE };
    gdouble dx[5] = { 10, 0, 20, 0, 30 }, dy[5] = { 1, 0, 2, 0, 3 };

    ck_assert(stripe_drift_fill_missing(5, has, dx, dy));
    ck_assert(dx[1] == 10 && dy[1] == 1);
    ck_assert(dx[3] == 20 && dy[3] == 2);
    ck_assert(dx[0] == 10 && dx[2] == 20 && dx[4] == 30);
}
END_TEST

START_TEST(test_nearest_first_last_blank)
{
    gboolean has[7] = { FALSE, FALSE, TRUE, FALSE, TRUE, FALSE, FALSE };
    gdouble dx[7] = { 0, 0, 2, 0, 4, 0, 0 }, dy[7] = { 0, 0, -2, 0, -4, 0, 0 };
    static const gdouble want[7] = { 2, 2, 2, 2, 4, 4, 4 };
    gint s;

    ck_assert(stripe_drift_fill_missing(7, has, dx, dy));
    for (s = 0; s < 7; s++) {
        ck_assert(dx[s] == want[s]);
        ck_assert(dy[s] == -want[s]);
    }
}
END_TEST

START_TEST(test_nearest_all_blank)
{
    gboolean has[3] = { FALSE, FALSE, FALSE };
    gdouble dx[3] = { 7, 8, 9 }, dy[3] = { 1, 2, 3 };
    gboolean one[1] = { FALSE };
    gdouble x1 = 5, y1 = 6;
    gint s;

    ck_assert(!stripe_drift_fill_missing(3, has, dx, dy));
    for (s = 0; s < 3; s++) {
        ck_assert(dx[s] == 7 + s && dy[s] == 1 + s);
        ck_assert_int_eq(stripe_drift_nearest_source(s, 3, has), -1);
    }
    ck_assert(!stripe_drift_fill_missing(1, one, &x1, &y1));
    ck_assert(x1 == 5 && y1 == 6);
}
END_TEST

START_TEST(test_nearest_single)
{
    gboolean has[1] = { TRUE };
    gdouble dx = 3, dy = 4;
    gboolean only_last[4] = { FALSE, FALSE, FALSE, TRUE };
    gdouble lx[4] = { 0, 0, 0, -8 }, ly[4] = { 0, 0, 0, 8 };
    gint s;

    ck_assert(stripe_drift_fill_missing(1, has, &dx, &dy));
    ck_assert(dx == 3 && dy == 4);
    ck_assert(stripe_drift_fill_missing(4, only_last, lx, ly));
    for (s = 0; s < 4; s++)
        ck_assert(lx[s] == -8 && ly[s] == 8);
}
END_TEST

int
main(void)
{
    TCase *tc;
    Suite *suite = test_suite_new("stripe-geometry", "core", &tc);

    tcase_add_test(tc, test_bounds_multiple);
    tcase_add_test(tc, test_bounds_not_multiple);
    tcase_add_test(tc, test_bounds_extremes);
    tcase_add_test(tc, test_of_row_consistent);
    tcase_add_test(tc, test_nearest_rule);
    tcase_add_test(tc, test_nearest_tie_lower_wins);
    tcase_add_test(tc, test_nearest_first_last_blank);
    tcase_add_test(tc, test_nearest_all_blank);
    tcase_add_test(tc, test_nearest_single);
    return test_run_suite(suite);
}
