/*
 *  The localscan_drift process function as batch callers see it: its name
 *  and the parameters it reads from Gwyddion's settings.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <app/gwyapp.h>
#include "localscan-settings.h"

#define KEY LOCALSCAN_SETTINGS_KEY

/* GwyParams keeps enums and ints as int32, booleans as booleans. */
void
localscan_settings_apply(const LocalscanBatchParams *params)
{
    GwyContainer *settings = gwy_app_settings_get();
    gchar *table_file;

    gwy_container_set_int32_by_name(settings, KEY(SOURCE), params->source);
    if (params->source == LOCALSCAN_SOURCE_FILE) {
        /* Absolute, so it means the same file whatever the module's cwd. */
        table_file = g_canonicalize_filename(params->table_file, NULL);
        gwy_container_set_string_by_name(settings, KEY(TABLE_FILE),
                                         (const guchar*)table_file);
    }
    gwy_container_set_int32_by_name(settings, KEY(MODE), params->mode);
    gwy_container_set_double_by_name(settings, KEY(LINE_TIME), params->line_time);
    gwy_container_set_int32_by_name(settings, KEY(DIRECTION), params->direction);
    gwy_container_set_double_by_name(settings, KEY(FRAME_START), params->frame_start);
    gwy_container_set_int32_by_name(settings, KEY(FILL), LOCALSCAN_FILL_MEAN);
    gwy_container_set_boolean_by_name(settings, KEY(ADD_MASK), TRUE);
    gwy_container_set_boolean_by_name(settings, KEY(PLOT_DRIFT), FALSE);
    if (params->interpolation >= 0)
        gwy_container_set_int32_by_name(settings, KEY(INTERPOLATION), params->interpolation);
    gwy_container_set_boolean_by_name(settings, KEY(FORCE), params->force);
    gwy_container_set_boolean_by_name(settings, KEY(ALL_CHANNELS), params->all_channels);
}
