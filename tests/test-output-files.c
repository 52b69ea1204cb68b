/*
 *  Tests of simscan's output files: all written or none changed, never one
 *  over an input or over another output.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <check.h>
#include <glib.h>
#include <glib/gstdio.h>
#include "output-files.h"
#include "test-common.h"

static gchar *dir;

/* The user id root takes to meet a file it may not write: nobody's. */
#define UNPRIVILEGED_UID 65534

static void
make_dir(void)
{
    dir = g_dir_make_tmp("test-output-files-XXXXXX", NULL);
    ck_assert_ptr_nonnull(dir);
}

static void
remove_dir(void)
{
    gchar *cmd = g_strdup_printf("rm -rf '%s'", dir);

    ck_assert_int_eq(system(cmd), 0);
    g_free(cmd);
    g_free(dir);
}

static gchar*
path(const gchar *name)
{
    return g_build_filename(dir, name, NULL);
}

static void
put(const gchar *name, const gchar *text)
{
    gchar *p = path(name);

    ck_assert(g_file_set_contents(p, text, -1, NULL));
    g_free(p);
}

/* A symbolic link name -> target in the folder. */
static void
make_link(const gchar *name, const gchar *target)
{
    gchar *p = path(name);

    ck_assert_int_eq(symlink(target, p), 0);
    g_free(p);
}

static void
assert_contents(const gchar *name, const gchar *expected)
{
    gchar *p = path(name), *text = NULL;

    ck_assert_msg(g_file_get_contents(p, &text, NULL, NULL),
                  "%s is missing", name);
    ck_assert_str_eq(text, expected);
    g_free(text);
    g_free(p);
}

static gint
compare_names(gconstpointer a, gconstpointer b)
{
    return strcmp(*(const gchar *const*)a, *(const gchar *const*)b);
}

/* The folder's names, sorted, separated by spaces. */
static gchar*
listing(void)
{
    GDir *d = g_dir_open(dir, 0, NULL);
    GPtrArray *names = g_ptr_array_new_with_free_func(g_free);
    const gchar *name;
    gchar *text;

    while ((name = g_dir_read_name(d)))
        g_ptr_array_add(names, g_strdup(name));
    g_dir_close(d);
    g_ptr_array_sort(names, compare_names);
    g_ptr_array_add(names, NULL);
    text = g_strjoinv(" ", (gchar**)names->pdata);
    g_ptr_array_free(names, TRUE);
    return text;
}

static void
assert_listing(const gchar *expected)
{
    gchar *text = listing();

    ck_assert_str_eq(text, expected);
    g_free(text);
}

static gboolean
add(OutputFiles *files, const gchar *name, const gchar *text, GError **error)
{
    gchar *p = path(name);
    gboolean ok = output_files_add(files, p, (const guchar*)text,
                                   strlen(text), error);

    g_free(p);
    return ok;
}

START_TEST(test_commit_writes_all)
{
    OutputFiles *files = output_files_new();

    make_dir();
    put("old.csv", "old\n");
    ck_assert(add(files, "new.gwy", "gwy", NULL));
    ck_assert(add(files, "old.csv", "csv", NULL));
    /* Nothing changes before the commit. */
    assert_contents("old.csv", "old\n");
    ck_assert(output_files_commit(files, NULL));
    output_files_free(files);
    assert_contents("new.gwy", "gwy");
    assert_contents("old.csv", "csv");
    assert_listing("new.gwy old.csv");
    remove_dir();
}
END_TEST

/* The symbolic link's target, read back as the link's own text. */
static void
assert_link(const gchar *name, const gchar *expected)
{
    gchar *p = path(name), *target = g_file_read_link(p, NULL);

    ck_assert_msg(target != NULL, "%s is no longer a link", name);
    ck_assert_str_eq(target, expected);
    g_free(target);
    g_free(p);
}

/* An output named by a symbolic link is written where the link points,
 * through relative and absolute links, a chain of them, and a dangling
 * one, and every link stays a link: renamed over the link, the output
 * replaced it and left its target as it was (as root, --json /dev/stdout
 * replaced /dev/stdout). */
START_TEST(test_links_written_through)
{
    OutputFiles *files = output_files_new();
    gchar *absolute, *p;

    make_dir();
    p = path("sub");
    g_mkdir(p, 0700);
    g_free(p);
    put("target.csv", "old\n");
    make_link("rel.csv", "target.csv");
    make_link("sub/up.csv", "../chained.csv");
    make_link("chain.csv", "sub/up.csv");
    absolute = path("fresh.csv");
    make_link("abs.csv", absolute);
    ck_assert(add(files, "rel.csv", "through a relative link", NULL));
    ck_assert(add(files, "chain.csv", "through a chain", NULL));
    ck_assert(add(files, "abs.csv", "through a dangling absolute link", NULL));
    ck_assert(output_files_commit(files, NULL));
    output_files_free(files);
    assert_contents("target.csv", "through a relative link");
    assert_contents("chained.csv", "through a chain");
    assert_contents("fresh.csv", "through a dangling absolute link");
    assert_link("rel.csv", "target.csv");
    assert_link("sub/up.csv", "../chained.csv");
    assert_link("chain.csv", "sub/up.csv");
    assert_link("abs.csv", absolute);
    assert_listing("abs.csv chain.csv chained.csv fresh.csv rel.csv sub target.csv");
    g_free(absolute);
    remove_dir();
}
END_TEST

