/*
 *  Headless Gwyddion for batch tools: load a file, pick a channel, run a
 *  process function the way a pygwy script does, save the result as .gwy
 *  without ever leaving a partial file.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_HEADLESS_RUN_H
#define LOCALSCAN_HEADLESS_RUN_H

#include <glib.h>
#include <libgwyddion/gwycontainer.h>
#include "output-files.h"

G_BEGIN_DECLS

#define HEADLESS_RUN_ERROR headless_run_error_quark()

typedef enum {
    HEADLESS_RUN_ERROR_MODULE,     /* module file unusable, function missing */
    HEADLESS_RUN_ERROR_LOAD,       /* input unreadable */
    HEADLESS_RUN_ERROR_CHANNEL,    /* no channel, or no such channel */
    HEADLESS_RUN_ERROR_RUN,        /* the function produced no new channel */
    HEADLESS_RUN_ERROR_SAVE,       /* output could not be written */
} HeadlessRunError;

GQuark        headless_run_error_quark     (void);

/* Initialises Gwyddion without a display (settings are read, never
 * written).  With module_file, that module is registered explicitly and an
 * installed module of the same name is kept from loading, so a build tree's
 * module cannot be shadowed by an old installed copy. */
gboolean      headless_run_init            (const gchar *module_file,
                                            GError **error);

/* Makes sure process function funcname exists, looking in extra_dir (may be
 * NULL or empty) when Gwyddion's own module folders did not provide it. */
gboolean      headless_run_require_function(const gchar *funcname,
                                            const gchar *extra_dir,
                                            GError **error);

GwyContainer* headless_run_load            (const gchar *filename,
                                            GError **error);

gboolean      headless_run_has_channel     (GwyContainer *data, gint id);

/* Runs funcname on channel id with GWY_RUN_IMMEDIATE and returns the id of
 * the channel it created, or -1 with error set when none appeared: the
 * function's own error when it left one with localscan_run_error_set().
 * What it prints is shown only with --verbose (library-log.h). */
gint          headless_run_process         (GwyContainer *data,
                                            gint id,
                                            const gchar *funcname,
                                            GError **error);

/* Saves data in Gwyddion's native format to a temporary file beside
 * filename and renames it into place only when complete; on failure no
 * file is left behind. */
gboolean      headless_run_save_gwy        (GwyContainer *data,
                                            const gchar *filename,
                                            GError **error);

/* Several output files that appear together or not at all: each is added
 * to a set of output-files.h, written to a temporary file beside its final
 * name, and output_files_commit() renames them all into place (should one
 * rename fail, those done are put back as they were). */
gboolean      headless_run_add_gwy         (OutputFiles *files,
                                            GwyContainer *data,
                                            const gchar *filename,
                                            GError **error);
gboolean      headless_run_add_text        (OutputFiles *files,
                                            const gchar *text,
                                            const gchar *filename,
                                            GError **error);

G_END_DECLS

#endif
