/*
 *  Tests of paper-mode compensation against docs/paper-mode.md.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <check.h>
#include <glib.h>
#include "paper-compensate.h"
#include "test-common.h"
#include "worked-example.h"

static guint32 test_seed;

/* The reference: rules 1-3 spelt out pixel by pixel, sharing no code with
 * the implementation (not even the stripe geometry). */
static gint
reference_stripe_of_row(gint row, gint n, gint yres)
{
    gint s;

    for (s = 0; s < n; s++) {
        if ((gint64)(s + 1)*yres/n > row)
            return s;
    }
    g_assert_not_reached();
    return -1;
}

static void
reference_compensate(const gdouble *a, gint xres, gint yres, gint n,
                     const gint *dx, const gint *dy, gdouble d,
                     gdouble *result, gdouble *mask)
{
    gint r, c, s, t;
    gint64 src_row, src_col;

    for (r = 0; r < yres; r++) {
        s = reference_stripe_of_row(r, n, yres);
        src_row = (gint64)r + dy[s];
        for (c = 0; c < xres; c++) {
            result[r*xres + c] = d;
            mask[r*xres + c] = 1.0;
            if (src_row < 0 || src_row >= yres)
                continue;
            t = reference_stripe_of_row((gint)src_row, n, yres);
            src_col = (gint64)c + dx[t];
            if (src_col < 0 || src_col >= xres)
                continue;
            result[r*xres + c] = a[src_row*xres + src_col];
            mask[r*xres + c] = 0.0;
        }
    }
}

/* Bitwise, so that -0.0 against 0.0 or any NaN would count as a difference. */
static void
assert_same_pixels(const gdouble *got, const gdouble *expected, gint size,
                   const gchar *what, const gchar *label)
{
    gint i;

    for (i = 0; i < size; i++) {
        ck_assert_msg(memcmp(got + i, expected + i, sizeof(gdouble)) == 0,
                      "%s: %s pixel %d is %.17g, expected %.17g",
                      label, what, i, got[i], expected[i]);
    }
}

START_TEST(test_worked_example)
{
    const gdouble *a = worked_a, *expected = worked_c, *expected_mask = worked_mask;
    const gint *dx = worked_dx, *dy = worked_dy;
    gdouble result[6*4], mask[6*4], d;

    d = paper_image_mean(a, 4, 6);
    ck_assert(d == WORKED_FILL);
    paper_compensate(a, 4, 6, 3, dx, dy, d, result, mask);
    assert_same_pixels(result, expected, 24, "result", "worked example");
    assert_same_pixels(mask, expected_mask, 24, "mask", "worked example");

    /* Without a mask the result must not change. */
    memset(result, 0, sizeof(result));
    paper_compensate(a, 4, 6, 3, dx, dy, d, result, NULL);
    assert_same_pixels(result, expected, 24, "result", "worked example, no mask");
}
END_TEST