/* A link to a file not made yet and that file are one output: the second
 * is refused (both were written there, and the first lost).  A loop of
 * links, or a chain longer than the system follows, named as an output is
 * refused, every link kept (the link named was replaced by a file, and at
 * the end of a chain of 45 the file was left as it was). */
START_TEST(test_links_named_twice_and_loops)
{
    OutputFiles *files = output_files_new();
    GError *error = NULL;
    gint i;

    make_dir();
    make_link("l.csv", "t.csv");
    ck_assert(add(files, "t.csv", "first", NULL));
    ck_assert(!add(files, "l.csv", "second", &error));
    ck_assert_msg(strstr(error->message, "are the same file"), "%s", error->message);
    g_clear_error(&error);
    output_files_free(files);

    files = output_files_new();
    make_link("a", "b");
    make_link("b", "c");
    make_link("c", "a");
    ck_assert(!add(files, "a", "through a loop", &error));
    ck_assert_msg(strstr(error->message, "its symbolic links loop or are nested too deep"), "%s",
                  error->message);
    g_clear_error(&error);
    output_files_free(files);
    assert_link("a", "b");
    assert_link("b", "c");
    assert_link("c", "a");

    files = output_files_new();
    for (i = 0; i < 45; i++) {
        gchar *name = g_strdup_printf("chain%02d", i), *next = g_strdup_printf("chain%02d", i + 1);

        make_link(name, next);
        g_free(name);
        g_free(next);
    }
    put("chain45", "end");
    ck_assert(!add(files, "chain00", "through 45 links", &error));
    ck_assert_msg(strstr(error->message, "nested too deep"), "%s", error->message);
    g_clear_error(&error);
    output_files_free(files);
    assert_link("chain00", "chain01");
    assert_contents("chain45", "end");
    remove_dir();
}
END_TEST

/* The last target becomes a folder after it was checked: its rename fails
 * and the targets renamed before it get their old state back. */
START_TEST(test_failed_rename_rolls_back)
{
    OutputFiles *files = output_files_new();
    GError *error = NULL;
    gchar *late;

    make_dir();
    put("kept.csv", "old contents\n");
    ck_assert(add(files, "kept.csv", "new table", NULL));
    ck_assert(add(files, "fresh.gwy", "new gwy", NULL));
    ck_assert(add(files, "late.json", "{}", NULL));
    late = path("late.json");
    ck_assert_int_eq(g_mkdir(late, 0755), 0);
    put("late.json/inside", "x");
    ck_assert(!output_files_commit(files, &error));
    ck_assert_ptr_nonnull(error);
    ck_assert(g_str_has_prefix(error->message, "cannot write "));
    ck_assert(strstr(error->message, "late.json"));
    g_clear_error(&error);
    output_files_free(files);
    assert_contents("kept.csv", "old contents\n");
    assert_listing("kept.csv late.json");
    g_free(late);
    remove_dir();
}
END_TEST

START_TEST(test_free_without_commit)
{
    OutputFiles *files = output_files_new();

    make_dir();
    put("a.csv", "a");
    ck_assert(add(files, "a.csv", "b", NULL));
    ck_assert(add(files, "b.csv", "b", NULL));
    output_files_free(files);
    assert_contents("a.csv", "a");
    assert_listing("a.csv");
    remove_dir();
}
END_TEST

START_TEST(test_add_refuses_folder_and_repeats)
{
    OutputFiles *files = output_files_new();
    GError *error = NULL;
    gchar *sub, *msg;

    make_dir();
    sub = path("sub");
    ck_assert_int_eq(g_mkdir(sub, 0755), 0);
    ck_assert(!add(files, "sub", "x", &error));
    msg = g_strdup_printf("cannot write %s: it is a folder", sub);
    ck_assert_str_eq(error->message, msg);
    g_free(msg);
    g_clear_error(&error);

    ck_assert(add(files, "x.gwy", "x", NULL));
    /* The same file, spelled otherwise, before it exists. */
    ck_assert(!add(files, "sub/../x.gwy", "y", &error));
    ck_assert(strstr(error->message, "are the same file"));
    g_clear_error(&error);
    output_files_free(files);
    assert_listing("sub");
    g_free(sub);
    remove_dir();
}
END_TEST

