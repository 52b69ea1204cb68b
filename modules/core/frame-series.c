/*
 *  A time series of frames of one area, with scan timing from metadata or
 *  options.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <string.h>
#include <stdlib.h>
#include <math.h>
#include <libgwyddion/gwyddion.h>
#include <libprocess/gwyprocess.h>
#include "frame-series.h"
#include "scan-timing-meta.h"
#include "localscan-channel.h"
#include "localscan-intl.h"

/* Timing facts read from one channel's metadata; NaN/-1 when absent. */
typedef struct {
    gdouble line_time;
    gdouble start;
    gint direction;
    gboolean start_is_end;   /* the stamp marks the end of the frame */
    gdouble given_start;     /* the frame's time in options->frame_times */
    /* Where the line time or the start is absent though a key of it is
     * there: that key and its value (scan_timing_meta_unusable), so that
     * the refusal says what the file holds; empty otherwise. */
    gchar line_time_seen[256];
    gchar start_seen[256];
} MetaTiming;

GQuark
frame_series_error_quark(void)
{
    return g_quark_from_static_string("frame-series-error-quark");
}

void
frame_series_options_init(FrameSeriesOptions *options)
{
    memset(options, 0, sizeof(FrameSeriesOptions));
    options->line_time = -1.0;
    options->direction = -1;
    options->fallback_direction = -1;
    options->first_id = options->last_id = -1;
}

FrameSeries*
frame_series_new(void)
{
    FrameSeries *series = g_new0(FrameSeries, 1);

    series->notes = g_ptr_array_new_with_free_func(g_free);
    return series;
}

void
frame_series_append(FrameSeries *series, GwyDataField *field,
                    const gchar *label, const ScanTiming *timing)
{
    SeriesFrame *frame;

    series->frames = g_renew(SeriesFrame, series->frames, series->n_frames + 1);
    frame = series->frames + series->n_frames;
    memset(frame, 0, sizeof(SeriesFrame));
    frame->field = g_object_ref(field);
    frame->label = g_strdup(label);
    frame->channel_id = -1;
    frame->absolute_start = NAN;
    if (timing) {
        frame->timing = *timing;
        frame->start_source = frame->line_time_source = FRAME_TIME_OPTION;
        frame->direction_source = FRAME_TIME_OPTION;
    }
    else
        scan_timing_init(&frame->timing, gwy_data_field_get_xres(field),
                         gwy_data_field_get_yres(field), NAN, -1.0,
                         SCAN_DIRECTION_DOWN);
    series->n_frames++;
}

void
frame_series_free(FrameSeries *series)
{
    gint i;

    if (!series)
        return;
    for (i = 0; i < series->n_frames; i++) {
        g_object_unref(series->frames[i].field);
        g_free(series->frames[i].label);
    }
    g_free(series->frames);
    g_ptr_array_free(series->notes, TRUE);
    g_free(series);
}

gdouble
frame_series_dx(const FrameSeries *series)
{
    return gwy_data_field_get_dx(series->frames[0].field);
}

gdouble
frame_series_dy(const FrameSeries *series)
{
    return gwy_data_field_get_dy(series->frames[0].field);
}

static void
keep_unusable(GwyContainer *meta, ScanMetaFound found, ScanMetaFound part, gchar *seen, gsize size)
{
    gchar *text = (found & part) ? NULL : scan_timing_meta_unusable(meta, part);

    /* SCAN_META_SHOWN_CHARS characters and a key fit. */
    g_strlcpy(seen, text ? text : "", size);
    g_free(text);
}

/* The core's reader (scan-timing-meta.h) knows every format's keys,
 * simscan's own among them. */
static void
read_meta_timing(GwyContainer *meta, gint yres, MetaTiming *mt)
{
    ScanMetaTiming timing;
    ScanMetaFound found;

    timing.line_time = timing.frame_start = NAN;
    timing.direction = SCAN_DIRECTION_DOWN;
    timing.start_is_end = FALSE;
    found = scan_timing_meta_read(meta, yres, &timing);
    mt->line_time = (found & SCAN_META_LINE_TIME) ? timing.line_time : NAN;
    mt->start = (found & SCAN_META_FRAME_START) ? timing.frame_start : NAN;
    mt->direction = (found & SCAN_META_DIRECTION) ? (gint)timing.direction : -1;
    mt->start_is_end = (found & SCAN_META_FRAME_START) && timing.start_is_end;
    keep_unusable(meta, found, SCAN_META_LINE_TIME, mt->line_time_seen, sizeof(mt->line_time_seen));
    keep_unusable(meta, found, SCAN_META_FRAME_START, mt->start_seen, sizeof(mt->start_seen));
}

