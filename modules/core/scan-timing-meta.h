/*
 *  A channel's scan timing as its file's metadata states it: the one reader
 *  of the keys simscan and Gwyddion's importers write, for the module, the
 *  tools and simscan fit.  GTK-free.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_SCAN_TIMING_META_H
#define LOCALSCAN_SCAN_TIMING_META_H

#include <glib.h>
#include <libgwyddion/gwycontainer.h>
#include "scan-timing.h"

G_BEGIN_DECLS

/* The parts of the timing the metadata gave. */
typedef enum {
    SCAN_META_LINE_TIME   = 1 << 0,
    SCAN_META_DIRECTION   = 1 << 1,
    SCAN_META_FRAME_START = 1 << 2,
} ScanMetaFound;

/* Fields not found are left as they were. */
typedef struct {
    gdouble line_time;         /* s per line, trace and retrace */
    ScanDirection direction;
    gdouble frame_start;       /* s; see start_is_end, wall_clock */
    gboolean start_is_end;     /* the stamp is the frame's end (its last line
                                  scanned), not its start */
    gboolean wall_clock;       /* frame_start is a date (s since 1970), not
                                  seconds in the series' own clock */
} ScanMetaTiming;

/* Reads a metadata container (a channel's "/<id>/meta") of an image of yres
 * rows.  Keys, the first that parses winning:
 * - line time: "Line time (s)" (simscan), "Line time"/"Line Time" (with a
 *   time unit or bare seconds), else the line rate "Scan rate"/"Scan Rate"
 *   (Nanoscope)/"ScanRate" (Anasys, Asylum) in Hz, else "Frame time (s)"
 *   (HS-AFM) over the rows;
 * - slow-scan direction: "Slow scan" (simscan) or "Frame direction"
 *   (Nanoscope), "down" or "up" in any case;
 * - frame start: "Frame start (s)" (simscan), "Time since first kept frame
 *   (s)" (HS-AFM), "Relative frame time" (Nanoscope), else the dates
 *   "TimeStamp" (Anasys, ISO 8601, when the image was stored: its end) and
 *   "Date" (Nanoscope, "04:06:25 PM Thu Sep 26 2019").
 * Values that do not parse (or a line time outside LOCALSCAN_LINE_TIME_MIN
 * to LOCALSCAN_LINE_TIME_MAX) count as absent.  meta may be NULL.  Returns what was found. */
ScanMetaFound scan_timing_meta_read        (GwyContainer *meta,
                                            gint yres,
                                            ScanMetaTiming *timing);
/* Where the line time or the frame start (part) was not found although
 * one of its keys is there (a value that does not parse, or a line time
 * no instrument has): the first such key and its value, "'Line time (s)'
 * is 'nan'", newly allocated, valid UTF-8, the value cut to
 * SCAN_META_SHOWN_CHARS characters; NULL when none of its keys is there
 * (and for the direction). */
#define SCAN_META_SHOWN_CHARS 40

gchar*        scan_timing_meta_unusable    (GwyContainer *meta,
                                            ScanMetaFound part);

/* The same for channel id of data (its metadata and its field's rows). */
ScanMetaFound scan_timing_meta_read_channel(GwyContainer *data,
                                            gint id,
                                            ScanMetaTiming *timing);

G_END_DECLS

#endif
