/*
 *  Which channels may serve as the registration reference of an image,
 *  how they are named to the user, and which one is offered first.
 *  GTK-free.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_REFERENCE_CHOICE_H
#define LOCALSCAN_REFERENCE_CHOICE_H

#include <glib.h>
#include <libgwyddion/gwycontainer.h>

G_BEGIN_DECLS

/* How good a candidate is; higher is better. */
typedef enum {
    REFERENCE_RANK_UNFIT      = 0,   /* the image itself, or not the same
                                        pixels, physical size, lateral unit */
    REFERENCE_RANK_SIBLING    = 1,   /* another channel of the same scan: it
                                        shares the drift, which then
                                        registers to zero */
    REFERENCE_RANK_OTHER_FILE = 2,   /* another file, its time unknown */
    REFERENCE_RANK_OTHER_TIME = 3,   /* metadata say another scan time */
} ReferenceRank;

/* The rank of channel cand_id of cand_data as the reference of channel
 * image_id of image_data.  Scan times come from the channels' metadata
 * (scan-timing-meta.h); a channel of the same file whose time is unknown
 * or equal counts as a sibling. */
ReferenceRank reference_choice_rank (GwyContainer *image_data,
                                     gint image_id,
                                     GwyContainer *cand_data,
                                     gint cand_id);

/* "FILE — TITLE": the file's base name ("/filename" of data, else
 * untitled_name) and the channel's title (else "channel ID"). */
gchar*        reference_choice_label(GwyContainer *data,
                                     gint id,
                                     const gchar *untitled_name);

G_END_DECLS

#endif
