/*
 *  The localscan_drift process function's parameters as stored in
 *  Gwyddion's settings (/module/localscan_drift/<key>): function name, keys,
 *  defaults and limits, for the module's GwyParamDef, the batch tools and
 *  the tests alike.  GTK-free.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_PARAMS_H
#define LOCALSCAN_PARAMS_H

#include <libprocess/gwyprocessenums.h>
#include "localscan-channel.h"

/* Process function names are global in Gwyddion; "drift" is Gwyddion's own. */
#define LOCALSCAN_FUNCTION_NAME "localscan_drift"
#define LOCALSCAN_SETTINGS_PREFIX "/module/" LOCALSCAN_FUNCTION_NAME "/"
/* The settings key of a parameter: LOCALSCAN_SETTINGS_KEY(MODE). */
#define LOCALSCAN_SETTINGS_KEY(name) (LOCALSCAN_SETTINGS_PREFIX LOCALSCAN_KEY_##name)

/* Keys under LOCALSCAN_SETTINGS_PREFIX.  Users' settings files hold them:
 * never rename one.  GwyParams stores enums and ints as int32, booleans as
 * booleans, doubles as doubles. */
#define LOCALSCAN_KEY_SOURCE            "source"
#define LOCALSCAN_KEY_TABLE_FILE        "table-file"
#define LOCALSCAN_KEY_REFERENCE         "reference"
#define LOCALSCAN_KEY_STRIPES           "stripes"
#define LOCALSCAN_KEY_MODE              "mode"
#define LOCALSCAN_KEY_INTERPOLATION     "interpolation"
#define LOCALSCAN_KEY_DIRECTION         "direction"
#define LOCALSCAN_KEY_LINE_TIME         "line-time"
#define LOCALSCAN_KEY_FRAME_START       "frame-start"
#define LOCALSCAN_KEY_FILL              "fill"
#define LOCALSCAN_KEY_ADD_MASK          "add-mask"
#define LOCALSCAN_KEY_PLOT_DRIFT        "plot-drift"
#define LOCALSCAN_KEY_REFERENCE_CHANNEL "reference-channel"
#define LOCALSCAN_KEY_FORCE             "force"
#define LOCALSCAN_KEY_ALL_CHANNELS      "all-channels"
#define LOCALSCAN_KEY_MASKING           "masking"

#define LOCALSCAN_DEFAULT_SOURCE        LOCALSCAN_SOURCE_STORED
#define LOCALSCAN_DEFAULT_MODE          LOCALSCAN_MODE_PAPER
#define LOCALSCAN_DEFAULT_INTERPOLATION GWY_INTERPOLATION_ROUND
#define LOCALSCAN_DEFAULT_DIRECTION     SCAN_DIRECTION_DOWN
#define LOCALSCAN_DEFAULT_FILL          LOCALSCAN_FILL_MEAN
#define LOCALSCAN_DEFAULT_ADD_MASK      TRUE
#define LOCALSCAN_DEFAULT_PLOT_DRIFT    FALSE
/* A compensated channel is compensated again only when forced. */
#define LOCALSCAN_DEFAULT_FORCE         FALSE
/* One correction, from the image's drift, for every channel of its scan. */
#define LOCALSCAN_DEFAULT_ALL_CHANNELS  FALSE
/* What the channels' masks mean to the registration against a reference:
 * as Gwyddion's levelling functions take them, masked pixels are left out
 * (importers mask the pixels a file lacks and fill them with the mean). */
#define LOCALSCAN_DEFAULT_MASKING       GWY_MASK_EXCLUDE

/* Stripes registered against a reference image. */
#define LOCALSCAN_STRIPES_MIN           1
#define LOCALSCAN_STRIPES_MAX           4096
#define LOCALSCAN_STRIPES_DEFAULT       16

/* Scan timing used where the channel's metadata does not give it
 * (continuous mode; the metadata always wins): seconds per line, trace and
 * retrace, and the frame's start in the clock of the table's t_image,
 * t_local. */
#define LOCALSCAN_LINE_TIME_MIN         1e-6
#define LOCALSCAN_LINE_TIME_MAX         1e4
#define LOCALSCAN_LINE_TIME_DEFAULT     LOCALSCAN_DEFAULT_LINE_TIME
#define LOCALSCAN_FRAME_START_MIN       -1e9
#define LOCALSCAN_FRAME_START_MAX       1e9
#define LOCALSCAN_FRAME_START_DEFAULT   0.0

/* The dialog's reference chooser, a GtkComboBox named so that tests find
 * it; its model's columns: label (string), data number, channel id, rank
 * (ints). */
#define LOCALSCAN_REFERENCE_WIDGET_NAME "localscan-reference"
enum {
    LOCALSCAN_REFERENCE_COLUMN_LABEL,
    LOCALSCAN_REFERENCE_COLUMN_DATANO,
    LOCALSCAN_REFERENCE_COLUMN_ID,
    LOCALSCAN_REFERENCE_COLUMN_RANK,
    LOCALSCAN_REFERENCE_NCOLUMNS
};

/* A channel id of the image's own file, for batch callers; -1: none. */
#define LOCALSCAN_REFERENCE_CHANNEL_NONE -1

#endif
