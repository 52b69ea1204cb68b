/*
 *  gwy_stream_save() writes what Gwyddion's own writer writes: a container
 *  of every kind of item (large and small data fields with offsets and
 *  units, masks, strings, numbers, a graph, metadata, a log) saved by both,
 *  the files the same size and every item loaded back the same, byte for
 *  byte as Gwyddion serialises it.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <string.h>
#include <check.h>
#include <glib/gstdio.h>
#include <libgwyddion/gwyddion.h>
#include <libprocess/gwyprocess.h>
#include <libgwydgets/gwygraphmodel.h>
#include <libgwydgets/gwygraphcurvemodel.h>
#include <libgwymodule/gwymodule-file.h>
#include <app/gwyapp.h>
#include "gwy-stream-save.h"
#include "test-common.h"

static guint32 seed;

static GwyDataField*
random_field(GRand *rng, gint xres, gint yres, const gchar *zunit)
{
    GwyDataField *field = gwy_data_field_new(xres, yres, xres*1.5e-9, yres*2.5e-9, FALSE);
    gdouble *d = gwy_data_field_get_data(field);
    gint i;

    for (i = 0; i < xres*yres; i++)
        d[i] = g_rand_double_range(rng, -1e-8, 1e-8);
    gwy_data_field_set_xoffset(field, g_rand_double(rng)*1e-6);
    gwy_data_field_set_yoffset(field, -g_rand_double(rng)*1e-6);
    gwy_si_unit_set_from_string(gwy_data_field_get_si_unit_xy(field), "m");
    gwy_si_unit_set_from_string(gwy_data_field_get_si_unit_z(field), zunit);
    return field;
}

/* A random field of the size and z unit stored in data under key. */
static void
set_random_field(GwyContainer *data, const gchar *key, GRand *rng,
                 gint xres, gint yres, const gchar *unit)
{
    GwyDataField *field = random_field(rng, xres, yres, unit);

    gwy_container_set_object_by_name(data, key, field);
    g_object_unref(field);
}

static GwyContainer*
make_container(GRand *rng)
{
    GwyContainer *data = gwy_container_new(), *meta = gwy_container_new();
    GwyGraphModel *gmodel = gwy_graph_model_new();
    GwyGraphCurveModel *gcmodel = gwy_graph_curve_model_new();
    GwyStringList *log = gwy_string_list_new();
    gdouble x[3] = { 0, 1, 2 }, y[3] = { 3, -1, 4 };

    set_random_field(data, "/0/data", rng, 130, 70, "m");
    set_random_field(data, "/0/mask", rng, 130, 70, "");
    set_random_field(data, "/1/data", rng, 9, 7, "V");
    set_random_field(data, "/2/data", rng, 64, 64, "deg");
    gwy_container_set_const_string_by_name(data, "/0/data/title", (const guchar*)"Height \342\200\224 a");
    gwy_container_set_const_string_by_name(data, "/0/base/palette", (const guchar*)"Gray");
    gwy_container_set_boolean_by_name(data, "/0/data/realsquare", TRUE);
    gwy_container_set_int32_by_name(data, "/0/base/range-type", 2);
    gwy_container_set_double_by_name(data, "/0/base/min", -3.25e-9);
    gwy_container_set_int64_by_name(data, "/test/int64", G_GINT64_CONSTANT(-1234567890123));
    gwy_container_set_uchar_by_name(data, "/test/uchar", 'x');
    gwy_container_set_const_string_by_name(meta, "Local-scan drift table", (const guchar*)"stripe,dx,dy\n0,1,2\n");
    gwy_container_set_object_by_name(data, "/0/meta", meta);
    g_object_unref(meta);
    gwy_graph_curve_model_set_data(gcmodel, x, y, 3);
    gwy_graph_model_add_curve(gmodel, gcmodel);
    g_object_unref(gcmodel);
    gwy_container_set_object_by_name(data, "/0/graph/graph/1", gmodel);
    g_object_unref(gmodel);
    gwy_string_list_append(log, "proc::localscan_drift(mode=paper)@2026-11-25 13:00:00");
    gwy_container_set_object_by_name(data, "/0/data/log", log);
    g_object_unref(log);
    return data;
}

typedef struct {
    GwyContainer *other;
    gint compared;
    GString *problems;
} Comparison;

