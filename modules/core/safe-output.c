/*
 *  Kill-safe temporary files for outputs.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <errno.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <glib/gstdio.h>
#include "safe-output.h"

/* Outputs being written at once: a command writes a handful, simscan
 * benchmark every file of its cases as one set (over 1600 with --size
 * full); 32 slots left the rest behind when it was killed (hostile-input
 * run).  The handler's pass over them costs nothing. */
#define MAX_REGISTERED 8192

/* Read by the signal handler: slots are set and cleared with single pointer
 * stores, and a string is freed only after its slot was cleared. */
static gchar *volatile registered[MAX_REGISTERED];
static gboolean handlers_installed = FALSE;

static const int caught_signals[] = { SIGTERM, SIGINT, SIGHUP, SIGQUIT };

/* Only async-signal-safe calls: unlink, rmdir, signal, raise. */
static void
remove_registered(int signum)
{
    gint i;

    for (i = MAX_REGISTERED-1; i >= 0; i--) {
        const gchar *path = registered[i];

        if (path && unlink(path) != 0)
            rmdir(path);
    }
    signal(signum, SIG_DFL);
    raise(signum);
}

static void
install_handlers(void)
{
    struct sigaction action;
    struct sigaction old;
    guint i;

    if (handlers_installed)
        return;
    handlers_installed = TRUE;
    memset(&action, 0, sizeof(action));
    action.sa_handler = remove_registered;
    sigemptyset(&action.sa_mask);
    for (i = 0; i < G_N_ELEMENTS(caught_signals); i++)
        sigaddset(&action.sa_mask, caught_signals[i]);
    for (i = 0; i < G_N_ELEMENTS(caught_signals); i++) {
        /* A signal the caller ignores (nohup) stays ignored. */
        if (sigaction(caught_signals[i], NULL, &old) == 0 && old.sa_handler == SIG_IGN)
            continue;
        sigaction(caught_signals[i], &action, NULL);
    }
    /* A file grown past the size limit (ulimit -f) killed the program and
     * left its temporary; ignored, the write fails with EFBIG and the
     * output is given up like any that cannot be written. */
    signal(SIGXFSZ, SIG_IGN);
}

static sigset_t held_before;

/* Blocks the caught signals; *before gets the mask to restore. */
static void
block_caught_signals(sigset_t *before)
{
    sigset_t caught;
    guint i;

    sigemptyset(&caught);
    for (i = 0; i < G_N_ELEMENTS(caught_signals); i++)
        sigaddset(&caught, caught_signals[i]);
    sigprocmask(SIG_BLOCK, &caught, before);
}

void
safe_output_hold_signals(void)
{
    block_caught_signals(&held_before);
}

void
safe_output_release_signals(void)
{
    sigprocmask(SIG_SETMASK, &held_before, NULL);
}

void
safe_output_register(const gchar *path)
{
    gint i;

    install_handlers();
    for (i = 0; i < MAX_REGISTERED; i++) {
        if (!registered[i]) {
            registered[i] = g_strdup(path);
            return;
        }
    }
    /* More outputs than slots: this one is only swept by a later run. */
}

void
safe_output_forget(const gchar *path)
{
    gchar *slot;
    gint i;

    for (i = 0; path && i < MAX_REGISTERED; i++) {
        slot = registered[i];
        if (slot && g_str_equal(slot, path)) {
            registered[i] = NULL;
            g_free(slot);
            return;
        }
    }
}

void
safe_output_discard(const gchar *path)
{
    if (!path)
        return;
    g_unlink(path);
    safe_output_forget(path);
}

gboolean
safe_output_is_temp_name(const gchar *name)
{
    return name[0] == '.' && g_str_has_suffix(name, SAFE_OUTPUT_SUFFIX);
}

/* The PID in ".BASE.ROLEPID.XXXXXX.localscan-tmp" whose prefix up to ROLE
 * is prefix; 0 if name is not such a file. */
