/*
 *  A measured image as simscan's sample: any file Gwyddion reads.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef SIMSCAN_SAMPLE_FILE_H
#define SIMSCAN_SAMPLE_FILE_H

#include <glib.h>
#include <libgwyddion/gwycontainer.h>
#include <libprocess/datafield.h>

G_BEGIN_DECLS

/* The whole file (screened, loaded in a child process), a new reference,
 * or NULL with error set.  Starts Gwyddion's application library headless
 * on first use. */
GwyContainer*  simscan_load_file     (const gchar *filename,
                                      GError **error);
/* Channel id of filename (-1: the lowest id), a new reference.  Starts
 * Gwyddion's application library headless on first use. */
GwyDataField*  simscan_load_channel  (const gchar *filename,
                                      gint id,
                                      GError **error);

G_END_DECLS

#endif
