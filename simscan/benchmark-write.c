/*
 *  `simscan benchmark`: scans the cases of benchmark-cases.c and writes
 *  each as a folder of frames with its truth (docs/benchmark.md gives the
 *  layout).  Everything is written or nothing: the folder is made new and
 *  removed again when anything fails.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <string.h>
#include <errno.h>
#include <math.h>
#include <glib/gstdio.h>
#include <libgwyddion/gwyddion.h>
#include <libprocess/gwyprocess.h>
#include "json-values.h"
#include "output-files.h"
#include "trajectory-csv.h"
#include "raw-artefacts.h"
#include "sample.h"
#include "scanner.h"
#include "simscan-output.h"
#include "simscan-sample-file.h"
#include "simscan-i18n.h"
#include "benchmark-write.h"

/* The sample reaches this far (of the frame) beyond the frame on every
 * side: room for a third of the frame of drift and the initial offset. */
#define SAMPLE_MARGIN 0.45
/* Synthetic particles: radius and how many per square metre (the hidden
 * effect tests' density: 90 on 1.6 um square). */
#define PARTICLE_RADIUS 20e-9
#define PARTICLE_DENSITY (90.0/(1.6e-6*1.6e-6))
/* Measurement noise and raw-channel artefacts relative to the sample's
 * RMS height in the frame. */
#define NOISE_OF_RMS 0.02
#define RAW_OF_RMS 3.0
/* Missing pixels: a block of about this fraction of each frame. */
#define MISSING_BLOCK 0.3

static gchar*
measured_file(const gchar *measured_dir, BenchmarkSample sample)
{
    if (sample == BENCHMARK_SAMPLE_FILM)
        return g_build_filename(measured_dir, "particles-film",
                                "PTO_110_Virgin0001.gwy", NULL);
    return g_build_filename(measured_dir, "hsafm-minicircles",
                            "hsafm_sample0_frames50-140.gwy", NULL);
}

/* A measured image stretched over the case's sample area (its texture is
 * what matters; heights are kept). */
static SimSample*
measured_sample(const BenchmarkCase *bc, const gchar *measured_dir,
                gdouble extent, GError **error)
{
    gchar *filename = measured_file(measured_dir, bc->sample);
    GwyDataField *field;
    SimSample *sample;
    gdouble scale;

    if (!g_file_test(filename, G_FILE_TEST_IS_REGULAR)) {
        g_set_error(error, G_FILE_ERROR, G_FILE_ERROR_NOENT,
                    _("measured data absent (%s)"), filename);
        g_free(filename);
        return NULL;
    }
    field = simscan_load_channel(filename, -1, error);
    g_free(filename);
    if (!field)
        return NULL;
    scale = extent/MIN(gwy_data_field_get_xreal(field),
                       gwy_data_field_get_yreal(field));
    gwy_data_field_set_xreal(field, scale*gwy_data_field_get_xreal(field));
    gwy_data_field_set_yreal(field, scale*gwy_data_field_get_yreal(field));
    sample = sim_sample_new_from_field(field);
    g_object_unref(field);
    return sample;
}

static SimSample*
case_sample(const BenchmarkCase *bc, guint32 seed, gint index,
            const gchar *measured_dir, GError **error)
{
    gdouble extent = bc->field*(1.0 + 2.0*SAMPLE_MARGIN);
    SimParticleParams pp;

    if (bc->sample != BENCHMARK_SAMPLE_PARTICLES)
        return measured_sample(bc, measured_dir, extent, error);
    sim_particle_params_init(&pp);
    pp.xreal = pp.yreal = extent;
    pp.radius = PARTICLE_RADIUS;
    pp.count = (gint)ceil(PARTICLE_DENSITY*extent*extent);
    return sim_sample_new_particles(&pp, seed + 1000u*index);
}

static void
case_scan_params(const BenchmarkCase *bc, const SimSample *sample, gint k,
                 SimScanParams *sp)
{
    sim_scan_params_init(sp, sample, bc->xres, bc->yres);
    sp->xreal = sp->yreal = bc->field;
    sp->xoff = sp->yoff = SAMPLE_MARGIN*bc->field;
    sp->line_time = bc->line_time;
    sp->direction = bc->direction;
    sp->frame_start = benchmark_case_frame_start(bc, k);
}

