/*
 *  End-to-end tests of the gwy-localscan command: the built program is run
 *  on .gwy files written here, and its output is compared bit for bit with
 *  paper_compensate() called directly.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <check.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <math.h>
#include <unistd.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <glib/gstdio.h>
#include <libgwyddion/gwymacros.h>
#include <libprocess/datafield.h>
#include <libprocess/stats.h>
#include <libprocess/brick.h>
#include <libgwymodule/gwymodule-file.h>
#include <app/gwyapp.h>
#include "drift-table.h"
#include "paper-compensate.h"
#include "registration-frames.h"
#include "localscan-channel.h"
#include "localscan-params.h"
#include "compensation-marker.h"
#include "simscan-file-case.h"
#include "test-common.h"

#define TOOL_PATH TEST_BUILDDIR "/tools/gwy-localscan"
#define DEFAULT_MODULE TEST_BUILDDIR "/modules/.libs/localscan.so"
#define TITLE_SUFFIX " (local-scan compensated)"
#define N_RANDOM_CASES 24

static guint32 seed;
/* Continuous mode's accuracy (against paper mode, against a reference) is
 * judged with a sub-pixel kernel; the default nearest pixel keeps heights
 * instead (tests/test-height-keeping). */
#define SIMSCAN_KERNEL GWY_INTERPOLATION_BSPLINE
#define SIMSCAN_KERNEL_NAME "bspline"

static gchar *scratch;      /* per test: in/, out/, home/ */
static gchar *in_dir;
static gchar *out_dir;
static gchar *child_home;

typedef struct {
    gint status;            /* exit status; -1 when not a normal exit */
    gchar *out;
    gchar *err;
} ToolRun;

/* run_tool() or run_tool_tmpdir(). */
typedef void (*ToolRunner)(ToolRun *run, const gchar *const *args);

/* What a test expects of one compensated channel. */
typedef struct {
    GwyDataField *source;
    gint *dx;               /* per stripe, after the nearest-stripe rule */
    gint *dy;
    gint n;
    gchar *title;
    gchar *table_text;      /* the table the new channel must carry */
    gint source_id;         /* >= 0: its other metadata must be carried too */
} Expected;

/************************************************************************
 * Scratch folders and files
 ************************************************************************/

static void
setup_scratch(void)
{
    /* In the build tree: Check skips teardown after a failed test, and a
     * failure's files are then left where they are found and cleaned. */
    scratch = g_strdup(TEST_BUILDDIR "/tests/scratch-gwy-localscan-XXXXXX");
    ck_assert_ptr_nonnull(g_mkdtemp(scratch));
    in_dir = g_build_filename(scratch, "in", NULL);
    out_dir = g_build_filename(scratch, "out", NULL);
    child_home = g_build_filename(scratch, "home", NULL);
    g_mkdir(in_dir, 0700);
    g_mkdir(out_dir, 0700);
    g_mkdir(child_home, 0700);
}

static void
teardown_scratch(void)
{
    test_remove_tree(scratch);
    g_free(scratch);
    g_free(in_dir);
    g_free(out_dir);
    g_free(child_home);
}

static gchar*
in_path(const gchar *name)
{
    return g_build_filename(in_dir, name, NULL);
}

static gchar*
out_path(const gchar *name)
{
    return g_build_filename(out_dir, name, NULL);
}

static void
write_text(const gchar *filename, const gchar *text)
{
    ck_assert(g_file_set_contents(filename, text, -1, NULL));
}

static gchar*
file_checksum(const gchar *filename)
{
    gchar *contents = NULL, *sum;
    gsize length;

    ck_assert_msg(g_file_get_contents(filename, &contents, &length, NULL),
                  "cannot read %s", filename);
    sum = g_compute_checksum_for_data(G_CHECKSUM_SHA256, (const guchar*)contents, length);
    g_free(contents);
    return sum;
}

static gint
compare_names(gconstpointer a, gconstpointer b)
{
    return strcmp(*(const gchar *const*)a, *(const gchar *const*)b);
}

/* Names in a folder, sorted, joined with spaces ("" when empty). */
static gchar*
folder_listing(const gchar *path)
{
    GPtrArray *names = g_ptr_array_new_with_free_func(g_free);
    const gchar *name;
    gchar *joined;
    GDir *dir;

    dir = g_dir_open(path, 0, NULL);
    ck_assert_ptr_nonnull(dir);
    while ((name = g_dir_read_name(dir)))
        g_ptr_array_add(names, g_strdup(name));
    g_dir_close(dir);
    g_ptr_array_sort(names, compare_names);
    g_ptr_array_add(names, NULL);
    joined = g_strjoinv(" ", (gchar**)names->pdata);
    g_ptr_array_free(names, TRUE);
    return joined;
}

/************************************************************************
 * Running the tool
 ************************************************************************/

static void
tool_run_clear(ToolRun *run)
{
    g_free(run->out);
    g_free(run->err);
}

/* env: NULL or name, value pairs, NULL-terminated, applied last. */
static void
run_tool_env(ToolRun *run, const gchar *module, const gchar *const *env, const gchar *const *args)
{
    GPtrArray *argv = g_ptr_array_new();
    gchar **envp = g_get_environ();
    GError *error = NULL;
    gint wait_status = 0;
    guint i;

    g_ptr_array_add(argv, (gpointer)TOOL_PATH);
    for (i = 0; args[i]; i++)
        g_ptr_array_add(argv, (gpointer)args[i]);
    g_ptr_array_add(argv, NULL);

    /* A scratch HOME: neither an installed module nor the user's settings
     * can interfere, and a settings file written by mistake would show. */
    envp = g_environ_setenv(envp, "HOME", child_home, TRUE);
    envp = g_environ_setenv(envp, "LC_ALL", "C", TRUE);
    envp = g_environ_unsetenv(envp, "LANGUAGE");
    if (module)
        envp = g_environ_setenv(envp, "LOCALSCAN_MODULE", module, TRUE);
    else
        envp = g_environ_unsetenv(envp, "LOCALSCAN_MODULE");
    for (i = 0; env && env[i] && env[i+1]; i += 2)
        envp = g_environ_setenv(envp, env[i], env[i+1], TRUE);

    ck_assert_msg(g_spawn_sync(NULL, (gchar**)argv->pdata, envp, G_SPAWN_DEFAULT,
                               NULL, NULL, &run->out, &run->err, &wait_status, &error),
                  "cannot run %s: %s", TOOL_PATH, error ? error->message : "?");
    run->status = WIFEXITED(wait_status) ? WEXITSTATUS(wait_status) : -1;
    g_ptr_array_free(argv, TRUE);
    g_strfreev(envp);
}

static const gchar*
module_path(void)
{
    const gchar *module = g_getenv("LOCALSCAN_MODULE");

    return module && *module ? module : DEFAULT_MODULE;
}

static void
run_tool(ToolRun *run, const gchar *const *args)
{
    run_tool_env(run, module_path(), NULL, args);
}

static void
assert_success(const ToolRun *run)
{
    ck_assert_msg(run->status == 0, "gwy-localscan failed with status %d: %s",
                  run->status, run->err);
    ck_assert_str_eq(run->err, "");
}

/* Failure: the status, exactly the expected one line on stderr (a trailing
 * "*" in expected matches any rest of the line), nothing in out/. */
static void
assert_failure(const ToolRun *run, gint status, const gchar *expected)
{
    gsize len = strlen(expected);
    gchar *listing;

    ck_assert_msg(run->status == status, "status %d, expected %d; stderr: %s",
                  run->status, status, run->err);
    ck_assert_msg(strchr(run->err, '\n') == run->err + strlen(run->err) - 1,
                  "stderr is not exactly one line: <%s>", run->err);
    if (len && expected[len-1] == '*')
        ck_assert_msg(strncmp(run->err, expected, len-1) == 0,
                      "stderr <%s> does not start with <%.*s>", run->err, (gint)len-1, expected);
    else {
        gchar *line = g_strconcat(expected, "\n", NULL);
        ck_assert_str_eq(run->err, line);
        g_free(line);
    }
    listing = folder_listing(out_dir);
    ck_assert_msg(!*listing, "files left in the output folder: %s", listing);
    g_free(listing);
}

/************************************************************************
 * Building inputs
 ************************************************************************/

static GwyDataField*
random_field(GRand *rng, gint xres, gint yres, gdouble dx, gdouble dy)
{
    GwyDataField *field = gwy_data_field_new(xres, yres, xres*dx, yres*dy, FALSE);
    gdouble *d = gwy_data_field_get_data(field);
    gint i;

    for (i = 0; i < xres*yres; i++)
        d[i] = g_rand_double_range(rng, -5e-9, 5e-9);
    gwy_si_unit_set_from_string(gwy_data_field_get_si_unit_xy(field), "m");
    gwy_si_unit_set_from_string(gwy_data_field_get_si_unit_z(field), "m");
    return field;
}

/* The channel's metadata container, made when asked to and absent. */
static GwyContainer*
channel_meta(GwyContainer *data, gint id, gboolean create)
{
    GQuark key = gwy_app_get_data_meta_key_for_id(id);
    GObject *meta = NULL;

    if (gwy_container_gis_object(data, key, &meta)) {
        ck_assert(GWY_IS_CONTAINER(meta));
        return GWY_CONTAINER(meta);
    }
    if (!create)
        return NULL;
    meta = G_OBJECT(gwy_container_new());
    gwy_container_set_object(data, key, meta);
    g_object_unref(meta);
    return GWY_CONTAINER(meta);
}

/* The drift table stored with a channel: an item of its metadata. */
static const gchar*
stored_table_text(GwyContainer *data, gint id)
{
    GwyContainer *meta = channel_meta(data, id, FALSE);
    const guchar *text = NULL;

    if (meta)
        gwy_container_gis_string_by_name(meta, DRIFT_TABLE_META_KEY, &text);
    return (const gchar*)text;
}

static void
add_channel(GwyContainer *data, gint id, GwyDataField *field, const gchar *title,
            const gchar *table_text)
{
    gwy_container_set_object(data, gwy_app_get_data_key_for_id(id), field);
    gwy_container_set_const_string(data, gwy_app_get_data_title_key_for_id(id),
                                   (const guchar*)title);
    if (table_text) {
        gwy_container_set_const_string_by_name(channel_meta(data, id, TRUE), DRIFT_TABLE_META_KEY,
                                               (const guchar*)table_text);
    }
}

/* Metadata a channel may carry besides its drift table. */
static void
add_other_metadata(GwyContainer *data, gint id, const gchar *comment)
{
    GwyContainer *meta = channel_meta(data, id, TRUE);

    gwy_container_set_const_string_by_name(meta, "Comment", (const guchar*)comment);
    gwy_container_set_const_string_by_name(meta, "Operator", (const guchar*)"test-gwy-localscan");
}

static void
save_gwy(GwyContainer *data, const gchar *filename)
{
    GError *error = NULL;

    ck_assert_msg(gwy_file_func_run_save("gwyfile", data, filename, GWY_RUN_NONINTERACTIVE, &error),
                  "cannot save %s: %s", filename, error ? error->message : "?");
}

/* A px table of n stripes; blank_percent of the stripes have no drift (at
 * least one keeps it); shifts up to max_shift pixels either way. */
static DriftTable*
random_table(GRand *rng, gint n, gint max_shift, gint blank_percent)
{
    DriftTable *table = drift_table_new(n, DRIFT_UNIT_PX);
    gint s, keep = g_rand_int_range(rng, 0, n);

    for (s = 0; s < n; s++) {
        DriftTableRow *row = table->rows + s;

        row->has_drift = (s == keep || g_rand_int_range(rng, 0, 100) >= blank_percent);
        if (row->has_drift) {
            row->dx = g_rand_int_range(rng, -max_shift, max_shift + 1);
            row->dy = g_rand_int_range(rng, -max_shift, max_shift + 1);
        }
    }
    return table;
}

/* The paper's nearest-stripe rule, written out independently of the core:
 * the nearest stripe with drift, the lower index on a tie. */
static void
expected_drift(const DriftTable *table, gint *dx, gint *dy)
{
    gint n = table->n_stripes, s, d, src;

    for (s = 0; s < n; s++) {
        src = -1;
        for (d = 0; d < n && src < 0; d++) {
            if (s - d >= 0 && table->rows[s-d].has_drift)
                src = s - d;
            else if (s + d < n && table->rows[s+d].has_drift)
                src = s + d;
        }
        ck_assert_int_ge(src, 0);
        dx[s] = (gint)table->rows[src].dx;
        dy[s] = (gint)table->rows[src].dy;
    }
}

static void
expected_init(Expected *exp, GwyDataField *source, const gchar *title, const DriftTable *table)
{
    exp->source = source;
    exp->n = table->n_stripes;
    exp->dx = g_new(gint, exp->n);
    exp->dy = g_new(gint, exp->n);
    expected_drift(table, exp->dx, exp->dy);
    exp->title = g_strconcat(title, TITLE_SUFFIX, NULL);
    exp->table_text = drift_table_to_string(table);
    exp->source_id = -1;
}

static void
expected_clear(Expected *exp)
{
    g_free(exp->dx);
    g_free(exp->dy);
    g_free(exp->title);
    g_free(exp->table_text);
}

/************************************************************************
 * Checking outputs
 ************************************************************************/

static GwyContainer*
load_gwy(const gchar *filename)
{
    GError *error = NULL;
    GwyContainer *data = gwy_file_load(filename, GWY_RUN_NONINTERACTIVE, &error);

    ck_assert_msg(data, "cannot load %s: %s", filename, error ? error->message : "?");
    return data;
}

static GwyDataField*
get_field(GwyContainer *data, GQuark key)
{
    GObject *object = NULL;

    if (!gwy_container_gis_object(data, key, &object))
        return NULL;
    ck_assert(GWY_IS_DATA_FIELD(object));
    return GWY_DATA_FIELD(object);
}

static gboolean
fields_identical(GwyDataField *a, GwyDataField *b)
{
    gint xres = gwy_data_field_get_xres(a), yres = gwy_data_field_get_yres(a);

    return (xres == gwy_data_field_get_xres(b) && yres == gwy_data_field_get_yres(b)
            && !memcmp(gwy_data_field_get_data_const(a), gwy_data_field_get_data_const(b),
                       xres*yres*sizeof(gdouble)));
}

static const gchar*
get_string(GwyContainer *data, const gchar *key)
{
    const guchar *s = NULL;

    gwy_container_gis_string_by_name(data, key, &s);
    return (const gchar*)s;
}

/* Every string item of metadata a is in b with the same value, except the
 * drift table (not compared); returns how many were compared. */
static guint
check_meta_contained(GwyContainer *a, GwyContainer *b)
{
    const gchar **keys;
    const guchar *va, *vb;
    guint i, n = 0, nkeys;

    if (!a)
        return 0;
    ck_assert_msg(b, "metadata missing");
    keys = gwy_container_keys_by_name(a);
    nkeys = gwy_container_get_n_items(a);
    for (i = 0; i < nkeys; i++) {
        if (gwy_strequal(keys[i], DRIFT_TABLE_META_KEY))
            continue;
        ck_assert(gwy_container_gis_string_by_name(a, keys[i], &va));
        ck_assert_msg(gwy_container_gis_string_by_name(b, keys[i], &vb), "metadata item '%s' lost", keys[i]);
        ck_assert_str_eq((const gchar*)vb, (const gchar*)va);
        n++;
    }
    g_free(keys);
    return n;
}

/* Every item of every channel of in is in out unchanged, and out has
 * exactly one channel more; returns its id. */
