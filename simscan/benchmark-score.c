/*
 *  `simscan score`: a method's trajectory, corrected frames and flags on
 *  one benchmark case against the case's truth (docs/benchmark.md).  The
 *  trajectory is read by the same parser as the truth's; corrected frames
 *  are registered stripe by stripe against the drift-free truth with the
 *  product's registration.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <string.h>
#include <stdlib.h>
#include <math.h>
#include <json-glib/json-glib.h>
#include <libgwyddion/gwyddion.h>
#include <libprocess/gwyprocess.h>
#include <app/gwyapp.h>
#include "displacement-measure.h"
#include "localscan-channel.h"
#include "trajectory-csv.h"
#include "simscan-sample-file.h"
#include "simscan-i18n.h"
#include "benchmark-score.h"

/* Lines within this many line times of a jump are scored by nobody. */
#define JUMP_LINES 3
/* Scan lines a case may have (frames x rows): a case description from
 * elsewhere must not make the scorer allocate without bound. */
#define MAX_LINES (1 << 22)
/* A trajectory value beyond this is no drift a frame can show: refused
 * (squares of 1e200 overflow the figures into infinities). */
#define MAX_DRIFT_PX 1e6
/* A stripe of a corrected frame is judged when this fraction of its
 * pixels hold data. */
#define MIN_STRIPE_COVERAGE 0.6
/* Stripes a corrected frame is judged in. */
#define JUDGE_STRIPES 8
/* Corrected channels are those titled so, when any is. */
#define CORRECTED_SUFFIX "(drift corrected)"

typedef struct {
    gint n_frames, xres, yres;
    gdouble line_time;
    gdouble aspect;            /* y pixel over x pixel */
    gdouble t_jump;            /* NAN without a jump */
    gdouble p0[2];             /* px: where the truth lies in corrected
                                  frames */
    gboolean *disturbed;       /* per frame */
    TrajectoryTable truth;     /* per frame and row */
} TruthCase;

/* Reads the trajectory CSV at path into table (trajectory-csv.h); NULL,
 * or why it cannot be read. */
static gchar*
read_trajectory(const gchar *path, gint n_frames, gint yres,
                TrajectoryTable *table)
{
    gchar *text = NULL, *failure;
    GError *err = NULL;

    memset(table, 0, sizeof(TrajectoryTable));
    if (!g_file_get_contents(path, &text, NULL, &err)) {
        failure = g_strdup(err->message);
        g_clear_error(&err);
        return failure;
    }
    failure = trajectory_csv_parse(text, n_frames, yres, table);
    g_free(text);
    return failure;
}

static gboolean
json_get_int(JsonObject *o, const gchar *name, gint lo, gint hi, gint *v)
{
    JsonNode *node = json_object_get_member(o, name);

    gint64 value;

    if (!node || json_node_get_value_type(node) != G_TYPE_INT64)
        return FALSE;
    value = json_node_get_int(node);
    if (value < lo || value > hi)
        return FALSE;
    *v = (gint)value;
    return TRUE;
}

static gboolean
json_get_double(JsonObject *o, const gchar *name, gdouble *v)
{
    JsonNode *node = json_object_get_member(o, name);

    if (!node || (json_node_get_value_type(node) != G_TYPE_DOUBLE
                  && json_node_get_value_type(node) != G_TYPE_INT64))
        return FALSE;
    *v = json_node_get_double(node);
    return isfinite(*v);
}

static gboolean
json_get_pair(JsonObject *o, const gchar *name, gdouble *v)
{
    JsonNode *node = json_object_get_member(o, name);
    JsonArray *a;
    guint i;

    if (!node || !JSON_NODE_HOLDS_ARRAY(node)
        || json_array_get_length(a = json_node_get_array(node)) != 2)
        return FALSE;
    for (i = 0; i < 2; i++) {
        GType type = json_node_get_value_type(json_array_get_element(a, i));

        if (type != G_TYPE_DOUBLE && type != G_TYPE_INT64)
            return FALSE;
    }
    v[0] = json_array_get_double_element(a, 0);
    v[1] = json_array_get_double_element(a, 1);
    return isfinite(v[0]) && isfinite(v[1]);
}

