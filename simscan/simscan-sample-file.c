/*
 *  A measured image as simscan's sample.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <libgwymodule/gwymodule-file.h>
#include <app/gwyapp.h>
#include "simscan-sample-file.h"
#include "simscan-i18n.h"

/* Gwyddion keeps channel ids small; a generous bound for the search. */
#define MAX_CHANNEL_ID 4096

static GQuark
simscan_sample_error_quark(void)
{
    return g_quark_from_static_string("simscan-sample-error-quark");
}

GwyDataField*
simscan_load_channel(const gchar *filename, gint id, GError **error)
{
    static gboolean initialised = FALSE;
    GwyContainer *data;
    GwyDataField *field = NULL;
    GError *err = NULL;
    gchar key[32];
    gint i;

    if (!initialised) {
        gwy_app_init_nongui("enable-threads", FALSE, NULL);
        initialised = TRUE;
    }
    if (!(data = gwy_file_load(filename, GWY_RUN_NONINTERACTIVE, &err))) {
        g_set_error(error, simscan_sample_error_quark(), 0,
                    _("cannot read %s: %s"), filename,
                    err ? err->message : _("unknown format"));
        g_clear_error(&err);
        return NULL;
    }
    for (i = (id >= 0 ? id : 0); i <= (id >= 0 ? id : MAX_CHANNEL_ID); i++) {
        g_snprintf(key, sizeof(key), "/%d/data", i);
        if (gwy_container_gis_object_by_name(data, key, &field))
            break;
    }
    if (field)
        g_object_ref(field);
    else if (id >= 0)
        g_set_error(error, simscan_sample_error_quark(), 0,
                    _("%s has no channel %d"), filename, id);
    else
        g_set_error(error, simscan_sample_error_quark(), 0,
                    _("%s has no image channel"), filename);
    g_object_unref(data);
    return field;
}