gchar*
frame_series_title_base(const gchar *title)
{
    const gchar *end;

    if (!title)
        return g_strdup("");
    end = title + strlen(title);
    while (end > title && g_ascii_isdigit(end[-1]))
        end--;
    if (end > title + 1 && end < title + strlen(title) && end[-1] == ' ')
        return g_strndup(title, end - 1 - title);
    return g_strdup(title);
}

gboolean
frame_series_title_matches(const gchar *title, const gchar *wanted)
{
    gsize len = strlen(wanted);
    const gchar *p;

    if (!title)
        return FALSE;
    if (strcmp(title, wanted) == 0)
        return TRUE;
    if (strncmp(title, wanted, len) != 0 || title[len] != ' ' || !title[len+1])
        return FALSE;
    for (p = title + len + 1; *p; p++) {
        if (!g_ascii_isdigit(*p))
            return FALSE;
    }
    return TRUE;
}

static gboolean
fields_alike(GwyDataField *a, GwyDataField *b)
{
    if (gwy_data_field_get_xres(a) != gwy_data_field_get_xres(b)
        || gwy_data_field_get_yres(a) != gwy_data_field_get_yres(b))
        return FALSE;
    if (fabs(gwy_data_field_get_dx(a)/gwy_data_field_get_dx(b) - 1.0) > 1e-6
        || fabs(gwy_data_field_get_dy(a)/gwy_data_field_get_dy(b) - 1.0) > 1e-6)
        return FALSE;
    return (gwy_si_unit_equal(gwy_data_field_get_si_unit_z(a),
                              gwy_data_field_get_si_unit_z(b))
            && gwy_si_unit_equal(gwy_data_field_get_si_unit_xy(a),
                                 gwy_data_field_get_si_unit_xy(b)));
}

/* Pixels of a usable size: finite, positive, and not so unlike along the
 * two axes that a blur of one physical size is meaningless.  A file may
 * say anything (a NaN width crashed the blur). */
#define PIXEL_ASPECT_MAX 1000.0

static gboolean
check_pixels(const FrameSeries *series, GError **error)
{
    GwyDataField *field = series->frames[0].field;
    gdouble dx = gwy_data_field_get_dx(field), dy = gwy_data_field_get_dy(field);

    if (isfinite(dx) && isfinite(dy) && dx > 0.0 && dy > 0.0
        && isfinite(gwy_data_field_get_xreal(field))
        && isfinite(gwy_data_field_get_yreal(field))
        && dy/dx <= PIXEL_ASPECT_MAX && dx/dy <= PIXEL_ASPECT_MAX)
        return TRUE;
    g_set_error(error, FRAME_SERIES_ERROR, FRAME_SERIES_ERROR_MISMATCH,
                _("%s: the frame's pixel size (%g by %g) is not usable"),
                series->frames[0].label, dx, dy);
    return FALSE;
}

static gboolean
fields_identical(GwyDataField *a, GwyDataField *b)
{
    gint n = gwy_data_field_get_xres(a)*gwy_data_field_get_yres(a);

    if (!fields_alike(a, b))
        return FALSE;
    return memcmp(gwy_data_field_get_data_const(a),
                  gwy_data_field_get_data_const(b), n*sizeof(gdouble)) == 0;
}