START_TEST(test_figure6)
{
    enum { RES = 256, N = 16 };
    gdouble *a, *result, *mask, *ref, *ref_mask, d, filled = 0.0;
    gint dx[N], dy[N], s, c, i;

    /* The paper's 1-based stripe k = s + 1 has dx = -k and dy = 0, -1, -2, -3
     * per group of four. */
    for (s = 0; s < N; s++) {
        dx[s] = -(s + 1);
        dy[s] = -(s/4);
    }
    a = g_new(gdouble, RES*RES);
    result = g_new(gdouble, RES*RES);
    mask = g_new(gdouble, RES*RES);
    ref = g_new(gdouble, RES*RES);
    ref_mask = g_new(gdouble, RES*RES);
    for (i = 0; i < RES*RES; i++)
        a[i] = i + 0.5;
    d = paper_image_mean(a, RES, RES);
    ck_assert(d == RES*RES/2.0);

    paper_compensate(a, RES, RES, N, dx, dy, d, result, mask);
    reference_compensate(a, RES, RES, N, dx, dy, d, ref, ref_mask);
    assert_same_pixels(result, ref, RES*RES, "result", "figure 6");
    assert_same_pixels(mask, ref_mask, RES*RES, "mask", "figure 6");

    /* Hand-derived values.  Row 0: stripe 0, dx = -1, no y shift. */
    ck_assert(result[0] == d && mask[0] == 1.0);
    for (c = 1; c < RES; c++)
        ck_assert(result[c] == a[c - 1] && mask[c] == 0.0);
    /* Row 64 (stripe 4, dy = -1) takes row 63 of stripe 3, so dx = -4. */
    for (c = 0; c < 4; c++)
        ck_assert(result[64*RES + c] == d && mask[64*RES + c] == 1.0);
    for (c = 4; c < RES; c++)
        ck_assert(result[64*RES + c] == a[63*RES + c - 4]);
    /* Row 65 takes row 64, its own stripe: dx = -5. */
    ck_assert(mask[65*RES + 4] == 1.0 && mask[65*RES + 5] == 0.0);
    ck_assert(result[65*RES + 5] == a[64*RES]);
    /* Row 255 (stripe 15, dy = -3) takes row 252 of stripe 15: dx = -16. */
    ck_assert(mask[255*RES + 15] == 1.0);
    ck_assert(result[255*RES + 16] == a[252*RES]);
    ck_assert(result[255*RES + 255] == a[252*RES + 239]);

    /* Every row has a source row; each row loses |dx| of its source stripe:
     * 16 rows times (s+1) per stripe, less one pixel for each of the
     * 1+2+3 borrowed rows in the 4 stripes of groups 1..3. */
    for (i = 0; i < RES*RES; i++)
        filled += mask[i];
    ck_assert_int_eq((gint)filled, 16*136 - 4*(1 + 2 + 3));

    g_free(a);
    g_free(result);
    g_free(mask);
    g_free(ref);
    g_free(ref_mask);
}
END_TEST

/* A shift: mostly small, sometimes beyond a stripe or the whole image, now
 * and then the extremes of gint. */
static gint
random_shift(GRand *rng, gint size)
{
    static const gint extremes[] = { G_MININT, G_MAXINT, G_MININT + 1,
                                     G_MAXINT - 1, 0 };
    gint kind = g_rand_int_range(rng, 0, 10);

    if (kind < 6)
        return g_rand_int_range(rng, -3, 4);
    if (kind < 8)
        return g_rand_int_range(rng, -size - 2, size + 3);
    if (kind < 9)
        return g_rand_int_range(rng, -10*size - 10, 10*size + 11);
    return extremes[g_rand_int_range(rng, 0, G_N_ELEMENTS(extremes))];
}

static void
check_random_case(GRand *rng, gint xres, gint yres, gint n, const gchar *label)
{
    gint size = xres*yres, s, i;
    gdouble *a, *result, *mask, *ref, *ref_mask, *nomask, d;
    gint *dx, *dy;

    a = g_new(gdouble, size);
    result = g_new(gdouble, size);
    mask = g_new(gdouble, size);
    nomask = g_new(gdouble, size);
    ref = g_new(gdouble, size);
    ref_mask = g_new(gdouble, size);
    dx = g_new(gint, n);
    dy = g_new(gint, n);
    for (i = 0; i < size; i++)
        a[i] = g_rand_double_range(rng, -1e3, 1e3);
    for (s = 0; s < n; s++) {
        dx[s] = random_shift(rng, xres);
        dy[s] = random_shift(rng, yres);
    }
    d = paper_image_mean(a, xres, yres);
    /* Poison the outputs so that an unwritten pixel cannot pass. */
    for (i = 0; i < size; i++)
        result[i] = mask[i] = nomask[i] = -777.0;

    paper_compensate(a, xres, yres, n, dx, dy, d, result, mask);
    paper_compensate(a, xres, yres, n, dx, dy, d, nomask, NULL);
    reference_compensate(a, xres, yres, n, dx, dy, d, ref, ref_mask);
    assert_same_pixels(result, ref, size, "result", label);
    assert_same_pixels(mask, ref_mask, size, "mask", label);
    assert_same_pixels(nomask, ref, size, "result without mask", label);

    g_free(a);
    g_free(result);
    g_free(mask);
    g_free(nomask);
    g_free(ref);
    g_free(ref_mask);
    g_free(dx);
    g_free(dy);
}