static pid_t
temp_owner(const gchar *name, const gchar *prefix)
{
    const gchar *p;
    gchar *end;
    gint64 pid;

    if (!g_str_has_prefix(name, prefix) || !safe_output_is_temp_name(name))
        return 0;
    p = name + strlen(prefix);
    while (*p && !g_ascii_isdigit(*p))
        p++;
    pid = g_ascii_strtoll(p, &end, 10);
    if (end == p || *end != '.' || pid <= 0 || pid > G_MAXINT)
        return 0;
    return (pid_t)pid;
}

static gboolean
run_is_dead(pid_t pid)
{
    return pid != getpid() && kill(pid, 0) != 0 && errno == ESRCH;
}

/* A file name's longest length in bytes on the file systems in use. */
#define NAME_MAX_BYTES 255
/* What a temporary's name adds to the target's base name at most: the
 * dots, the longest role (the tools' are a few letters), the PID, the
 * random part and the suffix. */
#define TEMP_NAME_EXTRA (3 + 16 + 20 + 7 + sizeof(SAFE_OUTPUT_SUFFIX))

/* The target's base name as its temporaries carry it: cut (at a character
 * boundary) where the whole temporary's name would exceed a file name's
 * length, which a valid output name of 235 bytes did ("File name too
 * long"). */
static gchar*
temp_base(const gchar *target)
{
    gchar *base = g_path_get_basename(target);
    gsize most = NAME_MAX_BYTES - TEMP_NAME_EXTRA;

    if (strlen(base) > most) {
        const gchar *end = base + most;

        if (g_utf8_validate(base, -1, NULL))
            end = g_utf8_find_prev_char(base, end + 1);
        base[end - base] = '\0';
    }
    return base;
}

guint
safe_output_sweep(const gchar *target)
{
    gchar *dirname = g_path_get_dirname(target), *base = temp_base(target);
    gchar *prefix = g_strconcat(".", base, ".", NULL), *path;
    const gchar *name;
    guint swept = 0;
    GDir *dir;
    pid_t pid;

    if ((dir = g_dir_open(dirname, 0, NULL))) {
        while ((name = g_dir_read_name(dir))) {
            if ((pid = temp_owner(name, prefix)) && run_is_dead(pid)) {
                path = g_build_filename(dirname, name, NULL);
                swept += (g_unlink(path) == 0);
                g_free(path);
            }
        }
        g_dir_close(dir);
    }
    g_free(prefix);
    g_free(base);
    g_free(dirname);
    return swept;
}

gchar*
safe_output_temp_new(const gchar *target, const gchar *role, gint *fd)
{
    gchar *dir = g_path_get_dirname(target), *base = temp_base(target);
    gchar *name = g_strdup_printf("%s%c.%s.%s%ld.XXXXXX%s", dir, G_DIR_SEPARATOR, base,
                                  role ? role : "", (glong)getpid(), SAFE_OUTPUT_SUFFIX);
    gint saved_errno, tmpfd;
    sigset_t before;

    g_free(dir);
    g_free(base);
    safe_output_sweep(target);
    install_handlers();
    /* A signal between the file's creation and its registration would
     * leave it behind (test-hostile-input, seed 107000003, under load):
     * it waits until the handler knows the file. */
    block_caught_signals(&before);
    if ((tmpfd = g_mkstemp(name)) < 0) {
        saved_errno = errno;
        sigprocmask(SIG_SETMASK, &before, NULL);
        g_free(name);
        errno = saved_errno;
        return NULL;
    }
    safe_output_register(name);
    sigprocmask(SIG_SETMASK, &before, NULL);
    if (fd)
        *fd = tmpfd;
    else
        close(tmpfd);
    return name;
}

gchar*
safe_output_temp_dir_new(const gchar *what)
{
    gchar *tmpl = g_strdup_printf("%s-XXXXXX", what), *dir;
    sigset_t before;

    install_handlers();
    block_caught_signals(&before);
    if ((dir = g_dir_make_tmp(tmpl, NULL)))
        safe_output_register(dir);
    sigprocmask(SIG_SETMASK, &before, NULL);
    g_free(tmpl);
    return dir;
}