static gint
check_inputs_preserved(GwyContainer *in, GwyContainer *out)
{
    gint *in_ids = gwy_app_data_browser_get_data_ids(in);
    gint *out_ids = gwy_app_data_browser_get_data_ids(out);
    gint i, j, n_in = 0, n_out = 0, newid = -1;
    GwyDataField *a, *b;

    for (i = 0; in_ids[i] != -1; i++) {
        n_in++;
        a = get_field(in, gwy_app_get_data_key_for_id(in_ids[i]));
        b = get_field(out, gwy_app_get_data_key_for_id(in_ids[i]));
        ck_assert_msg(b, "channel %d of the input is missing in the output", in_ids[i]);
        ck_assert_msg(fields_identical(a, b), "channel %d changed", in_ids[i]);
        a = get_field(in, gwy_app_get_mask_key_for_id(in_ids[i]));
        b = get_field(out, gwy_app_get_mask_key_for_id(in_ids[i]));
        ck_assert(!a == !b);
        ck_assert(!a || fields_identical(a, b));
        ck_assert_str_eq(get_string(out, g_quark_to_string(gwy_app_get_data_title_key_for_id(in_ids[i]))),
                         get_string(in, g_quark_to_string(gwy_app_get_data_title_key_for_id(in_ids[i]))));
        ck_assert_pstr_eq(stored_table_text(out, in_ids[i]), stored_table_text(in, in_ids[i]));
        check_meta_contained(channel_meta(in, in_ids[i], FALSE), channel_meta(out, in_ids[i], FALSE));
        check_meta_contained(channel_meta(out, in_ids[i], FALSE), channel_meta(in, in_ids[i], FALSE));
    }
    for (j = 0; out_ids[j] != -1; j++) {
        n_out++;
        for (i = 0; in_ids[i] != -1 && in_ids[i] != out_ids[j]; i++)
            ;
        if (in_ids[i] == -1)
            newid = out_ids[j];
    }
    ck_assert_int_eq(n_out, n_in + 1);
    ck_assert_int_ge(newid, 0);
    g_free(in_ids);
    g_free(out_ids);
    return newid;
}

static void
check_compensated(GwyContainer *out, gint newid, const Expected *exp)
{
    GwyDataField *src = exp->source, *result, *mask;
    gint xres = gwy_data_field_get_xres(src), yres = gwy_data_field_get_yres(src);
    const gdouble *a = gwy_data_field_get_data_const(src);
    gdouble *want = g_new(gdouble, xres*yres), *want_mask = g_new(gdouble, xres*yres);
    gint i, n_filled = 0;

    paper_compensate(a, xres, yres, exp->n, exp->dx, exp->dy, paper_image_mean(a, xres, yres),
                     want, want_mask);
    result = get_field(out, gwy_app_get_data_key_for_id(newid));
    ck_assert_msg(result, "no compensated channel");
    ck_assert_int_eq(gwy_data_field_get_xres(result), xres);
    ck_assert_int_eq(gwy_data_field_get_yres(result), yres);
    ck_assert_double_eq(gwy_data_field_get_xreal(result), gwy_data_field_get_xreal(src));
    ck_assert_double_eq(gwy_data_field_get_yreal(result), gwy_data_field_get_yreal(src));
    ck_assert_msg(!memcmp(gwy_data_field_get_data_const(result), want, xres*yres*sizeof(gdouble)),
                  "the compensated channel differs from paper_compensate() (seed %u)", seed);

    for (i = 0; i < xres*yres; i++)
        n_filled += (want_mask[i] > 0.0);
    mask = get_field(out, gwy_app_get_mask_key_for_id(newid));
    if (n_filled) {
        ck_assert_msg(mask, "no mask although %d pixels are filled", n_filled);
        ck_assert(!memcmp(gwy_data_field_get_data_const(mask), want_mask, xres*yres*sizeof(gdouble)));
    }
    else
        ck_assert(!mask || gwy_data_field_get_max(mask) == 0.0);

    ck_assert_str_eq(get_string(out, g_quark_to_string(gwy_app_get_data_title_key_for_id(newid))),
                     exp->title);
    ck_assert_pstr_eq(stored_table_text(out, newid), exp->table_text);
    if (exp->source_id >= 0) {
        ck_assert_uint_gt(check_meta_contained(channel_meta(out, exp->source_id, FALSE),
                                               channel_meta(out, newid, FALSE)), 0);
    }
    g_free(want);
    g_free(want_mask);
}

/* Runs the tool through runner with args on input (already saved from
 * data): it must succeed and leave the input as it was.  Returns output,
 * loaded, with every channel of data preserved; the new channel's id in
 * newid. */
static GwyContainer*
run_successfully(ToolRunner runner, const gchar *const *args, GwyContainer *data,
                 const gchar *input, const gchar *output, gint *newid)
{
    gchar *sum_before = file_checksum(input), *sum_after;
    GwyContainer *out;
    ToolRun run;

    runner(&run, args);
    assert_success(&run);
    sum_after = file_checksum(input);
    ck_assert_str_eq(sum_before, sum_after);
    out = load_gwy(output);
    *newid = check_inputs_preserved(data, out);

    tool_run_clear(&run);
    g_free(sum_before);
    g_free(sum_after);
    return out;
}

/* Runs the tool on in.gwy (already saved from data) with args and checks
 * everything: success, input unchanged, channels preserved, result exact. */
static void
run_and_check(GwyContainer *data, const gchar *input, const gchar *const *args, const Expected *exp)
{
    gchar *output = out_path("out.gwy");
    gchar *settings_file = g_build_filename(child_home, ".gwyddion", "settings", NULL);
    GwyContainer *out;
    gint newid;

    out = run_successfully(run_tool, args, data, input, output, &newid);
    check_compensated(out, newid, exp);
    ck_assert_msg(!g_file_test(settings_file, G_FILE_TEST_EXISTS), "gwy-localscan wrote a settings file");

    g_object_unref(out);
    g_free(output);
    g_free(settings_file);
}

/************************************************************************
 * Tests of results
 ************************************************************************/

/* Three channels with ids 3, 1, 6 (the first channel is the lowest id, 1),
 * each with its own stored table and other metadata; channel 3 has a mask
 * of its own. */
typedef struct {
    GwyContainer *data;
    GwyDataField *fields[3];
    DriftTable *tables[3];
    gchar *input;
} ThreeChannels;

static const gint three_ids[3] = { 3, 1, 6 };
/* One title beyond ASCII: the tool runs in the C locale here, as in a
 * container, where GLib converts no such option value (-c was refused). */
static const gchar *three_titles[3] = { "Height", "Amplitude", "Phase (\xc2\xb0)" };

static void
three_channels_init(ThreeChannels *tc, GRand *rng)
{
    static const gint sizes[3][3] = { { 40, 30, 7 }, { 33, 50, 6 }, { 21, 17, 17 } };
    GwyDataField *mask;
    gchar *text;
    gint i;

    tc->data = gwy_container_new();
    for (i = 0; i < 3; i++) {
        tc->fields[i] = random_field(rng, sizes[i][0], sizes[i][1], 2e-9, 3e-9);
        tc->tables[i] = random_table(rng, sizes[i][2], 8, 30);
        text = drift_table_to_string(tc->tables[i]);
        add_channel(tc->data, three_ids[i], tc->fields[i], three_titles[i], text);
        g_free(text);
        add_other_metadata(tc->data, three_ids[i], three_titles[i]);
    }
    mask = gwy_data_field_new_alike(tc->fields[0], TRUE);
    gwy_data_field_area_fill(mask, 2, 3, 5, 4, 1.0);
    gwy_container_set_object(tc->data, gwy_app_get_mask_key_for_id(3), mask);
    g_object_unref(mask);
    tc->input = in_path("in.gwy");
    save_gwy(tc->data, tc->input);
}

static void
three_channels_clear(ThreeChannels *tc)
{
    gint i;

    for (i = 0; i < 3; i++) {
        g_object_unref(tc->fields[i]);
        drift_table_free(tc->tables[i]);
    }
    g_object_unref(tc->data);
    g_free(tc->input);
}

/* Compensates the three channels' file with options (then -o OUT IN) from a
 * generator seeded with rng_seed; the result must be channel which's,
 * compensated by its own stored table, its other metadata carried. */
static void
run_three_channels(guint32 rng_seed, gint which, const gchar *const *options)
{
    GRand *rng = g_rand_new_with_seed(rng_seed);
    GPtrArray *args = g_ptr_array_new();
    ThreeChannels tc;
    Expected exp;
    gchar *output;
    guint i;

    three_channels_init(&tc, rng);
    output = out_path("out.gwy");
    for (i = 0; options[i]; i++)
        g_ptr_array_add(args, (gpointer)options[i]);
    g_ptr_array_add(args, "-o");
    g_ptr_array_add(args, output);
    g_ptr_array_add(args, tc.input);
    g_ptr_array_add(args, NULL);
    expected_init(&exp, tc.fields[which], three_titles[which], tc.tables[which]);
    exp.source_id = three_ids[which];
    run_and_check(tc.data, tc.input, (const gchar *const*)args->pdata, &exp);
    expected_clear(&exp);
    g_ptr_array_free(args, TRUE);
    g_free(output);
    three_channels_clear(&tc);
    g_rand_free(rng);
}

START_TEST(test_stored_table_first_channel)
{
    run_three_channels(seed, 1, (const gchar *const[]){ NULL });
}
END_TEST

START_TEST(test_channel_option)
{
    run_three_channels(seed + 1, 2, (const gchar *const[]){ "-c", "6", "-m", "paper", NULL });
}
END_TEST

/* Users know channels by their titles: -c 'Phase (°)' is channel 6 (not
 * the first, which -c left out would give). */
START_TEST(test_channel_by_title)
{
    run_three_channels(seed + 2, 2, (const gchar *const[]){ "-c", "Phase (\xc2\xb0)", NULL });
}
END_TEST

/* The id of the channel whose title ends in the result suffix. */
static gint
result_channel(GwyContainer *data)
{
    gint *ids = gwy_app_data_browser_get_data_ids(data), i, found = -1;
    gchar key[40];

    for (i = 0; ids[i] >= 0; i++) {
        g_snprintf(key, sizeof(key), "/%d/data/title", ids[i]);
        if (g_str_has_suffix(get_string(data, key), TITLE_SUFFIX))
            found = ids[i];
    }
    g_free(ids);
    return found;
}

/* A result carries its drift table: compensating it again must be refused
 * in one line, and done when forced, its marker naming the run. */
START_TEST(test_no_double_correction)
{
    GRand *rng = g_rand_new_with_seed(seed + 7);
    gchar *first = g_build_filename(scratch, "first.gwy", NULL), *output = out_path("again.gwy");
    gchar *channel, *expected;
    GwyContainer *out, *meta;
    const guchar *marker;
    ThreeChannels tc;
    ToolRun run;
    gint id;

    three_channels_init(&tc, rng);
    run_tool(&run, (const gchar *const[]){ "-o", first, tc.input, NULL });
    assert_success(&run);
    tool_run_clear(&run);
    out = load_gwy(first);
    id = result_channel(out);
    ck_assert_int_ge(id, 0);
    channel = g_strdup_printf("/%d/meta", id);
    ck_assert(gwy_container_gis_object_by_name(out, channel, &meta));
    g_free(channel);
    ck_assert(gwy_container_gis_string_by_name(meta, LOCALSCAN_META_COMPENSATED, &marker));
    printf("test-gwy-localscan: marker of the result: %s\n", (const gchar*)marker);
    ck_assert_msg(g_str_has_prefix((const gchar*)marker, "source=stored table, mode=paper, "
                                   "fill=mean\nstripe,dx,dy"), "marker %s", marker);
    g_object_unref(out);

    channel = g_strdup_printf("%d", id);
    run_tool(&run, (const gchar *const[]){ "-c", channel, "-o", output, first, NULL });
    expected = g_strdup_printf("gwy-localscan: %s channel %d is already local-scan compensated*",
                               first, id);
    assert_failure(&run, 1, expected);
    ck_assert_msg(strstr(run.err, "--force"), "the refusal does not say how to force: %s", run.err);
    tool_run_clear(&run);

    run_tool(&run, (const gchar *const[]){ "--force", "-c", channel, "-o", output, first, NULL });
    assert_success(&run);
    tool_run_clear(&run);
    out = load_gwy(output);
    ck_assert_int_ge(result_channel(out), 0);
    g_object_unref(out);

    g_unlink(output);
    g_unlink(first);
    g_free(expected);
    g_free(channel);
    g_free(output);
    g_free(first);
    three_channels_clear(&tc);
    g_rand_free(rng);
}
END_TEST

/* --all-channels: the first channel's table moves its sibling of the same
 * size too; a channel of another size stays as it was. */
START_TEST(test_all_channels)
{
    GRand *rng = g_rand_new_with_seed(seed + 11);
    GwyDataField *height = random_field(rng, 40, 30, 2e-9, 3e-9);
    GwyDataField *phase = random_field(rng, 40, 30, 2e-9, 3e-9);
    GwyDataField *other = random_field(rng, 33, 50, 2e-9, 3e-9);
    DriftTable *table = random_table(rng, 7, 8, 30);
    GwyContainer *data = gwy_container_new(), *out;
    gchar *text = drift_table_to_string(table), *input = in_path("in.gwy");
    gchar *output = out_path("out.gwy");
    ToolRun run;
    gint *ids, n, i;
    gboolean phase_done = FALSE, other_done = FALSE;

    add_channel(data, 0, height, "Height", text);
    add_channel(data, 1, phase, "Phase", NULL);
    add_channel(data, 2, other, "Other", NULL);
    save_gwy(data, input);
    run_tool(&run, (const gchar *const[]){ "--all-channels", "-o", output, input, NULL });
    assert_success(&run);
    tool_run_clear(&run);
    out = load_gwy(output);
    ids = gwy_app_data_browser_get_data_ids(out);
    for (n = 0; ids[n] >= 0; n++) {
        gchar key[40];

        g_snprintf(key, sizeof(key), "/%d/data/title", ids[n]);
        phase_done = phase_done || gwy_strequal(get_string(out, key), "Phase" TITLE_SUFFIX);
        other_done = other_done || gwy_strequal(get_string(out, key), "Other" TITLE_SUFFIX);
    }
    printf("test-gwy-localscan: --all-channels wrote %d channels\n", n);
    ck_assert_int_eq(n, 5);
    ck_assert(phase_done && !other_done);
    for (i = 0; ids[i] >= 0; i++) {
        gchar key[40];

        g_snprintf(key, sizeof(key), "/%d/data/title", ids[i]);
        if (gwy_strequal(get_string(out, key), "Phase" TITLE_SUFFIX))
            ck_assert(compensation_marker_get(out, ids[i]));
    }

    g_free(ids);
    g_object_unref(out);
    g_unlink(output);
    g_free(output);
    g_free(input);
    g_free(text);
    drift_table_free(table);
    g_object_unref(data);
    g_object_unref(other);
    g_object_unref(phase);
    g_object_unref(height);
    g_rand_free(rng);
}
END_TEST

/* -d with a table in physical units on non-square pixels (2.5 nm by 4 nm);
 * values a third of a pixel off whole pixels must round.  The stored table
 * of the channel, different, must be ignored. */
static const gchar *unit_names[] = { "nm", "um", "m" };
static const gdouble unit_metres[] = { 1e-9, 1e-6, 1.0 };