static gboolean
read_disturbed(JsonObject *o, TruthCase *tc)
{
    JsonNode *node = json_object_get_member(o, "disturbed_frames");
    JsonArray *a;
    gint64 k;
    guint i;

    if (!node || !JSON_NODE_HOLDS_ARRAY(node))
        return FALSE;
    a = json_node_get_array(node);
    for (i = 0; i < json_array_get_length(a); i++) {
        if (json_node_get_value_type(json_array_get_element(a, i)) != G_TYPE_INT64)
            return FALSE;
        k = json_array_get_int_element(a, i);
        if (k < 0 || k >= tc->n_frames)
            return FALSE;
        tc->disturbed[k] = TRUE;
    }
    return TRUE;
}

static gboolean
read_case_json(const gchar *path, TruthCase *tc, GError **error)
{
    JsonParser *parser = json_parser_new();
    JsonObject *o, *drift;
    JsonNode *root;
    gdouble pixel[2];
    gboolean ok;

    ok = json_parser_load_from_file(parser, path, error);
    if (ok) {
        root = json_parser_get_root(parser);
        ok = (root && JSON_NODE_HOLDS_OBJECT(root));
        o = ok ? json_node_get_object(root) : NULL;
        ok = (ok && json_get_int(o, "frames", 1, 100000, &tc->n_frames)
              && json_get_int(o, "xres", 2, 1 << 16, &tc->xres)
              && json_get_int(o, "yres", 2, 1 << 16, &tc->yres)
              && json_get_double(o, "line_time_s", &tc->line_time)
              && json_get_pair(o, "pixel_m", pixel) && pixel[0] > 0.0
              && json_get_pair(o, "p0_px", tc->p0)
              && json_object_has_member(o, "drift")
              && JSON_NODE_HOLDS_OBJECT(json_object_get_member(o, "drift"))
              && (gint64)tc->n_frames*tc->yres <= MAX_LINES);
        if (ok) {
            tc->aspect = pixel[1]/pixel[0];
            tc->disturbed = g_new0(gboolean, tc->n_frames);
            ok = read_disturbed(o, tc);
            drift = json_object_get_object_member(o, "drift");
            tc->t_jump = NAN;
            if (drift && !json_get_double(drift, "t_s", &tc->t_jump))
                tc->t_jump = NAN;
        }
        if (!ok)
            g_set_error(error, G_FILE_ERROR, G_FILE_ERROR_INVAL,
                        _("%s: not a benchmark case description"), path);
    }
    g_object_unref(parser);
    return ok;
}

static void
truth_case_free(TruthCase *tc)
{
    g_free(tc->disturbed);
    tc->disturbed = NULL;
    trajectory_table_free(&tc->truth);
}

static gboolean
read_truth(const gchar *dir, TruthCase *tc, GError **error)
{
    gchar *path = g_build_filename(dir, "case.json", NULL), *failure;
    gboolean ok;

    memset(tc, 0, sizeof(TruthCase));
    ok = read_case_json(path, tc, error);
    g_free(path);
    if (!ok) {
        truth_case_free(tc);
        return FALSE;
    }
    path = g_build_filename(dir, "truth.csv", NULL);
    if ((failure = read_trajectory(path, tc->n_frames, tc->yres, &tc->truth))) {
        g_set_error(error, G_FILE_ERROR, G_FILE_ERROR_INVAL, "%s: %s", path,
                    failure);
        g_free(failure);
        truth_case_free(tc);
        ok = FALSE;
    }
    g_free(path);
    return ok;
}

static gboolean
line_scored(const TruthCase *tc, gint k, gint i)
{
    return (tc->truth.have[i] && !tc->disturbed[k]
            && !(fabs(tc->truth.t[i] - tc->t_jump) < JUMP_LINES*tc->line_time));
}