static void
compare_item(gpointer hkey, gpointer hvalue, gpointer user_data)
{
    GQuark key = GPOINTER_TO_UINT(hkey);
    GValue *value = (GValue*)hvalue, other = G_VALUE_INIT;
    Comparison *cmp = (Comparison*)user_data;
    GByteArray *a, *b;

    /* Loading sets it to the file loaded. */
    if (gwy_strequal(g_quark_to_string(key), "/filename"))
        return;
    if (!gwy_container_contains(cmp->other, key)) {
        g_string_append_printf(cmp->problems, "%s missing; ", g_quark_to_string(key));
        return;
    }
    other = gwy_container_get_value(cmp->other, key);
    if (G_VALUE_TYPE(value) != G_VALUE_TYPE(&other))
        g_string_append_printf(cmp->problems, "%s of another type; ", g_quark_to_string(key));
    else if (G_VALUE_HOLDS_OBJECT(value)) {
        a = gwy_serializable_serialize(g_value_get_object(value), NULL);
        b = gwy_serializable_serialize(g_value_get_object(&other), NULL);
        if (a->len != b->len || memcmp(a->data, b->data, a->len))
            g_string_append_printf(cmp->problems, "%s differs; ", g_quark_to_string(key));
        g_byte_array_free(a, TRUE);
        g_byte_array_free(b, TRUE);
    }
    else if (G_VALUE_HOLDS_STRING(value)) {
        if (g_strcmp0(g_value_get_string(value), g_value_get_string(&other)))
            g_string_append_printf(cmp->problems, "%s differs; ", g_quark_to_string(key));
    }
    else {
        gchar *s = g_strdup_value_contents(value), *t = g_strdup_value_contents(&other);

        if (g_strcmp0(s, t))
            g_string_append_printf(cmp->problems, "%s differs; ", g_quark_to_string(key));
        g_free(s);
        g_free(t);
    }
    g_value_unset(&other);
    cmp->compared++;
}

START_TEST(test_same_as_gwyddion)
{
    GRand *rng = g_rand_new_with_seed(seed);
    GwyContainer *data = make_container(rng), *ours_back, *theirs_back;
    gchar *dir = g_dir_make_tmp("stream-save-XXXXXX", NULL);
    gchar *ours = g_build_filename(dir, "ours.gwy", NULL), *theirs = g_build_filename(dir, "theirs.gwy", NULL);
    GError *error = NULL;
    GStatBuf st_ours, st_theirs;
    Comparison cmp;

    /* Gwyddion's writer stores the file name in the container it saves
     * ("/filename"), so it writes first and both files hold that item. */
    ck_assert(gwy_file_func_run_save("gwyfile", data, theirs, GWY_RUN_NONINTERACTIVE, NULL));
    ck_assert(gwy_stream_save(data, ours, &error));
    ck_assert(g_stat(ours, &st_ours) == 0 && g_stat(theirs, &st_theirs) == 0);
    printf("test-gwy-stream-save: %ld bytes ours, %ld bytes Gwyddion's\n",
           (long)st_ours.st_size, (long)st_theirs.st_size);
    ck_assert_int_eq(st_ours.st_size, st_theirs.st_size);

    ours_back = gwy_file_load(ours, GWY_RUN_NONINTERACTIVE, &error);
    ck_assert_msg(ours_back, "Gwyddion cannot read our file: %s", error ? error->message : "?");
    theirs_back = gwy_file_load(theirs, GWY_RUN_NONINTERACTIVE, NULL);
    ck_assert(theirs_back);
    cmp.other = ours_back;
    cmp.compared = 0;
    cmp.problems = g_string_new(NULL);
    gwy_container_foreach(data, NULL, compare_item, &cmp);
    ck_assert_msg(!cmp.problems->len, "seed %u: %s", seed, cmp.problems->str);
    ck_assert_int_eq(cmp.compared + 1, (gint)gwy_container_get_n_items(data));
    ck_assert_int_eq(gwy_container_get_n_items(ours_back), gwy_container_get_n_items(theirs_back));

    g_string_free(cmp.problems, TRUE);
    g_object_unref(ours_back);
    g_object_unref(theirs_back);
    g_unlink(ours);
    g_unlink(theirs);
    g_rmdir(dir);
    g_free(ours);
    g_free(theirs);
    g_free(dir);
    g_object_unref(data);
    g_rand_free(rng);
}
END_TEST

START_TEST(test_unwritable)
{
    GRand *rng = g_rand_new_with_seed(seed);
    GwyContainer *data = make_container(rng);
    GError *error = NULL;

    ck_assert(!gwy_stream_save(data, "/nonexistent-folder/x.gwy", &error));
    ck_assert(error && strstr(error->message, "/nonexistent-folder/x.gwy"));
    g_clear_error(&error);
    g_object_unref(data);
    g_rand_free(rng);
}
END_TEST

int
main(void)
{
    TCase *tc;
    Suite *suite = test_suite_new("gwy-stream-save", "stream-save", &tc);

    seed = test_seed_from_env("test-gwy-stream-save");
    gwy_app_init_nongui("enable-threads", FALSE, NULL);
    tcase_add_test(tc, test_same_as_gwyddion);
    tcase_add_test(tc, test_unwritable);
    return test_run_suite(suite);
}
