/*
 *  simscan's output files.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <string.h>
#include <math.h>
#include "json-values.h"
#include <libgwyddion/gwyserializable.h>
#include "localscan-channel.h"
#include "output-files.h"
#include "simscan-presets.h"
#include "simscan-output.h"
#include "simscan-i18n.h"

#define GWY_MAGIC "GWYP"

/* Numbers in metadata as the shortest text that reads back exactly. */
static void
set_meta_number(GwyContainer *meta, const gchar *key, gdouble value)
{
    gchar buf[G_ASCII_DTOSTR_BUF_SIZE];

    gwy_container_set_string_by_name(meta, key, (const guchar*)
                                     g_strdup(g_ascii_dtostr(buf, sizeof(buf),
                                                             value)));
}

static void
set_meta_pair(GwyContainer *meta, const gchar *key, const gdouble *v,
              gdouble scale)
{
    gchar bx[G_ASCII_DTOSTR_BUF_SIZE], by[G_ASCII_DTOSTR_BUF_SIZE];

    gwy_container_set_string_by_name(meta, key, (const guchar*)
        g_strdup_printf("%s, %s", g_ascii_dtostr(bx, sizeof(bx), v[0]*scale),
                        g_ascii_dtostr(by, sizeof(by), v[1]*scale)));
}

static const gchar*
model_name(const SimscanScene *scene)
{
    return scene->shift_dx ? "figure6" : drift_model_type_name(scene->drift.type);
}

void
simscan_output_timing_meta(GwyContainer *meta, gdouble line_time,
                           ScanDirection direction, gdouble frame_start)
{
    set_meta_number(meta, SIMSCAN_META_LINE_TIME, line_time);
    gwy_container_set_const_string_by_name(meta, SIMSCAN_META_SLOW_SCAN,
        (const guchar*)scan_direction_name(direction));
    set_meta_number(meta, SIMSCAN_META_FRAME_START, frame_start);
}

static GwyContainer*
make_meta(const SimscanScene *scene, const SimscanMeasurement *m)
{
    const SimscanConfig *config = scene->config;
    GwyContainer *meta = gwy_container_new();

    simscan_output_timing_meta(meta, scene->scan.line_time,
                               scene->scan.direction, scene->scan.frame_start);
    set_meta_number(meta, "Seed", config->seed);
    gwy_container_set_const_string_by_name(meta, "Drift model",
                                           (const guchar*)model_name(scene));
    if (!scene->shift_dx)
        set_meta_pair(meta, "Drift velocity (nm/s)", scene->drift.v, 1e9);
    gwy_container_set_const_string_by_name(meta, "Preset",
        (const guchar*)simscan_preset_name(config->preset));
    set_meta_number(meta, "Stripes", m->n_stripes);
    set_meta_number(meta, "Local scans start (s)", m->t_start);
    set_meta_number(meta, "Local scans end (s)", m->t_end);
    set_meta_pair(meta, "Reference drift (nm)", m->ref_drift, 1e9);
    gwy_container_set_const_string_by_name(meta, "Simulator",
                                           (const guchar*)("simscan "
                                                           PACKAGE_VERSION));
    return meta;
}

static gchar*
particles_text(const SimscanMeasurement *m)
{
    gchar b[4][G_ASCII_DTOSTR_BUF_SIZE];
    GString *str = g_string_new("x,y,x_shown,y_shown\n");
    gint i, k;

    for (i = 0; i < m->n_particles; i++) {
        gdouble v[4] = { m->truth_px[2*i], m->truth_px[2*i + 1],
                         m->shown_px[2*i], m->shown_px[2*i + 1] };

        for (k = 0; k < 4; k++)
            g_ascii_formatd(b[k], sizeof(b[k]), "%.6f", v[k]);
        g_string_append_printf(str, "%s,%s,%s,%s\n", b[0], b[1], b[2], b[3]);
    }
    return g_string_free(str, FALSE);
}

GwyContainer*
simscan_output_container(const SimscanScene *scene,
                         const SimscanMeasurement *m)
{
    GwyContainer *data = gwy_container_new();
    GwyContainer *meta = make_meta(scene, m);

    if (m->n_particles)
        gwy_container_set_string_by_name(meta, SIMSCAN_META_PARTICLES,
                                         (const guchar*)particles_text(m));
    gwy_container_set_object_by_name(data, "/0/data", scene->image);
    gwy_container_set_const_string_by_name(data, "/0/data/title",
                                           (const guchar*)SIMSCAN_TITLE_IMAGE);
    gwy_container_set_object_by_name(data, "/0/meta", meta);
    localscan_channel_store_table(data, 0, m->table);
    gwy_container_set_object_by_name(data, "/1/data", scene->truth);
    gwy_container_set_const_string_by_name(data, "/1/data/title",
                                           (const guchar*)SIMSCAN_TITLE_TRUTH);
    g_object_unref(meta);
    return data;
}

const gchar*
simscan_output_particles(GwyContainer *data)
{
    GwyContainer *meta = NULL;
    const guchar *text = NULL;

    if (!gwy_container_gis_object_by_name(data, "/0/meta", &meta)
        || !GWY_IS_CONTAINER(meta))
        return NULL;
    gwy_container_gis_string_by_name(meta, SIMSCAN_META_PARTICLES, &text);
    return (const gchar*)text;
}