static gchar*
score_trajectory(const TruthCase *tc, const gchar *path, BenchmarkScore *score)
{
    gint k, r, i, count = 0;
    gdouble sum = 0.0, e;
    const TrajectoryTable *truth = &tc->truth;
    TrajectoryTable tr;
    gchar *failure;

    if (!g_file_test(path, G_FILE_TEST_EXISTS))
        return g_strdup(_("trajectory.csv absent"));
    failure = read_trajectory(path, tc->n_frames, tc->yres, &tr);
    score->trajectory_worst_px = 0.0;
    for (k = 0; k < tc->n_frames && !failure; k++) {
        for (r = 0; r < tc->yres && !failure; r++) {
            if (!line_scored(tc, k, i = k*tc->yres + r))
                continue;
            if (!tr.have[i]) {
                failure = g_strdup_printf(_("frame %d row %d is missing"), k,
                                          r);
                break;
            }
            if (!(fabs(tr.dx[i]) <= MAX_DRIFT_PX && fabs(tr.dy[i]) <= MAX_DRIFT_PX)) {
                failure = g_strdup_printf(_("frame %d row %d: beyond %g px"),
                                          k, r, MAX_DRIFT_PX);
                break;
            }
            e = hypot(tr.dx[i] - truth->dx[i], tr.dy[i] - truth->dy[i]);
            sum += e*e;
            score->trajectory_worst_px = MAX(score->trajectory_worst_px, e);
            count++;
        }
    }
    score->trajectory_rms_px = sqrt(sum/MAX(count, 1));
    trajectory_table_free(&tr);
    if (failure) {
        gchar *why = g_strdup_printf("trajectory.csv: %s", failure);

        g_free(failure);
        return why;
    }
    return NULL;
}

/* The channels holding the corrected frames: those titled as corrected
 * when any is, else every image channel, in the order of their ids. */
static GArray*
corrected_channels(GwyContainer *data)
{
    gint *ids = localscan_channel_ids(data), i;
    GArray *all = g_array_new(FALSE, FALSE, sizeof(gint));
    GArray *titled = g_array_new(FALSE, FALSE, sizeof(gint));
    gchar *title;

    for (i = 0; ids[i] >= 0; i++) {
        g_array_append_val(all, ids[i]);
        title = gwy_app_get_data_field_title(data, ids[i]);
        if (g_str_has_suffix(title, CORRECTED_SUFFIX))
            g_array_append_val(titled, ids[i]);
        g_free(title);
    }
    g_free(ids);
    if (titled->len) {
        g_array_free(all, TRUE);
        return titled;
    }
    g_array_free(titled, TRUE);
    return all;
}

/* The frame's data with its masked pixels missing (NaN): what the method
 * had no data for is not judged. */
static gdouble*
frame_with_mask(GwyContainer *data, gint id)
{
    GwyDataField *field = gwy_container_get_object(data,
                                                   gwy_app_get_data_key_for_id(id));
    GwyDataField *mask = NULL;
    gsize n = (gsize)gwy_data_field_get_xres(field)*gwy_data_field_get_yres(field), i;
    gdouble *d = g_memdup2(gwy_data_field_get_data_const(field),
                           n*sizeof(gdouble));
    const gdouble *m;

    if (gwy_container_gis_object(data, gwy_app_get_mask_key_for_id(id),
                                 (GObject**)&mask)
        && GWY_IS_DATA_FIELD(mask)
        && gwy_data_field_check_compatibility(field, mask,
                                              GWY_DATA_COMPATIBILITY_RES) == 0) {
        m = gwy_data_field_get_data_const(mask);
        for (i = 0; i < n; i++) {
            if (m[i] >= 0.5)
                d[i] = NAN;
        }
    }
    return d;
}

/* The fraction of stripe i's pixels that hold data. */
static gdouble
stripe_coverage(const TruthCase *tc, const gdouble *frame, gint i)
{
    gint first = i*tc->yres/JUDGE_STRIPES, end = (i + 1)*tc->yres/JUDGE_STRIPES;
    gsize k, n = (gsize)(end - first)*tc->xres, valid = 0;
    const gdouble *d = frame + (gsize)first*tc->xres;

    for (k = 0; k < n; k++)
        valid += !isnan(d[k]);
    return n ? (gdouble)valid/n : 0.0;
}

/* Stripes mostly without data (content drifted out of the frame) are not
 * judged: what is left of them registers ambiguously (a stripe 69 %
 * masked read 2.4 px off at a score of 0.93, benchmark seed 780307). */
static void
score_frame(const TruthCase *tc, const gdouble *frame, const gdouble *truth,
            gdouble *sum, gint *count, BenchmarkScore *score)
{
    gdouble dx[JUDGE_STRIPES], dy[JUDGE_STRIPES], s[JUDGE_STRIPES], e;
    gint i;

    displacement_register_blocks(frame, truth, tc->xres, tc->yres,
                                 JUDGE_STRIPES, NULL, tc->aspect, NULL,
                                 dx, dy, s, NULL);
    for (i = 0; i < JUDGE_STRIPES; i++) {
        if (stripe_coverage(tc, frame, i) < MIN_STRIPE_COVERAGE)
            continue;
        score->stripes_judged++;
        if (!(s[i] > 0.0)) {
            score->stripes_lost++;
            continue;
        }
        e = hypot(dx[i] - tc->p0[0], dy[i] - tc->p0[1]);
        *sum += e*e;
        score->frame_worst_px = MAX(score->frame_worst_px, e);
        (*count)++;
    }
}