static gdouble
field_rms(GwyDataField *field)
{
    gdouble rms = gwy_data_field_get_rms(field);

    return (rms > 0.0) ? rms : 1e-9;
}

/* A block of missing pixels (NaN) at a random place in every frame, and
 * two random lines: what dropouts and cropped exports leave. */
static void
punch_missing(GwyDataField *field, GRand *rng)
{
    gint xres = gwy_data_field_get_xres(field);
    gint yres = gwy_data_field_get_yres(field);
    gint w = (gint)(MISSING_BLOCK*xres), h = (gint)(MISSING_BLOCK*yres);
    gint col = g_rand_int_range(rng, 0, xres - w + 1);
    gint row = g_rand_int_range(rng, 0, yres - h + 1);
    gdouble *d = gwy_data_field_get_data(field);
    gint r, c, i;

    for (r = row; r < row + h; r++) {
        for (c = col; c < col + w; c++)
            d[r*xres + c] = NAN;
    }
    for (i = 0; i < 2; i++) {
        r = g_rand_int_range(rng, 0, yres);
        for (c = 0; c < xres; c++)
            d[r*xres + c] = NAN;
    }
    gwy_data_field_invalidate(field);
}

/* A frame as Gwyddion files carry one: the channel, its title and the
 * timing in the metadata keys scan-timing-meta.h reads. */
static GByteArray*
frame_file_bytes(GwyDataField *field, const gchar *title,
                 const SimScanParams *sp)
{
    GwyContainer *data = gwy_container_new(), *meta = gwy_container_new();
    GByteArray *bytes;

    gwy_container_set_object_by_name(data, "/0/data", field);
    gwy_container_set_const_string_by_name(data, "/0/data/title",
                                           (const guchar*)title);
    simscan_output_timing_meta(meta, sp->line_time, sp->direction,
                               sp->frame_start);
    gwy_container_set_object_by_name(data, "/0/meta", meta);
    bytes = simscan_output_gwy_bytes(data);
    g_object_unref(meta);
    g_object_unref(data);
    return bytes;
}

static gboolean
add_bytes(OutputFiles *files, const gchar *dir, const gchar *name,
          GByteArray *bytes, GError **error)
{
    gchar *path = g_build_filename(dir, name, NULL);
    gboolean ok = output_files_add(files, path, bytes->data, bytes->len,
                                   error);

    g_byte_array_free(bytes, TRUE);
    g_free(path);
    return ok;
}

static gboolean
add_text(OutputFiles *files, const gchar *dir, const gchar *name,
         gchar *text, GError **error)
{
    return add_bytes(files, dir, name,
                     g_byte_array_new_take((guint8*)text, strlen(text)), error);
}

/* The truth in the series trajectory format of `gwy-localscan series
 * --trajectory`: p(t) - p(0) at the centre of each line's trace, in pixels
 * of the frames, the disturbed frame's slip not included (it is no drift). */
static gchar*
truth_trajectory_csv(const BenchmarkCase *bc)
{
    GString *text = g_string_new(NULL);
    gdouble xstep = bc->field/bc->xres, ystep = bc->field/bc->yres;
    gdouble x0, y0, x, y, t;
    ScanTiming timing;
    gint k, r;

    trajectory_csv_begin(text, "true drift", xstep, ystep);
    drift_model_eval(&bc->drift, 0.0, &x0, &y0);
    for (k = 0; k < bc->n_frames; k++) {
        benchmark_case_timing(bc, k, &timing);
        for (r = 0; r < bc->yres; r++) {
            t = scan_timing_rows_time(&timing, r, r+1);
            drift_model_eval(&bc->drift, t, &x, &y);
            trajectory_csv_line(text, k, r, t, (x - x0)/xstep, (y - y0)/ystep,
                                6);
        }
    }
    return g_string_free(text, FALSE);
}