START_TEST(test_table_file_physical_units)
{
    GRand *rng = g_rand_new_with_seed(seed + 2 + _i);
    GwyDataField *field = random_field(rng, 37, 29, 2.5e-9, 4e-9);
    DriftTable *px = random_table(rng, 5, 6, 0), *stored = random_table(rng, 4, 3, 0), *loaded;
    GwyContainer *data = gwy_container_new();
    gchar *input = in_path("in.gwy"), *csv = in_path("drift.csv"), *output = out_path("out.gwy");
    gchar *text;
    GString *str = g_string_new(NULL);
    Expected exp;
    gint s;

    text = drift_table_to_string(stored);
    add_channel(data, 0, field, "Topo", text);
    add_other_metadata(data, 0, "Topo");
    g_free(text);
    save_gwy(data, input);

    g_string_append_printf(str, "# written by test-gwy-localscan\n# units: %s\nstripe,dx,dy,score\n",
                           unit_names[_i]);
    for (s = 0; s < px->n_stripes; s++) {
        gdouble offx = (s % 2 ? 0.3 : -0.3), offy = (s % 2 ? -0.3 : 0.3);

        g_string_append_printf(str, "%d,%.17g,%.17g,0.%d\n", s,
                               (px->rows[s].dx + offx)*2.5e-9/unit_metres[_i],
                               (px->rows[s].dy + offy)*4e-9/unit_metres[_i], s);
    }
    write_text(csv, str->str);
    loaded = drift_table_load(csv, NULL);
    ck_assert_ptr_nonnull(loaded);

    expected_init(&exp, field, "Topo", px);
    g_free(exp.table_text);
    exp.table_text = drift_table_to_string(loaded);
    exp.source_id = 0;
    run_and_check(data, input, (const gchar *const[]){ "-o", output, "-d", csv, input, NULL }, &exp);

    expected_clear(&exp);
    drift_table_free(loaded);
    drift_table_free(px);
    drift_table_free(stored);
    g_string_free(str, TRUE);
    g_object_unref(field);
    g_object_unref(data);
    g_free(input);
    g_free(csv);
    g_free(output);
    g_rand_free(rng);
}
END_TEST

/* Seeded random images and tables: non-square, yres not a multiple of N,
 * N = yres, N = 1, shifts beyond the image, blank stripes. */
START_TEST(test_random_cases)
{
    GRand *rng = g_rand_new_with_seed(seed + 100 + _i);
    gint xres = g_rand_int_range(rng, 2, 61), yres = g_rand_int_range(rng, 1, 61);
    gint n, max_shift;
    GwyDataField *field;
    GwyContainer *data = gwy_container_new();
    gchar *input = in_path("in.gwy"), *output = out_path("out.gwy"), *text;
    DriftTable *table;
    Expected exp;

    if (_i % 6 == 0)
        n = yres;
    else if (_i % 6 == 1)
        n = 1;
    else
        n = g_rand_int_range(rng, 1, yres + 1);
    max_shift = (_i % 4 == 0 ? 2*MAX(xres, yres) : MAX(1, MIN(xres, yres)/3));
    field = random_field(rng, xres, yres, 1e-9, 1e-9);
    table = random_table(rng, n, max_shift, _i % 3 ? 25 : 0);
    text = drift_table_to_string(table);
    add_channel(data, 0, field, "Random", text);
    save_gwy(data, input);
    expected_init(&exp, field, "Random", table);
    run_and_check(data, input, (const gchar *const[]){ "-o", output, input, NULL }, &exp);

    expected_clear(&exp);
    drift_table_free(table);
    g_free(text);
    g_object_unref(field);
    g_object_unref(data);
    g_free(input);
    g_free(output);
    g_rand_free(rng);
}
END_TEST

START_TEST(test_write_drift)
{
    GRand *rng = g_rand_new_with_seed(seed + 3);
    ThreeChannels tc;
    ToolRun run;
    gchar *output, *used, *contents = NULL, *want, *listing;

    three_channels_init(&tc, rng);
    output = out_path("out.gwy");
    used = out_path("used.csv");
    run_tool(&run, (const gchar *const[]){ "--write-drift", used, "-c", "3", "-o", output, tc.input, NULL });
    assert_success(&run);
    ck_assert(g_file_get_contents(used, &contents, NULL, NULL));
    want = drift_table_to_string(tc.tables[0]);
    ck_assert_str_eq(contents, want);
    listing = folder_listing(out_dir);
    ck_assert_str_eq(listing, "out.gwy used.csv");

    g_free(listing);
    g_free(want);
    g_free(contents);
    g_free(used);
    g_free(output);
    tool_run_clear(&run);
    three_channels_clear(&tc);
    g_rand_free(rng);
}
END_TEST

/* The user's own settings for the module (as left by the GUI) must not
 * change a batch result: fill, mode, source, mask and graph are the batch
 * run's.  The settings file is read but never written. */
START_TEST(test_user_settings_do_not_leak)
{
    GRand *rng = g_rand_new_with_seed(seed + 4);
    GwyContainer *settings = gwy_container_new();
    gchar *dir = g_build_filename(child_home, ".gwyddion", NULL);
    gchar *settings_file = g_build_filename(dir, "settings", NULL);
    gchar *sum_before, *sum_after, *text, *output;
    GPtrArray *lines;
    GString *str = g_string_new("Gwyddion Settings 1.0\n");
    GwyContainer *out;
    ThreeChannels tc;
    Expected exp;
    ToolRun run;
    guint i;

    gwy_container_set_int32_by_name(settings, "/module/localscan_drift/fill", 1);
    gwy_container_set_int32_by_name(settings, "/module/localscan_drift/mode", 1);
    gwy_container_set_int32_by_name(settings, "/module/localscan_drift/source", 1);
    gwy_container_set_const_string_by_name(settings, "/module/localscan_drift/table-file",
                                           (const guchar*)"/nonexistent.csv");
    gwy_container_set_boolean_by_name(settings, "/module/localscan_drift/add-mask", FALSE);
    gwy_container_set_boolean_by_name(settings, "/module/localscan_drift/plot-drift", TRUE);
    lines = gwy_container_serialize_to_text(settings);
    for (i = 0; i < lines->len; i++) {
        g_string_append(str, g_ptr_array_index(lines, i));
        g_string_append_c(str, '\n');
        g_free(g_ptr_array_index(lines, i));
    }
    g_ptr_array_free(lines, TRUE);
    g_mkdir(dir, 0700);
    write_text(settings_file, str->str);
    sum_before = file_checksum(settings_file);

    three_channels_init(&tc, rng);
    output = out_path("out.gwy");
    run_tool(&run, (const gchar *const[]){ "-o", output, tc.input, NULL });
    assert_success(&run);
    out = load_gwy(output);
    expected_init(&exp, tc.fields[1], three_titles[1], tc.tables[1]);
    check_compensated(out, check_inputs_preserved(tc.data, out), &exp);
    text = g_strdup("/0/graph/graph/1");
    ck_assert_msg(!gwy_container_contains_by_name(out, text), "a drift graph was added");
    sum_after = file_checksum(settings_file);
    ck_assert_str_eq(sum_before, sum_after);

    g_free(text);
    expected_clear(&exp);
    g_object_unref(out);
    tool_run_clear(&run);
    three_channels_clear(&tc);
    g_free(output);
    g_free(sum_before);
    g_free(sum_after);
    g_string_free(str, TRUE);
    g_free(settings_file);
    g_free(dir);
    g_object_unref(settings);
    g_rand_free(rng);
}
END_TEST

/* A real instrument file (Nanoscope, three channels, non-square pixels):
 * any file Gwyddion reads is a valid INPUT.  Run only when the measured
 * data is present. */
#define NANOSCOPE_INPUT "fastscan-series/09261606.001"

START_TEST(test_nanoscope_input)
{
    gchar *input = g_build_filename(test_measured_dir(), NANOSCOPE_INPUT, NULL);
    gchar *csv = in_path("drift.csv"), *output = out_path("out.gwy");
    GwyContainer *data, *out;
    GwyDataField *field;
    DriftTable *table;
    Expected exp;
    ToolRun run;

    write_text(csv, "stripe,dx,dy\n0,-3,0\n1,,\n2,-5,-1\n3,-7,-1\n4,-9,-2\n5,-11,-2\n");
    table = drift_table_load(csv, NULL);
    data = load_gwy(input);
    /* Channel 0, the lowest id, is the tool's default channel. */
    field = get_field(data, gwy_app_get_data_key_for_id(0));
    ck_assert_ptr_nonnull(field);
    expected_init(&exp, field, get_string(data, "/0/data/title"), table);
    run_tool(&run, (const gchar *const[]){ "-d", csv, "-o", output, input, NULL });
    assert_success(&run);
    out = load_gwy(output);
    check_compensated(out, check_inputs_preserved(data, out), &exp);

    g_object_unref(out);
    tool_run_clear(&run);
    expected_clear(&exp);
    g_object_unref(data);
    drift_table_free(table);
    g_free(input);
    g_free(csv);
    g_free(output);
}
END_TEST

/************************************************************************
 * Command line
 ************************************************************************/

START_TEST(test_help_lists_options)
{
    static const gchar *options[] = {
        "-o, --output=OUT.gwy", "-d, --drift=TABLE.csv", "-c, --channel=ID|TITLE",
        "-m, --mode=paper|continuous", "--reference=FILE[:ID|:TITLE]", "--stripes=N", "--masking=MODE",
        "--write-drift=TABLE.csv", "--version", "INPUT", "--line-time=S", "--direction=down|up",
        "--frame-start=S",
    };
    ToolRun run;
    guint i;

    run_tool(&run, (const gchar *const[]){ "--help", NULL });
    ck_assert_int_eq(run.status, 0);
    for (i = 0; i < G_N_ELEMENTS(options); i++)
        ck_assert_msg(strstr(run.out, options[i]), "--help does not list %s:\n%s", options[i], run.out);
    ck_assert_msg(strstr(run.out, "(the metadata wins; default 1)"),
                  "--help does not say that the file's timing wins over --line-time:\n%s", run.out);
    ck_assert_msg(strstr(run.out, "(default 16; at most 4096 and half the image's rows)"),
                  "--help does not state the module's stripe default and limit:\n%s", run.out);
    ck_assert_msg(strstr(run.out, "timed by the file's metadata"), "--help does not say where continuous mode's "
                  "timing comes from:\n%s", run.out);
    tool_run_clear(&run);

    run_tool(&run, (const gchar *const[]){ "--version", NULL });
    ck_assert_int_eq(run.status, 0);
    ck_assert_str_eq(run.out, "gwy-localscan " PACKAGE_VERSION "\n");
    tool_run_clear(&run);
}
END_TEST

/************************************************************************
 * Errors: one line, non-zero status, nothing written, input unchanged
 ************************************************************************/

/* One channel (id 0, 6 rows) with a stored table, saved as in/in.gwy. */
static gchar*
simple_input(const gchar *table_text)
{
    GRand *rng = g_rand_new_with_seed(seed + 5);
    GwyDataField *field = random_field(rng, 8, 6, 1e-9, 1e-9);
    GwyContainer *data = gwy_container_new();
    gchar *input = in_path("in.gwy");

    add_channel(data, 0, field, "Simple", table_text);
    save_gwy(data, input);
    g_object_unref(data);
    g_object_unref(field);
    g_rand_free(rng);
    return input;
}

#define GOOD_TABLE "stripe,dx,dy\n0,1,0\n1,-1,1\n"

typedef struct {
    const gchar *name;
    const gchar *stored;       /* stored table of in.gwy, or NULL */
    const gchar *csv;          /* contents of in/drift.csv, or NULL */
    const gchar *args[8];      /* "@IN", "@OUTDIR", "@OUT", "@CSV" are replaced */
    gint status;
    const gchar *message;      /* the same replaced; a trailing * matches any rest */
} ErrorCase;