/* Appends one channel as a frame, with its metadata timing. */
static void
append_channel(FrameSeries *series, GwyContainer *data, gint id,
               const gchar *filename, gint file_index, gboolean with_title,
               MetaTiming *mts)
{
    GwyDataField *field = localscan_channel_item(data, id, "data");
    gchar *base = g_path_get_basename(filename);
    const gchar *title = localscan_channel_title(data, id);
    gchar *label;
    MetaTiming *mt = mts + series->n_frames;

    /* An untitled channel is named by its id: two '?' told nothing. */
    if (!with_title)
        label = g_strdup(base);
    else if (title)
        label = g_strdup_printf("%s:%s", base, title);
    else
        label = g_strdup_printf(_("%s channel %d"), base, id);
    frame_series_append(series, field, label, NULL);
    series->frames[series->n_frames-1].channel_id = id;
    series->frames[series->n_frames-1].file_index = file_index;
    read_meta_timing(localscan_channel_item(data, id, "meta"),
                     gwy_data_field_get_yres(field), mt);
    g_free(label);
    g_free(base);
}

/* The lowest channel id, or -1 (the ids come ascending). */
static gint
first_channel_id(GwyContainer *data)
{
    gint *ids = localscan_channel_ids(data), found = ids[0];

    g_free(ids);
    return found;
}

/* The ids of the channels titled wanted exactly, else of those titled
 * wanted and a number (frame_series_title_matches). */
static gint*
titled_channels(GwyContainer *data, const gchar *wanted)
{
    gint *ids = localscan_channel_ids_titled(data, wanted), i, n = 0;

    if (ids[0] != -1)
        return ids;
    g_free(ids);
    ids = localscan_channel_ids(data);
    for (i = 0; ids[i] != -1; i++) {
        if (frame_series_title_matches(localscan_channel_title(data, ids[i]), wanted))
            ids[n++] = ids[i];
    }
    ids[n] = -1;
    return ids;
}

/* The one channel of a file that title names; -1 with error set when none
 * or several do.  Two channels of one title in a file took the lower id
 * silently, where the one-image command refuses the title (docs/cli.md). */
static gint
titled_channel_id(GwyContainer *data, const gchar *filename, const gchar *wanted,
                  GError **error)
{
    gint *ids = titled_channels(data, wanted), n, id = ids[0];
    gchar *list;

    for (n = 0; ids[n] != -1; n++)
        ;
    if (!n)
        g_set_error(error, FRAME_SERIES_ERROR, FRAME_SERIES_ERROR_CHANNEL,
                    _("%s: no channel %s"), filename, wanted);
    else if (n > 1) {
        list = localscan_channel_id_list(ids);
        g_set_error(error, FRAME_SERIES_ERROR, FRAME_SERIES_ERROR_CHANNEL,
                    _("%s: %d channels are titled '%s' (ids %s): give the id"),
                    filename, n, wanted, list);
        g_free(list);
        id = -1;
    }
    g_free(ids);
    return id;
}

static gboolean
has_channel(GwyContainer *data, gint id)
{
    return id >= 0 && localscan_channel_item(data, id, "data") != NULL;
}

/* The channels listed by id, in the order given. */
static gboolean
load_listed_channels(FrameSeries *series, GwyContainer *data,
                     const gchar *filename, const FrameSeriesOptions *options,
                     MetaTiming **mts, GError **error)
{
    GwyDataField *first = NULL, *field;
    gint i, id;

    *mts = g_new0(MetaTiming, options->n_channel_ids + 1);
    for (i = 0; i < options->n_channel_ids; i++) {
        id = options->channel_ids[i];
        if (!has_channel(data, id)) {
            g_set_error(error, FRAME_SERIES_ERROR, FRAME_SERIES_ERROR_CHANNEL,
                        _("%s: no channel %d"), filename, id);
            return FALSE;
        }
        field = localscan_channel_item(data, id, "data");
        if (first && !fields_alike(first, field)) {
            g_set_error(error, FRAME_SERIES_ERROR, FRAME_SERIES_ERROR_MISMATCH,
                        _("%s: channel %d (%s) differs in size, pixel size or unit "
                          "from the first frame"),
                        filename, id, localscan_channel_title(data, id));
            return FALSE;
        }
        first = first ? first : field;
        append_channel(series, data, id, filename, 0, TRUE, *mts);
    }
    return TRUE;
}

/* A range of channels (--channels FIRST-LAST) skips the ids it holds that
 * the file lacks; one that reaches past the file's last channel is said,
 * and one that holds none of them is refused naming its ids (it ran on
 * the channels there were, or said 'found 0'). */
