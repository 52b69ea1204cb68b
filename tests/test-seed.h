/*
 *  What every seeded Check program does in main(): take the seed from
 *  LOCALSCAN_TEST_SEED or draw one, print it so a failure can be repeated,
 *  and run the suite with the summary line.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_TEST_SEED_H
#define LOCALSCAN_TEST_SEED_H

#include <stdio.h>
#include <stdlib.h>
#include <glib.h>
#include <check.h>

static inline guint32
test_seed_from_env(const gchar *program)
{
    const gchar *env = g_getenv("LOCALSCAN_TEST_SEED");
    guint32 seed = env ? (guint32)strtoul(env, NULL, 10) : (guint32)g_random_int();

    printf("%s: seed %u (set LOCALSCAN_TEST_SEED to repeat)\n", program, seed);
    fflush(stdout);
    return seed;
}

static inline int
test_run_suite(Suite *suite)
{
    SRunner *runner = srunner_create(suite);
    gint failed;

    srunner_run_all(runner, CK_NORMAL);
    failed = srunner_ntests_failed(runner);
    srunner_free(runner);
    return failed ? EXIT_FAILURE : EXIT_SUCCESS;
}

#endif