static const ErrorCase error_cases[] = {
    { "missing -o", GOOD_TABLE, NULL, { "@IN", }, 2,
      "gwy-localscan: no output file: give -o OUT.gwy" },
    { "no input", GOOD_TABLE, NULL, { "-o", "@OUT", }, 2,
      "gwy-localscan: no INPUT file given" },
    { "two inputs", GOOD_TABLE, NULL, { "-o", "@OUT", "@IN", "@IN", }, 2,
      "gwy-localscan: exactly one INPUT file is needed, 2 were given" },
    { "unknown mode", GOOD_TABLE, NULL, { "-m", "fast", "-o", "@OUT", "@IN", }, 2,
      "gwy-localscan: unknown mode 'fast' (known: paper, continuous)" },
    { "unknown option", GOOD_TABLE, NULL, { "--stripez", "3", "-o", "@OUT", "@IN", }, 2,
      "gwy-localscan: Unknown option --stripez" },
    { "-c no such title", GOOD_TABLE, NULL, { "-c", "two", "-o", "@OUT", "@IN", }, 1,
      "gwy-localscan: @IN has no channel titled 'two' (its channels: 0 'Simple')" },
    { "-c empty", GOOD_TABLE, NULL, { "-c", "", "-o", "@OUT", "@IN", }, 2,
      "gwy-localscan: -c is empty: give a channel's id or title" },
    { "-c id too large", GOOD_TABLE, NULL, { "-c", "99999999999", "-o", "@OUT", "@IN", }, 2,
      "gwy-localscan: -c 99999999999: no channel id lies that far from 0" },
    { "unreadable input", GOOD_TABLE, NULL, { "-o", "@OUT", "@IN.missing", }, 1,
      "gwy-localscan: cannot read @IN.missing: no such file" },
    { "input is a directory", GOOD_TABLE, NULL, { "-o", "@OUT", "@OUTDIR", }, 1,
      "gwy-localscan: cannot read @OUTDIR: it is a directory" },
    /* Names given empty and an output that is a folder are slips of the
     * command line (exit 2, as `series` says them), not files that failed
     * ("cannot write : No such file or directory", exit 1). */
    { "empty -o", GOOD_TABLE, NULL, { "-o", "", "@IN", }, 2,
      "gwy-localscan: -o: the file name is empty" },
    { "empty -d", GOOD_TABLE, NULL, { "-d", "", "-o", "@OUT", "@IN", }, 2,
      "gwy-localscan: -d: the file name is empty" },
    { "empty input", GOOD_TABLE, NULL, { "-o", "@OUT", "", }, 2,
      "gwy-localscan: INPUT: the file name is empty" },
    { "output is a folder", GOOD_TABLE, NULL, { "-o", "@OUTDIR", "@IN", }, 2,
      "gwy-localscan: cannot write @OUTDIR: it is a folder" },
    { "reference is a directory", GOOD_TABLE, NULL, { "--reference", "@OUTDIR", "-o", "@OUT", "@IN", }, 1,
      "gwy-localscan: cannot read @OUTDIR: it is a directory" },
    { "input not SPM data", NULL, "just some text\n", { "-o", "@OUT", "@CSV", }, 1,
      "gwy-localscan: cannot read @CSV: *" },
    { "no such channel", GOOD_TABLE, NULL, { "-c", "4", "-o", "@OUT", "@IN", }, 1,
      "gwy-localscan: @IN has no channel 4 (its channels: 0)" },
    { "negative channel", GOOD_TABLE, NULL, { "-c", "-1", "-o", "@OUT", "@IN", }, 1,
      "gwy-localscan: @IN has no channel -1 (its channels: 0)" },
    { "no stored table", NULL, NULL, { "-o", "@OUT", "@IN", }, 1,
      "gwy-localscan: @IN: channel 0 has no stored drift table (metadata item 'Local-scan drift table'); "
      "give one with -d TABLE.csv" },
    { "malformed stored table", "stripe,dx,dy\n0,1,0\n1,x,0\n", NULL, { "-o", "@OUT", "@IN", }, 1,
      "gwy-localscan: @IN, channel 0 drift table:3: bad number 'x' for dx" },
    { "stored table does not fit", "stripe,dx,dy\n0,0,0\n1,0,0\n2,0,0\n3,0,0\n4,0,0\n5,0,0\n6,0,0\n", NULL,
      { "-o", "@OUT", "@IN", }, 1,
      "gwy-localscan: @IN, channel 0 drift table:8: the table has 7 stripes but the image has only 6 rows" },
    { "missing table file", GOOD_TABLE, NULL, { "-d", "@CSV", "-o", "@OUT", "@IN", }, 1,
      "gwy-localscan: @CSV: cannot read: No such file or directory" },
    { "NaN in table file", GOOD_TABLE, "stripe,dx,dy\n0,1,0\n1,nan,0\n",
      { "-d", "@CSV", "-o", "@OUT", "@IN", }, 1,
      "gwy-localscan: @CSV:3: dx = nan: NaN or infinity is not a drift" },
    { "fraction in paper mode", GOOD_TABLE, "stripe,dx,dy\n0,1,0\n1,0.5,0\n",
      { "-d", "@CSV", "-o", "@OUT", "@IN", }, 1,
      "gwy-localscan: @CSV:3: dx = 0.5 px is not a whole number of pixels; paper mode needs whole pixels" },
    { "too many stripes", GOOD_TABLE, "stripe,dx,dy\n0,0,0\n1,0,0\n2,0,0\n3,0,0\n4,0,0\n5,0,0\n6,0,0\n",
      { "-d", "@CSV", "-o", "@OUT", "@IN", }, 1,
      "gwy-localscan: @CSV:8: the table has 7 stripes but the image has only 6 rows" },
    { "drift too fast for continuous mode", GOOD_TABLE, "stripe,dx,dy\n0,0,0\n1,0,3\n2,0,6\n",
      { "-m", "continuous", "-d", "@CSV", "-o", "@OUT", "@IN", }, 1,
      "gwy-localscan: @CSV: y drift near row 0 is a line or more per line, too fast to compensate" },
    { "stored table too fast for continuous mode", "stripe,dx,dy\n0,0,0\n1,0,3\n2,0,6\n", NULL,
      { "-m", "continuous", "-o", "@OUT", "@IN", }, 1,
      "gwy-localscan: @IN, channel 0 drift table: y drift near row 0 is a line or more per line, "
      "too fast to compensate" },
    { "time not finite in continuous mode", GOOD_TABLE, "stripe,dx,dy,t_image\n0,0,0,1\n1,0,0,inf\n",
      { "-m", "continuous", "-d", "@CSV", "-o", "@OUT", "@IN", }, 1,
      "gwy-localscan: @CSV:3: t_image = 'inf' is not a finite number" },
    { "table named as given in continuous mode", GOOD_TABLE, "stripe,dx,dy,t_image\n0,0,0,1\n1,0,0,inf\n",
      { "-m", "continuous", "-d", "@OUTDIR/../in/drift.csv", "-o", "@OUT", "@IN", }, 1,
      "gwy-localscan: @OUTDIR/../in/drift.csv:3: t_image = 'inf' is not a finite number" },
    { "output folder missing", GOOD_TABLE, NULL, { "-o", "@OUTDIR/../nowhere/out.gwy", "@IN", }, 1,
      "gwy-localscan: cannot write @OUTDIR/../nowhere/out.gwy: No such file or directory" },
    { "output folder is a file", GOOD_TABLE, "x\n", { "-o", "@CSV/out.gwy", "@IN", }, 1,
      "gwy-localscan: cannot write @CSV/out.gwy: Not a directory" },
    { "output is the input", GOOD_TABLE, NULL, { "-o", "@IN", "@IN", }, 2,
      "gwy-localscan: refusing to overwrite the input file @IN (named by -o)" },
    { "output is the input, spelt otherwise", GOOD_TABLE, NULL, { "-o", "@OUTDIR/../in/./in.gwy", "@IN", }, 2,
      "gwy-localscan: refusing to overwrite the input file @IN (named by -o)" },
    { "--write-drift is the input", GOOD_TABLE, NULL, { "--write-drift", "@IN", "-o", "@OUT", "@IN", }, 2,
      "gwy-localscan: refusing to overwrite the input file @IN (named by --write-drift)" },
    { "output is the table file", GOOD_TABLE, GOOD_TABLE, { "-o", "@CSV", "-d", "@CSV", "@IN", }, 2,
      "gwy-localscan: refusing to overwrite the drift table @CSV given with -d (named by -o)" },
    { "--write-drift is the table file", GOOD_TABLE, GOOD_TABLE,
      { "-o", "@OUT", "-d", "@CSV", "--write-drift", "@CSV", "@IN", }, 2,
      "gwy-localscan: refusing to overwrite the drift table @CSV given with -d (named by --write-drift)" },
    { "output is the reference file", GOOD_TABLE, "x\n", { "-o", "@CSV", "--reference", "@CSV:0", "@IN", }, 2,
      "gwy-localscan: refusing to overwrite the reference file @CSV (named by -o)" },
    { "--write-drift is the reference file", GOOD_TABLE, "x\n",
      { "-o", "@OUT", "--write-drift", "@CSV", "--reference", "@CSV", "@IN", }, 2,
      "gwy-localscan: refusing to overwrite the reference file @CSV (named by --write-drift)" },
    { "reference id beyond gint", GOOD_TABLE, NULL, { "--reference", ":99999999999999", "-o", "@OUT", "@IN", }, 2,
      "gwy-localscan: --reference :99999999999999: channel id 99999999999999 is out of range (0 to 2147483647)" },
    { "reference id one beyond gint", GOOD_TABLE, NULL,
      { "--reference", "@IN:2147483648", "-o", "@OUT", "@IN", }, 2,
      "gwy-localscan: --reference @IN:2147483648: channel id 2147483648 is out of range (0 to 2147483647)" },
    { "line time zero", GOOD_TABLE, NULL, { "-m", "continuous", "--line-time", "0", "-o", "@OUT", "@IN", }, 2,
      "gwy-localscan: --line-time must be a number of seconds from 1e-06 to 10000, not '0'" },
    { "line time not a number", GOOD_TABLE, NULL, { "--line-time", "1s", "-o", "@OUT", "@IN", }, 2,
      "gwy-localscan: --line-time must be a number of seconds from 1e-06 to 10000, not '1s'" },
    { "frame start NaN", GOOD_TABLE, NULL, { "--frame-start", "nan", "-o", "@OUT", "@IN", }, 2,
      "gwy-localscan: --frame-start must be a number of seconds from -1e+09 to 1e+09, not 'nan'" },
    { "unknown direction", GOOD_TABLE, NULL, { "--direction", "left", "-o", "@OUT", "@IN", }, 2,
      "gwy-localscan: unknown direction 'left' (known: down, up)" },
    { "both outputs one file", GOOD_TABLE, NULL, { "-o", "@OUT", "--write-drift", "@OUTDIR/./out.gwy", "@IN", }, 2,
      "gwy-localscan: -o and --write-drift name the same file @OUTDIR/./out.gwy" },
};

static gchar*
substitute(const gchar *text, const gchar *input, const gchar *output, const gchar *csv)
{
    gchar **parts, *joined, *result = g_strdup(text);
    const gchar *names[4] = { "@IN", "@OUTDIR", "@OUT", "@CSV" };
    const gchar *values[4] = { input, out_dir, output, csv };
    guint i;

    for (i = 0; i < G_N_ELEMENTS(names); i++) {
        parts = g_strsplit(result, names[i], -1);
        joined = g_strjoinv(values[i], parts);
        g_strfreev(parts);
        g_free(result);
        result = joined;
    }
    return result;
}

/* The files an error case names as @IN, @OUT and @CSV. */
typedef struct {
    gchar *input;
    gchar *output;
    gchar *csv;
} ErrorFiles;

static void
error_files_clear(ErrorFiles *files)
{
    g_free(files->input);
    g_free(files->output);
    g_free(files->csv);
}

/* Runs the tool through runner with args (NULL-terminated, @IN, @OUTDIR,
 * @OUT and @CSV replaced); it must fail with status and message (replaced
 * likewise) and leave the input as it was.  The run stays in run for any
 * further check. */
static void
run_failing_case(ToolRun *run, ToolRunner runner, const gchar *what,
                 const gchar *name, const gchar *const *args, gint status,
                 const gchar *message, const ErrorFiles *files)
{
    GPtrArray *argv = g_ptr_array_new_with_free_func(g_free);
    gchar *sum_before, *sum_after, *expected;
    guint i;

    for (i = 0; args[i]; i++)
        g_ptr_array_add(argv, substitute(args[i], files->input, files->output, files->csv));
    g_ptr_array_add(argv, NULL);
    sum_before = file_checksum(files->input);

    runner(run, (const gchar *const*)argv->pdata);
    expected = substitute(message, files->input, files->output, files->csv);
    printf("%s \"%s\": %s", what, name, run->err);
    assert_failure(run, status, expected);
    sum_after = file_checksum(files->input);
    ck_assert_str_eq(sum_before, sum_after);

    g_free(expected);
    g_free(sum_before);
    g_free(sum_after);
    g_ptr_array_free(argv, TRUE);
}

START_TEST(test_error_exit)
{
    const ErrorCase *ec = error_cases + _i;
    ErrorFiles files;
    ToolRun run;

    files.input = simple_input(ec->stored);
    files.csv = in_path("drift.csv");
    files.output = out_path("out.gwy");
    if (ec->csv)
        write_text(files.csv, ec->csv);
    run_failing_case(&run, run_tool, "error case", ec->name, ec->args,
                     ec->status, ec->message, &files);
    tool_run_clear(&run);
    error_files_clear(&files);
}
END_TEST

/* An input file with no image channel at all (volume data only). */
START_TEST(test_error_no_channel)
{
    GwyContainer *data = gwy_container_new();
    GwyBrick *brick = gwy_brick_new(3, 4, 5, 3e-9, 4e-9, 5.0, TRUE);
    gchar *input = in_path("volume.gwy"), *output = out_path("out.gwy"), *message;
    ToolRun run;

    gwy_container_set_object_by_name(data, "/brick/0", brick);
    save_gwy(data, input);
    run_tool(&run, (const gchar *const[]){ "-o", output, input, NULL });
    message = g_strdup_printf("gwy-localscan: %s contains no image channel", input);
    assert_failure(&run, 1, message);

    g_free(message);
    tool_run_clear(&run);
    g_object_unref(brick);
    g_object_unref(data);
    g_free(input);
    g_free(output);
}
END_TEST

START_TEST(test_error_module)
{
    gchar *input = simple_input(GOOD_TABLE), *output = out_path("out.gwy");
    gchar *missing = in_path("nowhere.so"), *bogus = in_path("bogus.so"), *message;
    ToolRun run;

    run_tool_env(&run, missing, NULL, (const gchar *const[]){ "-o", output, input, NULL });
    message = g_strdup_printf("gwy-localscan: cannot load module %s: no such file", missing);
    assert_failure(&run, 1, message);
    g_free(message);
    tool_run_clear(&run);

    write_text(bogus, "not a shared library\n");
    run_tool_env(&run, bogus, NULL, (const gchar *const[]){ "-o", output, input, NULL });
    message = g_strdup_printf("gwy-localscan: cannot load module %s: *", bogus);
    assert_failure(&run, 1, message);
    g_free(message);
    tool_run_clear(&run);

    /* Neither LOCALSCAN_MODULE nor the scratch HOME has the module; the
     * build's --with-dest folder is not installed to by make check. */
    if (!*GWY_LOCALSCAN_MODULE_DIR
        || !g_file_test(GWY_LOCALSCAN_MODULE_DIR "/localscan.so", G_FILE_TEST_EXISTS)) {
        run_tool_env(&run, NULL, NULL, (const gchar *const[]){ "-o", output, input, NULL });
        assert_failure(&run, 1, "gwy-localscan: Gwyddion has no process function localscan_drift: "
                       "the localscan module is not installed (install it, or set LOCALSCAN_MODULE "
                       "to its file)");
        tool_run_clear(&run);
    }

    g_free(missing);
    g_free(bogus);
    g_free(input);
    g_free(output);
}
END_TEST

/* Root may write anywhere but in sysfs, which stands in for the read-only
 * folder then (its reason may differ by system). */
START_TEST(test_error_output_not_writable)
{
    gchar *input = simple_input(GOOD_TABLE), *output = out_path("out.gwy"), *message;
    ToolRun run;

    if (geteuid() == 0) {
        run_tool(&run, (const gchar *const[]){ "-o", "/sys/localscan-test.gwy", input, NULL });
        assert_failure(&run, 1, "gwy-localscan: cannot write /sys/localscan-test.gwy: *");
        ck_assert(!g_file_test("/sys/localscan-test.gwy", G_FILE_TEST_EXISTS));
        tool_run_clear(&run);
        g_free(input);
        g_free(output);
        return;
    }
    g_chmod(out_dir, 0500);
    run_tool(&run, (const gchar *const[]){ "-o", output, input, NULL });
    g_chmod(out_dir, 0700);
    message = g_strdup_printf("gwy-localscan: cannot write %s: Permission denied", output);
    assert_failure(&run, 1, message);

    g_free(message);
    tool_run_clear(&run);
    g_free(input);
    g_free(output);
}
END_TEST

/* A --write-drift that cannot be written (its folder missing: no temporary
 * file; a folder at its name: refused with the command line, exit 2, as
 * `series` refuses it) leaves an older OUT as it was, and nothing else
 * behind. */
START_TEST(test_write_drift_failure_keeps_old_output)
{
    static const gchar *const targets[2] = { "nowhere/used.csv", "adir" };
    static const gchar *const reasons[2] = { "No such file or directory", "it is a folder" };
    static const gint statuses[2] = { 1, 2 };
    gchar *input = simple_input(GOOD_TABLE), *output = out_path("out.gwy"), *adir = out_path("adir");
    gchar *used, *contents, *message, *listing;
    ToolRun run;
    guint i;

    for (i = 0; i < G_N_ELEMENTS(targets); i++) {
        write_text(output, "an older result\n");
        g_mkdir(adir, 0700);
        used = out_path(targets[i]);
        run_tool(&run, (const gchar *const[]){ "-o", output, "--write-drift", used, input, NULL });
        message = g_strdup_printf("gwy-localscan: cannot write %s: %s\n", used, reasons[i]);
        printf("write-drift failure %u: %s", i, run.err);
        ck_assert_int_eq(run.status, statuses[i]);
        ck_assert_str_eq(run.err, message);
        ck_assert(g_file_get_contents(output, &contents, NULL, NULL));
        ck_assert_str_eq(contents, "an older result\n");
        listing = folder_listing(out_dir);
        ck_assert_str_eq(listing, "adir out.gwy");
        g_free(listing);
        g_free(contents);
        g_free(message);
        g_free(used);
        tool_run_clear(&run);
    }
    g_rmdir(adir);
    g_free(adir);
    g_free(output);
    g_free(input);
}
END_TEST

/* Continuous mode's timing options stand in where the file's metadata is
 * silent and never override it; a table with times matched to an assumed
 * timing gets one warning line. */
#define TIMED_TABLE "stripe,dx,dy,t_image,t_local\n0,0,0,2,30\n1,0.5,0.25,5,31\n2,1,0.5,8,32\n"

typedef struct {
    const gchar *name;
    const gchar *meta[7];      /* key, value pairs of the channel's metadata */
    const gchar *args[7];      /* timing options */
    gdouble line_time;         /* the timing the result must have */
    ScanDirection direction;
    gdouble frame_start;
    const gchar *warning;      /* stderr; NULL: nothing */
} TimingCase;

