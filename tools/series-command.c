/*
 *  `gwy-localscan series`: a whole frame series corrected from one fitted
 *  drift trajectory (docs/series.md), the command line over the core's
 *  series correction (modules/core/series-correction.h).
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <sys/stat.h>
#include <stdio.h>
#include <string.h>
#include <math.h>
#include <glib/gstdio.h>
#include <libgwyddion/gwyddion.h>
#include <libprocess/gwyprocess.h>
#include <libgwydgets/gwydgets.h>
#include <app/gwyapp.h>
#include "series-correction.h"
#include "series-options.h"
#include "isolated-load.h"
#include "headless-run.h"
#include "gwy-stream-save.h"
#include "output-files.h"
#include "localscan-channel.h"
#include "run-description.h"
#include "quoted-input.h"
#include "library-log.h"
#include "series-command.h"
#include "missing-data.h"
#include "series-graph.h"
#include "localscan-intl.h"
#include "option-parse.h"

#define COMMAND_NAME "gwy-localscan series"

/* Sub-pixel kernel: a series is judged by how well its frames overlay. */
#define SERIES_DEFAULT_INTERPOLATION GWY_INTERPOLATION_BSPLINE

enum {
    EXIT_OK    = 0,
    EXIT_ERROR = 1,
    EXIT_USAGE = 2,
};

typedef struct {
    gchar *output;
    gchar *trajectory;
    gchar *json;
    gchar *crop;
    gchar *interpolation_name;
    gboolean all_channels;
    SeriesArgs series;
    gchar **files;
} SeriesCommandArgs;

/* What the run produced, for the output file. */
typedef struct {
    FrameSeriesOptions options;
    gint n_files;
    gchar **files;           /* the command line's, not owned */
    GwyContainer **datas;
    FrameSeries *series;
    SeriesCorrection correction;
    GwyInterpolationType interpolation;
    gboolean crop;
    gint area[4];            /* col, row, width, height of the common area */
    gint next_id;            /* the output's next channel id: the output is
                                built here alone, and asking it (a walk over
                                all its items) for every channel stored made
                                a long series quadratic */
} SeriesRun;

static void
print_line(const gchar *prefix, const gchar *message)
{
    gchar *line = quoted_input_message_line(message);

    fprintf(stderr, "%s: %s%s\n", COMMAND_NAME, prefix, line);
    g_free(line);
}

static gboolean
parse_args(SeriesCommandArgs *args, gint *argc, gchar ***argv,
           GError **error)
{
    GOptionEntry entries[] = {
        { "output", 'o', 0, G_OPTION_ARG_FILENAME, &args->output,
          N_("Write every input channel and the corrected frames to OUT.gwy"),
          N_("OUT.gwy") },
        { "trajectory", 0, 0, G_OPTION_ARG_FILENAME, &args->trajectory,
          N_("Write the drift of every scan line as CSV (- for the standard output)"),
          N_("FILE.csv") },
        { "json", 0, 0, G_OPTION_ARG_FILENAME, &args->json,
          N_("Write the fit, the frames' verdicts and the warnings as JSON "
             "(- for the standard output)"),
          N_("FILE") },
        { "crop", 0, 0, G_OPTION_ARG_STRING, &args->crop,
          N_("common: crop the corrected frames to the area every frame "
             "covers; none (default): keep the frame, masked where no data "
             "exists"), N_("common|none") },
        { "all-channels", 0, 0, G_OPTION_ARG_NONE, &args->all_channels,
          N_("Correct every channel of each file with the drift measured "
             "on the chosen one"), NULL },
        { "interpolation", 0, 0, G_OPTION_ARG_STRING,
          &args->interpolation_name,
          N_("Interpolation kernel (default bspline)"), N_("NAME") },
        { G_OPTION_REMAINING, 0, 0, G_OPTION_ARG_FILENAME_ARRAY,
          &args->files, NULL, N_("FRAME...") },
        { NULL, 0, 0, 0, NULL, NULL, NULL },
    };
    GOptionContext *context;
    gboolean ok;

    context = g_option_context_new(_("- correct a series of frames of one "
                                     "area from one drift trajectory"));
    g_option_context_set_translation_domain(context, GETTEXT_PACKAGE);
    g_option_context_set_summary(context,
        _("FRAME... are several files of one frame each, or one file whose "
          "channels are the frames.\nThe files are never modified."));
    g_option_context_set_description(context,
        _("Exit status: 0 on success, 1 on any error, 2 on a bad command "
          "line.\nOn error nothing is written."));
    g_option_context_add_main_entries(context, entries, GETTEXT_PACKAGE);
    series_args_add_entries(context, &args->series);
    ok = option_parse_naming(context, argc, argv, error);
    g_option_context_free(context);
    return ok;
}

