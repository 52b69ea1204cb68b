/*
 *  The localscan_drift process function as batch callers see it: its name
 *  and the parameters it reads from Gwyddion's settings
 *  (/module/localscan_drift/<key>, the module's GwyParamDef).
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_SETTINGS_H
#define LOCALSCAN_SETTINGS_H

#include <glib.h>
#include "localscan-params.h"

G_BEGIN_DECLS

/* What a batch run decides; everything else the module reads (the
 * interpolation of continuous mode) stays as the user's settings have it, as
 * in a pygwy script. */
typedef struct {
    LocalscanSource source;
    const gchar *table_file;     /* LOCALSCAN_SOURCE_FILE only */
    LocalscanMode mode;
    /* Continuous mode's timing where the file's metadata does not say. */
    gdouble line_time;
    ScanDirection direction;
    gdouble frame_start;
    gint interpolation;          /* -1: the user's setting stays */
    gboolean force;              /* compensate a compensated channel again */
    gboolean all_channels;       /* the scan's other channels too */
    /* Reference registration adds the reference image and stripe count. */
} LocalscanBatchParams;

/* Puts the parameters into the settings container of this process only; the
 * settings file is never written.  The fill value is the image mean (the
 * paper's d), the mask of filled pixels is always made, no drift graph. */
void localscan_settings_apply(const LocalscanBatchParams *params);

G_END_DECLS

#endif