static gboolean
note_range_beyond(FrameSeries *series, const gchar *filename,
                  const FrameSeriesOptions *options, const gint *ids, gint n,
                  gint matched, GError **error)
{
    gint last = n ? ids[n-1] : -1, i;

    if (options->first_id < 0 || options->last_id < 0)
        return TRUE;
    for (i = 0; i < n; i++)
        last = MAX(last, ids[i]);
    if (!matched && !options->channel) {
        g_set_error(error, FRAME_SERIES_ERROR, FRAME_SERIES_ERROR_CHANNEL,
                    _("%s: no channel %d-%d (its last channel is %d)"),
                    filename, options->first_id, options->last_id, last);
        return FALSE;
    }
    if (options->last_id > last)
        g_ptr_array_add(series->notes,
                        g_strdup_printf(_("%s: channels %d-%d of the range "
                                          "%d-%d do not exist"), filename,
                                        MAX(last + 1, options->first_id), options->last_id,
                                        options->first_id, options->last_id));
    return TRUE;
}

/* How many titles the notes list at most. */
#define TITLES_NOTED 4

/* Channels taken as frames because nothing chose them (the series' frames,
 * all of this file), under titles that are not one signal's ("Height"
 * beside "Amplitude" in the same unit, or beside "Height 2"): a file of
 * several signals of one scan, or of two series, whose frames the user
 * should choose.  Said, not refused: a movie's frames may be titled
 * anyhow. */
static void
note_mixed_titles(FrameSeries *series, GwyContainer *data, const gchar *filename)
{
    GPtrArray *bases = g_ptr_array_new_with_free_func(g_free);
    GString *list;
    gchar *base;
    guint i;
    gint k;

    for (k = 0; k < series->n_frames; k++) {
        base = frame_series_title_base(localscan_channel_title(data,
                                                               series->frames[k].channel_id));
        for (i = 0; i < bases->len && strcmp(g_ptr_array_index(bases, i), base) != 0; i++)
            ;
        if (i < bases->len)
            g_free(base);
        else
            g_ptr_array_add(bases, base);
    }
    if (bases->len > 1) {
        list = g_string_new(NULL);
        for (i = 0; i < MIN(bases->len, TITLES_NOTED); i++)
            g_string_append_printf(list, i ? ", '%s'" : "'%s'",
                                   (const gchar*)g_ptr_array_index(bases, i));
        if (bases->len > TITLES_NOTED)
            g_string_append_printf(list, _(" and %u more"), bases->len - TITLES_NOTED);
        g_ptr_array_add(series->notes,
                        g_strdup_printf(_("%s: the frames are channels of %u different "
                                          "titles (%s), taken as one series in channel "
                                          "order; if they are different signals, choose "
                                          "the frames by title or id"),
                                        filename, bases->len, list->str));
        g_string_free(list, TRUE);
    }
    g_ptr_array_free(bases, TRUE);
}

static gboolean
load_channels_of_one_file(FrameSeries *series, GwyContainer *data,
                          const gchar *filename,
                          const FrameSeriesOptions *options,
                          MetaTiming **mts, GError **error)
{
    gint *ids = localscan_channel_ids(data);
    GwyDataField *first = NULL;
    gint i, n, matched = 0;
    gboolean ok, chosen = (options->channel || options->first_id >= 0
                           || options->last_id >= 0);

    for (n = 0; ids[n] >= 0; n++)
        ;
    *mts = g_new0(MetaTiming, n + 1);
    for (i = 0; i < n; i++) {
        GwyDataField *field = localscan_channel_item(data, ids[i], "data");

        if (options->first_id >= 0 && ids[i] < options->first_id)
            continue;
        if (options->last_id >= 0 && ids[i] > options->last_id)
            continue;
        if (options->channel
            && !frame_series_title_matches(localscan_channel_title(data, ids[i]),
                              options->channel))
            continue;
        matched++;
        if (!first)
            first = field;
        else if (!fields_alike(first, field)) {
            /* Channels not chosen by name or id that are no frames of the
             * series (another scan in the file) are passed over, said. */
            if (!chosen) {
                series->n_passed_over++;
                g_ptr_array_add(series->notes,
                                g_strdup_printf(_("%s: channel %d (%s) is "
                                                  "not a frame of the series: "
                                                  "other size, pixel size or "
                                                  "unit"), filename, ids[i],
                                                localscan_channel_title(data, ids[i])));
                continue;
            }
            g_set_error(error, FRAME_SERIES_ERROR, FRAME_SERIES_ERROR_MISMATCH,
                        _("%s: channel %d (%s) differs in size, pixel size or unit "
                          "from the first frame"),
                        filename, ids[i],
                        localscan_channel_title(data, ids[i]));
            g_free(ids);
            return FALSE;
        }
        append_channel(series, data, ids[i], filename, 0, TRUE, *mts);
    }
    if (options->channel && !matched) {
        g_set_error(error, FRAME_SERIES_ERROR, FRAME_SERIES_ERROR_CHANNEL,
                    _("%s: no channel %s"), filename, options->channel);
        g_free(ids);
        return FALSE;
    }
    if (!chosen)
        note_mixed_titles(series, data, filename);
    ok = note_range_beyond(series, filename, options, ids, n, matched, error);
    g_free(ids);
    return ok;
}

