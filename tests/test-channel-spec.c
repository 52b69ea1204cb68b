/*
 *  Tests of FILE[:ID] parsing (channel-spec.h).
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <stdlib.h>
#include <check.h>
#include <glib.h>
#include <glib/gstdio.h>
#include "channel-spec.h"
#include "test-common.h"

static void
assert_parses(const gchar *text, const gchar *filename, gint id)
{
    GError *error = NULL;
    gchar *file = NULL;
    gint got = -2;

    ck_assert_msg(channel_spec_parse(text, &file, &got, &error),
                  "%s refused: %s", text, error ? error->message : "");
    ck_assert_str_eq(file, filename);
    ck_assert_int_eq(got, id);
    g_free(file);
}

static void
assert_refused(const gchar *text, const gchar *message)
{
    GError *error = NULL;
    gchar *file = NULL;
    gint id = -2;

    ck_assert(!channel_spec_parse(text, &file, &id, &error));
    ck_assert(g_error_matches(error, CHANNEL_SPEC_ERROR,
                              CHANNEL_SPEC_ERROR_RANGE));
    ck_assert_str_eq(error->message, message);
    /* Nothing is set on failure. */
    ck_assert_ptr_null(file);
    ck_assert_int_eq(id, -2);
    g_error_free(error);
}

START_TEST(test_file_only)
{
    assert_parses("scan.gwy", "scan.gwy", CHANNEL_SPEC_NO_ID);
    assert_parses("", "", CHANNEL_SPEC_NO_ID);
}
END_TEST

START_TEST(test_file_and_id)
{
    assert_parses("scan.gwy:0", "scan.gwy", 0);
    assert_parses("scan.gwy:3", "scan.gwy", 3);
    assert_parses("scan.gwy:007", "scan.gwy", 7);
    assert_parses(":2", "", 2);
}
END_TEST

/* A file whose name ends in a colon and digits is that file, when it
 * exists: 'c:1' was read as channel 1 of 'c' (no such file). */
START_TEST(test_existing_file_with_digits)
{
    gchar *dir = g_dir_make_tmp("test-channel-spec-XXXXXX", NULL);
    gchar *name = g_build_filename(dir, "c:1", NULL), *missing = g_build_filename(dir, "d:2", NULL);
    gchar *missing_file = g_build_filename(dir, "d", NULL), *base = g_build_filename(dir, "c", NULL);

    assert_parses(name, base, 1);
    ck_assert(g_file_set_contents(name, "x", -1, NULL));
    assert_parses(name, name, CHANNEL_SPEC_NO_ID);
    assert_parses(missing, missing_file, 2);
    g_unlink(name);
    g_rmdir(dir);
    g_free(name);
    g_free(base);
    g_free(missing);
    g_free(missing_file);
    g_free(dir);
}
END_TEST

START_TEST(test_colons_in_names)
{
    /* Only an all-digit tail after the last colon is an id. */
    assert_parses("a:b/scan.gwy", "a:b/scan.gwy", CHANNEL_SPEC_NO_ID);
    assert_parses("a:1/scan.gwy:5", "a:1/scan.gwy", 5);
    assert_parses("scan.gwy:", "scan.gwy:", CHANNEL_SPEC_NO_ID);
    assert_parses("scan.gwy:-1", "scan.gwy:-1", CHANNEL_SPEC_NO_ID);
    assert_parses("scan.gwy:+1", "scan.gwy:+1", CHANNEL_SPEC_NO_ID);
    assert_parses("scan.gwy:1x", "scan.gwy:1x", CHANNEL_SPEC_NO_ID);
    assert_parses("scan.gwy: 1", "scan.gwy: 1", CHANNEL_SPEC_NO_ID);
}
END_TEST

START_TEST(test_id_range)
{
    assert_parses("scan.gwy:2147483647", "scan.gwy", G_MAXINT);
    /* atoi() made channel 0 of this (and garbage of longer ones). */
    assert_refused("scan.gwy:4294967296",
                   "scan.gwy:4294967296: channel id 4294967296 is out of "
                   "range (0 to 2147483647)");
    assert_refused("scan.gwy:2147483648",
                   "scan.gwy:2147483648: channel id 2147483648 is out of "
                   "range (0 to 2147483647)");
    assert_refused("x:99999999999999999999999",
                   "x:99999999999999999999999: channel id "
                   "99999999999999999999999 is out of range (0 to "
                   "2147483647)");
}
END_TEST

int
main(void)
{
    TCase *tc;
    Suite *suite = test_suite_new("channel-spec", "core", &tc);

    tcase_add_test(tc, test_file_only);
    tcase_add_test(tc, test_file_and_id);
    tcase_add_test(tc, test_colons_in_names);
    tcase_add_test(tc, test_existing_file_with_digits);
    tcase_add_test(tc, test_id_range);
    return test_run_suite(suite);
}
