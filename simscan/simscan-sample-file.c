/*
 *  A measured image as simscan's sample.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <stdlib.h>
#include <libgwymodule/gwymodule-file.h>
#include <app/gwyapp.h>
#include "simscan-sample-file.h"
#include "localscan-channel.h"
#include "simscan-i18n.h"

static GQuark
simscan_sample_error_quark(void)
{
    return g_quark_from_static_string("simscan-sample-error-quark");
}

static GwyDataField*
channel_field(GwyContainer *data, gint id)
{
    GObject *object = NULL;

    if (gwy_container_gis_object(data, gwy_app_get_data_key_for_id(id),
                                 &object)
        && GWY_IS_DATA_FIELD(object))
        return GWY_DATA_FIELD(object);
    return NULL;
}

GwyDataField*
simscan_load_channel(const gchar *filename, gint id, GError **error)
{
    static gboolean initialised = FALSE;
    GwyContainer *data;
    GwyDataField *field = NULL;
    GError *err = NULL;
    gint *ids;

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
    if (id < 0) {
        ids = localscan_channel_ids(data);
        if (ids[0] >= 0)
            field = channel_field(data, ids[0]);
        g_free(ids);
    }
    else
        field = channel_field(data, id);
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