static gboolean
load_one_channel_per_file(FrameSeries *series, gchar **filenames, gint n_files,
                          GwyContainer **datas,
                          const FrameSeriesOptions *options,
                          MetaTiming **mts, GError **error)
{
    gint k, id;

    *mts = g_new0(MetaTiming, MAX(n_files, 1));
    for (k = 0; k < n_files; k++) {
        if (options->n_channel_ids) {
            id = options->channel_ids[0];
            if (!has_channel(datas[k], id)) {
                g_set_error(error, FRAME_SERIES_ERROR,
                            FRAME_SERIES_ERROR_CHANNEL,
                            _("%s: no channel %d"), filenames[k], id);
                return FALSE;
            }
        }
        else if (options->channel) {
            if ((id = titled_channel_id(datas[k], filenames[k], options->channel, error)) < 0)
                return FALSE;
        }
        else
            id = first_channel_id(datas[k]);
        if (id < 0) {
            g_set_error(error, FRAME_SERIES_ERROR, FRAME_SERIES_ERROR_CHANNEL,
                        _("%s: no channel %s"), filenames[k], "at all");
            return FALSE;
        }
        if (k && !fields_alike(series->frames[0].field,
                               localscan_channel_item(datas[k], id, "data"))) {
            g_set_error(error, FRAME_SERIES_ERROR, FRAME_SERIES_ERROR_MISMATCH,
                        _("%s: the frame differs in size, pixel size or unit "
                          "from %s"), filenames[k], filenames[0]);
            return FALSE;
        }
        append_channel(series, datas[k], id, filenames[k], k, FALSE, *mts);
    }
    return TRUE;
}

/* Removes frame i, keeping the metadata timings in step. */
static void
remove_frame(FrameSeries *series, MetaTiming *mts, gint i)
{
    g_object_unref(series->frames[i].field);
    g_free(series->frames[i].label);
    memmove(series->frames + i, series->frames + i+1,
            (series->n_frames - i-1)*sizeof(SeriesFrame));
    memmove(mts + i, mts + i+1, (series->n_frames - i-1)*sizeof(MetaTiming));
    series->n_frames--;
}

static void
drop_duplicates(FrameSeries *series, MetaTiming *mts)
{
    gint i, j;

    for (i = 1; i < series->n_frames; i++) {
        for (j = 0; j < i; j++) {
            if (fields_identical(series->frames[j].field,
                                 series->frames[i].field))
                break;
        }
        if (j < i) {
            g_ptr_array_add(series->notes,
                            g_strdup_printf(_("dropped %s: identical to %s"),
                                            series->frames[i].label,
                                            series->frames[j].label));
            remove_frame(series, mts, i);
            i--;
        }
    }
}

typedef enum {
    HINT_LINE_TIME,
    HINT_DIRECTION,
    HINT_FRAME_TIMES,
} TimingHint;

/* What the user can do where the metadata lacks some timing, in the words
 * of the front end that asked. */
