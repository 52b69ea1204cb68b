/*
 *  Tests of continuous compensation on images larger than its row buffers:
 *  the y prefilter solved block by block through a ring of rows (each block
 *  from a truncated back substitution), the x prefilter in batches of rows,
 *  rows in chunks with a remainder, and rows not aligned for streaming
 *  stores must all give Gwyddion's values.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <check.h>
#include <glib.h>
#include <libprocess/interpolation.h>
#include "continuous-compensate.h"
#include "test-common.h"
#include "continuous-fixtures.h"

static guint32 test_seed;

/* A fractional shift of either sign, at least 0.1 px from whole, in
 * 1/1024 px: then c + shift is exact for any column, in Gwyddion's
 * positions here as in the module's, and the comparison sees the filters
 * alone (a position rounded near column 1000 moves a value by 1e-12). */
static gdouble
random_fractional_shift(GRand *rng)
{
    gdouble shift;

    do {
        shift = g_rand_int_range(rng, -2969, 2970)/1024.0;
    } while (fabs(shift - floor(shift + 0.5)) < 0.1);
    return shift;
}

/* Gwyddion's interpolation of n values (stride apart) at every position
 * first + shift .. last + shift: coefficients resolved once for the line. */
static void
gwyddion_line(const gdouble *data, gint n, gsize stride, gdouble shift,
              gint first, gint last, GwyInterpolationType type,
              gdouble *values)
{
    gdouble *coeffs = g_new(gdouble, n), x;
    gint support = gwy_interpolation_get_support_size(type), k, i, from;

    for (k = 0; k < n; k++)
        coeffs[k] = data[k*stride];
    gwy_interpolation_resolve_coeffs_1d(n, coeffs, type);
    for (k = first; k <= last; k++) {
        x = k + shift;
        i = (gint)floor(x);
        from = (support == 4) ? i - 1 : i;
        g_assert(from >= 0 && from + support <= n);
        values[k] = gwy_interpolation_interpolate_1d(x - i, coeffs + from,
                                                     type);
    }
    g_free(coeffs);
}

/* A constant fractional shift along x (along_x) or y of a random xres x
 * yres image in n stripes: every line along that axis, row or column, is
 * Gwyddion's interpolation of the line, prefilter included, to 1e-12 from
 * 4 px off its ends in. */
static void
check_shift_matches_gwyddion(guint32 salt, gint xres, gint yres, gint n,
                             gboolean along_x, GwyInterpolationType type)
{
    GRand *rng = test_rand_salted(test_seed, salt);
    gint size = xres*yres, len = along_x ? xres : yres, n_lines = size/len;
    gint stride = along_x ? 1 : xres, l, i, r, c, checked = 0;
    gdouble *a = random_image(xres, yres, -5.0, 10.0, rng);
    gdouble *result = g_new(gdouble, 2*size), *mask = result + size;
    gdouble *expected = g_new(gdouble, len);
    gdouble shift = random_fractional_shift(rng);
    DriftTable *table = constant_table(n, along_x ? shift : 0.0, along_x ? 0.0 : shift, NULL);

    ck_assert(continuous_compensate_table(a, xres, yres, table, 1.0, 1.0,
                                          NULL, type, -1.0, result, mask,
                                          NULL));
    for (l = 0; l < n_lines; l++) {
        gwyddion_line(a + l*(along_x ? xres : 1), len, stride, shift, 4, len - 5, type, expected);
        for (i = 4; i < len - 4; i++) {
            r = along_x ? l : i;
            c = along_x ? i : l;
            ck_assert_msg(fabs(result[r*xres + c] - expected[i]) < 1e-12,
                          "kernel %d, shift %g, (%d,%d): %.15g vs %.15g",
                          type, shift, r, c, result[r*xres + c], expected[i]);
            checked++;
        }
    }
    ck_assert_int_eq(checked, n_lines*(len - 8));
    drift_table_free(table);
    g_free(expected);
    g_free(result);
    g_free(a);
    g_rand_free(rng);
}

/* An image several y blocks tall (and of odd width, so every other row is
 * not 16-byte aligned), shifted in y. */
START_TEST(test_tall_shift_matches_gwyddion)
{
    check_shift_matches_gwyddion(10, 23, 397, 9, FALSE, all_kernels[_i]);
}
END_TEST

/* A wide image of nine rows (x prefilter batches of eight rows overlap at
 * the bottom; rows run in chunks with a remainder), shifted in x. */
START_TEST(test_wide_shift_matches_gwyddion)
{
    check_shift_matches_gwyddion(20, 1031, 9, 3, TRUE, all_kernels[_i]);
}
END_TEST

static Suite*
continuous_blocks_suite(void)
{
    TCase *tc;
    Suite *suite = test_suite_new("continuous-blocks", "core", &tc);

    tcase_set_timeout(tc, 60);
    tcase_add_loop_test(tc, test_tall_shift_matches_gwyddion,
                        0, G_N_ELEMENTS(all_kernels));
    tcase_add_loop_test(tc, test_wide_shift_matches_gwyddion,
                        0, G_N_ELEMENTS(all_kernels));
    return suite;
}

int
main(void)
{
    test_seed = test_seed_from_env("test-continuous-blocks");
    return test_run_suite(continuous_blocks_suite());
}
