/*
 *  Which channels may be the registration reference of an image and which
 *  is preferred (modules/core/reference-choice.c): never the image, never
 *  another size, a scan of another time (metadata) above another file of
 *  unknown time above a channel of the same scan; and how they are named.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <check.h>
#include <libgwyddion/gwyddion.h>
#include <libprocess/gwyprocess.h>
#include "reference-choice.h"
#include "localscan-channel.h"
#include "test-common.h"

static void
add_channel(GwyContainer *data, gint id, gint xres, const gchar *title, const gchar *frame_start)
{
    GwyDataField *field = gwy_data_field_new(xres, 20, xres*1e-9, 20e-9, TRUE);
    GwyContainer *meta;
    gchar key[40];

    g_snprintf(key, sizeof(key), "/%d/data", id);
    gwy_container_set_object_by_name(data, key, field);
    g_object_unref(field);
    if (title) {
        g_snprintf(key, sizeof(key), "/%d/data/title", id);
        gwy_container_set_const_string_by_name(data, key, (const guchar*)title);
    }
    if (frame_start) {
        meta = gwy_container_new();
        gwy_container_set_const_string_by_name(meta, "Frame start (s)", (const guchar*)frame_start);
        g_snprintf(key, sizeof(key), "/%d/meta", id);
        gwy_container_set_object_by_name(data, key, meta);
        g_object_unref(meta);
    }
}

START_TEST(test_ranks)
{
    GwyContainer *a = gwy_container_new(), *b = gwy_container_new(), *c = gwy_container_new();

    /* a: an HS-AFM-like file of frames, plus an Amplitude of frame 0. */
    add_channel(a, 0, 30, "Height", "0");
    add_channel(a, 1, 30, "Amplitude", "0");
    add_channel(a, 2, 30, "Height", "64.5");
    add_channel(a, 3, 31, "Height", "129");
    add_channel(b, 0, 30, "Height", NULL);
    add_channel(c, 0, 30, "Height", "0.2");

    ck_assert_int_eq(reference_choice_rank(a, 0, a, 0), REFERENCE_RANK_UNFIT);
    ck_assert_int_eq(reference_choice_rank(a, 0, a, 3), REFERENCE_RANK_UNFIT);
    ck_assert_int_eq(reference_choice_rank(a, 0, a, 1), REFERENCE_RANK_SIBLING);
    ck_assert_int_eq(reference_choice_rank(a, 0, a, 2), REFERENCE_RANK_OTHER_TIME);
    ck_assert_int_eq(reference_choice_rank(a, 0, b, 0), REFERENCE_RANK_OTHER_FILE);
    /* Another file, its frame started within a second: the same scan. */
    ck_assert_int_eq(reference_choice_rank(a, 0, c, 0), REFERENCE_RANK_SIBLING);
    ck_assert_int_eq(reference_choice_rank(a, 0, a, 7), REFERENCE_RANK_UNFIT);
    ck_assert(REFERENCE_RANK_OTHER_TIME > REFERENCE_RANK_OTHER_FILE
              && REFERENCE_RANK_OTHER_FILE > REFERENCE_RANK_SIBLING
              && REFERENCE_RANK_SIBLING > REFERENCE_RANK_UNFIT);

    g_object_unref(a);
    g_object_unref(b);
    g_object_unref(c);
}
END_TEST

START_TEST(test_labels)
{
    GwyContainer *a = gwy_container_new();
    gchar *label;

    add_channel(a, 0, 30, "Height", NULL);
    add_channel(a, 4, 30, NULL, NULL);
    label = reference_choice_label(a, 0, "Untitled 3");
    ck_assert_str_eq(label, "Untitled 3 \342\200\224 Height");
    g_free(label);
    gwy_container_set_const_string_by_name(a, "/filename", (const guchar*)"/data/series/frame-7.gwy");
    label = reference_choice_label(a, 0, "Untitled 3");
    ck_assert_str_eq(label, "frame-7.gwy \342\200\224 Height");
    g_free(label);
    label = reference_choice_label(a, 4, "Untitled 3");
    ck_assert_str_eq(label, "frame-7.gwy \342\200\224 channel 4");
    g_free(label);
    g_object_unref(a);
}
END_TEST

/* A channel of another quantity (another value unit) is no reference:
 * not offered, and refused naming both units. */
START_TEST(test_other_quantity_refused)
{
    static const gchar *const units[] = { "V", "deg", "A", "" };
    GRand *rng = test_rand_salted(test_seed_from_env("test-reference-choice"), 1);
    const gchar *unit = units[g_rand_int_range(rng, 0, G_N_ELEMENTS(units))];
    GwyContainer *data = gwy_container_new();
    GwyDataField *image, *reference;
    GError *error = NULL;
    gchar *expected;

    add_channel(data, 0, 30, "Height", "0");
    add_channel(data, 1, 30, "Phase", "64");
    add_channel(data, 2, 30, "Height", "64");
    image = GWY_DATA_FIELD(gwy_container_get_object_by_name(data, "/0/data"));
    reference = GWY_DATA_FIELD(gwy_container_get_object_by_name(data, "/1/data"));
    gwy_si_unit_set_from_string(gwy_data_field_get_si_unit_z(image), "m");
    gwy_si_unit_set_from_string(gwy_data_field_get_si_unit_z(reference), unit);
    gwy_si_unit_set_from_string(gwy_data_field_get_si_unit_z(GWY_DATA_FIELD(gwy_container_get_object_by_name(data, "/2/data"))), "m");
    ck_assert(!localscan_reference_fits(image, reference));
    ck_assert_int_eq(reference_choice_rank(data, 0, data, 1), REFERENCE_RANK_UNFIT);
    ck_assert_int_eq(reference_choice_rank(data, 0, data, 2), REFERENCE_RANK_OTHER_TIME);
    ck_assert(!localscan_reference_check(image, "img", reference, "ref", 4, &error));
    expected = g_strdup_printf("the reference ref holds values in %s, the image img in m: register against a "
                               "channel of the same quantity", *unit ? unit : "no unit");
    ck_assert_msg(g_str_equal(error->message, expected), "'%s'", error->message);
    g_clear_error(&error);
    g_free(expected);
    g_object_unref(data);
    g_rand_free(rng);
}
END_TEST

int
main(void)
{
    TCase *tc;
    Suite *suite = test_suite_new("reference-choice", "choice", &tc);

    tcase_add_test(tc, test_ranks);
    tcase_add_test(tc, test_labels);
    tcase_add_test(tc, test_other_quantity_refused);
    return test_run_suite(suite);
}
