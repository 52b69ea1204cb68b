/*
 *  libFuzzer harness: the scan-timing metadata reader on a metadata
 *  container made of arbitrary lines, each a value of the key its first
 *  byte chooses (the input's first byte chooses the image's rows).  Whatever it finds must be usable: a positive finite line
 *  time, a known direction, a finite frame start.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <libgwyddion/gwycontainer.h>
#include "scan-timing-meta.h"

int LLVMFuzzerTestOneInput(const guint8 *data, size_t size);

/* The keys the reader knows, and a few it must ignore.  Keys are chosen
 * from this list (by each line's first byte), not taken from the input:
 * Gwyddion interns every key as a GQuark, never freed, so random keys would
 * only measure the quark table's growth. */
static const gchar *const keys[] = {
    "Line time (s)", "Line time", "Line Time", "Scan rate", "Scan Rate", "ScanRate",
    "Frame time (s)", "Slow scan", "Frame direction", "Frame start (s)",
    "Time since first kept frame (s)", "Relative frame time", "TimeStamp", "Date",
    "Title", "Scan size",
};

static GwyContainer*
meta_from_lines(const gchar *text)
{
    GwyContainer *meta = gwy_container_new();
    gchar **lines = g_strsplit(text, "\n", 64), **line;

    for (line = lines; *line; line++) {
        if (!**line)
            continue;
        /* Metadata strings are UTF-8 in Gwyddion; importers validate. */
        if (g_utf8_validate(*line + 1, -1, NULL))
            gwy_container_set_const_string_by_name(meta,
                                                   keys[(guchar)**line % G_N_ELEMENTS(keys)],
                                                   (const guchar*)(*line + 1));
    }
    g_strfreev(lines);
    return meta;
}

int
LLVMFuzzerTestOneInput(const guint8 *data, size_t size)
{
    ScanMetaTiming timing = { 1.0, SCAN_DIRECTION_DOWN, 0.0, FALSE, FALSE };
    GwyContainer *meta;
    ScanMetaFound found;
    gchar *text;
    gint yres;

    if (!size)
        return 0;
    yres = 1 + data[0]*37;
    text = g_strndup((const gchar*)data + 1, size - 1);
    meta = meta_from_lines(text);
    found = scan_timing_meta_read(meta, yres, &timing);
    if ((found & SCAN_META_LINE_TIME) && !(isfinite(timing.line_time) && timing.line_time > 0.0))
        abort();
    if ((found & SCAN_META_FRAME_START) && !isfinite(timing.frame_start))
        abort();
    if (timing.direction != SCAN_DIRECTION_DOWN && timing.direction != SCAN_DIRECTION_UP)
        abort();
    g_object_unref(meta);
    g_free(text);
    return 0;
}
