/*
 *  A time series of frames of one area: from several files or from the
 *  channels of one file, with each frame's scan timing
 *  (docs/conventions.md) taken from the file metadata or from options.  Loading the
 *  files needs Gwyddion's file modules, outside this GTK-free core:
 *  tools/frame-series-load.h does it and calls frame_series_from_files.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_FRAME_SERIES_H
#define LOCALSCAN_FRAME_SERIES_H

#include <glib.h>
#include <libgwyddion/gwycontainer.h>
#include <libprocess/datafield.h>
#include "scan-timing.h"

G_BEGIN_DECLS

#define FRAME_SERIES_ERROR frame_series_error_quark()

typedef enum {
    FRAME_SERIES_ERROR_LOAD,      /* a file Gwyddion cannot read */
    FRAME_SERIES_ERROR_CHANNEL,   /* no such channel, or too few frames */
    FRAME_SERIES_ERROR_MISMATCH,  /* frames of different size or pixels */
    FRAME_SERIES_ERROR_TIMING,    /* timing unknown or inconsistent */
} FrameSeriesError;

/* Where a frame's timing came from. */
typedef enum {
    FRAME_TIME_UNKNOWN = 0,
    FRAME_TIME_METADATA,
    FRAME_TIME_OPTION,
} FrameTimeSource;

typedef struct {
    GwyDataField *field;          /* a reference is held */
    gchar *label;                 /* "file" or "file:channel title" */
    gint channel_id;
    gint file_index;              /* the file it came from */
    ScanTiming timing;            /* frame_start relative to the first frame */
    gdouble absolute_start;       /* s, metadata clock (NaN when unknown) */
    FrameTimeSource start_source;
    FrameTimeSource line_time_source;
    FrameTimeSource direction_source;
} SeriesFrame;

typedef struct {
    gint n_frames;
    SeriesFrame *frames;          /* in time order */
    GPtrArray *notes;             /* human-readable remarks (dropped duplicates,
                                     assumptions made), strings */
    gint n_passed_over;           /* channels of a one-file series not taken
                                     as frames: another size, pixel size or
                                     unit than the first */
} FrameSeries;

/* Options: anything given here overrides the metadata. */
typedef struct {
    gdouble line_time;            /* s; <= 0: metadata */
    gdouble *frame_times;         /* s, one per frame as given (a frame dropped
                                     as a duplicate takes its own); NULL:
                                     metadata */
    gint n_frame_times;
    gint direction;               /* -1: metadata (else down), or ScanDirection */
    gint fallback_direction;      /* where the metadata is silent: -1 down,
                                     with a note; else this ScanDirection
                                     (a setting the user chose) */
    const gchar *channel;         /* title (exact, or prefix followed by a space
                                     and digits); NULL: see
                                     frame_series_from_files */
    gint first_id, last_id;       /* channel id range in a one-file series;
                                     -1: no limit */
    const gint *channel_ids;      /* a one-file series: these channels, in
                                     this order; several files: the first
                                     names the channel of every file */
    gint n_channel_ids;           /* 0: not given */
    gboolean keep_duplicates;     /* keep frames with bit-identical data */
    gboolean hints_for_dialog;    /* errors name the dialog's settings, not
                                     the command line's options */
} FrameSeriesOptions;

GQuark        frame_series_error_quark  (void);
void          frame_series_options_init (FrameSeriesOptions *options);

/* The frames of n_files loaded files (datas[k] loaded from filenames[k],
 * which label the frames and errors).  With several files, each file gives
 * one frame: the channel named by options->channel, else its first channel.
 * With one file, its channels are the frames: those named by options->channel (titles equal
 * to it or to it followed by " <number>") within the id range, else every
 * channel with the same size, pixel size and value unit as the first.  Frames
 * with bit-identical data are dropped (a note says which).  Timing comes from
 * the metadata as scan_timing_meta_read() reads it (simscan's own keys,
 * Nanoscope, HS-AFM, Anasys, Asylum) unless options give it.
 * Refuses series of fewer than two frames, frames of different size and
 * series whose timing stays unknown. */
FrameSeries*  frame_series_from_files   (GwyContainer **datas,
                                         gchar **filenames,
                                         gint n_files,
                                         const FrameSeriesOptions *options,
                                         GError **error);

/* An empty series, for callers (tests) that build frames themselves. */
FrameSeries*  frame_series_new          (void);
/* Appends a frame (a reference to field is taken). */
void          frame_series_append       (FrameSeries *series,
                                         GwyDataField *field,
                                         const gchar *label,
                                         const ScanTiming *timing);
void          frame_series_free         (FrameSeries *series);

/* The pixel sizes (m) of the series, all frames being alike. */
gdouble       frame_series_dx           (const FrameSeries *series);
gdouble       frame_series_dy           (const FrameSeries *series);

/* Whether a channel's title is wanted, or wanted followed by a space and
 * digits ("Height" and "Height 12"): how a channel names the frames of a
 * series. */
gboolean      frame_series_title_matches (const gchar *title,
                                          const gchar *wanted);
/* The title without a trailing space and digits ("Height 12": "Height";
 * NULL: ""), newly allocated. */
gchar*        frame_series_title_base    (const gchar *title);

G_END_DECLS

#endif