START_TEST(test_random_against_reference)
{
    static const gint shapes[][2] = {
        { 1, 1 }, { 1, 17 }, { 17, 1 }, { 4, 6 }, { 64, 64 }, { 37, 100 },
        { 100, 37 }, { 3, 250 }, { 250, 3 }, { 129, 131 },
    };
    GRand *rng = g_rand_new_with_seed(test_seed);
    gchar *label;
    gint k, rep, xres, yres, n;

    for (k = 0; k < (gint)G_N_ELEMENTS(shapes); k++) {
        xres = shapes[k][0];
        yres = shapes[k][1];
        for (rep = 0; rep < 12; rep++) {
            /* n = 1 and n = yres every time, random n in between. */
            if (rep == 0)
                n = 1;
            else if (rep == 1)
                n = yres;
            else
                n = g_rand_int_range(rng, 1, yres + 1);
            label = g_strdup_printf("seed %u, %dx%d, n=%d, repetition %d",
                                    test_seed, xres, yres, n, rep);
            check_random_case(rng, xres, yres, n, label);
            g_free(label);
        }
    }
    g_rand_free(rng);
}
END_TEST

/* Large shifts everywhere: every pixel filled. */
START_TEST(test_everything_filled)
{
    static const gdouble a[3*2] = { 1, 2, 3, 4, 5, 6 };
    static const gint dx[2] = { 3, -3 }, dy[2] = { 0, 0 };
    static const gint dx0[2] = { 0, 0 }, dyfar[2] = { 2, -2 };
    gdouble result[6], mask[6];
    gint i;

    paper_compensate(a, 3, 2, 2, dx, dy, -1.5, result, mask);
    for (i = 0; i < 6; i++)
        ck_assert(result[i] == -1.5 && mask[i] == 1.0);
    paper_compensate(a, 3, 2, 2, dx0, dyfar, 7.0, result, mask);
    for (i = 0; i < 6; i++)
        ck_assert(result[i] == 7.0 && mask[i] == 1.0);
}
END_TEST

/* One huge value among many ones: a plain double sum loses every one of the
 * 999999 ones (1e16 + 1 == 1e16), the compensated mean keeps them. */
START_TEST(test_mean_accuracy)
{
    enum { N = 1000000 };
    gdouble *a = g_new(gdouble, N), mean;
    gint i;

    a[0] = 1e16;
    for (i = 1; i < N; i++)
        a[i] = 1.0;
    mean = paper_image_mean(a, 1000, 1000);
    ck_assert_msg(fabs(mean - (1e10 + 0.999999)) < 1e-5,
                  "mean %.17g, expected 10000000000.999999", mean);
    mean = paper_image_mean(a, N, 1);
    ck_assert_msg(fabs(mean - (1e10 + 0.999999)) < 1e-5,
                  "mean %.17g, expected 10000000000.999999", mean);

    /* Cancellation: +x, -x pairs around an offset mean exactly the offset. */
    for (i = 0; i < N; i++)
        a[i] = 3.0 + ((i % 2) ? 1e12 : -1e12);
    mean = paper_image_mean(a, 1000, 1000);
    ck_assert_msg(mean == 3.0, "mean %.17g, expected 3", mean);
    g_free(a);
}
END_TEST


int
main(void)
{
    TCase *tc;
    Suite *suite = test_suite_new("paper-compensate", "core", &tc);

    test_seed = test_seed_from_env("test-paper-compensate");
    tcase_add_test(tc, test_worked_example);
    tcase_add_test(tc, test_figure6);
    tcase_add_test(tc, test_random_against_reference);
    tcase_add_test(tc, test_everything_filled);
    tcase_add_test(tc, test_mean_accuracy);
    return test_run_suite(suite);
}