static gboolean
refuse_usage(GError **error, const gchar *message)
{
    g_set_error_literal(error, G_OPTION_ERROR, G_OPTION_ERROR_BAD_VALUE,
                        message);
    return FALSE;
}

static gboolean
parse_interpolation(const gchar *name, GwyInterpolationType *interpolation,
                    GError **error)
{
    gchar *lower = g_ascii_strdown(name, -1), *names, *quoted;
    gint value = run_description_interpolation_from_name(lower);

    g_free(lower);
    if (value >= 0) {
        *interpolation = value;
        return TRUE;
    }
    names = run_description_interpolation_names();
    quoted = quoted_input_excerpt(name, -1);
    g_set_error(error, G_OPTION_ERROR, G_OPTION_ERROR_BAD_VALUE,
                _("--interpolation: unknown kernel '%s' (known: %s)"),
                quoted, names);
    g_free(quoted);
    g_free(names);
    return FALSE;
}

/* Frames' files named empty or twice are refused.  One scan cannot be
 * two frames, and a list of thousands of copies cost time quadratic in
 * the copies (each compared with the others as a duplicate channel) and
 * an output file of every copy.  Files are told apart by device and
 * inode, so a link to a frame is the frame. */
static gboolean
check_frame_files(gchar **files, gint n, GError **error)
{
    GHashTable *seen = g_hash_table_new_full(g_str_hash, g_str_equal, g_free, NULL);
    GStatBuf st;
    gchar *key, *message;
    gpointer first;
    gboolean ok = TRUE;
    gint i;

    /* Frames are counted from 0 here as in the warnings, the JSON and the
     * trajectory (a refusal counting from 1 named the frame after). */
    for (i = 0; i < n && ok; i++) {
        if (!*files[i]) {
            message = g_strdup_printf(_("frame %d: the file name is empty"), i);
            refuse_usage(error, message);
            g_free(message);
            ok = FALSE;
            continue;
        }
        if (g_stat(files[i], &st) != 0)
            continue;
        key = g_strdup_printf("%" G_GUINT64_FORMAT ":%" G_GUINT64_FORMAT,
                              (guint64)st.st_dev, (guint64)st.st_ino);
        if (g_hash_table_lookup_extended(seen, key, NULL, &first)) {
            message = g_strdup_printf(_("%s is given twice, as frames %d and %d: "
                                        "one scan cannot be two frames"),
                                      files[i], GPOINTER_TO_INT(first), i);
            refuse_usage(error, message);
            g_free(message);
            g_free(key);
            ok = FALSE;
        }
        else
            g_hash_table_insert(seen, key, GINT_TO_POINTER(i));
    }
    g_hash_table_destroy(seen);
    return ok;
}

/* The file an output role checks: none for the standard output. */
static const gchar*
output_file(const gchar *filename)
{
    return output_files_is_stdout(filename) ? NULL : filename;
}