/* A file the user may not write is not replaced: renamed over, which
 * needs only the folder's rights, a file made read-only (chmod a-w) was
 * replaced by one the user owns.  The folder is open to all, so that only
 * the file's rights stand in the way; root, who may write any file, tries
 * it with nobody's rights (the effective user id only). */
START_TEST(test_read_only_target_kept)
{
    OutputFiles *files = output_files_new();
    gboolean as_root = (geteuid() == 0), added;
    GError *error = NULL;
    gchar *locked, *msg;

    make_dir();
    put("locked.gwy", "old");
    locked = path("locked.gwy");
    ck_assert_int_eq(g_chmod(locked, 0444), 0);
    ck_assert_int_eq(g_chmod(dir, 0777), 0);
    if (as_root)
        ck_assert_int_eq(seteuid(UNPRIVILEGED_UID), 0);
    added = add(files, "locked.gwy", "new", &error);
    output_files_free(files);
    if (as_root)
        ck_assert_int_eq(seteuid(0), 0);
    ck_assert_msg(!added, "a read-only file was taken as an output");
    msg = g_strdup_printf("cannot write %s: %s", locked, g_strerror(EACCES));
    ck_assert_str_eq(error->message, msg);
    g_clear_error(&error);
    assert_contents("locked.gwy", "old");
    assert_listing("locked.gwy");
    g_free(msg);
    g_free(locked);
    remove_dir();
}
END_TEST

START_TEST(test_same_file)
{
    gchar *a, *b, *c, *link_a, *dot_a, *missing, *missing2, *base;

    make_dir();
    put("a", "a");
    put("c", "a");
    a = path("a");
    b = path("b");
    c = path("c");
    link_a = path("link-a");
    dot_a = g_build_filename(dir, ".", "a", NULL);
    missing = path("missing");
    base = g_path_get_basename(dir);
    missing2 = g_build_filename(dir, "..", base, "missing", NULL);
    ck_assert_int_eq(link(a, link_a), 0);
    ck_assert(output_files_same(a, a));
    ck_assert(output_files_same(a, link_a));
    ck_assert(output_files_same(a, dot_a));
    ck_assert(!output_files_same(a, c));
    ck_assert(!output_files_same(a, b));
    ck_assert(output_files_same(missing, missing2));
    ck_assert(!output_files_same(missing, b));
    g_free(a);
    g_free(b);
    g_free(c);
    g_free(link_a);
    g_free(dot_a);
    g_free(missing);
    g_free(missing2);
    g_free(base);
    remove_dir();
}
END_TEST

START_TEST(test_check_roles)
{
    GError *error = NULL;
    gchar *frame_a, *frame_b, *out, *msg;
    OutputFilesRole roles[4];

    make_dir();
    put("A.gwy", "a");
    put("B.gwy", "b");
    frame_a = path("A.gwy");
    frame_b = path("B.gwy");
    out = path("out.json");
    roles[0] = (OutputFilesRole){ "frame", frame_a, TRUE };
    roles[1] = (OutputFilesRole){ "frame", frame_b, TRUE };
    roles[2] = (OutputFilesRole){ "frame", frame_a, TRUE };
    roles[3] = (OutputFilesRole){ "--json", out, FALSE };
    /* Inputs may repeat; a new output is fine. */
    ck_assert(output_files_check_roles(roles, 4, NULL));

    roles[3].filename = frame_a;
    ck_assert(!output_files_check_roles(roles, 4, &error));
    msg = g_strdup_printf("--json %s would overwrite the frame %s",
                          frame_a, frame_a);
    ck_assert_str_eq(error->message, msg);
    g_free(msg);
    g_clear_error(&error);

    roles[0] = (OutputFilesRole){ "--output", "X", FALSE };
    roles[1] = (OutputFilesRole){ "--table", "./X", FALSE };
    ck_assert(!output_files_check_roles(roles, 2, &error));
    ck_assert_str_eq(error->message, "--output X and --table ./X are the "
                     "same file");
    g_clear_error(&error);

    roles[1].filename = NULL;
    ck_assert(output_files_check_roles(roles, 2, NULL));
    g_free(frame_a);
    g_free(frame_b);
    g_free(out);
    remove_dir();
}
END_TEST

int
main(void)
{
    TCase *tc;
    Suite *suite = test_suite_new("output-files", "core", &tc);

    tcase_add_test(tc, test_commit_writes_all);
    tcase_add_test(tc, test_links_written_through);
    tcase_add_test(tc, test_links_named_twice_and_loops);
    tcase_add_test(tc, test_failed_rename_rolls_back);
    tcase_add_test(tc, test_free_without_commit);
    tcase_add_test(tc, test_add_refuses_folder_and_repeats);
    tcase_add_test(tc, test_read_only_target_kept);
    tcase_add_test(tc, test_same_file);
    tcase_add_test(tc, test_check_roles);
    return test_run_suite(suite);
}
