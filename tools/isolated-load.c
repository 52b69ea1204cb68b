/*
 *  A file loaded by Gwyddion's file modules in a child process.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <string.h>
#include <unistd.h>
#include <sys/wait.h>
#ifdef __linux__
#include <sys/prctl.h>
#endif
#include <libgwyddion/gwyddion.h>
#include <libgwymodule/gwymodule-file.h>
#include "isolated-load.h"
#include "file-screening.h"
#include "library-log.h"
#include "localscan-intl.h"

/* The first byte the child writes says what follows. */
#define REPLY_DATA  'D'    /* the serialised container */
#define REPLY_ERROR 'E'    /* the loader's message */

GQuark
isolated_load_error_quark(void)
{
    return g_quark_from_static_string("isolated-load-error-quark");
}

static void
write_all(gint fd, const guint8 *bytes, gsize length)
{
    gssize n;

    while (length) {
        n = write(fd, bytes, length);
        if (n < 0 && errno == EINTR)
            continue;
        if (n <= 0)
            return;
        bytes += n;
        length -= n;
    }
}

/* The child: loads, answers on fd, and leaves without running any exit
 * handler of the parent's (_exit). */
static void G_GNUC_NORETURN
load_in_child(const gchar *filename, gint fd)
{
    GwyContainer *data;
    GError *err = NULL;
    GByteArray *reply = g_byte_array_new();
    guint8 kind;
    gint devnull;

#ifdef __linux__
    /* A tool stopped by a signal takes its loader with it. */
    prctl(PR_SET_PDEATHSIG, SIGKILL);
#endif
    /* What a loader writes straight to stderr (libxml2) is dropped. */
    if (!library_log_verbose() && (devnull = open("/dev/null", O_WRONLY)) >= 0) {
        dup2(devnull, STDERR_FILENO);
        close(devnull);
    }
    data = gwy_file_load(filename, GWY_RUN_NONINTERACTIVE, &err);
    kind = data ? REPLY_DATA : REPLY_ERROR;
    g_byte_array_append(reply, &kind, 1);
    if (data)
        gwy_serializable_serialize(G_OBJECT(data), reply);
    else {
        const gchar *message = (err ? err->message : _("not a file Gwyddion can read"));

        g_byte_array_append(reply, (const guint8*)message, strlen(message));
    }
    write_all(fd, reply->data, reply->len);
    close(fd);
    _exit(0);
}

/* Reads fd to its end into reply; FALSE when the deadline passes first. */
static gboolean
read_reply(gint fd, GByteArray *reply, gint64 deadline)
{
    struct pollfd pfd = { fd, POLLIN, 0 };
    guint8 buf[65536];
    gint64 left;
    gssize n;

    for (;;) {
        left = (deadline - g_get_monotonic_time())/1000;
        if (left <= 0)
            return FALSE;
        if (poll(&pfd, 1, (gint)MIN(left, G_MAXINT)) < 0) {
            if (errno == EINTR)
                continue;
            return TRUE;
        }
        if (!pfd.revents)
            continue;
        n = read(fd, buf, sizeof(buf));
        if (n < 0 && errno == EINTR)
            continue;
        if (n <= 0)
            return TRUE;
        g_byte_array_append(reply, buf, n);
    }
}

static GwyContainer*
decode_reply(const gchar *filename, const GByteArray *reply, gint status, GError **error)
{
    GObject *object;
    gsize pos = 0;

    if (reply->len && reply->data[0] == REPLY_ERROR) {
        g_set_error(error, ISOLATED_LOAD_ERROR, ISOLATED_LOAD_ERROR_LOADER, "%s: %.*s", filename,
                    (gint)MIN(reply->len - 1, 1000), (const gchar*)reply->data + 1);
        return NULL;
    }
    if (!reply->len || reply->data[0] != REPLY_DATA) {
        if (WIFSIGNALED(status))
            g_set_error(error, ISOLATED_LOAD_ERROR, ISOLATED_LOAD_ERROR_CRASHED,
                        _("%s: Gwyddion's loader crashed on it (signal %d): a damaged file"),
                        filename, WTERMSIG(status));
        else
            g_set_error(error, ISOLATED_LOAD_ERROR, ISOLATED_LOAD_ERROR_CRASHED,
                        _("%s: Gwyddion's loader failed on it: a damaged file"), filename);
        return NULL;
    }
    /* Gwyddion's own serialisation of a loaded container: well formed. */
    object = gwy_serializable_deserialize(reply->data + 1, reply->len - 1, &pos);
    if (object && GWY_IS_CONTAINER(object))
        return GWY_CONTAINER(object);
    if (object)
        g_object_unref(object);
    g_set_error(error, ISOLATED_LOAD_ERROR, ISOLATED_LOAD_ERROR_CRASHED,
                _("%s: what Gwyddion's loader read cannot be used"), filename);
    return NULL;
}

/* ISOLATED_LOAD_SECONDS, or fewer from LOCALSCAN_LOAD_SECONDS (tests). */
static gint
load_seconds(void)
{
    const gchar *env = g_getenv("LOCALSCAN_LOAD_SECONDS");
    gint64 v;

    if (env && g_ascii_string_to_signed(env, 10, 1, ISOLATED_LOAD_SECONDS, &v, NULL))
        return (gint)v;
    return ISOLATED_LOAD_SECONDS;
}

GwyContainer*
isolated_load(const gchar *filename, GError **error)
{
    GByteArray *reply;
    GwyContainer *data = NULL;
    gboolean finished;
    gint fds[2], status = 0, seconds = load_seconds();
    pid_t pid;

    if (!file_screening_check(filename, error))
        return NULL;
    if (pipe(fds) != 0 || (pid = fork()) < 0) {
        g_set_error(error, ISOLATED_LOAD_ERROR, ISOLATED_LOAD_ERROR_SYSTEM,
                    _("%s: cannot start the loader: %s"), filename, g_strerror(errno));
        return NULL;
    }
    if (pid == 0) {
        close(fds[0]);
        load_in_child(filename, fds[1]);
    }
    close(fds[1]);
    reply = g_byte_array_new();
    finished = read_reply(fds[0], reply, g_get_monotonic_time() + seconds*G_USEC_PER_SEC);
    close(fds[0]);
    if (!finished)
        kill(pid, SIGKILL);
    while (waitpid(pid, &status, 0) < 0 && errno == EINTR)
        ;
    if (finished)
        data = decode_reply(filename, reply, status, error);
    else {
        g_set_error(error, ISOLATED_LOAD_ERROR, ISOLATED_LOAD_ERROR_TIMEOUT,
                    _("%s: Gwyddion's loader did not finish in %d s: a damaged file"), filename,
                    seconds);
    }
    g_byte_array_free(reply, TRUE);
    return data;
}
