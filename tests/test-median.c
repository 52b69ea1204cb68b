/*
 *  The core's median and ranks (modules/core/median.h) against a sort, on
 *  sets drawn at random (seeded): uniform values, few distinct values,
 *  sorted and reversed runs, and the sets Gwyddion 2.62's gwy_math_median
 *  got wrong.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <stdlib.h>
#include <string.h>
#include <check.h>
#include "median.h"
#include "test-common.h"

#define MAX_N 300
#define N_DRAWS 20000

static guint32 base_seed;

static gint
compare_values(gconstpointer a, gconstpointer b)
{
    gdouble x = *(const gdouble*)a, y = *(const gdouble*)b;

    return (x > y) - (x < y);
}

/* n values of one of four kinds. */
static void
draw_set(GRand *rng, gdouble *v, gint n)
{
    gint kind = g_rand_int_range(rng, 0, 4), i;

    for (i = 0; i < n; i++) {
        if (kind == 0)
            v[i] = g_rand_double(rng);
        else if (kind == 1)
            v[i] = g_rand_int_range(rng, 0, 4);
        else if (kind == 2)
            v[i] = i + 0.25*g_rand_double(rng);
        else
            v[i] = -i;
    }
}

/* The ranks (every one of up to 40 values, some of more) and the median
 * of random sets equal a sort's. */
START_TEST(test_ranks_match_a_sort)
{
    GRand *rng = test_rand_salted(base_seed, 1);
    gdouble v[MAX_N], sorted[MAX_N], work[MAX_N], expected;
    gint d, n, k;

    for (d = 0; d < N_DRAWS; d++) {
        n = g_rand_int_range(rng, 1, (d % 10) ? 40 : MAX_N + 1);
        draw_set(rng, v, n);
        memcpy(sorted, v, n*sizeof(gdouble));
        qsort(sorted, n, sizeof(gdouble), compare_values);
        for (k = 0; k < n; k += (n <= 40) ? 1 : g_rand_int_range(rng, 1, 40)) {
            memcpy(work, v, n*sizeof(gdouble));
            ck_assert_msg(median_kth_in_place(work, n, k) == sorted[k],
                          "seed %u draw %d: rank %d of %d wrong", base_seed, d, k, n);
        }
        memcpy(work, v, n*sizeof(gdouble));
        expected = (n % 2) ? sorted[n/2] : 0.5*(sorted[n/2 - 1] + sorted[n/2]);
        ck_assert_msg(median_in_place(work, n) == expected,
                      "seed %u draw %d: median of %d wrong", base_seed, d, n);
    }
    g_rand_free(rng);
}
END_TEST

/* Sets Gwyddion 2.62's gwy_math_median returned a wrong element of: the
 * 4th smallest of the 23 line costs of test-jump-votes seed 540000260
 * (draw 9), 0.304 of the seven below. */
START_TEST(test_gwyddion_failures)
{
    gdouble seven[7] = { 0.836, 0.285, 0.186, 0.304, 0.435, 0.641, 0.871 };
    gdouble costs[23] = {
        4.02e-18, 4.12e-18, 2.79e-18, 6.08e-18, 3.76e-18, 6.25e-18, 8.38e-18, 3.47e-18,
        5.67e-18, 5.43e-18, 4.3e-18, 4.6e-18, 2.84e-19, 2.83e-19, 2.81e-19, 3.08e-19,
        1.58e-19, 2.57e-18, 5.96e-18, 7.61e-18, 5.79e-18, 3.5e-18, 7.47e-18,
    };

    ck_assert(median_in_place(seven, 7) == 0.435);
    ck_assert(median_in_place(costs, 23) == 4.12e-18);
    ck_assert(median_kth_in_place(costs, 23, 0) == 1.58e-19);
    ck_assert(median_kth_in_place(costs, 23, 22) == 8.38e-18);
}
END_TEST

int
main(void)
{
    TCase *tc;
    Suite *s = test_suite_new("median", "ranks", &tc);

    base_seed = test_seed_from_env("test-median");
    tcase_add_test(tc, test_ranks_match_a_sort);
    tcase_add_test(tc, test_gwyddion_failures);
    return test_run_suite(s);
}
