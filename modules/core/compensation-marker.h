/*
 *  The mark a compensated channel carries, so that it is not compensated
 *  a second time by mistake (Repeat last on the result, a batch run over
 *  files that were already processed).  GTK-free.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_COMPENSATION_MARKER_H
#define LOCALSCAN_COMPENSATION_MARKER_H

#include <glib.h>
#include <libgwyddion/gwycontainer.h>
#include "drift-table.h"

G_BEGIN_DECLS

/* Metadata item of a compensated channel: how it was compensated (the run
 * description, run-description.h) and the table used.  Part of the file
 * format users keep: never rename it. */
#define LOCALSCAN_META_COMPENSATED "Local-scan compensation"

/* Marks channel id of data as compensated by a run described by
 * description with table. */
void         compensation_marker_set   (GwyContainer *data,
                                        gint id,
                                        const gchar *description,
                                        const DriftTable *table);
/* The marker's text, or NULL when channel id is not marked. */
const gchar* compensation_marker_get   (GwyContainer *data,
                                        gint id);
/* FALSE with a one-line error (LOCALSCAN_CHANNEL_ERROR_COMPENSATED) naming
 * channel_name when channel id is marked and force is not given. */
gboolean     compensation_marker_check (GwyContainer *data,
                                        gint id,
                                        const gchar *channel_name,
                                        gboolean force,
                                        const gchar *how_to_force,
                                        GError **error);

G_END_DECLS

#endif
