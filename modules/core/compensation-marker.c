/*
 *  The mark a compensated channel carries.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <libgwyddion/gwymacros.h>
#include "compensation-marker.h"
#include "localscan-channel.h"
#include "localscan-intl.h"

/* The table is kept beside the description so the marker alone says
 * what was done, even after the drift table item is replaced. */
void
compensation_marker_set(GwyContainer *data, gint id, const gchar *description,
                        const DriftTable *table)
{
    gchar *text = drift_table_to_string(table);

    gwy_container_set_string_by_name(localscan_channel_meta(data, id, TRUE), LOCALSCAN_META_COMPENSATED,
                                     (const guchar*)g_strconcat(description, "\n", text, NULL));
    g_free(text);
}

const gchar*
compensation_marker_get(GwyContainer *data, gint id)
{
    return localscan_channel_meta_string(data, id, LOCALSCAN_META_COMPENSATED);
}

gboolean
compensation_marker_check(GwyContainer *data, gint id, const gchar *channel_name, gboolean force,
                          const gchar *how_to_force, GError **error)
{
    if (force || !compensation_marker_get(data, id))
        return TRUE;
    g_set_error(error, LOCALSCAN_CHANNEL_ERROR, LOCALSCAN_CHANNEL_ERROR_COMPENSATED,
                _("%s is already local-scan compensated (metadata item '%s'); "
                  "compensating it again would apply the drift twice (%s)"),
                channel_name, LOCALSCAN_META_COMPENSATED, how_to_force);
    return FALSE;
}