static void
add_drift_parameters(JsonBuilder *b, const DriftModel *m)
{
    gdouble v[2];

    json_builder_set_member_name(b, "drift");
    json_builder_begin_object(b);
    json_builder_set_member_name(b, "type");
    json_builder_add_string_value(b, drift_model_type_name(m->type));
    v[0] = 1e9*m->v[0];
    v[1] = 1e9*m->v[1];
    json_values_set_pair(b, "velocity_nm_per_s", v);
    if (m->type == DRIFT_MODEL_SETTLING) {
        json_values_set_number(b, "tau_s", m->tau);
        v[0] = 1e9*m->u[0];
        v[1] = 1e9*m->u[1];
        json_values_set_pair(b, "u_nm_per_s", v);
    }
    else if (m->type == DRIFT_MODEL_OSCILLATION) {
        json_values_set_number(b, "period_s", m->period);
        v[0] = 1e9*m->a[0];
        v[1] = 1e9*m->a[1];
        json_values_set_pair(b, "amplitude_nm", v);
        json_values_set_number(b, "phase_rad", m->phase);
    }
    else if (m->type == DRIFT_MODEL_JUMP) {
        json_values_set_number(b, "t_s", m->t_jump);
        v[0] = 1e9*m->step[0];
        v[1] = 1e9*m->step[1];
        json_values_set_pair(b, "step_nm", v);
    }
    else if (m->type == DRIFT_MODEL_ACCELERATION) {
        v[0] = 1e9*m->accel[0];
        v[1] = 1e9*m->accel[1];
        json_values_set_pair(b, "accel_nm_per_s2", v);
    }
    else if (m->type == DRIFT_MODEL_RANDOM_WALK)
        json_values_set_number(b, "walk_sigma_nm_per_s15", 1e9*m->walk_sigma);
    if (m->creep_period > 0.0) {
        v[0] = 1e9*m->creep[0];
        v[1] = 1e9*m->creep[1];
        json_values_set_pair(b, "frame_creep_nm", v);
        json_values_set_number(b, "frame_creep_tau_s", m->creep_tau);
    }
    json_builder_end_object(b);
}

/* What a scorer and a reader need to know of the case. */
static gchar*
case_json(const BenchmarkCase *bc, const gdouble *p0_px)
{
    JsonBuilder *b = json_builder_new();
    gdouble v[2];
    gint k;

    json_builder_begin_object(b);
    json_builder_set_member_name(b, "name");
    json_builder_add_string_value(b, bc->name);
    json_builder_set_member_name(b, "summary");
    json_builder_add_string_value(b, bc->summary);
    json_builder_set_member_name(b, "sample");
    json_builder_add_string_value(b, benchmark_sample_name(bc->sample));
    json_builder_set_member_name(b, "frames");
    json_builder_add_int_value(b, bc->n_frames);
    json_builder_set_member_name(b, "xres");
    json_builder_add_int_value(b, bc->xres);
    json_builder_set_member_name(b, "yres");
    json_builder_add_int_value(b, bc->yres);
    v[0] = bc->field/bc->xres;
    v[1] = bc->field/bc->yres;
    json_values_set_pair(b, "pixel_m", v);
    json_values_set_number(b, "line_time_s", bc->line_time);
    json_builder_set_member_name(b, "direction");
    json_builder_add_string_value(b, scan_direction_name(bc->direction));
    json_builder_set_member_name(b, "frame_start_s");
    json_builder_begin_array(b);
    for (k = 0; k < bc->n_frames; k++)
        json_values_add_number(b, benchmark_case_frame_start(bc, k));
    json_builder_end_array(b);
    add_drift_parameters(b, &bc->drift);
    json_values_set_pair(b, "p0_px", p0_px);
    json_builder_set_member_name(b, "raw_channel");
    json_builder_add_boolean_value(b, bc->raw);
    json_builder_set_member_name(b, "missing_pixels");
    json_builder_add_boolean_value(b, bc->missing);
    json_builder_set_member_name(b, "disturbed_frames");
    json_builder_begin_array(b);
    if (bc->disturbed >= 0)
        json_builder_add_int_value(b, bc->disturbed);
    json_builder_end_array(b);
    json_builder_end_object(b);
    return json_values_finish(b);
}

/* Frame k of the case: scanned under the drift (the disturbed frame
 * slipped), noise, then what the case adds. */
