/*
 *  Which channels may serve as the registration reference of an image.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <math.h>
#include <libgwyddion/gwymacros.h>
#include <libprocess/datafield.h>
#include "reference-choice.h"
#include "localscan-channel.h"
#include "scan-timing-meta.h"

/* Frames of one series start at least a frame apart; two stamps closer
 * than this are one scan written twice (channels of one frame). */
#define SAME_SCAN_SECONDS 1.0

static GwyDataField*
channel_field(GwyContainer *data, gint id)
{
    gpointer field = localscan_channel_item(data, id, "data");

    return GWY_IS_DATA_FIELD(field) ? field : NULL;
}

static gboolean
scan_time(GwyContainer *data, gint id, gdouble *t, gboolean *wall_clock)
{
    ScanMetaTiming timing;

    timing.frame_start = 0.0;
    timing.wall_clock = FALSE;
    if (!(scan_timing_meta_read_channel(data, id, &timing) & SCAN_META_FRAME_START))
        return FALSE;
    *t = timing.frame_start;
    *wall_clock = timing.wall_clock;
    return TRUE;
}

ReferenceRank
reference_choice_rank(GwyContainer *image_data, gint image_id,
                      GwyContainer *cand_data, gint cand_id)
{
    GwyDataField *image = channel_field(image_data, image_id);
    GwyDataField *cand = channel_field(cand_data, cand_id);
    gdouble t_image, t_cand;
    gboolean clock_image, clock_cand, known;

    if (!image || !cand || image == cand || !localscan_reference_fits(image, cand))
        return REFERENCE_RANK_UNFIT;
    known = (scan_time(image_data, image_id, &t_image, &clock_image)
             && scan_time(cand_data, cand_id, &t_cand, &clock_cand)
             && clock_image == clock_cand);
    if (known && fabs(t_image - t_cand) >= SAME_SCAN_SECONDS)
        return REFERENCE_RANK_OTHER_TIME;
    if (known || cand_data == image_data)
        return REFERENCE_RANK_SIBLING;
    return REFERENCE_RANK_OTHER_FILE;
}

gchar*
reference_choice_label(GwyContainer *data, gint id, const gchar *untitled_name)
{
    const gchar *title = localscan_channel_title(data, id);
    const guchar *filename = NULL;
    gchar *base, *label;

    gwy_container_gis_string_by_name(data, "/filename", &filename);
    base = filename ? g_path_get_basename((const gchar*)filename) : g_strdup(untitled_name);
    if (title && *title)
        label = g_strdup_printf("%s \342\200\224 %s", base, title);
    else
        label = g_strdup_printf("%s \342\200\224 channel %d", base, id);
    g_free(base);
    return label;
}