static const TimingCase timing_cases[] = {
    { "nothing known", { NULL }, { NULL }, 1.0, SCAN_DIRECTION_DOWN, 0.0,
      "gwy-localscan: warning: the table's t_image/t_local times are matched with an assumed line time 1 s "
      "(--line-time), slow scan down (--direction), frame start 0 s (--frame-start): @IN channel 0 does not say\n" },
    { "options", { NULL }, { "--line-time", "0.5", "--direction", "up", "--frame-start", "1.5", NULL },
      0.5, SCAN_DIRECTION_UP, 1.5, NULL },
    { "line time only", { NULL }, { "--line-time", "0.5", NULL }, 0.5, SCAN_DIRECTION_DOWN, 0.0,
      "gwy-localscan: warning: the table's t_image/t_local times are matched with an assumed slow scan down "
      "(--direction), frame start 0 s (--frame-start): @IN channel 0 does not say\n" },
    { "metadata wins", { "Line time (s)", "1.5", "Slow scan", "up", "Frame start (s)", "-2", NULL },
      { "--line-time", "0.5", "--direction", "down", "--frame-start", "1.5", NULL },
      1.5, SCAN_DIRECTION_UP, -2.0, NULL },
    { "metadata and an option", { "Scan Rate", "4 Hz", NULL }, { "--direction", "up", "--frame-start", "3", NULL },
      0.25, SCAN_DIRECTION_UP, 3.0, NULL },
    /* A value there but unusable is named, not called absent. */
    { "unusable metadata", { "Line time (s)", "nan", "Frame start (s)", "soon", NULL },
      { "--direction", "up", NULL }, 1.0, SCAN_DIRECTION_UP, 0.0,
      "gwy-localscan: warning: the table's t_image/t_local times are matched with an assumed line time 1 s "
      "(--line-time), frame start 0 s (--frame-start): @IN channel 0 gives no usable value ('Line time (s)' is "
      "'nan', 'Frame start (s)' is 'soon')\n" },
};

static GwyDataField*
expected_continuous(GwyDataField *source, const DriftTable *table, const TimingCase *tc)
{
    GwyDataField *want = gwy_data_field_new_alike(source, FALSE);
    LocalscanOptions lo;

    lo.mode = LOCALSCAN_MODE_CONTINUOUS;
    lo.fill = LOCALSCAN_FILL_MEAN;
    lo.interpolation = LOCALSCAN_DEFAULT_INTERPOLATION;
    lo.line_time = tc->line_time;
    lo.direction = tc->direction;
    lo.frame_start = tc->frame_start;
    ck_assert(localscan_compensate_field(source, table, &lo, want, NULL, NULL, NULL));
    return want;
}

START_TEST(test_continuous_timing_options)
{
    const TimingCase *tc = timing_cases + _i;
    GRand *rng = g_rand_new_with_seed(seed + 11);
    GwyDataField *field = random_field(rng, 24, 18, 1e-9, 1e-9), *want;
    GwyContainer *data = gwy_container_new(), *out;
    gchar *input = in_path("in.gwy"), *output = out_path("out.gwy"), *warning;
    DriftTable *table = drift_table_parse(TIMED_TABLE, -1, "t", NULL);
    const gchar *args[16];
    ToolRun run;
    guint i, n = 0;

    add_channel(data, 0, field, "Timed", TIMED_TABLE);
    for (i = 0; tc->meta[i]; i += 2)
        gwy_container_set_const_string_by_name(channel_meta(data, 0, TRUE), tc->meta[i],
                                               (const guchar*)tc->meta[i+1]);
    save_gwy(data, input);
    args[n++] = "-m";
    args[n++] = "continuous";
    for (i = 0; tc->args[i]; i++)
        args[n++] = tc->args[i];
    args[n++] = "-o";
    args[n++] = output;
    args[n++] = input;
    args[n] = NULL;
    run_tool(&run, args);
    printf("timing case \"%s\": %s", tc->name, *run.err ? run.err : "no warning\n");
    ck_assert_msg(run.status == 0, "status %d: %s", run.status, run.err);
    warning = substitute(tc->warning ? tc->warning : "", input, output, "");
    ck_assert_str_eq(run.err, warning);

    out = load_gwy(output);
    want = expected_continuous(field, table, tc);
    if (tc != timing_cases) {
        /* Else the comparison could not tell the timings apart. */
        GwyDataField *assumed = expected_continuous(field, table, timing_cases);

        ck_assert(!fields_identical(want, assumed));
        g_object_unref(assumed);
    }
    ck_assert_msg(fields_identical(get_field(out, gwy_app_get_data_key_for_id(1)), want),
                  "the result is not compensated with line time %g s, direction %d, frame start %g s",
                  tc->line_time, tc->direction, tc->frame_start);

    g_object_unref(want);
    g_object_unref(out);
    g_free(warning);
    tool_run_clear(&run);
    drift_table_free(table);
    g_object_unref(data);
    g_object_unref(field);
    g_free(input);
    g_free(output);
    g_rand_free(rng);
}
END_TEST

/* The same table that paper mode refuses is fine for continuous mode. */
START_TEST(test_continuous_mode_accepts_fractions)
{
    gchar *input = simple_input(NULL), *csv = in_path("drift.csv"), *output = out_path("out.gwy");
    GwyContainer *out;
    ToolRun run;
    gchar *listing;

    write_text(csv, "stripe,dx,dy\n0,1,0\n1,0.5,0\n");
    run_tool(&run, (const gchar *const[]){ "-m", "continuous", "-d", csv, "-o", output, input, NULL });
    assert_success(&run);
    out = load_gwy(output);
    ck_assert_str_eq(get_string(out, "/1/data/title"), "Simple" TITLE_SUFFIX);
    listing = folder_listing(out_dir);
    ck_assert_str_eq(listing, "out.gwy");

    g_free(listing);
    g_object_unref(out);
    tool_run_clear(&run);
    g_free(input);
    g_free(csv);
    g_free(output);
}
END_TEST

/* Whether a local scan's stated distance from the trajectory fits its
 * error: beyond the pixel that names it, and within a quarter of the
 * error and half a pixel.  The trajectory at its moment is what the other
 * 15 stripes of a smooth drift give there: gross errors of 5-19 px were
 * stated within 0.07 px (12 seeds; 200 seeds of a soak passed). */
static gboolean
stated_distance_fits(gdouble stated, gdouble error)
{
    return stated > LOCALSCAN_LEFT_OUT_MIN_PX && fabs(stated - error) <= 0.25*error + 0.5;
}

/* The same for a registered stripe among 8 of a drift in whole-pixel
 * steps, which the robust smoothing follows loosely and bends towards the
 * error at the frame's ends: beyond the pixel, and below twice the error
 * (jumps of 5.8, 6.1 and 9.4 px stated 8.2, 2.9 and 4.6 px in a soak of
 * 200 seeds).  That the distance is the trajectory's own, not its
 * extrapolation to the frame's end, test-drift-trajectory checks. */
static gboolean
stated_distance_plausible(gdouble stated, gdouble error)
{
    return stated > LOCALSCAN_LEFT_OUT_MIN_PX && stated < 2.0*error;
}

/* A local scan that found another particle (a gross error of 4-20 px in
 * a random direction, on a random stripe of a smooth drift that scatters
 * by a few hundredths of a pixel) is left out of the line-by-line
 * trajectory, and the user is told which line of the table it is; the
 * same table without it draws no such warning. */
START_TEST(test_continuous_gross_error_named)
{
    GRand *rng = test_rand_salted(seed, 7300);
    GwyDataField *field = random_field(rng, 64, 96, 1e-9, 1e-9);
    GwyContainer *data = gwy_container_new();
    gchar *input = in_path("in.gwy"), *csv = in_path("drift.csv"), *output = out_path("out.gwy");
    gchar *expected;
    gdouble x0 = g_rand_double_range(rng, -2.0, 2.0), y0 = g_rand_double_range(rng, -2.0, 2.0);
    gdouble vx = g_rand_double_range(rng, -0.1, 0.1), vy = g_rand_double_range(rng, -0.1, 0.1);
    gdouble size = g_rand_double_range(rng, 4.0, 20.0), angle = g_rand_double_range(rng, 0.0, 2.0*G_PI);
    gint bad = g_rand_int_range(rng, 0, 12), s, round;
    GString *text;
    ToolRun run;

    add_channel(data, 0, field, "Grossly", NULL);
    save_gwy(data, input);
    for (round = 0; round < 2; round++) {
        text = g_string_new("stripe,dx,dy\n");
        for (s = 0; s < 12; s++) {
            gdouble dx = x0 + vx*s + g_rand_double_range(rng, -0.03, 0.03);
            gdouble dy = y0 + vy*s + g_rand_double_range(rng, -0.03, 0.03);

            if (round == 1 && s == bad) {
                dx += size*cos(angle);
                dy += size*sin(angle);
            }
            g_string_append_printf(text, "%d,%.4f,%.4f\n", s, dx, dy);
        }
        write_text(csv, text->str);
        g_string_free(text, TRUE);
        run_tool(&run, (const gchar *const[]){ "-m", "continuous", "-d", csv, "-o", output, input,
                                               NULL });
        ck_assert_msg(run.status == 0, "round %d (seed %u): status %d: %s", round, seed, run.status,
                      run.err);
        if (round == 0)
            ck_assert_msg(!strstr(run.err, "left out"), "seed %u: smooth drift: %s", seed, run.err);
        else {
            /* The table's header is its line 1, stripe s its line s + 2. */
            expected = g_strdup_printf("gwy-localscan: warning: %s:%d: stripe %d's drift lies ",
                                       csv, bad + 2, bad);
            ck_assert_msg(g_str_has_prefix(run.err, expected)
                          && g_str_has_suffix(run.err, " px from what the other stripes give; "
                                              "continuous compensation leaves it out\n")
                          && stated_distance_fits(g_ascii_strtod(run.err + strlen(expected), NULL), size),
                          "seed %u: %.2f px on stripe %d: got \"%s\"", seed, size, bad, run.err);
            g_free(expected);
        }
        tool_run_clear(&run);
        g_unlink(output);
    }
    g_object_unref(data);
    g_object_unref(field);
    g_free(input);
    g_free(csv);
    g_free(output);
    g_rand_free(rng);
}
END_TEST

/* A German user reads German help and messages (the catalogue built from
 * po/de.po; LOCALSCAN_LOCALEDIR stands for the installed locale folder). */
START_TEST(test_german_messages)
{
    static const gchar *const german[] = {
        "LC_ALL", "C.UTF-8", "LANGUAGE", "de", "LOCALSCAN_LOCALEDIR", TEST_BUILDDIR "/tests/locale", NULL,
    };
    gchar *input = simple_input(GOOD_TABLE);
    ToolRun run;

    run_tool_env(&run, module_path(), german, (const gchar *const[]){ "--help", NULL });
    ck_assert_int_eq(run.status, 0);
    /* The gap between the two is GLib's, wide enough for the longest
     * option. */
    ck_assert_msg(strstr(run.out, "-o, --output=AUSGABE.gwy ")
                  && strstr(run.out, " Das Ergebnis nach AUSGABE.gwy schreiben"),
                  "no German --help:\n%s", run.out);
    tool_run_clear(&run);

    run_tool_env(&run, module_path(), german, (const gchar *const[]){ input, NULL });
    assert_failure(&run, 2, "gwy-localscan: keine Ausgabedatei: bitte -o AUSGABE.gwy angeben");
    tool_run_clear(&run);
    g_free(input);
}
END_TEST

/* The core's messages (drift table, channel) go through the project's
 * catalogue too: a catalogue made here translates one of each. */
START_TEST(test_core_messages_translated)
{
    static const gchar po[] =
        "msgid \"\"\nmsgstr \"Content-Type: text/plain; charset=UTF-8\\n\"\n"
        "msgid \"bad number '%s' for %s\"\nmsgstr \"ungültige Zahl '%s' für %s\"\n"
        "msgid \"%s, channel %d drift table\"\nmsgstr \"%s, Drifttabelle von Kanal %d\"\n";
    gchar *input = simple_input("stripe,dx,dy\n0,1,0\n1,x,0\n"), *output = out_path("out.gwy");
    gchar *localedir = g_build_filename(scratch, "locale", NULL);
    gchar *modir = g_build_filename(localedir, "de", "LC_MESSAGES", NULL);
    gchar *pofile = g_build_filename(scratch, "core.po", NULL);
    gchar *mofile = g_build_filename(modir, GETTEXT_PACKAGE ".mo", NULL), *message;
    const gchar *msgfmt[] = { "msgfmt", "-o", mofile, pofile, NULL };
    const gchar *german[] = { "LC_ALL", "C.UTF-8", "LANGUAGE", "de", "LOCALSCAN_LOCALEDIR", localedir, NULL };
    gint status = -1;
    ToolRun run;

    g_mkdir_with_parents(modir, 0700);
    write_text(pofile, po);
    ck_assert(g_spawn_sync(NULL, (gchar**)msgfmt, NULL, G_SPAWN_SEARCH_PATH, NULL, NULL, NULL, NULL, &status, NULL));
    ck_assert_msg(status == 0, "msgfmt failed");
    run_tool_env(&run, module_path(), german, (const gchar *const[]){ "-o", output, input, NULL });
    message = g_strdup_printf("gwy-localscan: %s, Drifttabelle von Kanal 0:3: ungültige Zahl 'x' für dx", input);
    assert_failure(&run, 1, message);
    tool_run_clear(&run);
    test_remove_tree(localedir);
    g_unlink(pofile);
    g_free(message);
    g_free(mofile);
    g_free(pofile);
    g_free(modir);
    g_free(localedir);
    g_free(output);
    g_free(input);
}
END_TEST

/************************************************************************
 * Drift measured against a reference (--reference, --stripes)
 ************************************************************************/

#define REF_SIZE 160
#define REF_STRIPES 8
#define REF_STEP 2e-9
/* Compared with the reference away from the edges, where drift brings in
 * content the reference does not have. */
#define REF_MARGIN 12
/* Registration's stated accuracy on these frames, px (dx_exact, dy_exact). */
#define REF_EXACT_TOLERANCE 0.25

/* A drift-free reference and a drifted image of one seeded random smooth
 * surface (tests/registration-frames.c), with the true drift per stripe. */
typedef struct {
    GwyDataField *reference;
    GwyDataField *image;
    gdouble truth_dx[REF_STRIPES];
    gdouble truth_dy[REF_STRIPES];
} RefFrames;

static GwyDataField*
field_from_values(const gdouble *values)
{
    GwyDataField *field = gwy_data_field_new(REF_SIZE, REF_SIZE, REF_SIZE*REF_STEP, REF_SIZE*REF_STEP, FALSE);

    memcpy(gwy_data_field_get_data(field), values, REF_SIZE*REF_SIZE*sizeof(gdouble));
    gwy_si_unit_set_from_string(gwy_data_field_get_si_unit_xy(field), "m");
    gwy_si_unit_set_from_string(gwy_data_field_get_si_unit_z(field), "m");
    return field;
}

static void
ref_spec_init(FramePairSpec *spec)
{
    frame_pair_spec_init(spec);
    spec->xres = spec->yres = REF_SIZE;
    spec->noise = 0.02;
    spec->drift = FALSE;
}

/* Each stripe drifts by its own constant (dx, dy): the surface is the same
 * for one seed whatever the shift, so stripe s of the image is taken from
 * a frame shifted by stripe s's drift. */