static gboolean
check_args(SeriesCommandArgs *args, SeriesRun *run, GError **error)
{
    gint n_files = args->files ? g_strv_length(args->files) : 0, i;
    OutputFilesRole *roles;
    gboolean ok;

    if (!args->output)
        return refuse_usage(error, _("-o OUT.gwy is required"));
    if (!output_files_check_names_given((const gchar *const[]){ "-o", "--trajectory", "--json" },
                                        (const gchar *const[]){ args->output, args->trajectory,
                                                                args->json },
                                        3, error))
        return FALSE;
    if (!n_files)
        return refuse_usage(error, _("no frames given (several files, or "
                                     "one file with a channel per frame)"));
    if (!check_frame_files(args->files, n_files, error))
        return FALSE;
    run->crop = FALSE;
    if (args->crop && g_ascii_strcasecmp(args->crop, "common") == 0)
        run->crop = TRUE;
    else if (args->crop && g_ascii_strcasecmp(args->crop, "none") != 0)
        return refuse_usage(error, _("--crop must be common or none"));
    if (output_files_is_stdout(args->output))
        return refuse_usage(error, _("-o names a file: the .gwy file is not "
                                     "written to the standard output"));
    if (output_files_is_stdout(args->trajectory) && output_files_is_stdout(args->json))
        return refuse_usage(error, _("--trajectory and --json cannot both go "
                                     "to the standard output"));
    if (!output_files_check_kind(args->output, error)
        || !output_files_check_kind(output_file(args->trajectory), error)
        || !output_files_check_kind(output_file(args->json), error))
        return FALSE;
    if (args->series.channels && n_files > 1)
        return refuse_usage(error, _("--channels names the channels of one "
                                     "file; with several files use -c"));
    run->interpolation = SERIES_DEFAULT_INTERPOLATION;
    if (args->interpolation_name && !parse_interpolation(args->interpolation_name,
                                                         &run->interpolation, error))
        return FALSE;
    if (args->all_channels && n_files == 1)
        return refuse_usage(error, _("--all-channels needs one file per "
                                     "frame"));
    if (!series_args_to_options(&args->series, &run->options, error))
        return FALSE;
    roles = g_new(OutputFilesRole, n_files + 3);
    for (i = 0; i < n_files; i++) {
        roles[i].role = _("frame");
        roles[i].filename = args->files[i];
        roles[i].is_input = TRUE;
    }
    roles[n_files].role = "-o";
    roles[n_files].filename = args->output;
    roles[n_files + 1].role = "--trajectory";
    roles[n_files + 1].filename = output_file(args->trajectory);
    roles[n_files + 2].role = "--json";
    roles[n_files + 2].filename = output_file(args->json);
    for (i = n_files; i < n_files + 3; i++)
        roles[i].is_input = FALSE;
    ok = output_files_check_roles(roles, n_files + 3, error);
    g_free(roles);
    return ok;
}

static gboolean
load_series(const SeriesCommandArgs *args, SeriesRun *run, GError **error)
{
    gint k;

    run->n_files = g_strv_length(args->files);
    run->files = args->files;
    run->datas = g_new0(GwyContainer*, run->n_files);
    for (k = 0; k < run->n_files; k++) {
        if (!(run->datas[k] = isolated_load(args->files[k], error)))
            return FALSE;
    }
    run->series = frame_series_from_files(run->datas, args->files,
                                          run->n_files, &run->options, error);
    return run->series != NULL;
}

static gint
next_free_id(SeriesRun *run)
{
    return run->next_id++;
}

/* A mask that is no field of its channel's size (or no field at all, or
 * one holding NaN: a file the tools write holds none) is left out of OUT,
 * with a warning: copied, a 7 x 9 px mask on a 128 x 128 px channel went into
 * the file the tools promise Gwyddion can open (hostile-input run). */
static void
drop_misfit_mask(SeriesRun *run, GwyContainer *out, gint id, gint k,
                 gint source_id)
{
    gchar key[32];
    gchar *name;

    g_snprintf(key, sizeof(key), "/%d/mask", id);
    if (!gwy_container_contains_by_name(out, key) || localscan_channel_mask(out, id))
        return;
    gwy_container_remove_by_name(out, key);
    name = g_path_get_basename(run->files[k]);
    g_ptr_array_add(run->correction.warnings,
                    g_strdup_printf(_("%s: the mask of channel %d does not "
                                      "fit the channel and is left out"),
                                    name, source_id));
    g_free(name);
}

static void
copy_inputs(SeriesRun *run, GwyContainer *out)
{
    gint k, i, *ids;
    gchar from[32], to[32];

    for (k = 0; k < run->n_files; k++) {
        ids = localscan_channel_ids(run->datas[k]);
        for (i = 0; ids[i] >= 0; i++) {
            gint id = next_free_id(run);

            g_snprintf(from, sizeof(from), "/%d", ids[i]);
            g_snprintf(to, sizeof(to), "/%d", id);
            gwy_container_transfer(run->datas[k], out, from, to, TRUE);
            drop_misfit_mask(run, out, id, k, ids[i]);
        }
        g_free(ids);
    }
}