static void
add_error(JsonBuilder *b, const gchar *name, const CentreError *e)
{
    json_builder_set_member_name(b, name);
    json_builder_begin_object(b);
    json_builder_set_member_name(b, "particles");
    json_builder_add_int_value(b, e->n_expected);
    json_builder_set_member_name(b, "matched");
    json_builder_add_int_value(b, e->n_matched);
    json_values_set_number(b, "rms_px", e->rms_px);
    json_values_set_number(b, "max_px", e->max_px);
    json_values_set_number(b, "rms_nm", e->rms_nm);
    json_values_set_number(b, "max_nm", e->max_nm);
    json_builder_end_object(b);
}

static void
add_number_or_null(JsonBuilder *b, const gchar *name, gboolean known,
                   gdouble value)
{
    json_values_set_number(b, name, known ? value : NAN);
}

static void
add_stripes(JsonBuilder *b, const SimscanMeasurement *m)
{
    gint s;

    json_builder_set_member_name(b, "stripes");
    json_builder_begin_array(b);
    for (s = 0; s < m->n_stripes; s++) {
        const LocalScanParticle *r = m->scans + s;
        const DriftTableRow *row = m->table->rows + s;

        json_builder_begin_object(b);
        json_builder_set_member_name(b, "stripe");
        json_builder_add_int_value(b, s);
        json_values_set_pair(b, "true_px",
                             (const gdouble[2]){ m->true_dx[s], m->true_dy[s] });
        add_number_or_null(b, "dx", row->has_drift, row->dx);
        add_number_or_null(b, "dy", row->has_drift, row->dy);
        add_number_or_null(b, "dx_exact", row->has_drift, r->dx);
        add_number_or_null(b, "dy_exact", row->has_drift, r->dy);
        add_number_or_null(b, "x", r->lines > 0, r->x_disp);
        add_number_or_null(b, "y", r->lines > 0, r->y_disp);
        add_number_or_null(b, "t_image", r->lines > 0, r->t_image);
        add_number_or_null(b, "t_local", row->has_drift, r->t_local);
        json_builder_set_member_name(b, "lines");
        json_builder_add_int_value(b, r->lines);
        json_builder_end_object(b);
    }
    json_builder_end_array(b);
}

gchar*
simscan_output_json(const SimscanScene *scene, const SimscanMeasurement *m)
{
    const SimscanConfig *config = scene->config;
    JsonBuilder *b = json_builder_new();

    json_builder_begin_object(b);
    json_builder_set_member_name(b, "preset");
    json_builder_add_string_value(b, simscan_preset_name(config->preset));
    json_builder_set_member_name(b, "seed");
    json_builder_add_int_value(b, config->seed);
    json_builder_set_member_name(b, "drift_model");
    json_builder_add_string_value(b, model_name(scene));
    json_builder_set_member_name(b, "xres");
    json_builder_add_int_value(b, scene->scan.xres);
    json_builder_set_member_name(b, "yres");
    json_builder_add_int_value(b, scene->scan.yres);
    json_values_set_pair(b, "pixel_nm",
                         (const gdouble[2]){
                             1e9*scene->scan.xreal/scene->scan.xres,
                             1e9*scene->scan.yreal/scene->scan.yres });
    json_values_set_number(b, "frame_time_s",
                           scan_timing_frame_end(&scene->timing));
    json_builder_set_member_name(b, "local_scans");
    json_builder_begin_object(b);
    json_values_set_number(b, "start_s", m->t_start);
    json_values_set_number(b, "end_s", m->t_end);
    json_builder_set_member_name(b, "lines");
    json_builder_add_int_value(b, m->lines);
    json_builder_end_object(b);
    json_values_set_pair(b, "reference_drift_nm",
                         (const gdouble[2]){ 1e9*m->ref_drift[0],
                                             1e9*m->ref_drift[1] });
    add_stripes(b, m);
    if (m->have_errors) {
        json_builder_set_member_name(b, "centre_error");
        json_builder_begin_object(b);
        add_error(b, "before", &m->before);
        add_error(b, "after", &m->after);
        json_builder_end_object(b);
    }
    json_builder_end_object(b);
    return json_values_finish(b);
}

GByteArray*
simscan_output_gwy_bytes(GwyContainer *data)
{
    GByteArray *bytes = g_byte_array_new();

    g_byte_array_append(bytes, (const guint8*)GWY_MAGIC, strlen(GWY_MAGIC));
    gwy_serializable_serialize(G_OBJECT(data), bytes);
    return bytes;
}

static GByteArray*
gwy_file_bytes(const SimscanScene *scene, const SimscanMeasurement *m)
{
    GwyContainer *data = simscan_output_container(scene, m);
    GByteArray *bytes = simscan_output_gwy_bytes(data);

    g_object_unref(data);
    return bytes;
}

static gboolean
add_text(OutputFiles *files, const gchar *filename, gchar *text,
         GError **error)
{
    gboolean ok = output_files_add(files, filename, (const guchar*)text,
                                   strlen(text), error);

    g_free(text);
    return ok;
}

gboolean
simscan_output_write_all(const SimscanScene *scene,
                         const SimscanMeasurement *m, GError **error)
{
    const SimscanConfig *config = scene->config;
    OutputFiles *files = output_files_new();
    gboolean ok = TRUE;

    if (config->output) {
        GByteArray *bytes = gwy_file_bytes(scene, m);

        ok = output_files_add(files, config->output, bytes->data, bytes->len,
                              error);
        g_byte_array_free(bytes, TRUE);
    }
    if (ok && config->table)
        ok = add_text(files, config->table, drift_table_to_string(m->table),
                      error);
    if (ok && config->json)
        ok = add_text(files, config->json, simscan_output_json(scene, m),
                      error);
    ok = ok && output_files_commit(files, error);
    output_files_free(files);
    return ok;
}