static void
ref_frames_stripewise(RefFrames *rf, guint32 frame_seed, const gdouble *dx, const gdouble *dy)
{
    gdouble *image = g_new(gdouble, REF_SIZE*REF_SIZE);
    FramePairSpec spec;
    FramePair *pair;
    gint s, first, end;

    ref_spec_init(&spec);
    for (s = 0; s < REF_STRIPES; s++) {
        spec.shift_x = rf->truth_dx[s] = dx[s];
        spec.shift_y = rf->truth_dy[s] = dy[s];
        pair = frame_pair_generate(&spec, frame_seed);
        first = s*REF_SIZE/REF_STRIPES;
        end = (s + 1)*REF_SIZE/REF_STRIPES;
        memcpy(image + first*REF_SIZE, pair->image + first*REF_SIZE, (end - first)*REF_SIZE*sizeof(gdouble));
        if (!s)
            rf->reference = field_from_values(pair->reference);
        frame_pair_free(pair);
    }
    rf->image = field_from_values(image);
    g_free(image);
}

/* A drift linear in the row, the kind continuous mode follows. */
static void
ref_frames_linear(RefFrames *rf, guint32 frame_seed, gdouble shift_x, gdouble shift_y,
                  gdouble velocity_x, gdouble velocity_y)
{
    FramePairSpec spec;
    FramePair *pair;

    ref_spec_init(&spec);
    spec.shift_x = shift_x;
    spec.shift_y = shift_y;
    spec.velocity_x = velocity_x;
    spec.velocity_y = velocity_y;
    pair = frame_pair_generate(&spec, frame_seed);
    frame_pair_stripe_truth(pair, REF_STRIPES, rf->truth_dx, rf->truth_dy);
    rf->reference = field_from_values(pair->reference);
    rf->image = field_from_values(pair->image);
    frame_pair_free(pair);
}

static void
ref_frames_clear(RefFrames *rf)
{
    g_object_unref(rf->reference);
    g_object_unref(rf->image);
}

/* Drift as a scanner has it: one direction, 3 to 9 px, changing by at most
 * 1 px from stripe to stripe (registration takes the neighbours' agreement
 * into account).  Whole pixels, or whole pixels plus a fraction of 0.2 to
 * 0.3 either way, so that rounding to whole pixels is never a coin toss. */
static void
random_stripe_drift(GRand *rng, gboolean subpixel, gdouble *drift)
{
    gint s, sign = (g_rand_boolean(rng) ? 1 : -1), v = g_rand_int_range(rng, 3, 10);
    gdouble fraction;

    for (s = 0; s < REF_STRIPES; s++) {
        v = CLAMP(v + g_rand_int_range(rng, -1, 2), 3, 9);
        fraction = g_rand_double_range(rng, 0.2, 0.3);
        drift[s] = sign*v + (subpixel ? (g_rand_boolean(rng) ? fraction : -fraction) : 0.0);
    }
}

/* RMS of (field - reference) over the interior pixels of the stripes the
 * table has a drift for that mask (may be NULL) leaves unfilled: stripes
 * without one get a neighbour's drift, which is only an estimate. */
static gdouble
interior_rms_difference(GwyDataField *field, GwyDataField *reference, GwyDataField *mask,
                        const DriftTable *table)
{
    const gdouble *d = gwy_data_field_get_data_const(field);
    const gdouble *ref = gwy_data_field_get_data_const(reference);
    const gdouble *m = mask ? gwy_data_field_get_data_const(mask) : NULL;
    gdouble sum = 0.0, e;
    gint r, c, k, count = 0;

    for (r = REF_MARGIN; r < REF_SIZE - REF_MARGIN; r++) {
        if (!table->rows[r*REF_STRIPES/REF_SIZE].has_drift)
            continue;
        for (c = REF_MARGIN; c < REF_SIZE - REF_MARGIN; c++) {
            k = r*REF_SIZE + c;
            if (m && m[k] > 0.5)
                continue;
            e = d[k] - ref[k];
            sum += e*e;
            count++;
        }
    }
    ck_assert_int_gt(count, (REF_SIZE - 2*REF_MARGIN)*(REF_SIZE - 2*REF_MARGIN)/3);
    return sqrt(sum/count);
}

/* The table stored with the new channel is the measured one: every stripe
 * it accepted within 0.5 px of the truth (exact columns within
 * REF_EXACT_TOLERANCE), whole pixels in paper mode, and at least 3/4 of the
 * stripes accepted. */
static DriftTable*
check_measured_table(GwyContainer *out, gint newid, const RefFrames *rf, gboolean paper)
{
    const gchar *text = stored_table_text(out, newid);
    DriftTable *table;
    gdouble ex, ey, worst = 0.0;
    gint s, accepted = 0;

    ck_assert_msg(text, "the new channel carries no drift table");
    table = drift_table_parse(text, -1, "stored", NULL);
    ck_assert_ptr_nonnull(table);
    ck_assert_int_eq(table->n_stripes, REF_STRIPES);
    ck_assert_int_eq(table->unit, DRIFT_UNIT_PX);
    for (s = 0; s < REF_STRIPES; s++) {
        const DriftTableRow *row = table->rows + s;

        if (!row->has_drift)
            continue;
        accepted++;
        ck_assert(drift_table_get_extra(table, s, "dx_exact", &ex));
        ck_assert(drift_table_get_extra(table, s, "dy_exact", &ey));
        ck_assert_msg(fabs(row->dx - rf->truth_dx[s]) <= 0.5 && fabs(row->dy - rf->truth_dy[s]) <= 0.5
                      && fabs(ex - rf->truth_dx[s]) <= REF_EXACT_TOLERANCE
                      && fabs(ey - rf->truth_dy[s]) <= REF_EXACT_TOLERANCE,
                      "stripe %d: table (%g, %g), exact (%.3f, %.3f), truth (%.3f, %.3f) px (seed %u)",
                      s, row->dx, row->dy, ex, ey, rf->truth_dx[s], rf->truth_dy[s], seed);
        if (paper)
            ck_assert(row->dx == floor(row->dx) && row->dy == floor(row->dy));
        worst = MAX(worst, MAX(fabs(ex - rf->truth_dx[s]), fabs(ey - rf->truth_dy[s])));
    }
    printf("reference registration: %d of %d stripes accepted, worst exact error %.3f px\n",
           accepted, REF_STRIPES, worst);
    ck_assert_msg(accepted >= REF_STRIPES*3/4, "only %d of %d stripes accepted (seed %u)",
                  accepted, REF_STRIPES, seed);
    return table;
}

/* Runs the tool with a private TMPDIR, which must be empty afterwards. */
static void
run_tool_tmpdir(ToolRun *run, const gchar *const *args)
{
    gchar *tmpdir = g_build_filename(scratch, "tmp", NULL), *listing;
    const gchar *env[] = { "TMPDIR", tmpdir, NULL };

    g_mkdir(tmpdir, 0700);
    run_tool_env(run, module_path(), env, args);
    listing = folder_listing(tmpdir);
    ck_assert_msg(!*listing, "temporary files left behind: %s", listing);
    g_free(listing);
    g_free(tmpdir);
}

/* Runs the tool on input (data saved there) and checks the result against
 * the truth: the stored (and written) table, the bits of the result (paper
 * mode: exactly paper_compensate() with that table) and how much better
 * the result lines up with the reference than the image does. */
static void
run_reference_case(GwyContainer *data, const gchar *input, gint image_id, const RefFrames *rf,
                   const gchar *const *args, gboolean paper, gdouble min_improvement)
{
    gchar *output = out_path("out.gwy"), *used = out_path("used.csv"), *written = NULL;
    GwyDataField *result, *mask;
    GwyContainer *out;
    DriftTable *table;
    Expected exp;
    gdouble before, after;
    gint newid;

    out = run_successfully(run_tool_tmpdir, args, data, input, output, &newid);
    table = check_measured_table(out, newid, rf, paper);
    ck_assert(g_file_get_contents(used, &written, NULL, NULL));
    ck_assert_str_eq(written, stored_table_text(out, newid));
    if (paper) {
        expected_init(&exp, rf->image, get_string(data, g_quark_to_string(
                          gwy_app_get_data_title_key_for_id(image_id))), table);
        check_compensated(out, newid, &exp);
        expected_clear(&exp);
    }

    result = get_field(out, gwy_app_get_data_key_for_id(newid));
    mask = get_field(out, gwy_app_get_mask_key_for_id(newid));
    before = interior_rms_difference(rf->image, rf->reference, mask, table);
    after = interior_rms_difference(result, rf->reference, mask, table);
    printf("reference registration, %s mode: interior RMS difference from the reference %.4f before, "
           "%.4f after: %.1fx better (need %.0fx)\n",
           paper ? "paper" : "continuous", before, after, before/after, min_improvement);
    ck_assert_msg(after*min_improvement <= before, "only %.2fx better (seed %u)", before/after, seed);

    drift_table_free(table);
    g_object_unref(out);
    g_free(written);
    g_free(used);
    g_free(output);
}

/* Whole-pixel drift; the reference is another file (its first channel). */
START_TEST(test_reference_two_files)
{
    GRand *rng = g_rand_new_with_seed(seed + 200);
    gdouble dx[REF_STRIPES], dy[REF_STRIPES];
    GwyContainer *data = gwy_container_new(), *refdata = gwy_container_new();
    gchar *input = in_path("in.gwy"), *reffile = in_path("ref.gwy");
    gchar *output = out_path("out.gwy"), *used = out_path("used.csv");
    RefFrames rf;

    random_stripe_drift(rng, FALSE, dx);
    random_stripe_drift(rng, FALSE, dy);
    ref_frames_stripewise(&rf, seed + 201, dx, dy);
    add_channel(data, 0, rf.image, "Drifting", NULL);
    add_other_metadata(data, 0, "Drifting");
    save_gwy(data, input);
    add_channel(refdata, 2, rf.reference, "Reference", NULL);
    save_gwy(refdata, reffile);
    run_reference_case(data, input, 0, &rf,
                       (const gchar *const[]){ "--reference", reffile, "--stripes", "8",
                                               "--write-drift", used, "-o", output, input, NULL },
                       TRUE, 4.0);

    ref_frames_clear(&rf);
    g_object_unref(data);
    g_object_unref(refdata);
    g_free(input);
    g_free(reffile);
    g_free(output);
    g_free(used);
    g_rand_free(rng);
}
END_TEST

/* Sub-pixel drift rounded for paper mode; the reference is channel 3 of
 * the input itself, named as ":3", "INPUT:3", ":Reference" and
 * "INPUT:Reference" (the image then named by its title too). */
START_TEST(test_reference_same_file)
{
    GRand *rng = g_rand_new_with_seed(seed + 300 + _i);
    gdouble dx[REF_STRIPES], dy[REF_STRIPES];
    GwyContainer *data = gwy_container_new();
    gchar *input = in_path("in.gwy"), *output = out_path("out.gwy"), *used = out_path("used.csv");
    gchar *refarg;
    RefFrames rf;

    random_stripe_drift(rng, TRUE, dx);
    random_stripe_drift(rng, TRUE, dy);
    ref_frames_stripewise(&rf, seed + 301 + _i, dx, dy);
    add_channel(data, 1, rf.image, "Drifting", NULL);
    add_channel(data, 3, rf.reference, "Reference", NULL);
    save_gwy(data, input);
    refarg = g_strconcat((_i % 2) ? input : "", (_i < 2) ? ":3" : ":Reference", NULL);
    run_reference_case(data, input, 1, &rf,
                       (const gchar *const[]){ "-c", (_i < 2) ? "1" : "Drifting", "--reference", refarg,
                                               "--stripes", "8",
                                               "--write-drift", used, "-o", output, input, NULL },
                       TRUE, 3.0);

    ref_frames_clear(&rf);
    g_object_unref(data);
    g_free(refarg);
    g_free(input);
    g_free(output);
    g_free(used);
    g_rand_free(rng);
}
END_TEST

/* The stripes of the table written to used whose content meets reference
 * rows [r0, r0 + h): their exact values within 0.1 px of the truth (with
 * the masks ignored, the filled patch pulls them 0.1-0.4 px off). */
static void
check_stripes_meeting_hole(const gchar *used, const RefFrames *rf, gint r0, gint h)
{
    gchar *text = NULL;
    DriftTable *table;
    gdouble ex, ey, worst = 0.0;
    gint s, first, end, met = 0;

    ck_assert(g_file_get_contents(used, &text, NULL, NULL));
    table = drift_table_parse(text, -1, "used", NULL);
    ck_assert_ptr_nonnull(table);
    for (s = 0; s < REF_STRIPES; s++) {
        first = s*REF_SIZE/REF_STRIPES;
        end = (s + 1)*REF_SIZE/REF_STRIPES;
        if (!table->rows[s].has_drift || first - rf->truth_dy[s] - 2 >= r0 + h
            || end - rf->truth_dy[s] + 2 <= r0)
            continue;
        ck_assert(drift_table_get_extra(table, s, "dx_exact", &ex));
        ck_assert(drift_table_get_extra(table, s, "dy_exact", &ey));
        worst = MAX(worst, hypot(ex - rf->truth_dx[s], ey - rf->truth_dy[s]));
        met++;
    }
    printf("reference registration, masked hole: %d stripes meeting it, worst %.3f px\n", met, worst);
    ck_assert_msg(worst <= 0.1, "a stripe meeting the masked hole %.3f px off (seed %u)", worst, seed);
    drift_table_free(table);
    g_free(text);
}

/* Gwyddion's importers fill the pixels a file lacks with the mean and mask
 * them.  A hole of 30-45 px so given in the reference (at a random place)
 * is left out by default: every stripe the registration gives is within
 * the usual tolerance (with --masking ignore the filled patch pulled the
 * stripes crossing it 0.26-0.35 px RMS off in the core's tests). */
START_TEST(test_reference_masked_hole)
{
    GRand *rng = g_rand_new_with_seed(seed + 700);
    gdouble dx[REF_STRIPES], dy[REF_STRIPES], mean, *ref;
    GwyContainer *data = gwy_container_new();
    gchar *input = in_path("in.gwy"), *output = out_path("out.gwy"), *used = out_path("used.csv");
    GwyDataField *reference, *mask;
    gint w = g_rand_int_range(rng, 30, 46), h = g_rand_int_range(rng, 30, 46), r0, c0, r, c;
    RefFrames rf;

    r0 = g_rand_int_range(rng, REF_MARGIN, REF_SIZE - REF_MARGIN - h);
    c0 = g_rand_int_range(rng, REF_MARGIN, REF_SIZE - REF_MARGIN - w);
    random_stripe_drift(rng, TRUE, dx);
    random_stripe_drift(rng, TRUE, dy);
    ref_frames_stripewise(&rf, seed + 701, dx, dy);
    reference = gwy_data_field_duplicate(rf.reference);
    mask = gwy_data_field_new_alike(reference, TRUE);
    ref = gwy_data_field_get_data(reference);
    mean = gwy_data_field_get_avg(reference);
    for (r = r0; r < r0 + h; r++) {
        for (c = c0; c < c0 + w; c++) {
            ref[r*REF_SIZE + c] = mean;
            gwy_data_field_set_val(mask, c, r, 1.0);
        }
    }
    gwy_data_field_invalidate(reference);
    add_channel(data, 0, rf.image, "Drifting", NULL);
    add_channel(data, 1, reference, "Reference", NULL);
    gwy_container_set_object(data, gwy_app_get_mask_key_for_id(1), mask);
    save_gwy(data, input);
    /* Judged against the whole reference, hole included. */
    run_reference_case(data, input, 0, &rf,
                       (const gchar *const[]){ "--reference", ":1", "--stripes", "8",
                                               "--write-drift", used, "-o", output, input, NULL },
                       TRUE, 3.0);
    check_stripes_meeting_hole(used, &rf, r0, h);

    g_object_unref(mask);
    g_object_unref(reference);
    ref_frames_clear(&rf);
    g_object_unref(data);
    g_free(input);
    g_free(output);
    g_free(used);
    g_rand_free(rng);
}
END_TEST

