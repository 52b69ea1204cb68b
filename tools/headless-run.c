/*
 *  Headless Gwyddion for batch tools: load a file, pick a channel, run a
 *  process function the way a pygwy script does, save the result as .gwy
 *  without ever leaving a partial file.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <errno.h>
#include <stdlib.h>
#include <unistd.h>
#include <string.h>
#include <sys/stat.h>
#include <glib/gstdio.h>
#include <libgwyddion/gwymacros.h>
#include <libgwymodule/gwymodule.h>
#include <app/gwyapp.h>
#include "headless-run.h"

#undef _
#define _(s) dgettext(GETTEXT_PACKAGE, s)

/* Gwyddion's native file format module. */
#define GWY_NATIVE_SAVER "gwyfile"

GQuark
headless_run_error_quark(void)
{
    return g_quark_from_static_string("headless-run-error-quark");
}

static gchar*
module_name_of_file(const gchar *module_file)
{
    gchar *name = g_path_get_basename(module_file);
    gchar *dot = strchr(name, '.');
    gchar *lower;

    if (dot)
        *dot = '\0';
    lower = g_ascii_strdown(name, -1);
    g_free(name);
    return lower;
}

gboolean
headless_run_init(const gchar *module_file, GError **error)
{
    const GwyModuleInfo *info;
    GError *err = NULL;
    gchar *name;

    if (module_file) {
        /* Blocking only affects folder scans; the explicit registration
         * below still loads the file. */
        name = module_name_of_file(module_file);
        gwy_module_disable_registration(name);
        g_free(name);
    }
    gwy_app_init_nongui("enable-threads", FALSE, NULL);
    if (!module_file)
        return TRUE;

    if (!g_file_test(module_file, G_FILE_TEST_IS_REGULAR)) {
        g_set_error(error, HEADLESS_RUN_ERROR, HEADLESS_RUN_ERROR_MODULE,
                    _("cannot load module %s: no such file"), module_file);
        return FALSE;
    }
    info = gwy_module_register_module(module_file, &err);
    if (!info) {
        g_set_error(error, HEADLESS_RUN_ERROR, HEADLESS_RUN_ERROR_MODULE,
                    _("cannot load module %s: %s"), module_file,
                    err ? err->message : _("unknown error"));
        g_clear_error(&err);
        return FALSE;
    }
    return TRUE;
}

gboolean
headless_run_require_function(const gchar *funcname,
                              const gchar *extra_dir,
                              GError **error)
{
    const gchar *dirs[2] = { extra_dir, NULL };

    if (!gwy_process_func_exists(funcname) && extra_dir && *extra_dir)
        gwy_module_register_modules(dirs);
    if (gwy_process_func_exists(funcname))
        return TRUE;

    g_set_error(error, HEADLESS_RUN_ERROR, HEADLESS_RUN_ERROR_MODULE,
                _("Gwyddion has no process function %s: the localscan module "
                  "is not installed (install it, or set LOCALSCAN_MODULE to "
                  "its file)"), funcname);
    return FALSE;
}

GwyContainer*
headless_run_load(const gchar *filename, GError **error)
{
    GwyContainer *data;
    GError *err = NULL;

    if (g_file_test(filename, G_FILE_TEST_IS_DIR)) {
        g_set_error(error, HEADLESS_RUN_ERROR, HEADLESS_RUN_ERROR_LOAD,
                    _("cannot read %s: it is a directory"), filename);
        return NULL;
    }
    if (!g_file_test(filename, G_FILE_TEST_IS_REGULAR)) {
        g_set_error(error, HEADLESS_RUN_ERROR, HEADLESS_RUN_ERROR_LOAD,
                    _("cannot read %s: no such file"), filename);
        return NULL;
    }
    data = gwy_file_load(filename, GWY_RUN_NONINTERACTIVE, &err);
    if (!data) {
        g_set_error(error, HEADLESS_RUN_ERROR, HEADLESS_RUN_ERROR_LOAD,
                    _("cannot read %s: %s"), filename,
                    err ? err->message : _("not a file Gwyddion can read"));
        g_clear_error(&err);
    }
    return data;
}

static gint
compare_ids(gconstpointer a, gconstpointer b)
{
    gint ia = *(const gint*)a, ib = *(const gint*)b;

    return (ia > ib) - (ia < ib);
}

gint*
headless_run_channel_ids(GwyContainer *data)
{
    gint *ids = gwy_app_data_browser_get_data_ids(data);
    guint n = 0;

    while (ids[n] != -1)
        n++;
    qsort(ids, n, sizeof(gint), compare_ids);
    return ids;
}

gboolean
headless_run_has_channel(GwyContainer *data, gint id)
{
    GObject *object;

    if (id < 0)
        return FALSE;
    object = NULL;
    return (gwy_container_gis_object(data, gwy_app_get_data_key_for_id(id),
                                     &object)
            && GWY_IS_DATA_FIELD(object));
}

static gint
first_new_id(const gint *before, const gint *after)
{
    guint i, j;

    for (j = 0; after[j] != -1; j++) {
        for (i = 0; before[i] != -1 && before[i] != after[j]; i++)
            ;
        if (before[i] == -1)
            return after[j];
    }
    return -1;
}

/* Without a main window a process function reports its errors with
 * g_printerr(); they are collected so that a failure is one message. */
static GString *function_output = NULL;

static void
collect_function_output(const gchar *text)
{
    g_string_append(function_output, text);
}