/* The drift-free frame of the case (channel 0 of truth.gwy, xres x yres),
 * or NULL with error set: the truth, not the method, is at fault. */
static gdouble*
load_truth_frame(const TruthCase *tc, const gchar *truth_dir, GError **error)
{
    gchar *path = g_build_filename(truth_dir, "truth.gwy", NULL);
    GwyContainer *data = simscan_load_file(path, error);
    GwyDataField *field = NULL;
    gdouble *truth = NULL;

    if (data
        && (!gwy_container_gis_object(data, gwy_app_get_data_key_for_id(0),
                                      (GObject**)&field)
            || !GWY_IS_DATA_FIELD(field)
            || gwy_data_field_get_xres(field) != tc->xres
            || gwy_data_field_get_yres(field) != tc->yres))
        g_set_error(error, G_FILE_ERROR, G_FILE_ERROR_INVAL,
                    _("%s: no drift-free frame of %dx%d in channel 0"), path,
                    tc->xres, tc->yres);
    else if (data)
        truth = frame_with_mask(data, 0);
    if (data)
        g_object_unref(data);
    g_free(path);
    return truth;
}

static gchar*
score_frames(const TruthCase *tc, const gdouble *truth, const gchar *path,
             BenchmarkScore *score)
{
    GwyContainer *data;
    gchar *failure = NULL;
    gdouble *frame, sum = 0.0;
    GError *err = NULL;
    GArray *ids = NULL;
    gint k, count = 0, id;

    if (!(data = simscan_load_file(path, &err))) {
        failure = g_strdup_printf("corrected.gwy: %s", err->message);
        g_clear_error(&err);
        return failure;
    }
    ids = corrected_channels(data);
    if ((gint)ids->len != tc->n_frames)
        failure = g_strdup_printf(_("corrected.gwy holds %u frames, the case "
                                    "%d"), ids->len, tc->n_frames);
    score->frame_worst_px = 0.0;
    for (k = 0; k < tc->n_frames && !failure; k++) {
        GwyDataField *field;

        id = g_array_index(ids, gint, k);
        field = gwy_container_get_object(data, gwy_app_get_data_key_for_id(id));
        if (gwy_data_field_get_xres(field) != tc->xres
            || gwy_data_field_get_yres(field) != tc->yres) {
            failure = g_strdup_printf(_("corrected frame %d is %dx%d, not "
                                        "%dx%d"), k,
                                      gwy_data_field_get_xres(field),
                                      gwy_data_field_get_yres(field),
                                      tc->xres, tc->yres);
            break;
        }
        if (tc->disturbed[k])
            continue;
        frame = frame_with_mask(data, id);
        score_frame(tc, frame, truth, &sum, &count, score);
        g_free(frame);
    }
    score->frame_rms_px = count ? sqrt(sum/count) : NAN;
    g_array_free(ids, TRUE);
    g_object_unref(data);
    return failure;
}

/* Flagged frames from flagged.txt (one index per line) or from result.json
 * (a `frames` array of objects with `index` and `flagged`, as
 * `gwy-localscan series --json` writes it). */
