/*
 *  Output files, all or nothing.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <string.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <glib/gstdio.h>
#include "output-files.h"
#include "safe-output.h"
#include "localscan-intl.h"

typedef struct {
    gchar *filename;
    gchar *tmpname;      /* the new contents until renamed */
    gchar *backup;       /* the replaced file while committing, or NULL */
    gboolean linked;     /* backup is a second link: the target stays */
    gboolean renamed;
} PendingOutput;

struct _OutputFiles {
    GArray *pending;     /* PendingOutput */
    gboolean committed;
};

static void
set_errno_error(GError **error, gint saved_errno, const gchar *filename)
{
    g_set_error(error, G_FILE_ERROR, g_file_error_from_errno(saved_errno),
                _("cannot write %s: %s"), filename, g_strerror(saved_errno));
}

#define LINK_DEPTH_MAX 40

/* Links followed to the file they name, existing or not: an output named
 * by a symbolic link is written where the link points.  Renamed over the
 * link itself, the new file replaced the link and left its target as it
 * was (as root, --json /dev/stdout replaced /dev/stdout).  A link
 * relative to its folder is read there.  A chain too long or a loop is
 * left as named here (followed 40 steps round a loop, it named another);
 * output_files_check_kind() refuses such an output. */
static gchar*
link_target(const gchar *filename)
{
    gchar *path = g_strdup(filename), *target, *dir, *next;
    GStatBuf st;
    gint depth;

    for (depth = 0; ; depth++) {
        if (g_lstat(path, &st) != 0 || !S_ISLNK(st.st_mode))
            return path;
        if (depth == LINK_DEPTH_MAX || !(target = g_file_read_link(path, NULL)))
            break;
        if (g_path_is_absolute(target))
            next = target;
        else {
            dir = g_path_get_dirname(path);
            next = g_build_filename(dir, target, NULL);
            g_free(dir);
            g_free(target);
        }
        g_free(path);
        path = next;
    }
    g_free(path);
    return g_strdup(filename);
}

/* The absolute path a file has or would get, its folder resolved (symbolic
 * links, .., .): a file that does not exist yet has no inode to compare,
 * and "out/../x" and "x" or a symlinked folder's name are one file. */
static gchar*
canonical_path(const gchar *filename)
{
    gchar *cwd = g_get_current_dir();
    /* The folder as written, for the system to resolve: folding ".." by
     * text first goes wrong past a symlinked folder. */
    gchar *written = g_path_is_absolute(filename) ? g_strdup(filename)
                     : g_build_filename(cwd, filename, NULL);
    gchar *absolute = g_canonicalize_filename(filename, NULL);
    gchar *dir = g_path_get_dirname(written);
    gchar *base = g_path_get_basename(written);
    gchar *real = realpath(dir, NULL);
    gchar *path;

    path = real ? g_build_filename(real, base, NULL) : g_strdup(absolute);
    g_free(written);
    g_free(cwd);
    free(real);
    g_free(dir);
    g_free(base);
    g_free(absolute);
    return path;
}

gboolean
output_files_same(const gchar *a, const gchar *b)
{
    GStatBuf sa, sb;
    /* Where each is written: a link to a file not made yet and that file
     * are one output (a link named as --trajectory to the -o file wrote
     * both there, and the .gwy was lost). */
    gchar *ta = link_target(a), *tb = link_target(b);
    gboolean a_exists = (g_stat(ta, &sa) == 0);
    gboolean b_exists = (g_stat(tb, &sb) == 0);
    gchar *ca, *cb;
    gboolean same;

    if (a_exists && b_exists)
        same = (sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino);
    else if (a_exists != b_exists)
        same = FALSE;
    else {
        ca = canonical_path(ta);
        cb = canonical_path(tb);
        same = g_str_equal(ca, cb);
        g_free(ca);
        g_free(cb);
    }
    g_free(ta);
    g_free(tb);
    return same;
}

gboolean
output_files_is_stdout(const gchar *filename)
{
    return filename && strcmp(filename, "-") == 0;
}

