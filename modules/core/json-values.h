/*
 *  Numbers in the JSON the tools write (json-glib builders): JSON has no
 *  NaN or infinity, so a number not known is null; pairs are arrays of two;
 *  the finished document is pretty-printed text.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_JSON_VALUES_H
#define LOCALSCAN_JSON_VALUES_H

#include <json-glib/json-glib.h>
#include "scan-timing.h"

G_BEGIN_DECLS

/* The value, or null when it is not finite. */
void    json_values_add_number (JsonBuilder *builder,
                                gdouble value);
/* [v[0], v[1]], each as json_values_add_number. */
void    json_values_add_pair   (JsonBuilder *builder,
                                const gdouble *v);
/* Member name with json_values_add_number / _add_pair. */
void    json_values_set_number (JsonBuilder *builder,
                                const gchar *name,
                                gdouble value);
void    json_values_set_pair   (JsonBuilder *builder,
                                const gchar *name,
                                const gdouble *v);
/* text as a string made valid UTF-8: labels and notes come from files,
 * whose bytes JSON cannot carry as they are. */
void    json_values_add_text   (JsonBuilder *builder,
                                const gchar *text);
/* A frame's timing: its start under start_name, "line_time_s" and
 * "direction". */
void    json_values_set_timing (JsonBuilder *builder,
                                const gchar *start_name,
                                const ScanTiming *timing);
/* The builder's document as pretty-printed text (g_free it); the builder
 * is released. */
gchar*  json_values_finish     (JsonBuilder *builder);

G_END_DECLS

#endif
