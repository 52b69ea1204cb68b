/*
 *  libFuzzer harness: the scan-timing metadata reader on a metadata
 *  container made of arbitrary "key=value" lines (the first byte chooses the
 *  image's rows).  Whatever it finds must be usable: a positive finite line
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

static GwyContainer*
meta_from_lines(const gchar *text)
{
    GwyContainer *meta = gwy_container_new();
    gchar **lines = g_strsplit(text, "\n", 64), **line;
    gchar *eq;

    for (line = lines; *line; line++) {
        if (!(eq = strchr(*line, '=')) || eq == *line)
            continue;
        *eq = '\0';
        /* Metadata strings are UTF-8 in Gwyddion; importers validate. */
        if (g_utf8_validate(*line, -1, NULL) && g_utf8_validate(eq + 1, -1, NULL))
            gwy_container_set_const_string_by_name(meta, *line, (const guchar*)(eq + 1));
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