gint
output_files_finish_stdout(const gchar *program, gint status)
{
    gint flush_failed, saved_errno;

    errno = 0;
    flush_failed = (fflush(stdout) != 0);
    saved_errno = errno;
    /* `simscan fit ... > /dev/full' lost its JSON with exit status 0.  An
     * earlier write's failure leaves only the stream's error flag, and
     * errno says nothing of it then. */
    if (!flush_failed && !ferror(stdout))
        return status;
    fprintf(stderr, _("%s: cannot write to the standard output: %s\n"), program,
            g_strerror((flush_failed && saved_errno) ? saved_errno : EIO));
    return 1;
}

gboolean
output_files_check_outside(const gchar *role, const gchar *filename, const gchar *folder,
                           const gchar *folder_role, GError **error)
{
    gchar *target, *written, *real_folder, *prefix;
    gboolean inside;

    if (!filename || !folder || !(real_folder = realpath(folder, NULL)))
        return TRUE;
    target = link_target(filename);
    written = canonical_path(target);
    prefix = g_str_has_suffix(real_folder, G_DIR_SEPARATOR_S) ? g_strdup(real_folder)
             : g_strconcat(real_folder, G_DIR_SEPARATOR_S, NULL);
    inside = g_str_has_prefix(written, prefix);
    if (inside)
        g_set_error(error, G_FILE_ERROR, G_FILE_ERROR_EXIST,
                    _("%s %s lies in %s %s: write it elsewhere, that folder is read"),
                    role, filename, folder_role, folder);
    free(real_folder);
    g_free(prefix);
    g_free(written);
    g_free(target);
    return !inside;
}

gboolean
output_files_check_names_given(const gchar *const *what, const gchar *const *names, guint n,
                               GError **error)
{
    guint i;

    for (i = 0; i < n; i++) {
        if (names[i] && !*names[i]) {
            g_set_error(error, G_FILE_ERROR, G_FILE_ERROR_INVAL,
                        _("%s: the file name is empty"), what[i]);
            return FALSE;
        }
    }
    return TRUE;
}

gboolean
output_files_check_kind(const gchar *filename, GError **error)
{
    GStatBuf st;

    if (!filename)
        return TRUE;
    if (g_stat(filename, &st) != 0) {
        /* A loop of links, or a chain longer than the system follows:
         * renamed over, the link named was replaced by a file, and the
         * file at the end of a long chain was left as it was. */
        if (errno == ELOOP) {
            g_set_error(error, G_FILE_ERROR, G_FILE_ERROR_LOOP,
                        _("cannot write %s: its symbolic links loop or are nested too deep"), filename);
            return FALSE;
        }
        return TRUE;
    }
    if (S_ISREG(st.st_mode))
        return TRUE;
    g_set_error(error, G_FILE_ERROR, G_FILE_ERROR_ISDIR,
                S_ISDIR(st.st_mode)
                ? _("cannot write %s: it is a folder")
                : _("cannot write %s: it is not a regular file"),
                filename);
    return FALSE;
}

static void
refuse_same(const OutputFilesRole *output, const OutputFilesRole *other,
            GError **error)
{
    if (other->is_input)
        g_set_error(error, G_FILE_ERROR, G_FILE_ERROR_EXIST,
                    _("%s %s would overwrite the %s %s"),
                    output->role, output->filename,
                    other->role, other->filename);
    else
        g_set_error(error, G_FILE_ERROR, G_FILE_ERROR_EXIST,
                    _("%s %s and %s %s are the same file"),
                    other->role, other->filename,
                    output->role, output->filename);
}

gboolean
output_files_check_roles(const OutputFilesRole *roles, guint n,
                         GError **error)
{
    guint i, j;

    for (i = 0; i < n; i++) {
        if (roles[i].is_input || !roles[i].filename)
            continue;
        for (j = 0; j < n; j++) {
            if (j == i || !roles[j].filename
                || (!roles[j].is_input && j > i))
                continue;
            if (output_files_same(roles[i].filename, roles[j].filename)) {
                refuse_same(roles + i, roles + j, error);
                return FALSE;
            }
        }
    }
    return TRUE;
}

OutputFiles*
output_files_new(void)
{
    OutputFiles *files = g_new0(OutputFiles, 1);

    files->pending = g_array_new(FALSE, TRUE, sizeof(PendingOutput));
    return files;
}

