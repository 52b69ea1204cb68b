/*
 *  Options naming a series' frames and their timing.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <string.h>
#include <math.h>
#include "quoted-input.h"
#include "localscan-params.h"
#include "series-options.h"
#include "localscan-intl.h"
#include "option-parse.h"

void
series_args_add_entries(GOptionContext *context, SeriesArgs *args)
{
    GOptionEntry entries[] = {
        { "line-time", 0, 0, G_OPTION_ARG_STRING, &args->line_time,
          N_("Seconds per scan line, trace and retrace together (default: "
             "the metadata)"), N_("S") },
        { "frame-times", 0, 0, G_OPTION_ARG_STRING, &args->frame_times,
          N_("Start time of each frame, seconds (default: the metadata)"),
          N_("T0,T1,...") },
        { "direction", 0, 0, G_OPTION_ARG_STRING, &args->direction,
          N_("Slow-scan direction (default: the metadata, else down)"),
          N_("down|up") },
        { "channel", 'c', 0, G_OPTION_ARG_FILENAME, &args->channel,
          N_("Channel id or title of the frames (a one-file series: the "
             "title followed by a number matches too)"), N_("ID|TITLE") },
        { "channels", 0, 0, G_OPTION_ARG_STRING, &args->channels,
          N_("Channels of a one-file series that are the frames: ids in "
             "order, or a range"), N_("ID,ID,...|FIRST-LAST") },
        { "keep-duplicates", 0, 0, G_OPTION_ARG_NONE, &args->keep_duplicates,
          N_("Keep frames whose data are identical"), NULL },
        { NULL, 0, 0, 0, NULL, NULL, NULL },
    };

    g_option_context_add_main_entries(context, entries, GETTEXT_PACKAGE);
}

static gboolean
refuse(const gchar *option, const gchar *text, const gchar *what,
       GError **error)
{
    gchar *quoted = quoted_input_excerpt(text, -1);

    g_set_error(error, G_OPTION_ERROR, G_OPTION_ERROR_BAD_VALUE,
                "--%s: '%s' %s", option, quoted, what);
    g_free(quoted);
    return FALSE;
}

gboolean
series_options_parse_seconds(const gchar *option, const gchar *text,
                             gdouble min, gdouble max, gdouble *value,
                             GError **error)
{
    gchar *quoted;
    gdouble v;

    if (!option_parse_number(text, &v) || v < min || v > max) {
        quoted = quoted_input_excerpt(text, -1);
        g_set_error(error, G_OPTION_ERROR, G_OPTION_ERROR_BAD_VALUE,
                    _("%s must be a number of seconds from %g to %g, not '%s'"),
                    option, min, max, quoted);
        g_free(quoted);
        return FALSE;
    }
    *value = v;
    return TRUE;
}

gboolean
series_options_parse_direction(const gchar *text, gint *direction,
                               GError **error)
{
    gchar *quoted;

    if (g_ascii_strcasecmp(text, "down") == 0)
        *direction = SCAN_DIRECTION_DOWN;
    else if (g_ascii_strcasecmp(text, "up") == 0)
        *direction = SCAN_DIRECTION_UP;
    else {
        quoted = quoted_input_excerpt(text, -1);
        g_set_error(error, G_OPTION_ERROR, G_OPTION_ERROR_BAD_VALUE,
                    _("unknown direction '%s' (known: down, up)"), quoted);
        g_free(quoted);
        return FALSE;
    }
    return TRUE;
}

static gboolean
parse_frame_times(const gchar *text, FrameSeriesOptions *options,
                  GError **error)
{
    gchar **parts = g_strsplit(text, ",", -1);
    gint i, n = g_strv_length(parts);

    options->frame_times = g_new(gdouble, MAX(n, 1));
    options->n_frame_times = n;
    for (i = 0; i < n; i++) {
        if (!series_options_parse_seconds("--frame-times", parts[i],
                                          LOCALSCAN_FRAME_START_MIN,
                                          LOCALSCAN_FRAME_START_MAX,
                                          options->frame_times + i, error)) {
            g_strfreev(parts);
            return FALSE;
        }
    }
    g_strfreev(parts);
    return TRUE;
}

static gboolean
parse_channel_id(const gchar *text, gint *id)
{
    guint64 v;

    if (!g_ascii_string_to_unsigned(text, 10, 0, G_MAXINT, &v, NULL))
        return FALSE;
    *id = (gint)v;
    return TRUE;
}

/* An id listed twice is one scan taken as two frames, refused as a file
 * named twice is: it was dropped as identical to itself, or with
 * --keep-duplicates kept as two frames (with --frame-times) or refused as
 * out of time order with itself (times from the metadata). */