gint
headless_run_process(GwyContainer *data, gint id, const gchar *funcname,
                     GError **error)
{
    gint *before, *after;
    GPrintFunc printerr;
    gint newid;

    before = headless_run_channel_ids(data);
    gwy_app_data_browser_add(data);
    gwy_app_data_browser_select_data_field(data, id);
    function_output = g_string_new(NULL);
    printerr = g_set_printerr_handler(collect_function_output);
    gwy_process_func_run(funcname, data, GWY_RUN_IMMEDIATE);
    g_set_printerr_handler(printerr);
    after = headless_run_channel_ids(data);
    gwy_app_data_browser_remove(data);

    newid = first_new_id(before, after);
    g_free(before);
    g_free(after);
    g_strstrip(function_output->str);
    if (newid < 0 && *function_output->str) {
        g_set_error(error, HEADLESS_RUN_ERROR, HEADLESS_RUN_ERROR_RUN,
                    "%s", function_output->str);
    }
    else if (newid < 0) {
        g_set_error(error, HEADLESS_RUN_ERROR, HEADLESS_RUN_ERROR_RUN,
                    _("process function %s created no new channel"),
                    funcname);
    }
    else if (*function_output->str)
        g_printerr("%s\n", function_output->str);
    g_string_free(function_output, TRUE);
    function_output = NULL;
    return newid;
}

/* mkstemp() creates 0600 files; the result should get the usual mode. */
static void
give_default_permissions(const gchar *filename)
{
    mode_t mask = umask(0);

    umask(mask);
    g_chmod(filename, 0666 & ~mask);
}

static void
set_save_error(GError **error, const gchar *filename, const gchar *reason)
{
    g_set_error(error, HEADLESS_RUN_ERROR, HEADLESS_RUN_ERROR_SAVE,
                _("cannot write %s: %s"), filename, reason);
}

/* An empty temporary file beside filename (same folder, so a rename puts it
 * in place atomically), with the usual permissions; NULL on failure. */
static gchar*
make_temp_beside(const gchar *filename, GError **error)
{
    gchar *dir = g_path_get_dirname(filename), *base = g_path_get_basename(filename);
    gchar *tmpl = g_strconcat(".", base, ".XXXXXX.tmp", NULL);
    gchar *tmpname = g_build_filename(dir, tmpl, NULL);
    gint fd = g_mkstemp(tmpname);

    if (fd < 0) {
        set_save_error(error, filename, g_strerror(errno));
        g_free(tmpname);
        tmpname = NULL;
    }
    else {
        close(fd);
        give_default_permissions(tmpname);
    }
    g_free(tmpl);
    g_free(base);
    g_free(dir);
    return tmpname;
}

gchar*
headless_run_save_gwy_temp(GwyContainer *data, const gchar *filename, GError **error)
{
    GError *err = NULL;
    gchar *tmpname;

    if (!(tmpname = make_temp_beside(filename, error)))
        return NULL;
    if (!gwy_file_func_run_save(GWY_NATIVE_SAVER, data, tmpname, GWY_RUN_NONINTERACTIVE, &err)) {
        set_save_error(error, filename, err ? err->message : _("the .gwy writer failed"));
        g_clear_error(&err);
        g_unlink(tmpname);
        g_free(tmpname);
        return NULL;
    }
    return tmpname;
}

gchar*
headless_run_write_text_temp(const gchar *text, const gchar *filename, GError **error)
{
    GError *err = NULL;
    gchar *tmpname;

    if (!(tmpname = make_temp_beside(filename, error)))
        return NULL;
    if (!g_file_set_contents(tmpname, text, -1, &err)) {
        set_save_error(error, filename, err->message);
        g_clear_error(&err);
        g_unlink(tmpname);
        g_free(tmpname);
        return NULL;
    }
    /* g_file_set_contents() replaced the file with a private one. */
    give_default_permissions(tmpname);
    return tmpname;
}

/* A second name for an existing file, so it can be put back; NULL when
 * there is no file (or no hard links on this file system). */
static gchar*
keep_old_file(const gchar *filename)
{
    gchar *backup;

    if (!g_file_test(filename, G_FILE_TEST_EXISTS))
        return NULL;
    if (!(backup = make_temp_beside(filename, NULL)))
        return NULL;
    g_unlink(backup);
    if (link(filename, backup) != 0) {
        g_free(backup);
        return NULL;
    }
    return backup;
}

/* Undoes the first n renames of a commit: the older file back, or none. */
static void
restore_old_files(const gchar *const *finals, gchar **backups, guint n)
{
    guint i;

    for (i = 0; i < n; i++) {
        if (backups[i])
            g_rename(backups[i], finals[i]);
        else
            g_unlink(finals[i]);
    }
}

gboolean
headless_run_commit(gchar **temps, const gchar *const *finals, guint n, GError **error)
{
    gchar **backups = g_new0(gchar*, n);
    gboolean ok = TRUE;
    guint i, done;

    for (i = 0; i < n; i++)
        backups[i] = keep_old_file(finals[i]);
    for (done = 0; done < n; done++) {
        if (g_rename(temps[done], finals[done]) != 0) {
            set_save_error(error, finals[done], g_strerror(errno));
            restore_old_files(finals, backups, done);
            ok = FALSE;
            break;
        }
    }
    for (i = 0; i < n; i++) {
        if (!ok && i >= done)
            g_unlink(temps[i]);
        if (ok && backups[i])
            g_unlink(backups[i]);
        g_free(backups[i]);
    }
    g_free(backups);
    return ok;
}

gboolean
headless_run_save_gwy(GwyContainer *data, const gchar *filename, GError **error)
{
    gchar *tmpname = headless_run_save_gwy_temp(data, filename, error);
    gboolean ok;

    if (!tmpname)
        return FALSE;
    ok = headless_run_commit(&tmpname, &filename, 1, error);
    g_free(tmpname);
    return ok;
}
