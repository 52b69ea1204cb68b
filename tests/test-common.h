/*
 *  What every Check program shares: the seed from LOCALSCAN_TEST_SEED (or
 *  drawn) printed so that a failure can be repeated, the suite with its one
 *  test case, the run with its summary line, where the measured data lives
 *  and how a part that cannot run is reported: SKIPPED with its reason and
 *  exit status 77 (automake's SKIP) when nothing failed, never PASS.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_TEST_COMMON_H
#define LOCALSCAN_TEST_COMMON_H

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <glib.h>
#include <glib/gstdio.h>
#include <sys/wait.h>
#include <check.h>

/* automake's exit status of a test that could not run. */
#define TEST_EXIT_SKIP 77

/* Set by test_skip_part(): the program ran, but not all of it. */
static gboolean test_part_skipped = FALSE;

static inline guint32
test_seed_from_env(const gchar *program)
{
    const gchar *env = g_getenv("LOCALSCAN_TEST_SEED");
    guint32 seed = ((env && *env) ? (guint32)strtoul(env, NULL, 10)
                    : (guint32)g_random_int());

    printf("%s: seed %u (set LOCALSCAN_TEST_SEED to repeat)\n", program, seed);
    fflush(stdout);
    return seed;
}

/* A generator of its own for each part of a program, from the program's
 * seed and the part's salt (multiplied by Knuth's golden-ratio constant so
 * that neighbouring salts give unrelated seeds). */
static inline GRand*
test_rand_salted(guint32 seed, guint32 salt)
{
    return g_rand_new_with_seed(seed ^ (salt*2654435761u));
}

/* A suite of one test case, which is returned in tc. */
static inline Suite*
test_suite_new(const gchar *suite_name, const gchar *case_name, TCase **tc)
{
    Suite *suite = suite_create(suite_name);

    *tc = tcase_create(case_name);
    suite_add_tcase(suite, *tc);
    return suite;
}

/* Prints why a part of the program does not run and remembers it. */
static inline void G_GNUC_PRINTF(2, 3)
test_skip_part(const gchar *program, const gchar *format, ...)
{
    va_list ap;
    gchar *reason;

    va_start(ap, format);
    reason = g_strdup_vprintf(format, ap);
    va_end(ap);
    printf("%s: SKIPPED: %s\n", program, reason);
    fflush(stdout);
    g_free(reason);
    test_part_skipped = TRUE;
}

/* For main(): prints why the whole program cannot run; returns the exit
 * status to return. */
#define test_skip_all(program, ...) \
    (test_skip_part((program), __VA_ARGS__), TEST_EXIT_SKIP)

/* Whether one of the strings (notes, warnings) holds text. */
static inline gboolean
test_strings_hold(const GPtrArray *strings, const gchar *text)
{
    guint i;

    for (i = 0; i < strings->len; i++) {
        if (strstr(g_ptr_array_index(strings, i), text))
            return TRUE;
    }
    return FALSE;
}

/* The folder of the measured data: $LOCALSCAN_MEASURED_DIR, else
 * ../shared/data/measured beside the source tree. */
static inline const gchar*
test_measured_dir(void)
{
    const gchar *dir = g_getenv("LOCALSCAN_MEASURED_DIR");

    return (dir && *dir) ? dir : TEST_SRCDIR "/../shared/data/measured";
}

/* The measured file at relpath (newly allocated), or NULL after
 * test_skip_part() saying which part (what) needs it. */
static inline gchar*
test_measured_file(const gchar *program, const gchar *relpath,
                   const gchar *what)
{
    gchar *path = g_build_filename(test_measured_dir(), relpath, NULL);

    if (g_file_test(path, G_FILE_TEST_IS_REGULAR))
        return path;
    test_skip_part(program, "%s: measured data absent (%s)", what, path);
    g_free(path);
    return NULL;
}

/* Removes path with everything below it, folders made unreadable or
 * unwritable by a test included. */
static inline void
test_remove_tree(const gchar *path)
{
    const gchar *name;
    gchar *child;
    GDir *dir;

    if ((dir = g_dir_open(path, 0, NULL))) {
        while ((name = g_dir_read_name(dir))) {
            child = g_build_filename(path, name, NULL);
            test_remove_tree(child);
            g_free(child);
        }
        g_dir_close(dir);
        g_chmod(path, 0700);
        g_rmdir(path);
    }
    else
        g_unlink(path);
}

/* A PID that ran and is gone (a child that exited): a dead run's, for the
 * sweeps of stale temporaries. */
static inline GPid
test_dead_pid(void)
{
    const gchar *argv[] = { "true", NULL };
    GPid pid;
    gint status;

    ck_assert(g_spawn_async(NULL, (gchar**)argv, NULL, G_SPAWN_SEARCH_PATH | G_SPAWN_DO_NOT_REAP_CHILD,
                            NULL, NULL, &pid, NULL));
    waitpid(pid, &status, 0);
    return pid;
}

/* Runs the suite (forking each test unless fork is FALSE); failure when a
 * test failed, else SKIP when a part was skipped, else success. */
static inline int
test_run_suite_forking(Suite *suite, gboolean fork)
{
    SRunner *runner = srunner_create(suite);
    gint failed;

    if (!fork)
        srunner_set_fork_status(runner, CK_NOFORK);
    srunner_run_all(runner, CK_NORMAL);
    failed = srunner_ntests_failed(runner);
    srunner_free(runner);
    if (failed)
        return EXIT_FAILURE;
    return test_part_skipped ? TEST_EXIT_SKIP : EXIT_SUCCESS;
}

static inline int
test_run_suite(Suite *suite)
{
    return test_run_suite_forking(suite, TRUE);
}

#endif
