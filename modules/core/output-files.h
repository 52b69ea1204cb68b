/*
 *  Output files: written to temporary files beside their targets and
 *  renamed only when all are written, all or nothing, and never over an
 *  input or over each other.  The one file writer of simscan, its
 *  subcommands and gwy-localscan.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_OUTPUT_FILES_H
#define LOCALSCAN_OUTPUT_FILES_H

#include <glib.h>

G_BEGIN_DECLS

typedef struct _OutputFiles OutputFiles;

/* A file a command reads or writes, for output_files_check_roles(). */
typedef struct {
    const gchar *role;       /* how messages name it: "--json", "frame" */
    const gchar *filename;   /* NULL: not given */
    gboolean is_input;
} OutputFilesRole;

/* Whether a and b are one file: the same device and inode when both
 * exist, else the same canonical absolute path (symbolic links in the
 * folder resolved). */
gboolean      output_files_same         (const gchar *a,
                                         const gchar *b);

/* Refuses (one line naming both) an output (role, as messages name it)
 * that would be written inside folder, a folder the command reads
 * (folder_role names it: "the truth folder"): a benchmark's scores written
 * over its manifest or a case's truth.  TRUE when either is NULL or the
 * folder does not exist. */
gboolean      output_files_check_outside(const gchar *role,
                                         const gchar *filename,
                                         const gchar *folder,
                                         const gchar *folder_role,
                                         GError **error);

/* For the end of a program's main(): what it printed to the standard
 * output reaches it (flushed; a full disk or a closed pipe is an error
 * like any other), else one line on standard error naming program, and 1.
 * Returns status otherwise. */
gint          output_files_finish_stdout(const gchar *program,
                                         gint status);

/* Whether filename is "-", the name of the standard output for the
 * command lines' text outputs (--json, --trajectory). */
gboolean      output_files_is_stdout    (const gchar *filename);

/* Refuses, naming what[i], a file name names[i] given empty ("-o ''"): a
 * slip of the command line, not a file that cannot be opened.  NULL
 * names were not given. */
gboolean      output_files_check_names_given (const gchar *const *what,
                                              const gchar *const *names,
                                              guint n,
                                              GError **error);

/* An output that exists must be a regular file: a folder, a device or a
 * fifo would be renamed over.  For checking a command line before the
 * work (output_files_add() refuses the same, after it). */
gboolean      output_files_check_kind   (const gchar *filename,
                                         GError **error);

/* Refuses (one line naming both) an output that is the same file as an
 * input or as another output.  Inputs may repeat. */
gboolean      output_files_check_roles  (const OutputFilesRole *roles,
                                         guint n,
                                         GError **error);

OutputFiles*  output_files_new          (void);

/* Checks the target (absent or a regular file, not a target of the set
 * already) and writes data to a temporary file beside it; the target is
 * not touched until output_files_commit(). */
gboolean      output_files_add          (OutputFiles *files,
                                         const gchar *filename,
                                         const guchar *data,
                                         gsize length,
                                         GError **error);

/* For a writer that wants a file name (Gwyddion's file savers): an empty
 * temporary file beside filename, with the usual permissions, for the
 * caller to fill before output_files_commit(); owned by the set.  The
 * target is checked as output_files_add() checks it.  NULL with error set
 * on failure. */
const gchar*  output_files_reserve      (OutputFiles *files,
                                         const gchar *filename,
                                         GError **error);

/* Renames every temporary file over its target.  When one rename fails,
 * those done are undone (replaced files get their old contents back, new
 * ones are removed), so either every target is written or none changed.
 * Call once. */
gboolean      output_files_commit       (OutputFiles *files,
                                         GError **error);

/* Removes the temporary files of a set not committed. */
void          output_files_free         (OutputFiles *files);

/* One file, atomically: a set of one. */
gboolean      output_files_write_one    (const gchar *filename,
                                         const guchar *data,
                                         gsize length,
                                         GError **error);

G_END_DECLS

#endif