static const gchar*
timing_hint(const FrameSeriesOptions *options, TimingHint which)
{
    static const gchar *const command[] = {
        N_("give --line-time"), N_("give --direction"), N_("give --frame-times"),
    };
    static const gchar *const dialog[] = {
        N_("set the line time"), N_("set the slow scan direction"),
        N_("set the frame interval"),
    };

    return _(options->hints_for_dialog ? dialog[which] : command[which]);
}

static gboolean
assign_line_times(FrameSeries *series, const MetaTiming *mts,
                  const FrameSeriesOptions *options, GError **error)
{
    gint i, assumed = 0;

    for (i = 0; i < series->n_frames; i++) {
        SeriesFrame *frame = series->frames + i;

        if (options->line_time > 0.0) {
            frame->timing.line_time = options->line_time;
            frame->line_time_source = FRAME_TIME_OPTION;
        }
        else if (isfinite(mts[i].line_time)) {
            frame->timing.line_time = mts[i].line_time;
            frame->line_time_source = FRAME_TIME_METADATA;
        }
        else if (*mts[i].line_time_seen) {
            g_set_error(error, FRAME_SERIES_ERROR, FRAME_SERIES_ERROR_TIMING,
                        _("%s: the metadata gives no usable line time (%s); %s"),
                        frame->label, mts[i].line_time_seen, timing_hint(options, HINT_LINE_TIME));
            return FALSE;
        }
        else {
            g_set_error(error, FRAME_SERIES_ERROR, FRAME_SERIES_ERROR_TIMING,
                        _("%s: the line time is not in the metadata; %s"),
                        frame->label, timing_hint(options, HINT_LINE_TIME));
            return FALSE;
        }
        if (options->direction >= 0) {
            frame->timing.direction = options->direction;
            frame->direction_source = FRAME_TIME_OPTION;
        }
        else if (mts[i].direction >= 0) {
            frame->timing.direction = mts[i].direction;
            frame->direction_source = FRAME_TIME_METADATA;
        }
        else if (options->fallback_direction >= 0) {
            frame->timing.direction = options->fallback_direction;
            frame->direction_source = FRAME_TIME_OPTION;
        }
        else {
            frame->timing.direction = SCAN_DIRECTION_DOWN;
            assumed++;
        }
    }
    /* Scanned up, a frame's lines run backwards in time: an assumption
     * that deserves a word. */
    if (assumed)
        g_ptr_array_add(series->notes,
                        g_strdup_printf(_("the slow-scan direction of %d of "
                                          "%d frames is not in the metadata: "
                                          "taken as down (%s)"),
                                        assumed, series->n_frames,
                                        timing_hint(options, HINT_DIRECTION)));
    return TRUE;
}

/* Time stamps from different clocks (one file's relative frame time,
 * another's date, two uptime counters) put frames days to decades apart;
 * a series whose frames lie more than CLOCK_GAP_FRAMES frame times and
 * CLOCK_GAP_SECONDS apart is refused, not fitted.  Fast frames taken
 * minutes apart (a time lapse of 64 ms frames, 100 s apart) lie thousands
 * of frame times apart on one clock: by frame times alone they were
 * refused.  A day covers a night's time lapse. */
#define CLOCK_GAP_FRAMES 1000.0
#define CLOCK_GAP_SECONDS 86400.0

static gboolean
check_one_clock(const FrameSeries *series, const FrameSeriesOptions *options,
                GError **error)
{
    gdouble first = G_MAXDOUBLE, last = -G_MAXDOUBLE, longest = 0.0;
    gint i, a = 0, b = 0;

    for (i = 0; i < series->n_frames; i++) {
        const ScanTiming *timing = &series->frames[i].timing;

        longest = MAX(longest, timing->yres*timing->line_time);
        if (timing->frame_start < first) {
            first = timing->frame_start;
            a = i;
        }
        if (timing->frame_start > last) {
            last = timing->frame_start;
            b = i;
        }
    }
    if (last - first <= MAX(CLOCK_GAP_FRAMES*series->n_frames*longest, CLOCK_GAP_SECONDS))
        return TRUE;
    g_set_error(error, FRAME_SERIES_ERROR, FRAME_SERIES_ERROR_TIMING,
                _("%s and %s start %.3g s apart in the metadata: their time "
                  "stamps cannot come from one clock; %s"),
                series->frames[a].label, series->frames[b].label,
                last - first, timing_hint(options, HINT_FRAME_TIMES));
    return FALSE;
}

