/*
 *  Headless Gwyddion for batch tools: load a file, pick a channel, run a
 *  process function the way a pygwy script does, save the result as .gwy
 *  without ever leaving a partial file.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <glib/gstdio.h>
#include <libgwyddion/gwymacros.h>
#include <libgwymodule/gwymodule.h>
#include <app/gwyapp.h>
#include "headless-run.h"
#include "isolated-load.h"
#include "library-log.h"
#include "localscan-channel.h"
#include "gwy-stream-save.h"

#undef _
#define _(s) dgettext(GETTEXT_PACKAGE, s)

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
    /* Again: Gwyddion may have installed handlers of its own. */
    library_log_capture(g_get_prgname(), library_log_verbose());
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

    /* Screened, then loaded in a child process (isolated-load.h). */
    if (!(data = isolated_load(filename, &err))) {
        g_set_error(error, HEADLESS_RUN_ERROR, HEADLESS_RUN_ERROR_LOAD,
                    _("cannot read %s"), err->message);
        g_clear_error(&err);
    }
    return data;
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

/* What a process function prints with g_printerr() without a main window
 * is its message for a script's user; the tool has the error itself
 * (localscan_run_error_take()) and says it once, so the text is kept from
 * the terminal, shown only with --verbose. */
static void
keep_function_output(const gchar *text)
{
    if (library_log_verbose())
        fputs(text, stderr);
}

gint
headless_run_process(GwyContainer *data, gint id, const gchar *funcname,
                     GError **error)
{
    gint *before, *after;
    GPrintFunc printerr;
    GError *err;
    gint newid;

    before = localscan_channel_ids(data);
    /* Whatever an earlier run left is not this run's error. */
    err = localscan_run_error_take(data);
    g_clear_error(&err);
    gwy_app_data_browser_add(data);
    gwy_app_data_browser_select_data_field(data, id);
    printerr = g_set_printerr_handler(keep_function_output);
    gwy_process_func_run(funcname, data, GWY_RUN_IMMEDIATE);
    g_set_printerr_handler(printerr);
    after = localscan_channel_ids(data);
    gwy_app_data_browser_remove(data);

    newid = first_new_id(before, after);
    g_free(before);
    g_free(after);
    err = localscan_run_error_take(data);
    if (newid < 0 && err) {
        g_propagate_error(error, err);
        err = NULL;
    }
    else if (newid < 0) {
        g_set_error(error, HEADLESS_RUN_ERROR, HEADLESS_RUN_ERROR_RUN,
                    _("process function %s created no new channel"),
                    funcname);
    }
    g_clear_error(&err);
    return newid;
}

static void
set_save_error(GError **error, const gchar *filename, const gchar *reason)
{
    g_set_error(error, HEADLESS_RUN_ERROR, HEADLESS_RUN_ERROR_SAVE,
                _("cannot write %s: %s"), filename, reason);
}

gboolean
headless_run_add_gwy(OutputFiles *files, GwyContainer *data,
                     const gchar *filename, GError **error)
{
    GError *err = NULL;
    const gchar *tmpname;

    if (!(tmpname = output_files_reserve(files, filename, error)))
        return FALSE;
    /* Not Gwyddion's own .gwy writer (file module "gwyfile"), which builds
     * the whole file in memory first (gwy-stream-save.h). */
    if (!gwy_stream_save_as(data, tmpname, filename, &err)) {
        if (err)
            g_set_error_literal(error, HEADLESS_RUN_ERROR, HEADLESS_RUN_ERROR_SAVE, err->message);
        else
            set_save_error(error, filename, _("the .gwy writer failed"));
        g_clear_error(&err);
        return FALSE;
    }
    return TRUE;
}

gboolean
headless_run_add_text(OutputFiles *files, const gchar *text,
                      const gchar *filename, GError **error)
{
    GError *err = NULL;
    const gchar *tmpname;

    if (!(tmpname = output_files_reserve(files, filename, error)))
        return FALSE;
    /* In place: the set renames the temporary file when all are written. */
    if (!g_file_set_contents_full(tmpname, text, -1,
                                  G_FILE_SET_CONTENTS_NONE, 0666, &err)) {
        set_save_error(error, filename, err->message);
        g_clear_error(&err);
        return FALSE;
    }
    return TRUE;
}

gboolean
headless_run_save_gwy(GwyContainer *data, const gchar *filename, GError **error)
{
    OutputFiles *files = output_files_new();
    gboolean ok;

    ok = (headless_run_add_gwy(files, data, filename, error)
          && output_files_commit(files, error));
    output_files_free(files);
    return ok;
}
