/*
 *  The options that say which frames form a series and when they were
 *  scanned, shared by `gwy-localscan series` and `simscan fit`
 *  (docs/series.md): one parser, one set of messages.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_SERIES_OPTIONS_H
#define LOCALSCAN_SERIES_OPTIONS_H

#include <glib.h>
#include "frame-series.h"

G_BEGIN_DECLS

/* The options as given: text until series_args_to_options() checks it, so
 * that an option given with any value counts as given. */
typedef struct {
    gchar *line_time;
    gchar *frame_times;
    gchar *direction;
    gchar *channel;
    gchar *channels;
    gboolean keep_duplicates;
} SeriesArgs;

/* A whole argument that is a finite number of seconds within [min, max];
 * the message names option ("--line-time"). */
gboolean  series_options_parse_seconds  (const gchar *option,
                                         const gchar *text,
                                         gdouble min,
                                         gdouble max,
                                         gdouble *value,
                                         GError **error);
/* "down" or "up" (any case) as a ScanDirection. */
gboolean  series_options_parse_direction(const gchar *text,
                                         gint *direction,
                                         GError **error);

/* Adds --line-time, --frame-times, --direction, -c/--channel, --channels
 * and --keep-duplicates to the context's main group. */
void      series_args_add_entries (GOptionContext *context,
                                   SeriesArgs *args);

/* Checks the options into options (initialised here); the frame time and
 * channel id arrays belong to options until series_args_clear().  The
 * channel's text, taken as bytes, is made UTF-8 in args
 * (option_value_to_utf8). */
gboolean  series_args_to_options  (SeriesArgs *args,
                                   FrameSeriesOptions *options,
                                   GError **error);

/* Frees what args (may be NULL) and options (may be NULL) hold. */
void      series_args_clear       (SeriesArgs *args,
                                   FrameSeriesOptions *options);

G_END_DECLS

#endif
