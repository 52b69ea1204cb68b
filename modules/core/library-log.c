/*
 *  Messages libraries log kept from the user of a command-line tool.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <stdio.h>
#include "library-log.h"
#include "quoted-input.h"

/* Domains whose libraries set handlers of their own or that log most:
 * a handler per domain wins over the default one. */
static const gchar *const known_domains[] = {
    "GLib", "GLib-GObject", "GLib-GIO", "GModule", "GThread",
    "Gwyddion", "GwyProcess", "GwyDraw", "Gwydgets", "GwyModule", "GwyApp", "Module",
    "Gtk", "Gdk", "GdkPixbuf", "Pango", "Json",
};

/* At most this many are kept, the last always: a loader complaining about
 * every one of a million pixels must not fill memory. */
#define KEPT_MAX 64

static gchar *program_name = NULL;
static gboolean print_them = FALSE;
static gboolean installed = FALSE;
static GPtrArray *kept = NULL;

static void
keep(const gchar *domain, GLogLevelFlags level, const gchar *message)
{
    const gchar *what = (level & G_LOG_LEVEL_CRITICAL) ? "critical"
                        : (level & G_LOG_LEVEL_WARNING) ? "warning"
                        : (level & G_LOG_LEVEL_MESSAGE) ? "message" : "info";
    gchar *line = quoted_input_message_line(message ? message : "");
    gchar *text = g_strdup_printf("%s %s: %s", domain ? domain : "", what, line);

    g_free(line);
    if (print_them)
        fprintf(stderr, "%s: library %s\n", program_name ? program_name : g_get_prgname(), text);
    if (!kept)
        kept = g_ptr_array_new_with_free_func(g_free);
    if (kept->len < KEPT_MAX)
        g_ptr_array_add(kept, text);
    else {
        g_free(g_ptr_array_index(kept, KEPT_MAX - 1));
        g_ptr_array_index(kept, KEPT_MAX - 1) = text;
    }
}

static void
log_handler(const gchar *domain, GLogLevelFlags level, const gchar *message,
            G_GNUC_UNUSED gpointer user_data)
{
    /* Debug output is what G_MESSAGES_DEBUG asked for: left as GLib does. */
    if ((level & G_LOG_LEVEL_DEBUG) && !(level & ~(G_LOG_LEVEL_DEBUG | G_LOG_FLAG_FATAL
                                                  | G_LOG_FLAG_RECURSION))) {
        g_log_default_handler(domain, level, message, NULL);
        return;
    }
    keep(domain, level, message);
}

static GLogWriterOutput
log_writer(GLogLevelFlags level, const GLogField *fields, gsize n_fields,
           G_GNUC_UNUSED gpointer user_data)
{
    const gchar *domain = NULL, *message = NULL;
    gsize i;

    if (level & G_LOG_LEVEL_DEBUG)
        return g_log_writer_default(level, fields, n_fields, NULL);
    for (i = 0; i < n_fields; i++) {
        if (g_str_equal(fields[i].key, "GLIB_DOMAIN") && fields[i].length < 0)
            domain = fields[i].value;
        else if (g_str_equal(fields[i].key, "MESSAGE") && fields[i].length < 0)
            message = fields[i].value;
    }
    keep(domain, level, message);
    return G_LOG_WRITER_HANDLED;
}

void
library_log_capture(const gchar *program, gboolean verbose)
{
    GLogLevelFlags levels = G_LOG_LEVEL_MASK | G_LOG_FLAG_FATAL | G_LOG_FLAG_RECURSION;
    guint i;

    g_free(program_name);
    program_name = g_strdup(program);
    print_them = verbose;
    g_log_set_default_handler(log_handler, NULL);
    for (i = 0; i < G_N_ELEMENTS(known_domains); i++)
        g_log_set_handler(known_domains[i], levels, log_handler, NULL);
    g_log_set_handler(NULL, levels, log_handler, NULL);
    /* The writer can be set once per process. */
    if (!installed) {
        g_log_set_writer_func(log_writer, NULL, NULL);
        installed = TRUE;
    }
}

gboolean
library_log_verbose(void)
{
    return print_them;
}

const gchar*
library_log_last(void)
{
    return (kept && kept->len) ? g_ptr_array_index(kept, kept->len - 1) : NULL;
}