static GwyDataField*
scan_case_frame(const BenchmarkCase *bc, const SimSample *sample,
                guint32 seed, gint index, gint k, gdouble rms,
                SimScanParams *sp)
{
    DriftModel drift;
    GwyDataField *field;
    GRand *rng;

    case_scan_params(bc, sample, k, sp);
    sp->noise_rms = NOISE_OF_RMS*rms;
    sp->noise_seed = seed + 7919u*index + k;
    drift_model_copy(&drift, &bc->drift);
    if (k == bc->disturbed) {
        drift.p0[0] += bc->slip_px[0]*bc->field/bc->xres;
        drift.p0[1] += bc->slip_px[1]*bc->field/bc->yres;
    }
    field = sim_scan_frame(sample, &drift, sp);
    drift_model_clear(&drift);
    if (!field)
        return NULL;
    rng = g_rand_new_with_seed(seed ^ (0x9a77u + 131u*index + k));
    if (bc->raw)
        sim_raw_artefacts_add(gwy_data_field_get_data(field), bc->xres,
                              bc->yres, RAW_OF_RMS*rms, rng);
    if (bc->missing)
        punch_missing(field, rng);
    gwy_data_field_invalidate(field);
    g_rand_free(rng);
    return field;
}

static gboolean
write_case(OutputFiles *files, const gchar *dir, const BenchmarkCase *bc,
           const SimSample *sample, guint32 seed, gint index, GError **error)
{
    SimScanParams sp;
    GwyDataField *truth, *field;
    GwyContainer *data;
    gdouble rms, p0[2];
    gboolean ok = TRUE;
    gchar *name;
    gint k;

    case_scan_params(bc, sample, 0, &sp);
    truth = sim_scan_truth(sample, &sp);
    rms = field_rms(truth);
    for (k = 0; k < bc->n_frames && ok; k++) {
        if (!(field = scan_case_frame(bc, sample, seed, index, k, rms, &sp))) {
            g_set_error(error, G_FILE_ERROR, G_FILE_ERROR_FAILED,
                        _("%s: frame %d could not be scanned"), bc->name, k);
            ok = FALSE;
            break;
        }
        name = g_strdup_printf("frame-%03d.gwy", k);
        ok = add_bytes(files, dir, name, frame_file_bytes(field, "Height", &sp),
                       error);
        g_free(name);
        g_object_unref(field);
    }
    data = gwy_container_new();
    gwy_container_set_object_by_name(data, "/0/data", truth);
    gwy_container_set_const_string_by_name(data, "/0/data/title",
                                           (const guchar*)"Drift-free truth");
    ok = ok && add_bytes(files, dir, "truth.gwy",
                         simscan_output_gwy_bytes(data), error);
    g_object_unref(data);
    g_object_unref(truth);
    drift_model_eval(&bc->drift, 0.0, p0, p0 + 1);
    p0[0] /= bc->field/bc->xres;
    p0[1] /= bc->field/bc->yres;
    ok = ok && add_text(files, dir, "truth.csv", truth_trajectory_csv(bc),
                        error);
    ok = ok && add_text(files, dir, "case.json", case_json(bc, p0), error);
    return ok;
}

static gchar*
manifest_json(const BenchmarkCase *cases, const gboolean *written, gint n,
              guint32 seed, BenchmarkSize size, gchar **reasons)
{
    JsonBuilder *b = json_builder_new();
    gint i;

    json_builder_begin_object(b);
    json_builder_set_member_name(b, "benchmark_version");
    json_builder_add_string_value(b, BENCHMARK_VERSION);
    json_builder_set_member_name(b, "generator");
    json_builder_add_string_value(b, "simscan " PACKAGE_VERSION);
    json_builder_set_member_name(b, "seed");
    json_builder_add_int_value(b, seed);
    json_builder_set_member_name(b, "size");
    json_builder_add_string_value(b, size == BENCHMARK_SIZE_FULL
                                  ? "full" : "small");
    json_builder_set_member_name(b, "cases");
    json_builder_begin_array(b);
    for (i = 0; i < n; i++) {
        if (written[i])
            json_builder_add_string_value(b, cases[i].name);
    }
    json_builder_end_array(b);
    json_builder_set_member_name(b, "skipped");
    json_builder_begin_array(b);
    for (i = 0; i < n; i++) {
        if (written[i])
            continue;
        json_builder_begin_object(b);
        json_builder_set_member_name(b, "name");
        json_builder_add_string_value(b, cases[i].name);
        json_builder_set_member_name(b, "reason");
        json_builder_add_string_value(b, reasons[i]);
        json_builder_end_object(b);
    }
    json_builder_end_array(b);
    json_builder_end_object(b);
    return json_values_finish(b);
}