static void
set_channel(GwyContainer *out, gint id, const gchar *item, gpointer object)
{
    gchar key[48];

    g_snprintf(key, sizeof(key), "/%d/%s", id, item);
    gwy_container_set_object_by_name(out, key, object);
}

/* The corrected channel's metadata: the source's, plus what was done. */
static GwyContainer*
corrected_meta(GwyContainer *source, gint source_id, const SeriesRun *run,
               gint k)
{
    GwyContainer *meta = localscan_channel_item(source, source_id, "meta");
    const SeriesFrameVerdict *v = run->correction.frames + k;
    const DriftFit *fit = run->correction.fit.fits + run->correction.fit.chosen;
    gchar text[64];

    meta = meta ? gwy_container_duplicate(meta) : gwy_container_new();
    gwy_container_set_const_string_by_name(meta, SERIES_CORRECTED_META_KEY,
                                           (const guchar*)SERIES_CORRECTED_BY_TOOL ", line by line");
    gwy_container_set_const_string_by_name(meta, "Drift model",
                                           (const guchar*)drift_model_type_name(fit->type));
    g_snprintf(text, sizeof(text), "%.6g s",
               run->series->frames[k].timing.frame_start);
    gwy_container_set_const_string_by_name(meta, "Frame start", (const guchar*)text);
    gwy_container_set_const_string_by_name(meta, "Frame flagged",
                                           (const guchar*)(v->flagged ? v->reason : "no"));
    return meta;
}

/* Stores a corrected field and its mask as a new channel; returns its id. */
static gint
store_corrected(GwyContainer *out, SeriesRun *run, gint k,
                GwyContainer *source, gint source_id, GwyDataField *result,
                GwyDataField *mask)
{
    gint id = next_free_id(run);
    const gchar *title = localscan_channel_title(source, source_id);
    GwyContainer *meta;
    gchar *text, key[48];

    set_channel(out, id, "data", result);
    set_channel(out, id, "mask", mask);
    text = g_strdup_printf(_("%s (drift corrected)"), title ? title : _("Frame"));
    g_snprintf(key, sizeof(key), "/%d/data/title", id);
    gwy_container_set_string_by_name(out, key, (const guchar*)text);
    meta = corrected_meta(source, source_id, run, k);
    set_channel(out, id, "meta", meta);
    g_object_unref(meta);
    return id;
}

/* The channels of file `file` that share the frame's pixels: the frame's
 * own first, then the others with --all-channels. */
static GArray*
channels_to_correct(SeriesRun *run, gint k, gboolean all_channels)
{
    const SeriesFrame *frame = run->series->frames + k;
    GwyContainer *data = run->datas[frame->file_index];
    GArray *ids = g_array_new(FALSE, FALSE, sizeof(gint));
    gint *all, i;

    g_array_append_val(ids, frame->channel_id);
    if (!all_channels)
        return ids;
    all = localscan_channel_ids(data);
    for (i = 0; all[i] >= 0; i++) {
        GwyDataField *field = localscan_channel_item(data, all[i], "data");

        if (all[i] == frame->channel_id)
            continue;
        if (gwy_data_field_check_compatibility(field, frame->field,
                                               GWY_DATA_COMPATIBILITY_RES
                                               | GWY_DATA_COMPATIBILITY_REAL) == 0)
            g_array_append_val(ids, all[i]);
        else
            g_ptr_array_add(run->correction.warnings,
                            g_strdup_printf(_("%s: channel %d (%s) not "
                                              "corrected: it is not scanned "
                                              "like the frame"),
                                            frame->label, all[i],
                                            localscan_channel_title(data, all[i])));
    }
    g_free(all);
    return ids;
}

static void
mask_union(GwyDataField **area, GwyDataField *mask)
{
    if (!*area)
        *area = gwy_data_field_duplicate(mask);
    else
        gwy_data_field_max_of_fields(*area, *area, mask);
}

/* Every frame (and with --all-channels every channel of its file)
 * corrected; `stored` gets the new channel ids, `area` the union of the
 * masks of the frames not flagged. */