/* A drift linear in time, sub-pixel, growing from 2 to 4 px at the top by
 * 3 to 6 px in x and 2 to 4 px in y to the bottom: continuous mode follows
 * it with the exact measured values. */
START_TEST(test_reference_continuous)
{
    GRand *rng = g_rand_new_with_seed(seed + 400);
    GwyContainer *data = gwy_container_new();
    gchar *input = in_path("in.gwy"), *output = out_path("out.gwy"), *used = out_path("used.csv");
    gdouble sx, sy;
    RefFrames rf;

    sx = (g_rand_boolean(rng) ? 1.0 : -1.0);
    sy = (g_rand_boolean(rng) ? 1.0 : -1.0);
    ref_frames_linear(&rf, seed + 401,
                      sx*g_rand_double_range(rng, 2.0, 4.0), sy*g_rand_double_range(rng, 2.0, 4.0),
                      sx*g_rand_double_range(rng, 3.0, 6.0)/REF_SIZE, sy*g_rand_double_range(rng, 2.0, 4.0)/REF_SIZE);
    add_channel(data, 0, rf.image, "Drifting", NULL);
    add_channel(data, 1, rf.reference, "Reference", NULL);
    save_gwy(data, input);
    run_reference_case(data, input, 0, &rf,
                       (const gchar *const[]){ "-m", "continuous", "--interpolation", SIMSCAN_KERNEL_NAME,
                                               "--reference", ":1", "--stripes", "8",
                                               "--write-drift", used, "-o", output, input, NULL },
                       FALSE, 6.0);

    ref_frames_clear(&rf);
    g_object_unref(data);
    g_free(input);
    g_free(output);
    g_free(used);
    g_rand_free(rng);
}
END_TEST

/* A stripe whose content jumped 6-10 px (a random direction, a random
 * stripe) against a drift of whole pixels that changes by at most one
 * from stripe to stripe: registered, it is named as the registration's
 * stripe (no table file says it) and how far it lies. */
START_TEST(test_reference_continuous_names_jumped_stripe)
{
    GRand *rng = test_rand_salted(seed, 7500);
    GwyContainer *data = gwy_container_new();
    gchar *input = in_path("in.gwy"), *output = out_path("out.gwy"), *expected;
    gdouble dx[REF_STRIPES], dy[REF_STRIPES], size = g_rand_double_range(rng, 6.0, 10.0);
    gdouble angle = g_rand_double_range(rng, 0.0, 2.0*G_PI);
    gint bad = g_rand_int_range(rng, 0, REF_STRIPES), s;
    RefFrames rf;
    ToolRun run;

    for (s = 0; s < REF_STRIPES; s++) {
        dx[s] = 2.0 + s/4;
        dy[s] = -1.0 - s/3;
    }
    dx[bad] += GWY_ROUND(size*cos(angle));
    dy[bad] += GWY_ROUND(size*sin(angle));
    size = hypot(GWY_ROUND(size*cos(angle)), GWY_ROUND(size*sin(angle)));
    ref_frames_stripewise(&rf, seed + 7501, dx, dy);
    add_channel(data, 0, rf.image, "Jumped", NULL);
    add_channel(data, 1, rf.reference, "Reference", NULL);
    save_gwy(data, input);
    run_tool(&run, (const gchar *const[]){ "-m", "continuous", "--reference", ":1",
                                           "--stripes", "8", "-o", output, input, NULL });
    ck_assert_msg(run.status == 0, "seed %u: status %d: %s", seed, run.status, run.err);
    expected = g_strdup_printf("gwy-localscan: warning: the registration's stripe %d lies ", bad);
    ck_assert_msg(g_str_has_prefix(run.err, expected)
                  && g_str_has_suffix(run.err, " px from what the other stripes give; "
                                      "continuous compensation leaves it out\n")
                  && stated_distance_plausible(g_ascii_strtod(run.err + strlen(expected), NULL),
                                               size),
                  "seed %u: %.1f px on stripe %d: got \"%s\"", seed, size, bad, run.err);
    g_free(expected);
    tool_run_clear(&run);
    ref_frames_clear(&rf);
    g_object_unref(data);
    g_free(input);
    g_free(output);
    g_rand_free(rng);
}
END_TEST

/* in.gwy: channel 0 the image (a drifting frame, 160 x 160), channel 1
 * white noise of its size (nothing to match), channel 2 a smaller field
 * titled as channel 1 is. */
static gchar*
reference_error_input(void)
{
    GRand *rng = g_rand_new_with_seed(seed + 500);
    GwyContainer *data = gwy_container_new();
    GwyDataField *noise, *small;
    gchar *input = in_path("in.gwy");
    gdouble dx[REF_STRIPES] = { 0 }, dy[REF_STRIPES] = { 0 };
    RefFrames rf;

    dx[0] = 3.0;
    ref_frames_stripewise(&rf, seed + 501, dx, dy);
    noise = random_field(rng, REF_SIZE, REF_SIZE, REF_STEP, REF_STEP);
    small = random_field(rng, REF_SIZE/2, REF_SIZE, REF_STEP, REF_STEP);
    add_channel(data, 0, rf.image, "Drifting", NULL);
    add_channel(data, 1, noise, "Noise", NULL);
    add_channel(data, 2, small, "Noise", NULL);
    save_gwy(data, input);
    g_object_unref(noise);
    g_object_unref(small);
    ref_frames_clear(&rf);
    g_object_unref(data);
    g_rand_free(rng);
    return input;
}

typedef struct {
    const gchar *name;
    const gchar *args[10];     /* "@IN", "@OUT", "@CSV" are replaced */
    gint status;
    const gchar *message;
} ReferenceErrorCase;

static const ReferenceErrorCase reference_error_cases[] = {
    { "with -d", { "-d", "@CSV", "--reference", ":1", "-o", "@OUT", "@IN", }, 2,
      "gwy-localscan: -d and --reference both give the drift: use one of them" },
    { "stripes alone", { "--stripes", "4", "-o", "@OUT", "@IN", }, 2,
      "gwy-localscan: --stripes needs --reference" },
    { "no stripes", { "--stripes", "0", "--reference", ":1", "-o", "@OUT", "@IN", }, 2,
      "gwy-localscan: --stripes must be from 1 to 4096, not 0" },
    { "more stripes than the module allows", { "--stripes", "4097", "--reference", ":1", "-o", "@OUT", "@IN", }, 2,
      "gwy-localscan: --stripes must be from 1 to 4096, not 4097" },
    { "unreadable reference", { "--reference", "@IN.missing", "-o", "@OUT", "@IN", }, 1,
      "gwy-localscan: cannot read @IN.missing: no such file" },
    { "reference not SPM data", { "--reference", "@CSV:0", "-o", "@OUT", "@IN", }, 1,
      "gwy-localscan: cannot read @CSV: *" },
    { "no such reference channel", { "--reference", "@IN:7", "-o", "@OUT", "@IN", }, 1,
      "gwy-localscan: @IN has no channel 7 (its channels: 0, 1, 2)" },
    { "reference is the image", { "--reference", ":0", "-o", "@OUT", "@IN", }, 1,
      "gwy-localscan: the reference @IN channel 0 is the image itself: "
      "name another channel with --reference FILE:ID" },
    { "reference of another size", { "--reference", ":2", "-o", "@OUT", "@IN", }, 1,
      "gwy-localscan: the reference @IN channel 2 (80 x 160 px, *" },
    { "more stripes than rows", { "--reference", ":1", "--stripes", "161", "-o", "@OUT", "@IN", }, 1,
      "gwy-localscan: 161 stripes do not fit the 160 rows of the image @IN channel 0" },
    { "stripes no whole number", { "--reference", ":1", "--stripes", "2.5", "-o", "@OUT", "@IN", }, 2,
      "gwy-localscan: --stripes must be a whole number from 1 to 4096, not '2.5'" },
    /* Space around a number is no part of it: past the parsing, the
     * registration itself answers. */
    { "stripes with space around", { "--reference", ":1", "--stripes", " 4 ", "-o", "@OUT", "@IN", }, 1,
      "gwy-localscan: no stripe of @IN channel 0 matched the reference @IN channel 1" },
    { "stripes of one row", { "--reference", ":1", "--stripes", "81", "-o", "@OUT", "@IN", }, 1,
      "gwy-localscan: 81 stripes of the 160 rows of the image @IN channel 0 leave stripes of one row, "
      "which cannot be registered: give at most 80" },
    { "nothing matches", { "--reference", ":1", "-o", "@OUT", "@IN", }, 1,
      "gwy-localscan: no stripe of @IN channel 0 matched the reference @IN channel 1" },
    { "no reference channel of that title", { "--reference", ":Nothing", "-o", "@OUT", "@IN", }, 1,
      "gwy-localscan: @IN has no channel titled 'Nothing' (its channels: 0 'Drifting', 1 'Noise', 2 'Noise')" },
    { "reference empty", { "--reference", "", "-o", "@OUT", "@IN", }, 2,
      "gwy-localscan: --reference: the file name is empty" },
    { "reference title of two channels", { "--reference", "@IN:Noise", "-o", "@OUT", "@IN", }, 1,
      "gwy-localscan: @IN has 2 channels titled 'Noise' (1, 2): give its id instead" },
    { "title of two channels", { "-c", "Noise", "--reference", ":0", "-o", "@OUT", "@IN", }, 1,
      "gwy-localscan: @IN has 2 channels titled 'Noise' (1, 2): give its id instead" },
    { "masking alone", { "--masking", "ignore", "-o", "@OUT", "@IN", }, 2,
      "gwy-localscan: --masking needs --reference" },
    { "unknown masking", { "--masking", "maybe", "--reference", ":1", "-o", "@OUT", "@IN", }, 2,
      "gwy-localscan: --masking takes exclude, include or ignore, not \"maybe\"" },
};

/* A single image whose channels carry masks that are none (a field of
 * 7 x 9 px on 40 x 30, a container): compensated with every channel of
 * the scan, they are not moved as masks (a container gave criticals and a
 * refusal blaming the image's pixel size), and OUT leaves them out with a
 * warning each.  A channel of the scan too large for arithmetic is
 * refused by its id, not as the image. */
START_TEST(test_single_image_misfit_masks)
{
    GRand *rng = g_rand_new_with_seed(seed + 700);
    GwyDataField *height = random_field(rng, 40, 30, 2e-9, 3e-9), *phase = random_field(rng, 40, 30, 2e-9, 3e-9);
    GwyDataField *small = gwy_data_field_new(7, 9, 7.0, 9.0, TRUE);
    GwyContainer *data = gwy_container_new(), *odd = gwy_container_new(), *out;
    DriftTable *table = random_table(rng, 5, 4, 0);
    gchar *text = drift_table_to_string(table), *input = in_path("masks.gwy"), *output = out_path("masks.gwy");
    ToolRun run;
    gint *ids, i, results = 0;

    add_channel(data, 0, height, "Height", text);
    add_channel(data, 1, phase, "Phase", NULL);
    gwy_container_set_object(data, gwy_app_get_mask_key_for_id(0), odd);
    gwy_container_set_object(data, gwy_app_get_mask_key_for_id(1), small);
    save_gwy(data, input);
    run_tool(&run, (const gchar *const[]){ "--all-channels", "-o", output, input, NULL });
    ck_assert_msg(run.status == 0, "exit %d: %s", run.status, run.err);
    for (i = 0; i < 2; i++) {
        gchar *line = g_strdup_printf("gwy-localscan: warning: the mask of channel %d does not fit the channel "
                                      "and is left out of %s\n", i, output);

        ck_assert_msg(strstr(run.err, line), "no warning of channel %d's mask: %s", i, run.err);
        g_free(line);
    }
    out = load_gwy(output);
    ids = gwy_app_data_browser_get_data_ids(out);
    for (i = 0; ids[i] >= 0; i++) {
        GObject *mask = NULL;

        results += (g_str_has_suffix(localscan_channel_title(out, ids[i]), TITLE_SUFFIX));
        if (gwy_container_gis_object(out, gwy_app_get_mask_key_for_id(ids[i]), &mask))
            ck_assert_msg(GWY_IS_DATA_FIELD(mask) && gwy_data_field_get_xres(GWY_DATA_FIELD(mask)) == 40,
                          "channel %d of OUT has a mask that is none", ids[i]);
    }
    ck_assert_int_eq(results, 2);
    g_free(ids);
    g_object_unref(out);
    tool_run_clear(&run);

    /* The other channel near the largest double. */
    gwy_data_field_set_val(phase, 3, 4, 1.5e308);
    save_gwy(data, input);
    run_tool(&run, (const gchar *const[]){ "--all-channels", "-o", output, input, NULL });
    ck_assert_int_eq(run.status, 1);
    ck_assert_msg(g_str_has_prefix(run.err, "gwy-localscan: the other channel 1 of the scan: ")
                  && strstr(run.err, "holds the value 1.5e+308, beyond 1e+150 in magnitude"), "%s", run.err);
    tool_run_clear(&run);
    g_free(text);
    g_free(input);
    g_free(output);
    drift_table_free(table);
    g_object_unref(small);
    g_object_unref(odd);
    g_object_unref(height);
    g_object_unref(phase);
    g_object_unref(data);
    g_rand_free(rng);
}
END_TEST

/* A series whose middle frame carries a mask of the wrong size (7 x 9 px
 * on 160 x 160): the mask is left out of OUT with a warning, not copied
 * into the file Gwyddion is to open (the hostile-input run found it
 * copied).  Frames: one smooth surface with noise of their own, timed by
 * their metadata. */
START_TEST(test_series_drops_misfit_mask)
{
    GRand *rng = g_rand_new_with_seed(seed + 600);
    gdouble zero[REF_STRIPES] = { 0 };
    gchar *inputs[3], *output = out_path("series.gwy"), *name, start[32];
    GwyContainer *out;
    RefFrames rf;
    ToolRun run;
    gint k, i;

    ref_frames_stripewise(&rf, seed + 601, zero, zero);
    for (k = 0; k < 3; k++) {
        GwyContainer *data = gwy_container_new(), *meta;
        GwyDataField *field = gwy_data_field_duplicate(rf.reference);
        gdouble *d = gwy_data_field_get_data(field);

        for (i = 0; i < REF_SIZE*REF_SIZE; i++)
            d[i] += 0.01*gwy_data_field_get_rms(rf.reference)*g_rand_double_range(rng, -1.0, 1.0);
        add_channel(data, 0, field, "Height", NULL);
        meta = channel_meta(data, 0, TRUE);
        gwy_container_set_const_string_by_name(meta, "Line time (s)", (const guchar*)"0.01");
        gwy_container_set_const_string_by_name(meta, "Slow scan", (const guchar*)"down");
        g_snprintf(start, sizeof(start), "%d", 2*k);
        gwy_container_set_string_by_name(meta, "Frame start (s)", (const guchar*)g_strdup(start));
        if (k == 1) {
            GwyDataField *mask = gwy_data_field_new(7, 9, 7.0, 9.0, TRUE);

            gwy_container_set_object(data, gwy_app_get_mask_key_for_id(0), mask);
            g_object_unref(mask);
        }
        name = g_strdup_printf("frame%d.gwy", k);
        inputs[k] = in_path(name);
        save_gwy(data, inputs[k]);
        g_free(name);
        g_object_unref(field);
        g_object_unref(data);
    }
    run_tool(&run, (const gchar *const[]){ "series", "-o", output, inputs[0], inputs[1], inputs[2], NULL });
    ck_assert_msg(run.status == 0, "series failed: %s", run.err);
    ck_assert_msg(strstr(run.err, "frame1.gwy: the mask of channel 0 does not fit the channel and is left out"),
                  "no warning of the mask: %s", run.err);
    out = load_gwy(output);
    for (k = 0; k < 3; k++) {
        GObject *mask;

        if (gwy_container_gis_object(out, gwy_app_get_mask_key_for_id(k), &mask))
            ck_assert_msg(gwy_data_field_get_xres(GWY_DATA_FIELD(mask)) == REF_SIZE,
                          "channel %d of OUT has a mask of %d px across", k,
                          gwy_data_field_get_xres(GWY_DATA_FIELD(mask)));
        g_free(inputs[k]);
    }
    g_object_unref(out);
    tool_run_clear(&run);
    ref_frames_clear(&rf);
    g_free(output);
    g_rand_free(rng);
}
END_TEST