static gchar*
read_flags(const gchar *dir, gint n_frames, gboolean *flagged, gboolean *given)
{
    gchar *path = g_build_filename(dir, "flagged.txt", NULL), *text = NULL;
    gchar **lines, *failure = NULL;
    gint64 v;
    gint i, k;

    *given = FALSE;
    if (g_file_get_contents(path, &text, NULL, NULL)) {
        *given = TRUE;
        lines = g_strsplit(text, "\n", -1);
        for (i = 0; lines[i] && !failure; i++) {
            g_strstrip(lines[i]);
            if (!*lines[i] || lines[i][0] == '#')
                continue;
            if (g_ascii_string_to_signed(lines[i], 10, 0, n_frames - 1, &v,
                                         NULL))
                flagged[v] = TRUE;
            else
                failure = g_strdup_printf(_("flagged.txt line %d: not a frame "
                                            "0 to %d"), i + 1, n_frames - 1);
        }
        g_strfreev(lines);
        g_free(text);
    }
    g_free(path);
    if (*given || failure)
        return failure;
    path = g_build_filename(dir, "result.json", NULL);
    if (g_file_test(path, G_FILE_TEST_EXISTS)) {
        JsonParser *parser = json_parser_new();
        JsonNode *root, *node = NULL;
        JsonArray *a;
        JsonObject *o;
        guint j;

        *given = TRUE;
        if (!json_parser_load_from_file(parser, path, NULL)
            || !(root = json_parser_get_root(parser))
            || !JSON_NODE_HOLDS_OBJECT(root)
            || !(node = json_object_get_member(json_node_get_object(root),
                                               "frames"))
            || !JSON_NODE_HOLDS_ARRAY(node))
            failure = g_strdup(_("result.json has no frames array"));
        a = failure ? NULL : json_node_get_array(node);
        for (j = 0; a && j < json_array_get_length(a) && !failure; j++) {
            o = json_array_get_object_element(a, j);
            if (!o || !json_get_int(o, "index", 0, n_frames - 1, &k)
                || !json_object_has_member(o, "flagged")
                || json_node_get_value_type(json_object_get_member(o, "flagged"))
                   != G_TYPE_BOOLEAN)
                failure = g_strdup_printf(_("result.json frame %u: no index "
                                            "0 to %d or no flagged true or "
                                            "false"), j,
                                          n_frames - 1);
            else
                flagged[k] = json_object_get_boolean_member(o, "flagged");
        }
        g_object_unref(parser);
    }
    g_free(path);
    return failure;
}

static gchar*
score_flags(const TruthCase *tc, const gchar *dir, BenchmarkScore *score)
{
    gboolean *flagged = g_new0(gboolean, tc->n_frames), given;
    gchar *failure = read_flags(dir, tc->n_frames, flagged, &given);
    gint k;

    score->flags_missed = score->flags_false = -1;
    for (k = 0; k < tc->n_frames; k++)
        score->disturbed += tc->disturbed[k];
    if (given && !failure) {
        score->flags_missed = score->flags_false = 0;
        for (k = 0; k < tc->n_frames; k++) {
            score->flags_missed += (tc->disturbed[k] && !flagged[k]);
            score->flags_false += (!tc->disturbed[k] && flagged[k]);
        }
    }
    g_free(flagged);
    return failure;
}

/* One method's result folder against a truth read already; the drift-free
 * frame is loaded when the first corrected frames ask for it. */
static gboolean
score_result(const TruthCase *tc, const gchar *truth_case_dir,
             const gchar *result_case_dir, gdouble **truth,
             BenchmarkScore *score, GError **error)
{
    gboolean ok = TRUE;
    gchar *path;

    memset(score, 0, sizeof(BenchmarkScore));
    score->trajectory_rms_px = score->trajectory_worst_px = NAN;
    score->frame_rms_px = score->frame_worst_px = NAN;
    score->flags_missed = score->flags_false = -1;
    path = g_build_filename(result_case_dir, "trajectory.csv", NULL);
    score->failure = score_trajectory(tc, path, score);
    g_free(path);
    path = g_build_filename(result_case_dir, "corrected.gwy", NULL);
    if (!score->failure && g_file_test(path, G_FILE_TEST_EXISTS)) {
        if (*truth || (*truth = load_truth_frame(tc, truth_case_dir, error)))
            score->failure = score_frames(tc, *truth, path, score);
        else
            ok = FALSE;
    }
    g_free(path);
    if (ok && !score->failure)
        score->failure = score_flags(tc, result_case_dir, score);
    return ok;
}

gboolean
benchmark_score_case(const gchar *truth_case_dir, gchar **result_case_dirs,
                     gint n, BenchmarkScore *scores, GError **error)
{
    TruthCase tc;
    gdouble *truth = NULL;
    gboolean ok;
    gint j;

    for (j = 0; j < n; j++)
        memset(scores + j, 0, sizeof(BenchmarkScore));
    if (!read_truth(truth_case_dir, &tc, error))
        return FALSE;
    for (j = 0, ok = TRUE; j < n && ok; j++)
        ok = score_result(&tc, truth_case_dir, result_case_dirs[j], &truth,
                          scores + j, error);
    g_free(truth);
    truth_case_free(&tc);
    return ok;
}

void
benchmark_score_clear(BenchmarkScore *score)
{
    g_free(score->failure);
    score->failure = NULL;
}
