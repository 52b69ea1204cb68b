/*
 *  The dialog's reduced copy of a large image (modules/core/preview-field.c):
 *  its size, and the masks reduced with it for the registration, where a
 *  preview pixel is masked when it covers a masked pixel or its value was
 *  interpolated from one.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <check.h>
#include <libprocess/gwyprocess.h>
#include "preview-field.h"
#include "test-common.h"

static guint32 test_seed;

/* A small image is previewed as it is, and so is its mask. */
START_TEST(test_small_image_as_is)
{
    GwyDataField *field = gwy_data_field_new(64, 48, 64e-9, 48e-9, TRUE);
    GwyDataField *mask = gwy_data_field_new_alike(field, TRUE);
    PreviewField *preview = preview_field_new(field, 512);
    GwyDataField *reduced;

    ck_assert(!preview_field_is_reduced(preview));
    ck_assert_ptr_eq(preview_field_source(preview), field);
    reduced = preview_field_reduce_mask(preview, mask);
    ck_assert_ptr_eq(reduced, mask);
    g_object_unref(reduced);
    ck_assert_ptr_null(preview_field_reduce_mask(preview, NULL));
    preview_field_free(preview);
    g_object_unref(mask);
    g_object_unref(field);
}
END_TEST

static void
check_interpolated_masked(GwyDataField *mask, GwyDataField *reduced)
{
    GwyDataField *sampled = gwy_data_field_new_resampled(mask, gwy_data_field_get_xres(reduced),
                                                         gwy_data_field_get_yres(reduced),
                                                         GWY_INTERPOLATION_LINEAR);
    const gdouble *s = gwy_data_field_get_data_const(sampled), *r = gwy_data_field_get_data_const(reduced);
    gint k, n = gwy_data_field_get_xres(reduced)*gwy_data_field_get_yres(reduced), touched = 0;

    for (k = 0; k < n; k++) {
        if (s[k] > 1e-9) {
            touched++;
            ck_assert_msg(r[k] == 1.0, "preview pixel %d interpolated from a masked pixel (%g) is not "
                          "masked (seed %u)", k, s[k], test_seed);
        }
    }
    ck_assert_int_gt(touched, 0);
    g_object_unref(sampled);
}

/* Masked pixels at random places of a 2000 x 1500 image: every preview
 * pixel that covers one is masked, and the preview pixels two or more away
 * from all of them are not (resampling the mask as the image is resampled
 * missed most single pixels: the copy samples, it does not average). */
START_TEST(test_reduced_mask_covers_masked_pixels)
{
    enum { XRES = 2000, YRES = 1500, MASKED = 40 };
    GwyDataField *field = gwy_data_field_new(XRES, YRES, XRES*1e-9, YRES*1e-9, TRUE);
    GwyDataField *mask = gwy_data_field_new_alike(field, TRUE), *reduced;
    PreviewField *preview = preview_field_new(field, 512);
    GRand *rng = g_rand_new_with_seed(test_seed);
    gint cols[MASKED], rows[MASKED], k, i, j, pxres, pyres, far = 0, far_masked = 0;
    gdouble sx, sy;

    ck_assert(preview_field_is_reduced(preview));
    for (k = 0; k < MASKED; k++) {
        cols[k] = g_rand_int_range(rng, 0, XRES);
        rows[k] = g_rand_int_range(rng, 0, YRES);
        gwy_data_field_set_val(mask, cols[k], rows[k], 1.0);
    }
    reduced = preview_field_reduce_mask(preview, mask);
    pxres = gwy_data_field_get_xres(reduced);
    pyres = gwy_data_field_get_yres(reduced);
    ck_assert_int_eq(pxres, preview_field_xres(preview));
    ck_assert_int_eq(pyres, preview_field_yres(preview));
    sx = (gdouble)pxres/XRES;
    sy = (gdouble)pyres/YRES;
    for (k = 0; k < MASKED; k++) {
        i = CLAMP((gint)(rows[k]*sy), 0, pyres - 1);
        j = CLAMP((gint)(cols[k]*sx), 0, pxres - 1);
        ck_assert_msg(gwy_data_field_get_val(reduced, j, i) == 1.0,
                      "masked pixel (%d, %d) unmasked in the preview at (%d, %d) (seed %u)",
                      cols[k], rows[k], j, i, test_seed);
    }
    /* Two preview pixels or more from every masked pixel: unmasked. */
    for (i = 0; i < pyres; i++) {
        for (j = 0; j < pxres; j++) {
            gboolean near = FALSE;

            for (k = 0; k < MASKED && !near; k++)
                near = (ABS(i - (gint)(rows[k]*sy)) <= 2 && ABS(j - (gint)(cols[k]*sx)) <= 2);
            if (near)
                continue;
            far++;
            far_masked += (gwy_data_field_get_val(reduced, j, i) != 0.0);
        }
    }
    ck_assert_int_gt(far, pxres*pyres/2);
    ck_assert_msg(far_masked == 0, "%d preview pixels far from every masked pixel masked (seed %u)",
                  far_masked, test_seed);
    /* The mask resampled as the copy is: every preview pixel whose value
     * a masked pixel entered is masked. */
    check_interpolated_masked(mask, reduced);
    g_object_unref(reduced);
    g_rand_free(rng);
    preview_field_free(preview);
    g_object_unref(mask);
    g_object_unref(field);
}
END_TEST

int
main(void)
{
    TCase *tc;
    Suite *suite = test_suite_new("preview-field", "preview", &tc);

    test_seed = test_seed_from_env("test-preview-field");
    tcase_add_test(tc, test_small_image_as_is);
    tcase_add_test(tc, test_reduced_mask_covers_masked_pixels);
    return test_run_suite(suite);
}