/* The folder must be new or empty: a benchmark never mixes with older
 * files. */
static gboolean
make_output_dir(const gchar *dir, gboolean *made, GError **error)
{
    GDir *d;
    gboolean empty;

    *made = FALSE;
    if (g_file_test(dir, G_FILE_TEST_IS_DIR)) {
        if (!(d = g_dir_open(dir, 0, error)))
            return FALSE;
        empty = (g_dir_read_name(d) == NULL);
        g_dir_close(d);
        if (!empty)
            g_set_error(error, G_FILE_ERROR, G_FILE_ERROR_EXIST,
                        _("%s: the folder is not empty"), dir);
        return empty;
    }
    if (g_mkdir(dir, 0777) != 0) {
        g_set_error(error, G_FILE_ERROR, g_file_error_from_errno(errno),
                    _("%s: cannot make the folder: %s"), dir,
                    g_strerror(errno));
        return FALSE;
    }
    *made = TRUE;
    return TRUE;
}

/* Scans one case into its folder (made here); a case whose measured sample
 * is absent is skipped with the reason, anything else that fails fails. */
static gboolean
generate_case(OutputFiles *files, const gchar *dir, const BenchmarkCase *bc,
              guint32 seed, gint index, const gchar *measured_dir,
              GPtrArray *made_dirs, gboolean *written, gchar **reason,
              GError **error)
{
    GError *err = NULL;
    SimSample *sample = case_sample(bc, seed, index, measured_dir, &err);
    gchar *case_dir;
    gboolean ok;

    *written = FALSE;
    if (!sample) {
        if (g_error_matches(err, G_FILE_ERROR, G_FILE_ERROR_NOENT)) {
            *reason = g_strdup(err->message);
            g_clear_error(&err);
            return TRUE;
        }
        g_propagate_prefixed_error(error, err, "%s: ", bc->name);
        return FALSE;
    }
    case_dir = g_build_filename(dir, bc->name, NULL);
    ok = (g_mkdir(case_dir, 0777) == 0);
    if (!ok)
        g_set_error(error, G_FILE_ERROR, g_file_error_from_errno(errno),
                    _("%s: cannot make the folder: %s"), case_dir,
                    g_strerror(errno));
    else {
        g_ptr_array_add(made_dirs, g_strdup(case_dir));
        ok = write_case(files, case_dir, bc, sample, seed, index, error);
    }
    *written = ok;
    g_free(case_dir);
    sim_sample_free(sample);
    return ok;
}

gboolean
benchmark_write(const gchar *dir, guint32 seed, BenchmarkSize size,
                const gchar *measured_dir, GError **error)
{
    BenchmarkCase *cases;
    OutputFiles *files;
    GPtrArray *made_dirs;
    gboolean *written, made, ok;
    gchar **reasons;
    gint n, i;

    if (!make_output_dir(dir, &made, error))
        return FALSE;
    cases = benchmark_cases_new(size, seed, &n);
    files = output_files_new();
    made_dirs = g_ptr_array_new_with_free_func(g_free);
    written = g_new0(gboolean, n);
    reasons = g_new0(gchar*, n);
    ok = TRUE;
    for (i = 0; i < n && ok; i++)
        ok = generate_case(files, dir, cases + i, seed, i, measured_dir,
                           made_dirs, written + i, reasons + i, error);
    ok = ok && add_text(files, dir, "benchmark.json",
                        manifest_json(cases, written, n, seed, size, reasons),
                        error);
    ok = ok && output_files_commit(files, error);
    output_files_free(files);
    /* Nothing half made: the case folders (empty once the files are
     * gone) and the folder itself when it was made here. */
    for (i = made_dirs->len - 1; i >= 0 && !ok; i--)
        g_rmdir(g_ptr_array_index(made_dirs, i));
    if (!ok && made)
        g_rmdir(dir);
    g_ptr_array_free(made_dirs, TRUE);
    for (i = 0; i < n; i++)
        g_free(reasons[i]);
    g_free(reasons);
    g_free(written);
    benchmark_cases_free(cases, n);
    return ok;
}