static gboolean
refuse_repeated_id(const gint *ids, gint n, GError **error)
{
    GHashTable *first_frame = g_hash_table_new(g_direct_hash, g_direct_equal);
    gpointer first;
    gboolean ok = TRUE;
    gint i;

    for (i = 0; i < n && ok; i++) {
        if (g_hash_table_lookup_extended(first_frame, GINT_TO_POINTER(ids[i]), NULL, &first)) {
            g_set_error(error, G_OPTION_ERROR, G_OPTION_ERROR_BAD_VALUE,
                        _("--channels: channel %d is given twice, as frames %d and %d: "
                          "one scan cannot be two frames"), ids[i], GPOINTER_TO_INT(first), i);
            ok = FALSE;
        }
        else
            g_hash_table_insert(first_frame, GINT_TO_POINTER(ids[i]), GINT_TO_POINTER(i));
    }
    g_hash_table_destroy(first_frame);
    return ok;
}

/* "FIRST-LAST" is a range (channels missing inside it are skipped), else a
 * comma-separated list of ids, each of which must exist. */
static gboolean
parse_channels(const gchar *text, FrameSeriesOptions *options,
               GError **error)
{
    const gchar *dash = strchr(text, '-');
    gchar **parts;
    gint *ids, i, n;

    if (dash && !strchr(text, ',')) {
        gchar *first = g_strndup(text, dash - text);
        gboolean ok = (parse_channel_id(first, &options->first_id)
                       && parse_channel_id(dash + 1, &options->last_id)
                       && options->first_id <= options->last_id);

        g_free(first);
        if (!ok)
            return refuse("channels", text,
                          _("is not a range FIRST-LAST of channel ids"),
                          error);
        return TRUE;
    }
    parts = g_strsplit(text, ",", -1);
    n = g_strv_length(parts);
    if (!n) {
        g_strfreev(parts);
        return refuse("channels", text,
                      _("is not a list of channel ids (0,2,4) or a range "
                        "(0-6)"), error);
    }
    ids = g_new(gint, MAX(n, 1));
    for (i = 0; i < n; i++) {
        if (!parse_channel_id(parts[i], ids + i)) {
            g_strfreev(parts);
            g_free(ids);
            return refuse("channels", text,
                          _("is not a list of channel ids (0,2,4) or a range "
                            "(0-6)"), error);
        }
    }
    g_strfreev(parts);
    if (!refuse_repeated_id(ids, n, error)) {
        g_free(ids);
        return FALSE;
    }
    options->channel_ids = ids;
    options->n_channel_ids = n;
    return TRUE;
}

gboolean
series_args_to_options(SeriesArgs *args, FrameSeriesOptions *options,
                       GError **error)
{
    gint id;

    frame_series_options_init(options);
    options->keep_duplicates = args->keep_duplicates;
    if (args->line_time
        && !series_options_parse_seconds("--line-time", args->line_time,
                                         LOCALSCAN_LINE_TIME_MIN,
                                         LOCALSCAN_LINE_TIME_MAX,
                                         &options->line_time, error))
        return FALSE;
    if (args->direction
        && !series_options_parse_direction(args->direction,
                                           &options->direction, error))
        return FALSE;
    if (args->frame_times
        && !parse_frame_times(args->frame_times, options, error))
        return FALSE;
    if (args->channels && !parse_channels(args->channels, options, error))
        return FALSE;
    if (!option_value_to_utf8(&args->channel, "-c", error))
        return FALSE;
    /* An empty title matches no channel: said as such, not as a frame's
     * missing channel. */
    if (args->channel && !*args->channel)
        return refuse("channel", args->channel, _("is empty: give a channel's id or title"), error);
    if (args->channel && parse_channel_id(args->channel, &id)) {
        if (args->channels)
            return refuse("channel", args->channel,
                          _("is an id, and --channels names the channels "
                            "already"), error);
        options->channel_ids = g_memdup2(&id, sizeof(gint));
        options->n_channel_ids = 1;
    }
    else
        options->channel = args->channel;
    return TRUE;
}

void
series_args_clear(SeriesArgs *args, FrameSeriesOptions *options)
{
    if (options) {
        g_free(options->frame_times);
        g_free((gint*)options->channel_ids);
        options->frame_times = NULL;
        options->channel_ids = NULL;
    }
    if (!args)
        return;
    g_free(args->line_time);
    g_free(args->frame_times);
    g_free(args->direction);
    g_free(args->channel);
    g_free(args->channels);
    memset(args, 0, sizeof(SeriesArgs));
}