/* A new empty file with a unique name beside filename, removed should the
 * program be stopped (safe-output.h); NULL on failure (errno says why). */
static gchar*
make_temp_beside(const gchar *filename, const gchar *what, gint *fd)
{
    return safe_output_temp_new(filename, what, fd);
}

static gboolean
write_all(gint fd, const guchar *data, gsize length)
{
    gsize done = 0;
    gssize n;
    mode_t mask = umask(0);

    /* mkstemp makes the file private; outputs get the usual permissions. */
    umask(mask);
    if (fchmod(fd, 0666 & ~mask) != 0)
        return FALSE;
    while (done < length) {
        n = write(fd, data + done, length - done);
        if (n < 0 && errno == EINTR)
            continue;
        if (n <= 0)
            return FALSE;
        done += n;
    }
    return TRUE;
}

/* Same target twice in one set: refused, whatever the target is. */
static gboolean
check_new_target(OutputFiles *files, const gchar *filename, GError **error)
{
    guint i;

    for (i = 0; i < files->pending->len; i++) {
        const gchar *other = g_array_index(files->pending, PendingOutput,
                                           i).filename;

        if (output_files_same(other, filename)) {
            g_set_error(error, G_FILE_ERROR, G_FILE_ERROR_EXIST,
                        _("%s and %s are the same file"), other, filename);
            return FALSE;
        }
    }
    return TRUE;
}

static gboolean
check_target(OutputFiles *files, const gchar *filename, GError **error)
{
    return output_files_check_kind(filename, error) && check_new_target(files, filename, error);
}

/* An existing file the user may not write is not replaced: the new
 * contents are renamed over it, which needs only the folder's rights, and
 * a file made read-only (chmod a-w) was replaced by one the user owns,
 * where a plain write is refused.  errno says why when FALSE. */
static gboolean
may_replace(const gchar *target)
{
    /* The effective user's rights, which a write would meet (access()
     * asks for the real user's). */
    if (faccessat(AT_FDCWD, target, W_OK, AT_EACCESS) == 0)
        return TRUE;
    return errno != EACCES && errno != EPERM;
}

/* Adds filename to the set with a new temporary file beside the file it
 * names, open as *fd; NULL with error set on failure. */
static PendingOutput*
add_pending(OutputFiles *files, const gchar *filename, gint *fd,
            GError **error)
{
    PendingOutput p;
    gchar *target = link_target(filename);

    memset(&p, 0, sizeof(p));
    if (!may_replace(target) || !(p.tmpname = make_temp_beside(target, "", fd))) {
        set_errno_error(error, errno, filename);
        g_free(target);
        return NULL;
    }
    p.filename = target;
    g_array_append_val(files->pending, p);
    return &g_array_index(files->pending, PendingOutput,
                          files->pending->len - 1);
}

/* Drops the last pending output, removing its temporary file. */
static void
drop_last_pending(OutputFiles *files)
{
    PendingOutput *p = &g_array_index(files->pending, PendingOutput,
                                      files->pending->len - 1);

    safe_output_discard(p->tmpname);
    g_free(p->tmpname);
    g_free(p->filename);
    g_array_set_size(files->pending, files->pending->len - 1);
}

gboolean
output_files_add(OutputFiles *files, const gchar *filename,
                 const guchar *data, gsize length, GError **error)
{
    gint fd, saved_errno;
    gboolean ok;

    g_return_val_if_fail(!files->committed, FALSE);
    if (!check_target(files, filename, error)
        || !add_pending(files, filename, &fd, error))
        return FALSE;
    ok = write_all(fd, data, length);
    saved_errno = errno;
    if (close(fd) != 0 && ok) {
        ok = FALSE;
        saved_errno = errno;
    }
    if (!ok) {
        set_errno_error(error, saved_errno, filename);
        drop_last_pending(files);
        return FALSE;
    }
    return TRUE;
}

