/*
 *  One compensation run in words, for the channel log and the compensated
 *  channel's marker: settings by their names, never enum numbers.  The
 *  names are a record kept in files, so they are never translated.
 *  GTK-free.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_RUN_DESCRIPTION_H
#define LOCALSCAN_RUN_DESCRIPTION_H

#include <glib.h>
#include "localscan-channel.h"

G_BEGIN_DECLS

typedef struct {
    LocalscanSource source;
    const gchar *table_file;        /* LOCALSCAN_SOURCE_FILE */
    const gchar *reference;         /* LOCALSCAN_SOURCE_REFERENCE: "file — channel" */
    gint stripes;                   /* LOCALSCAN_SOURCE_REFERENCE */
    GwyMaskingType masking;         /* LOCALSCAN_SOURCE_REFERENCE */
    LocalscanMode mode;
    GwyInterpolationType interpolation;   /* continuous mode */
    LocalscanFill fill;
} RunDescription;

const gchar* run_description_source_name       (LocalscanSource source);
const gchar* run_description_mode_name         (LocalscanMode mode);
const gchar* run_description_interpolation_name(GwyInterpolationType interpolation);
const gchar* run_description_fill_name         (LocalscanFill fill);
/* "exclude", "include", "ignore"; -1 from a name that is none of them. */
const gchar* run_description_masking_name      (GwyMaskingType masking);
gint         run_description_masking_from_name (const gchar *name);
/* The kernel of a name run_description_interpolation_name() gives; -1 for
 * none (and for "none", which cannot resample). */
gint         run_description_interpolation_from_name(const gchar *name);
/* "round, linear, key, ...": the names the above accepts. */
gchar*       run_description_interpolation_names(void);

/* The mode a description (or one of Gwyddion's own log entries, which
 * give it as a number) states with "mode=": -1 when it states none. */
gint         run_description_parse_mode        (const gchar *text);

/* "source=reference, reference=a.gwy — Height, stripes=16,
 * masking=exclude, mode=continuous, interpolation=round, fill=mean": only
 * what the run used. */
gchar*       run_description_format            (const RunDescription *run);

G_END_DECLS

#endif