/* Frames overlapping by more than this fraction of a frame are refused:
 * a clock's rounding (a second of a 209 s FastScan frame) explains less. */
#define MAX_OVERLAP_FRACTION 0.5

static gboolean
assign_start_times(FrameSeries *series, const MetaTiming *mts,
                   const FrameSeriesOptions *options, GError **error)
{
    gint i, n = series->n_frames;
    gdouble t0 = NAN;

    if (options->frame_times) {
        for (i = 0; i < n; i++) {
            series->frames[i].timing.frame_start = mts[i].given_start;
            series->frames[i].start_source = FRAME_TIME_OPTION;
        }
    }
    else {
        for (i = 0; i < n; i++) {
            SeriesFrame *frame = series->frames + i;
            gdouble t = mts[i].start;

            if (!isfinite(t) && *mts[i].start_seen) {
                g_set_error(error, FRAME_SERIES_ERROR, FRAME_SERIES_ERROR_TIMING,
                            _("%s: the metadata gives no usable start time of the frame (%s); %s"),
                            frame->label, mts[i].start_seen, timing_hint(options, HINT_FRAME_TIMES));
                return FALSE;
            }
            if (!isfinite(t)) {
                g_set_error(error, FRAME_SERIES_ERROR,
                            FRAME_SERIES_ERROR_TIMING,
                            _("%s: the frame's start time is not in the "
                              "metadata; %s"), frame->label,
                            timing_hint(options, HINT_FRAME_TIMES));
                return FALSE;
            }
            if (mts[i].start_is_end)
                t -= frame->timing.yres*frame->timing.line_time;
            frame->absolute_start = t;
            frame->start_source = FRAME_TIME_METADATA;
            if (!isfinite(t0) || t < t0)
                t0 = t;
        }
        for (i = 0; i < n; i++)
            series->frames[i].timing.frame_start
                = series->frames[i].absolute_start - t0;
        if (!check_one_clock(series, options, error))
            return FALSE;
        if (mts[0].start_is_end)
            g_ptr_array_add(series->notes,
                            g_strdup(_("time stamps taken as the end of each "
                                       "frame")));
    }
    for (i = 1; i < n; i++) {
        const SeriesFrame *prev = series->frames + i-1;
        const SeriesFrame *frame = series->frames + i;
        gdouble overlap = (scan_timing_frame_end(&prev->timing)
                           - frame->timing.frame_start);

        /* One file's channels that start together are signals of one scan
         * (a FastScan file's ZSensor, AmplitudeActual and Phase), which
         * 'not in time order' left the user to work out. */
        if (frame->timing.frame_start == prev->timing.frame_start
            && frame->file_index == prev->file_index) {
            g_set_error(error, FRAME_SERIES_ERROR, FRAME_SERIES_ERROR_TIMING,
                        _("%s and %s were scanned at the same time: they are "
                          "channels of one scan, not frames of a series; choose "
                          "the frames by title or id"), prev->label, frame->label);
            return FALSE;
        }
        if (frame->timing.frame_start <= prev->timing.frame_start) {
            g_set_error(error, FRAME_SERIES_ERROR, FRAME_SERIES_ERROR_TIMING,
                        _("%s starts at %g s, not after %s (%g s): frames "
                          "must be in time order"),
                        frame->label, frame->timing.frame_start,
                        prev->label, prev->timing.frame_start);
            return FALSE;
        }
        /* Time stamps rounded or taken a little early: tolerated, said.
         * Beyond half a frame no rounding explains it: the times or the
         * line time are wrong (0,10,20 s given for frames of 64 s). */
        if (overlap > MAX_OVERLAP_FRACTION*(scan_timing_frame_end(&prev->timing)
                                            - prev->timing.frame_start)) {
            g_set_error(error, FRAME_SERIES_ERROR, FRAME_SERIES_ERROR_TIMING,
                        _("%s starts %.3g s before %s ends, which takes "
                          "%.3g s to scan: frames of one scanner cannot "
                          "overlap; check the frame times and the line time"),
                        frame->label, overlap, prev->label,
                        scan_timing_frame_end(&prev->timing) - prev->timing.frame_start);
            return FALSE;
        }
        if (overlap > 1e-3*prev->timing.line_time)
            g_ptr_array_add(series->notes,
                            g_strdup_printf(_("%s starts %.3g s before %s "
                                              "ends"), frame->label, overlap,
                                            prev->label));
    }
    return TRUE;
}

