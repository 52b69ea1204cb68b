/*
 *  A measured image as simscan's sample.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <stdlib.h>
#include <string.h>
#include <libgwymodule/gwymodule-file.h>
#include <app/gwyapp.h>
#include "simscan-sample-file.h"
#include "isolated-load.h"
#include "localscan-channel.h"
#include "missing-data.h"
#include "paper-compensate.h"
#include "library-log.h"
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

/* Missing pixels (NaN, infinite; docs/missing-data.md) of a measured
 * sample are filled with the mean of the others: the simulated scan sees a
 * flat patch there, never a NaN.  A sample mostly missing is refused.
 * Returns a new reference, or NULL with error set. */
static GwyDataField*
sample_without_missing(GwyDataField *field, const gchar *filename, GError **error)
{
    gint xres = gwy_data_field_get_xres(field), yres = gwy_data_field_get_yres(field);
    const gdouble *a = gwy_data_field_get_data_const(field);
    GwyDataField *filled;
    gdouble *copy;

    if (!missing_data_check(a, xres, yres, filename, error))
        return NULL;
    if (!missing_data_count(a, (gsize)xres*yres))
        return g_object_ref(field);
    copy = missing_data_filled_copy(a, (gsize)xres*yres, paper_image_mean(a, xres, yres));
    filled = gwy_data_field_new_alike(field, FALSE);
    memcpy(gwy_data_field_get_data(filled), copy, (gsize)xres*yres*sizeof(gdouble));
    gwy_data_field_invalidate(filled);
    g_free(copy);
    return filled;
}

GwyContainer*
simscan_load_file(const gchar *filename, GError **error)
{
    static gboolean initialised = FALSE;
    GwyContainer *data;
    GError *err = NULL;

    if (!initialised) {
        gwy_app_init_nongui("enable-threads", FALSE, NULL);
        library_log_capture(g_get_prgname(), library_log_verbose());
        initialised = TRUE;
    }
    /* Screened, then loaded in a child process (isolated-load.h). */
    if (!(data = isolated_load(filename, &err))) {
        g_set_error(error, simscan_sample_error_quark(), 0, _("cannot read %s"), err->message);
        g_clear_error(&err);
    }
    return data;
}

GwyDataField*
simscan_load_channel(const gchar *filename, gint id, GError **error)
{
    GwyContainer *data;
    GwyDataField *field = NULL;
    gint *ids;

    if (!(data = simscan_load_file(filename, error)))
        return NULL;
    if (id < 0) {
        ids = localscan_channel_ids(data);
        if (ids[0] >= 0)
            field = channel_field(data, ids[0]);
        g_free(ids);
    }
    else
        field = channel_field(data, id);
    if (field)
        field = sample_without_missing(field, filename, error);
    else if (id >= 0)
        g_set_error(error, simscan_sample_error_quark(), 0,
                    _("%s has no channel %d"), filename, id);
    else
        g_set_error(error, simscan_sample_error_quark(), 0,
                    _("%s has no image channel"), filename);
    g_object_unref(data);
    return field;
}