START_TEST(test_reference_errors)
{
    const ReferenceErrorCase *ec = reference_error_cases + _i;
    ErrorFiles files;
    ToolRun run;

    files.input = reference_error_input();
    files.csv = in_path("drift.csv");
    files.output = out_path("out.gwy");
    write_text(files.csv, GOOD_TABLE);
    run_failing_case(&run, run_tool_tmpdir, "reference error case", ec->name,
                     ec->args, ec->status, ec->message, &files);
    ck_assert_str_eq(run.out, "");
    tool_run_clear(&run);
    error_files_clear(&files);
}
END_TEST

/************************************************************************
 * -m continuous on simscan's files: timing from their metadata
 ************************************************************************/

/* Seeds tried in order until enough had every local scan on its own
 * particle (one that measured a neighbour may make continuous mode lose to
 * paper mode: the trajectory's robustness, not the timing). */
#define SIMSCAN_SEEDS_TRIED 12
#define SIMSCAN_SEEDS_JUDGED 3
#define GOOD_STRIPE_PX 0.5
/* Measured 0.64-0.76 on such seeds (1-24, both cases); 2.0 scanning up
 * with the wrong timing. */
#define CONTINUOUS_VS_PAPER 0.85

static const SimscanFileCase *const simscan_cases[] = { &simscan_file_default, &simscan_file_up };

/* The stripe each "continuous compensation leaves it out" warning of
 * stderr names, in order, -1 after the last. */
static gint*
left_out_stripes(const gchar *err)
{
    gchar **lines = g_strsplit(err, "\n", -1);
    const gchar *at;
    gint *stripes = g_new(gint, g_strv_length(lines) + 1), n = 0, i;

    for (i = 0; lines[i]; i++) {
        if (strstr(lines[i], "continuous compensation leaves it out")
            && (at = strstr(lines[i], ": stripe ")))
            stripes[n++] = atoi(at + strlen(": stripe "));
    }
    stripes[n] = -1;
    g_strfreev(lines);
    return stripes;
}

/* Success, stderr empty but for warnings of local scans left out. */
static void
assert_only_left_out_warnings(const ToolRun *run)
{
    gchar **lines = g_strsplit(run->err, "\n", -1);
    gint i;

    ck_assert_msg(run->status == 0, "gwy-localscan failed with status %d: %s", run->status, run->err);
    for (i = 0; lines[i]; i++) {
        ck_assert_msg(!*lines[i] || strstr(lines[i], "continuous compensation leaves it out"),
                      "unexpected on stderr: %s", lines[i]);
    }
    g_strfreev(lines);
}

/* Runs gwy-localscan in a mode; the loaded output, or NULL when the tool
 * refused (its one line in *message). */
static GwyContainer*
run_simscan_mode(const gchar *input, const gchar *mode, gchar **message)
{
    gchar *output = out_path(mode), *title;
    GwyContainer *out = NULL;
    ToolRun run;

    run_tool(&run, (const gchar *const[]){ "-m", mode, "--interpolation", SIMSCAN_KERNEL_NAME,
                                           "-o", output, input, NULL });
    if (run.status == 0) {
        assert_only_left_out_warnings(&run);
        out = load_gwy(output);
        title = g_strconcat(get_string(out, "/0/data/title"), TITLE_SUFFIX, NULL);
        ck_assert_str_eq(get_string(out, "/2/data/title"), title);
        g_free(title);
        g_unlink(output);
    }
    else
        assert_failure(&run, 1, "gwy-localscan: *");
    *message = g_strdup(run.err);
    tool_run_clear(&run);
    g_free(output);
    return out;
}

/* Equal but for continuous compensation's rounding, which depends on the
 * buffers' alignment (2e-14 of the range seen); a wrong timing moves a good
 * fraction of the range. */
static gboolean
fields_equal_to_rounding(GwyDataField *a, GwyDataField *b)
{
    gint xres = gwy_data_field_get_xres(a), yres = gwy_data_field_get_yres(a), i;
    const gdouble *da = gwy_data_field_get_data_const(a), *db = gwy_data_field_get_data_const(b);
    gdouble range = gwy_data_field_get_max(b) - gwy_data_field_get_min(b), worst = 0.0;

    if (xres != gwy_data_field_get_xres(b) || yres != gwy_data_field_get_yres(b))
        return FALSE;
    for (i = 0; i < xres*yres; i++)
        worst = fmax(worst, fabs(da[i] - db[i]));
    return worst <= 1e-9*range;
}

/* The continuous result is continuous_compensate_table()'s with the timing
 * simscan was told; the input's metadata gives exactly that timing. */
static void
check_simscan_timing(const SimscanFileCase *fcase, guint32 seed, GwyContainer *in, GwyContainer *out)
{
    GwyDataField *expected;
    ScanTiming told, found;

    simscan_file_timing(fcase, get_field(in, gwy_app_get_data_key_for_id(0)), &told);
    ck_assert_int_eq(localscan_channel_scan_timing(in, 0, !fcase->direction, &found),
                     LOCALSCAN_TIMING_LINE_TIME | LOCALSCAN_TIMING_DIRECTION | LOCALSCAN_TIMING_FRAME_START);
    ck_assert_msg(found.line_time == told.line_time && found.direction == told.direction
                  && found.frame_start == 0.0,
                  "%s, seed %u: read %g s, direction %d, frame start %g s", fcase->name, seed,
                  found.line_time, found.direction, found.frame_start);
    expected = simscan_file_expected_continuous(in, &told, SIMSCAN_KERNEL);
    ck_assert_msg((expected != NULL) == (out != NULL), "%s, seed %u: the tool %s, the expected result %s",
                  fcase->name, seed, out ? "succeeded" : "failed", expected ? "exists" : "does not");
    if (expected) {
        ck_assert_msg(fields_equal_to_rounding(get_field(out, gwy_app_get_data_key_for_id(2)), expected),
                      "%s, seed %u: the result is not continuous mode's with simscan's timing",
                      fcase->name, seed);
        g_object_unref(expected);
    }
}

/* A local scan named as left out lies well off the truth: it measured a
 * neighbouring particle (its neighbours' scans within a few tenths of a
 * pixel, the trajectory near them); one that far off is named.  The seeds
 * the loop reaches named 7 scans (scanning up, seeds 2-5), 5.3-14.9 px
 * off, and no other. */
#define LEFT_OUT_TRUTH_MIN_PX 1.0
#define NAMED_TRUTH_MIN_PX 3.0

static void
check_left_out_named(const SimscanFileCase *fcase, guint32 seed, GwyContainer *in,
                     const DriftTable *table, const gchar *err)
{
    GwyDataField *field = get_field(in, gwy_app_get_data_key_for_id(0));
    gint *stripes = left_out_stripes(err), i, s;
    gdouble e;

    for (i = 0; stripes[i] >= 0; i++) {
        ck_assert_msg(stripes[i] < table->n_stripes, "%s", err);
        e = simscan_file_stripe_error_px(fcase, table, field, stripes[i]);
        printf("test-gwy-localscan: %s, simscan seed %u: stripe %d left out, %.2f px off the truth\n",
               fcase->name, seed, stripes[i], e);
        ck_assert_msg(e > LEFT_OUT_TRUTH_MIN_PX, "%s, simscan seed %u: stripe %d left out, %g px off the truth",
                      fcase->name, seed, stripes[i], e);
    }
    for (s = 0; s < table->n_stripes; s++) {
        e = simscan_file_stripe_error_px(fcase, table, field, s);
        for (i = 0; stripes[i] >= 0 && stripes[i] != s; i++)
            ;
        ck_assert_msg(!(e > NAMED_TRUTH_MIN_PX) || stripes[i] == s,
                      "%s, simscan seed %u: stripe %d, %g px off the truth, not named: %s",
                      fcase->name, seed, s, e, err);
    }
    g_free(stripes);
}

/* Judged against the truth channel shifted to continuous mode's reference
 * time (paper mode shows each stripe at its own local scan, all within
 * 4 s of it: 0.05 px of drift). */
static gboolean
judge_simscan_seed(const SimscanFileCase *fcase, guint32 seed, const gchar *input)
{
    GwyContainer *in = load_gwy(input), *continuous, *paper;
    DriftTable *table = localscan_channel_stored_table(in, 0, NULL);
    gdouble worst, t_ref, rms_paper, rms_continuous;
    gchar *message;
    gboolean judged = FALSE;

    ck_assert(table);
    continuous = run_simscan_mode(input, "continuous", &message);
    check_simscan_timing(fcase, seed, in, continuous);
    if (continuous)
        check_left_out_named(fcase, seed, in, table, message);
    worst = simscan_file_worst_stripe_px(fcase, table, get_field(in, gwy_app_get_data_key_for_id(0)));
    if (worst > GOOD_STRIPE_PX || !continuous) {
        printf("test-gwy-localscan: %s, simscan seed %u: a local scan is %.2f px off, not judged %s\n",
               fcase->name, seed, worst, message);
    }
    else {
        g_free(message);
        paper = run_simscan_mode(input, "paper", &message);
        ck_assert_msg(paper, "%s", message);
        t_ref = simscan_file_reference_time(table);
        rms_paper = simscan_file_truth_rms(fcase, paper, 2, t_ref);
        rms_continuous = simscan_file_truth_rms(fcase, continuous, 2, t_ref);
        printf("test-gwy-localscan: %s, simscan seed %u: RMS against the truth at %.1f s: paper %.3f nm, "
               "continuous %.3f nm (%.2f of paper)\n", fcase->name, seed, t_ref, 1e9*rms_paper,
               1e9*rms_continuous, rms_continuous/rms_paper);
        ck_assert_msg(rms_continuous < CONTINUOUS_VS_PAPER*rms_paper,
                      "%s, simscan seed %u: continuous %g nm RMS, paper %g nm", fcase->name, seed,
                      1e9*rms_continuous, 1e9*rms_paper);
        g_object_unref(paper);
        judged = TRUE;
    }
    g_free(message);
    if (continuous)
        g_object_unref(continuous);
    drift_table_free(table);
    g_object_unref(in);
    return judged;
}

START_TEST(test_continuous_simscan_files)
{
    const SimscanFileCase *fcase = simscan_cases[_i];
    gchar *input = in_path("simscan.gwy");
    GError *error = NULL;
    gint judged = 0;
    guint32 seed;

    for (seed = 1; seed <= SIMSCAN_SEEDS_TRIED && judged < SIMSCAN_SEEDS_JUDGED; seed++) {
        ck_assert_msg(simscan_file_write(fcase, seed, input, &error), "%s", error ? error->message : "");
        judged += judge_simscan_seed(fcase, seed, input);
    }
    ck_assert_msg(judged == SIMSCAN_SEEDS_JUDGED, "%s: only %d of simscan seeds 1-%d had every local scan "
                  "on its particle", fcase->name, judged, SIMSCAN_SEEDS_TRIED);
    g_free(input);
}
END_TEST

static Suite*
gwy_localscan_suite(void)
{
    Suite *suite = suite_create("gwy-localscan");
    gchar *measured;
    TCase *tc;

    tc = tcase_create("results");
    tcase_add_checked_fixture(tc, setup_scratch, teardown_scratch);
    tcase_add_test(tc, test_stored_table_first_channel);
    tcase_add_test(tc, test_channel_option);
    tcase_add_test(tc, test_channel_by_title);
    tcase_add_test(tc, test_no_double_correction);
    tcase_add_test(tc, test_all_channels);
    tcase_add_loop_test(tc, test_table_file_physical_units, 0, G_N_ELEMENTS(unit_names));
    tcase_add_loop_test(tc, test_random_cases, 0, N_RANDOM_CASES);
    tcase_add_test(tc, test_write_drift);
    tcase_add_test(tc, test_write_drift_failure_keeps_old_output);
    tcase_add_test(tc, test_user_settings_do_not_leak);
    if ((measured = test_measured_file("test-gwy-localscan", NANOSCOPE_INPUT,
                                       "test_nanoscope_input")))
        tcase_add_test(tc, test_nanoscope_input);
    g_free(measured);
    tcase_add_test(tc, test_continuous_mode_accepts_fractions);
    tcase_add_test(tc, test_continuous_gross_error_named);
    tcase_add_loop_test(tc, test_continuous_timing_options, 0, G_N_ELEMENTS(timing_cases));
    suite_add_tcase(suite, tc);

    tc = tcase_create("continuous on simscan files");
    tcase_add_checked_fixture(tc, setup_scratch, teardown_scratch);
    tcase_add_loop_test(tc, test_continuous_simscan_files, 0, G_N_ELEMENTS(simscan_cases));
    suite_add_tcase(suite, tc);

    tc = tcase_create("reference registration");
    tcase_add_checked_fixture(tc, setup_scratch, teardown_scratch);
    tcase_add_test(tc, test_reference_two_files);
    tcase_add_test(tc, test_reference_masked_hole);
    tcase_add_loop_test(tc, test_reference_same_file, 0, 4);
    tcase_add_test(tc, test_reference_continuous);
    tcase_add_test(tc, test_reference_continuous_names_jumped_stripe);
    tcase_add_loop_test(tc, test_reference_errors, 0, G_N_ELEMENTS(reference_error_cases));
    tcase_add_test(tc, test_series_drops_misfit_mask);
    tcase_add_test(tc, test_single_image_misfit_masks);
    suite_add_tcase(suite, tc);

    tc = tcase_create("command line and errors");
    tcase_add_checked_fixture(tc, setup_scratch, teardown_scratch);
    tcase_add_test(tc, test_help_lists_options);
    tcase_add_test(tc, test_german_messages);
    tcase_add_test(tc, test_core_messages_translated);
    tcase_add_loop_test(tc, test_error_exit, 0, G_N_ELEMENTS(error_cases));
    tcase_add_test(tc, test_error_no_channel);
    tcase_add_test(tc, test_error_module);
    tcase_add_test(tc, test_error_output_not_writable);
    suite_add_tcase(suite, tc);

    return suite;
}

int
main(void)
{
    gint status;

    seed = test_seed_from_env("test-gwy-localscan");
    if (!g_file_test(TOOL_PATH, G_FILE_TEST_IS_EXECUTABLE)) {
        printf("FAILED: %s is not built\n", TOOL_PATH);
        return 1;
    }
    gwy_app_init_nongui("enable-threads", FALSE, NULL);

    status = test_run_suite(gwy_localscan_suite());
    gwy_app_settings_free();
    return status;
}
