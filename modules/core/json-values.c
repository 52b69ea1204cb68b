/*
 *  Numbers in the JSON the tools write.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <math.h>
#include "json-values.h"

void
json_values_add_number(JsonBuilder *builder, gdouble value)
{
    if (isfinite(value))
        json_builder_add_double_value(builder, value);
    else
        json_builder_add_null_value(builder);
}

void
json_values_add_pair(JsonBuilder *builder, const gdouble *v)
{
    json_builder_begin_array(builder);
    json_values_add_number(builder, v[0]);
    json_values_add_number(builder, v[1]);
    json_builder_end_array(builder);
}

void
json_values_set_number(JsonBuilder *builder, const gchar *name,
                       gdouble value)
{
    json_builder_set_member_name(builder, name);
    json_values_add_number(builder, value);
}

void
json_values_set_pair(JsonBuilder *builder, const gchar *name,
                     const gdouble *v)
{
    json_builder_set_member_name(builder, name);
    json_values_add_pair(builder, v);
}

void
json_values_add_text(JsonBuilder *builder, const gchar *text)
{
    gchar *valid = g_utf8_make_valid(text, -1);

    json_builder_add_string_value(builder, valid);
    g_free(valid);
}

void
json_values_set_timing(JsonBuilder *builder, const gchar *start_name,
                       const ScanTiming *timing)
{
    json_values_set_number(builder, start_name, timing->frame_start);
    json_values_set_number(builder, "line_time_s", timing->line_time);
    json_builder_set_member_name(builder, "direction");
    json_builder_add_string_value(builder,
                                  scan_direction_name(timing->direction));
}

gchar*
json_values_finish(JsonBuilder *builder)
{
    JsonGenerator *gen = json_generator_new();
    JsonNode *root = json_builder_get_root(builder);
    gchar *text;

    json_generator_set_pretty(gen, TRUE);
    json_generator_set_root(gen, root);
    text = json_generator_to_data(gen, NULL);
    json_node_unref(root);
    g_object_unref(gen);
    g_object_unref(builder);
    return text;
}