/* The times --frame-times gives, one for each frame as given: a frame
 * dropped as a duplicate takes its own with it (counted after the drop,
 * three times for three files, one a copy, were 'three times for two
 * frames'). */
static gboolean
take_given_times(FrameSeries *series, MetaTiming *mts,
                 const FrameSeriesOptions *options, GError **error)
{
    gint i;

    if (!options->frame_times)
        return TRUE;
    if (options->n_frame_times != series->n_frames) {
        g_set_error(error, FRAME_SERIES_ERROR, FRAME_SERIES_ERROR_TIMING,
                    _("--frame-times gives %d times for %d frames"),
                    options->n_frame_times, series->n_frames);
        return FALSE;
    }
    for (i = 0; i < series->n_frames; i++)
        mts[i].given_start = options->frame_times[i];
    return TRUE;
}

/* Fewer than two frames: said with what else the file held, so that the
 * user knows where the frames went (an AFM-IR file of maps of several
 * sizes gave 'found 1' and nothing more). */
static void
refuse_too_few(const FrameSeries *series, const gchar *filename, gint n_dropped,
               GError **error)
{
    GString *why = g_string_new(NULL);

    g_string_printf(why, _("%s: a series needs at least two distinct frames, found %d"),
                    filename, series->n_frames);
    if (series->n_passed_over)
        g_string_append_printf(why, dngettext(GETTEXT_PACKAGE,
                                              "; %d channel was passed over (another size, "
                                              "pixel size or unit than the first)",
                                              "; %d channels were passed over (another size, "
                                              "pixel size or unit than the first)",
                                              series->n_passed_over),
                               series->n_passed_over);
    if (n_dropped)
        g_string_append_printf(why, dngettext(GETTEXT_PACKAGE,
                                              "; %d frame was dropped as a duplicate",
                                              "; %d frames were dropped as duplicates",
                                              n_dropped),
                               n_dropped);
    if (series->n_passed_over || n_dropped)
        g_string_append(why, _(": choose the frames by title or id"));
    g_set_error_literal(error, FRAME_SERIES_ERROR, FRAME_SERIES_ERROR_CHANNEL, why->str);
    g_string_free(why, TRUE);
}

FrameSeries*
frame_series_from_files(GwyContainer **datas, gchar **filenames,
                        gint n_files, const FrameSeriesOptions *options,
                        GError **error)
{
    FrameSeriesOptions defaults;
    FrameSeries *series = frame_series_new();
    MetaTiming *mts = NULL;
    gboolean ok;
    gint n_loaded;

    if (!options) {
        frame_series_options_init(&defaults);
        options = &defaults;
    }
    if (n_files < 1) {
        g_set_error(error, FRAME_SERIES_ERROR, FRAME_SERIES_ERROR_CHANNEL,
                    _("no frames given"));
        goto fail;
    }
    if (n_files == 1 && options->n_channel_ids)
        ok = load_listed_channels(series, datas[0], filenames[0], options,
                                  &mts, error);
    else if (n_files == 1)
        ok = load_channels_of_one_file(series, datas[0], filenames[0],
                                       options, &mts, error);
    else
        ok = load_one_channel_per_file(series, filenames, n_files, datas,
                                       options, &mts, error);
    if (!ok || !take_given_times(series, mts, options, error))
        goto fail;
    n_loaded = series->n_frames;
    if (!options->keep_duplicates)
        drop_duplicates(series, mts);
    if (series->n_frames < 2) {
        refuse_too_few(series, filenames[0], n_loaded - series->n_frames, error);
        goto fail;
    }
    if (!check_pixels(series, error)
        || !assign_line_times(series, mts, options, error)
        || !assign_start_times(series, mts, options, error))
        goto fail;
    g_free(mts);
    return series;

fail:
    g_free(mts);
    frame_series_free(series);
    return NULL;
}