static gboolean
correct_frames(SeriesRun *run, gboolean all_channels, GwyContainer *out,
               GArray *stored, GwyDataField **area, GError **error)
{
    gint k, i, id;

    for (k = 0; k < run->series->n_frames; k++) {
        const SeriesFrame *frame = run->series->frames + k;
        GwyContainer *data = run->datas[frame->file_index];
        GArray *ids = channels_to_correct(run, k, all_channels);

        for (i = 0; i < (gint)ids->len; i++) {
            gint source_id = g_array_index(ids, gint, i);
            GwyDataField *field = localscan_channel_item(data, source_id, "data");
            GwyDataField *result = gwy_data_field_new_alike(field, FALSE);
            GwyDataField *mask = gwy_data_field_new_alike(field, FALSE);
            gboolean ok;

            ok = series_correction_correct_field(&run->correction, field,
                                                 &frame->timing,
                                                 run->interpolation, result,
                                                 mask, error);
            if (ok) {
                /* The frames the trajectory trusts decide the common area:
                 * a flagged frame's missing pixels (1 % of NaN) cut it to
                 * 23 x 37 px of 128 x 128 (hostile-input run). */
                if (i == 0 && !run->correction.frames[k].flagged)
                    mask_union(area, mask);
                id = store_corrected(out, run, k, data, source_id, result,
                                     mask);
                g_array_append_val(stored, id);
            }
            g_object_unref(result);
            g_object_unref(mask);
            if (!ok) {
                g_array_free(ids, TRUE);
                return FALSE;
            }
        }
        g_array_free(ids, TRUE);
    }
    return TRUE;
}

/* Crops the corrected channels to the common area, or leaves them whole;
 * either way a mask stays only where pixels lack data (in the common area,
 * those of flagged frames only). */
static void
finish_channels(const SeriesRun *run, GwyContainer *out, GArray *stored)
{
    gchar key[48];
    guint i;

    for (i = 0; i < stored->len; i++) {
        gint id = g_array_index(stored, gint, i);
        GwyDataField *field, *mask, *part;

        g_snprintf(key, sizeof(key), "/%d/mask", id);
        mask = gwy_container_get_object_by_name(out, key);
        if (run->crop) {
            part = series_correction_crop_to_area(mask, run->area);
            gwy_container_set_object_by_name(out, key, part);
            g_object_unref(part);
            mask = part;
        }
        if (gwy_data_field_get_max(mask) <= 0.0)
            gwy_container_remove_by_name(out, key);
        if (!run->crop)
            continue;
        g_snprintf(key, sizeof(key), "/%d/data", id);
        field = gwy_container_get_object_by_name(out, key);
        part = series_correction_crop_to_area(field, run->area);
        gwy_container_set_object_by_name(out, key, part);
        g_object_unref(part);
    }
}

static GwyContainer*
build_output(SeriesRun *run, gboolean all_channels, GError **error)
{
    GwyContainer *out = gwy_container_new();
    GArray *stored = g_array_new(FALSE, FALSE, sizeof(gint));
    GwyDataField *area = NULL;
    GwyGraphModel *graph;
    gboolean ok;

    run->next_id = 0;
    copy_inputs(run, out);
    ok = correct_frames(run, all_channels, out, stored, &area, error);
    if (ok && run->crop
        && !series_correction_common_area(&area, 1, run->area, run->area + 1,
                                          run->area + 2, run->area + 3)) {
        g_set_error(error, SERIES_CORRECTION_ERROR,
                    SERIES_CORRECTION_ERROR_COMPENSATE,
                    _("--crop common: no part of the area is covered by "
                      "every frame not flagged"));
        ok = FALSE;
    }
    if (ok) {
        finish_channels(run, out, stored);
        /* Input channels with missing pixels are copied filled and masked:
         * a file the tools write holds no NaN (docs/missing-data.md). */
        localscan_channels_fill_missing(out);
        graph = series_graph_new(&run->correction, run->series);
        gwy_container_set_object_by_name(out, "/0/graph/graph/1", graph);
        g_object_unref(graph);
    }
    g_array_free(stored, TRUE);
    if (area)
        g_object_unref(area);
    if (!ok)
        g_clear_object(&out);
    return out;
}

