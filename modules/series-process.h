/*
 *  Local Scan Series Drift, the module's second process function
 *  (docs/series.md).
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_SERIES_PROCESS_H
#define LOCALSCAN_SERIES_PROCESS_H

#define LOCALSCAN_SERIES_FUNCTION_NAME "localscan_series"

/* The dialog's frame chooser, a GtkTreeView named so that tests find it;
 * its model's columns: checked (boolean), channel id (int), title, start
 * (strings; the start is empty where the metadata does not give it),
 * thumbnail (GdkPixbuf, made when first drawn).  Its rows are the
 * candidate frames in channel id order. */
#define LOCALSCAN_SERIES_FRAMES_WIDGET_NAME "localscan-series-frames"
enum {
    LOCALSCAN_SERIES_FRAME_COLUMN_CHECKED,
    LOCALSCAN_SERIES_FRAME_COLUMN_ID,
    LOCALSCAN_SERIES_FRAME_COLUMN_TITLE,
    LOCALSCAN_SERIES_FRAME_COLUMN_START,
    LOCALSCAN_SERIES_FRAME_COLUMN_THUMBNAIL,
    LOCALSCAN_SERIES_FRAME_NCOLUMNS
};

/* Registers the process function (from the module's registration). */
void localscan_series_register(void);

#endif