const gchar*
output_files_reserve(OutputFiles *files, const gchar *filename,
                     GError **error)
{
    PendingOutput *p;
    gint fd;
    gboolean ok;

    g_return_val_if_fail(!files->committed, NULL);
    /* A device or a fifo would be renamed over (as root, /dev/null). */
    if (!check_target(files, filename, error)
        || !(p = add_pending(files, filename, &fd, error)))
        return NULL;
    /* Nothing written: only the usual permissions given. */
    ok = write_all(fd, NULL, 0);
    if (close(fd) != 0 || !ok) {
        set_errno_error(error, errno, filename);
        drop_last_pending(files);
        return NULL;
    }
    return p->tmpname;
}

/* Keeps the target's old contents under p->backup: a second link when the
 * file system has them (the target never disappears), else the target
 * moved aside.  A target that became something else than a regular file
 * since it was checked is left alone: the commit fails. */
static gboolean
keep_old_contents(PendingOutput *p)
{
    GStatBuf st;
    gint fd;

    if (g_lstat(p->filename, &st) != 0)
        return TRUE;
    if (S_ISDIR(st.st_mode)) {
        errno = EISDIR;
        return FALSE;
    }
    if (!(p->backup = make_temp_beside(p->filename, "old.", &fd)))
        return FALSE;
    close(fd);
    g_unlink(p->backup);
    if (link(p->filename, p->backup) == 0) {
        p->linked = TRUE;
        return TRUE;
    }
    /* The only copy of the old contents now: a signal must not remove it. */
    safe_output_forget(p->backup);
    if (g_rename(p->filename, p->backup) == 0)
        return TRUE;
    g_free(p->backup);
    p->backup = NULL;
    return FALSE;
}

static gboolean
replace_target(PendingOutput *p, GError **error)
{
    gint saved_errno;

    if (!keep_old_contents(p)) {
        set_errno_error(error, errno, p->filename);
        return FALSE;
    }
    if (g_rename(p->tmpname, p->filename) == 0) {
        safe_output_forget(p->tmpname);
        p->renamed = TRUE;
        return TRUE;
    }
    saved_errno = errno;
    if (p->backup && !p->linked)
        g_rename(p->backup, p->filename);
    else if (p->backup)
        safe_output_discard(p->backup);
    g_free(p->backup);
    p->backup = NULL;
    set_errno_error(error, saved_errno, p->filename);
    return FALSE;
}

static void
undo_replace(PendingOutput *p)
{
    if (p->backup) {
        g_rename(p->backup, p->filename);
        safe_output_forget(p->backup);
    }
    else
        g_unlink(p->filename);
    g_free(p->backup);
    p->backup = NULL;
}

gboolean
output_files_commit(OutputFiles *files, GError **error)
{
    GArray *pending = files->pending;
    gboolean ok = TRUE;
    guint i, n;

    g_return_val_if_fail(!files->committed, FALSE);
    files->committed = TRUE;
    /* A signal meets all outputs in place or none (safe-output.h). */
    safe_output_hold_signals();
    for (n = 0; ok && n < pending->len; n++)
        ok = replace_target(&g_array_index(pending, PendingOutput, n), error);
    for (i = 0; i < n; i++) {
        PendingOutput *p = &g_array_index(pending, PendingOutput, i);

        if (!ok && p->renamed)
            undo_replace(p);
        else if (p->backup) {
            safe_output_discard(p->backup);
            g_free(p->backup);
            p->backup = NULL;
        }
    }
    safe_output_release_signals();
    return ok;
}

void
output_files_free(OutputFiles *files)
{
    guint i;

    if (!files)
        return;
    for (i = 0; i < files->pending->len; i++) {
        PendingOutput *p = &g_array_index(files->pending, PendingOutput, i);

        if (!p->renamed)
            safe_output_discard(p->tmpname);
        g_free(p->tmpname);
        g_free(p->filename);
        g_free(p->backup);
    }
    g_array_free(files->pending, TRUE);
    g_free(files);
}

gboolean
output_files_write_one(const gchar *filename, const guchar *data,
                       gsize length, GError **error)
{
    OutputFiles *files = output_files_new();
    gboolean ok;

    ok = (output_files_add(files, filename, data, length, error)
          && output_files_commit(files, error));
    output_files_free(files);
    return ok;
}