/* Text (consumed) into the set of files, or into *printed for "-". */
static gboolean
add_text(OutputFiles *files, const gchar *filename, gchar *text, gchar **printed,
         GError **error)
{
    gboolean ok;

    if (output_files_is_stdout(filename)) {
        g_free(*printed);
        *printed = text;
        return TRUE;
    }
    ok = output_files_add(files, filename, (const guchar*)text, strlen(text), error);
    g_free(text);
    return ok;
}

static gboolean
write_outputs(const SeriesCommandArgs *args, SeriesRun *run,
              GwyContainer *out, GError **error)
{
    OutputFiles *files = output_files_new();
    const gchar *temp;
    gchar *printed = NULL;
    gboolean ok;

    ok = ((temp = output_files_reserve(files, args->output, error))
          && gwy_stream_save_as(out, temp, args->output, error));
    if (ok && args->trajectory)
        ok = add_text(files, args->trajectory,
                      series_correction_trajectory_csv(&run->correction, run->series),
                      &printed, error);
    if (ok && args->json)
        ok = add_text(files, args->json,
                      series_correction_to_json(&run->correction, run->series),
                      &printed, error);
    ok = ok && output_files_commit(files, error);
    output_files_free(files);
    /* Printed once every file is in place: a failed run prints nothing a
     * pipe would take for its result (a write error of the standard
     * output is told at exit, output_files_finish_stdout). */
    if (ok && printed)
        fputs(printed, stdout);
    g_free(printed);
    return ok;
}

/* One line per flagged frame and per warning, on standard error. */
static void
report(const SeriesRun *run)
{
    const SeriesCorrection *c = &run->correction;
    gint k;
    guint i;

    for (k = 0; k < run->series->n_frames; k++) {
        if (c->frames[k].flagged) {
            gchar *text = g_strdup_printf(_("frame %d (%s) flagged: %s"), k,
                                          run->series->frames[k].label,
                                          c->frames[k].reason);
            print_line(_("warning: "), text);
            g_free(text);
        }
    }
    for (i = 0; i < c->warnings->len; i++)
        print_line(_("warning: "), g_ptr_array_index(c->warnings, i));
}

static gboolean
run_series(const SeriesCommandArgs *args, SeriesRun *run, GError **error)
{
    GwyContainer *out;
    gboolean ok;

    if (!load_series(args, run, error)
        || !series_correction_compute(run->series, NULL, NULL,
                                      &run->correction, error))
        return FALSE;
    if (!(out = build_output(run, args->all_channels, error)))
        return FALSE;
    ok = write_outputs(args, run, out, error);
    g_object_unref(out);
    if (ok)
        report(run);
    return ok;
}

static void
free_run(SeriesRun *run)
{
    gint k;

    if (run->correction.frames)
        series_correction_clear(&run->correction);
    frame_series_free(run->series);
    for (k = 0; k < run->n_files; k++) {
        if (run->datas[k])
            g_object_unref(run->datas[k]);
    }
    g_free(run->datas);
    series_args_clear(NULL, &run->options);
}

static void
free_args(SeriesCommandArgs *args)
{
    g_free(args->output);
    g_free(args->trajectory);
    g_free(args->json);
    g_free(args->crop);
    g_free(args->interpolation_name);
    g_strfreev(args->files);
    series_args_clear(&args->series, NULL);
}

int
series_command_main(int argc, char **argv)
{
    SeriesCommandArgs args;
    SeriesRun run;
    GError *error = NULL;
    gint status = EXIT_OK;

    memset(&args, 0, sizeof(args));
    memset(&run, 0, sizeof(run));
    if (!parse_args(&args, &argc, &argv, &error)
        || !check_args(&args, &run, &error))
        status = EXIT_USAGE;
    else if (!headless_run_init(NULL, &error) || !run_series(&args, &run, &error))
        status = EXIT_ERROR;
    if (status == EXIT_ERROR && !error)
        error = g_error_new(SERIES_CORRECTION_ERROR, SERIES_CORRECTION_ERROR_FIT,
                            _("failed: %s"), library_log_last() ? library_log_last()
                            : _("no reason given"));
    if (error) {
        print_line("", error->message);
        g_error_free(error);
    }
    free_run(&run);
    free_args(&args);
    return status;
}
