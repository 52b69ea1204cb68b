/*
 *  Local Scan Series Drift: the channels of the open file that are scanned
 *  like the current one are the frames of a series (those the dialog's
 *  frame chooser leaves checked), corrected from one fitted drift
 *  trajectory (docs/series.md), the process function beside Local Scan
 *  Drift.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <string.h>
#include <math.h>
#include <gtk/gtk.h>
#include <libgwyddion/gwyddion.h>
#include <libgwymodule/gwymodule-process.h>
#include <libprocess/gwyprocess.h>
#include <libgwydgets/gwydgets.h>
#include <app/gwyapp.h>
#include "series-correction.h"
#include "compensation-marker.h"
#include "dialog-tooltips.h"
#include "series-graph.h"
#include "localscan-channel.h"
#include "scan-timing-meta.h"
#include "series-process.h"

#undef _
#define _(s) dgettext(GETTEXT_PACKAGE, s)

#define SERIES_RUN_MODES (GWY_RUN_INTERACTIVE | GWY_RUN_IMMEDIATE)
/* The share of a run's wait dialog the measurement takes; correcting the
 * frames takes the rest. */
#define SERIES_MEASURE_SHARE 0.8
#define GRAPH_WIDTH 480
#define GRAPH_HEIGHT 240
/* The frame chooser: Gwyddion's channel lists' small thumbnails, and room
 * for about five rows before it scrolls. */
#define THUMBNAIL_SIZE 24
#define FRAME_LIST_HEIGHT 160
/* The line saying which timing settings are used wraps at this width:
 * unwrapped, the reason the file lacks the timing (a file's name, the
 * channel's) made the dialog 1378 px wide, its OK off a 1280 px screen. */
#define TIMING_USE_WIDTH 380

enum {
    PARAM_LINE_TIME,
    PARAM_FRAME_INTERVAL,
    PARAM_DIRECTION,
    PARAM_INTERPOLATION,
    PARAM_CROP,
    PARAM_ADD_GRAPH,
    INFO_TIMING_USE,
    WIDGET_FRAMES,
};

typedef struct {
    GwyParams *params;
    GwyContainer *data;
    gint id;
    GArray *candidates;        /* channel ids scanned like this one (frame_ids) */
    gboolean *checked;         /* per candidate: a frame of the series */
    FrameSeries *series;
    SeriesCorrection correction;
    gboolean computed;
    gboolean timing_assumed;   /* the metadata lacked it: the params' */
    gchar *timing_reason;      /* why the metadata's timing was not used */
} SeriesArgs;

typedef struct {
    SeriesArgs *args;
    GtkWidget *dialog;
    GwyParamTable *table;
    GwyGraphModel *gmodel;
    GtkWidget *summary;
    GtkWidget *timing_use;     /* which timing settings are used, wrapped */
    GtkListStore *frames;      /* the candidates, LOCALSCAN_SERIES_FRAME_COLUMN_* */
    gboolean any_start;        /* some candidate's metadata gives its start */
} SeriesGUI;

/* Which of the timing settings the frames need. */
typedef enum {
    TIMING_USE_UNKNOWN,     /* the frames could not be read */
    TIMING_USE_NONE,        /* the file gives it all */
    TIMING_USE_DIRECTION,   /* the file lacks the slow-scan direction */
    TIMING_USE_ALL,         /* the file lacks the timing */
} TimingUse;

static void
series_args_reset(SeriesArgs *args)
{
    if (args->computed)
        series_correction_clear(&args->correction);
    frame_series_free(args->series);
    args->series = NULL;
    args->computed = FALSE;
    g_free(args->timing_reason);
    args->timing_reason = NULL;
}

static GwyParamDef*
define_series_params(void)
{
    static const GwyEnum directions[] = {
        { N_("Down"), SCAN_DIRECTION_DOWN, },
        { N_("Up"),   SCAN_DIRECTION_UP,   },
    };
    static GwyParamDef *paramdef = NULL;

    if (paramdef)
        return paramdef;
    paramdef = gwy_param_def_new();
    gwy_param_def_set_function_name(paramdef, LOCALSCAN_SERIES_FUNCTION_NAME);
    /* Used only where the file's metadata does not give the timing. */
    gwy_param_def_add_double(paramdef, PARAM_LINE_TIME, "line_time",
                             _("_Line time"), 1e-6, 1e4, 1.0);
    gwy_param_def_add_double(paramdef, PARAM_FRAME_INTERVAL, "frame_interval",
                             _("_Frame interval (0: back to back)"), 0.0, 1e9,
                             0.0);
    gwy_param_def_add_gwyenum(paramdef, PARAM_DIRECTION, "direction",
                              _("Slow scan _direction"), directions,
                              G_N_ELEMENTS(directions), SCAN_DIRECTION_DOWN);
    gwy_param_def_add_enum(paramdef, PARAM_INTERPOLATION, "interpolation",
                           _("_Interpolation"), GWY_TYPE_INTERPOLATION_TYPE,
                           GWY_INTERPOLATION_BSPLINE);
    gwy_param_def_add_boolean(paramdef, PARAM_CROP, "crop",
                              _("C_rop to the area every frame covers"),
                              FALSE);
    gwy_param_def_add_boolean(paramdef, PARAM_ADD_GRAPH, "add_graph",
                              _("Add the trajectory _graph"), TRUE);
    return paramdef;
}

/* The tooltip of every setting, keyed by the labels of
 * define_series_params(). */
static const DialogTooltip series_tooltips[] = {
    { N_("Line time"),
      N_("Seconds per scan line, trace and retrace; used only where the file's metadata "
         "does not give the timing") },
    { N_("Frame interval (0: back to back)"),
      N_("Seconds from the start of one frame to the start of the next; 0: each frame "
         "starts when the one before ends.  Used only where the metadata does not give "
         "the frames' times") },
    { N_("Slow scan direction"),
      N_("Whether the frames were scanned top to bottom or bottom to top; used only "
         "where the metadata does not say") },
    { N_("Interpolation"),
      N_("How the corrected frames are resampled when every scan line is moved back by "
         "the drift at its own scan time") },
    { N_("Crop to the area every frame covers"),
      N_("Cut every corrected frame to the part of the sample that all frames show, so "
         "that no pixel is left without data") },
    { N_("Add the trajectory graph"),
      N_("Add a graph of the drift in x and y against time, the measurements with the "
         "fitted trajectory, to the file") },
};

/* A drift correction's result: the series correction's marker (its value
 * names the tool, so an instrument's own "Drift correction" item does not
 * count) or the local-scan compensation's. */
static gboolean
is_corrected(GwyContainer *data, gint id)
{
    const gchar *value = localscan_channel_meta_string(data, id, SERIES_CORRECTED_META_KEY);

    if (value && (g_str_has_prefix(value, SERIES_CORRECTED_BY_TOOL)
                  || g_str_has_prefix(value, SERIES_CORRECTED_BY_DIALOG)))
        return TRUE;
    return compensation_marker_get(data, id) != NULL;
}

/* The candidate frames: the current channel and every other scanned like
 * it (the same pixels and area, the same title but for a trailing number,
 * as the command line's -c names frames: "Height", "Height 12"), in id
 * order.
 * Channels a drift correction made are no frames: run again, the
 * correction took its own results for seven more frames. */
static GArray*
frame_ids(GwyContainer *data, gint current)
{
    GwyDataField *field = localscan_channel_item(data, current, "data");
    GArray *ids = g_array_new(FALSE, FALSE, sizeof(gint));
    gint *all = localscan_channel_ids(data), i;
    gchar *base = frame_series_title_base(localscan_channel_title(data, current));

    for (i = 0; all[i] >= 0; i++) {
        GwyDataField *other = localscan_channel_item(data, all[i], "data");

        if (gwy_data_field_check_compatibility(field, other,
                                               GWY_DATA_COMPATIBILITY_RES
                                               | GWY_DATA_COMPATIBILITY_REAL
                                               | GWY_DATA_COMPATIBILITY_LATERAL
                                               | GWY_DATA_COMPATIBILITY_VALUE)
            || is_corrected(data, all[i]))
            continue;
        /* Untitled channels are alike to an untitled one. */
        if (frame_series_title_matches(localscan_channel_title(data, all[i]), base)
            || (!*base && !localscan_channel_title(data, all[i])))
            g_array_append_val(ids, all[i]);
    }
    g_free(base);
    g_free(all);
    return ids;
}

/* Why fewer than two checked frames make no series: the dialog's summary
 * says it, and so does a run given them all the same. */
static const gchar*
too_few_checked_message(void)
{
    return _("Fewer than two frames are checked: check at least two to measure the series.");
}

/* Fewer than two frames left where the user unchecked some (a channel
 * with no partner at all is the core's to refuse, naming the file); none
 * checked is always too few: no ids would mean every channel. */
static gboolean
too_few_checked(const SeriesArgs *args)
{
    gint i, n = 0, n_candidates = args->candidates->len;

    for (i = 0; i < n_candidates; i++)
        n += !!args->checked[i];
    return n < 2 && (n < n_candidates || !n);
}

/* The checked candidates' channel ids and their places among all the
 * candidates, in id order; returns how many.  The settings' frame times
 * count every candidate: a frame left out still took its time to scan. */
static gint
checked_frames(const SeriesArgs *args, gint *ids, gint *places)
{
    gint i, n = 0;

    for (i = 0; i < (gint)args->candidates->len; i++) {
        if (!args->checked[i])
            continue;
        ids[n] = g_array_index(args->candidates, gint, i);
        places[n++] = i;
    }
    return n;
}

/* The checked frames, with the metadata's timing, else the params': frames
 * back to back or a frame interval apart. */
static FrameSeries*
load_series(SeriesArgs *args, GError **error)
{
    gint size = MAX(args->candidates->len, 1);
    gint *ids = g_new(gint, size), *places = g_new(gint, size);
    gint n = checked_frames(args, ids, places), yres, k;
    const gchar *filename = NULL;
    gchar *name = NULL;
    FrameSeriesOptions options;
    FrameSeries *series = NULL;
    GError *err = NULL;
    gdouble line_time, interval;

    if (is_corrected(args->data, args->id)) {
        g_set_error(error, FRAME_SERIES_ERROR, FRAME_SERIES_ERROR_CHANNEL,
                    _("This channel is the result of a drift correction: run the series "
                      "correction on the frames as they were measured."));
        goto end;
    }
    if (too_few_checked(args)) {
        g_set_error_literal(error, FRAME_SERIES_ERROR, FRAME_SERIES_ERROR_CHANNEL,
                            too_few_checked_message());
        goto end;
    }
    gwy_container_gis_string_by_name(args->data, "/filename",
                                     (const guchar**)&filename);
    name = g_strdup(filename ? filename : _("Untitled"));
    frame_series_options_init(&options);
    options.channel_ids = ids;
    options.n_channel_ids = n;
    options.hints_for_dialog = TRUE;
    /* Where the metadata gives the timing but not the direction. */
    options.fallback_direction = gwy_params_get_enum(args->params, PARAM_DIRECTION);
    args->timing_assumed = FALSE;
    g_free(args->timing_reason);
    args->timing_reason = NULL;
    series = frame_series_from_files(&args->data, &name, 1, &options, &err);
    if (!series && err->domain == FRAME_SERIES_ERROR
        && err->code == FRAME_SERIES_ERROR_TIMING) {
        args->timing_reason = g_strdup(err->message);
        g_clear_error(&err);
        line_time = gwy_params_get_double(args->params, PARAM_LINE_TIME);
        interval = gwy_params_get_double(args->params, PARAM_FRAME_INTERVAL);
        yres = gwy_data_field_get_yres(localscan_channel_item(args->data, args->id, "data"));
        if (interval <= 0.0)
            interval = yres*line_time;
        options.line_time = line_time;
        options.direction = gwy_params_get_enum(args->params, PARAM_DIRECTION);
        options.n_frame_times = n;
        options.frame_times = g_new(gdouble, n);
        for (k = 0; k < n; k++)
            options.frame_times[k] = places[k]*interval;
        args->timing_assumed = TRUE;
        series = frame_series_from_files(&args->data, &name, 1, &options,
                                         &err);
        g_free(options.frame_times);
    }
    if (err)
        g_propagate_error(error, err);

end:
    g_free(ids);
    g_free(places);
    g_free(name);
    return series;
}

/* Gwyddion's wait dialog as the measurement's progress (its Cancel stops
 * it).  A cancel the dialog took while it was being shown has destroyed it
 * already: setting its fraction then is an error. */
static gboolean
wait_dialog_progress(gdouble fraction, G_GNUC_UNUSED gpointer user_data)
{
    return !gwy_app_wait_was_canceled() && gwy_app_wait_set_fraction(fraction);
}

/* The series measured and fitted; with_progress: in Gwyddion's wait
 * dialog, started by the caller, over its fractions from .. to. */
static gboolean
execute(SeriesArgs *args, gboolean with_progress, gdouble from, gdouble to,
        GError **error)
{
    Progress progress = { wait_dialog_progress, NULL, from, to };

    if (args->computed)
        return TRUE;
    /* The frames read when the dialog opened serve until a timing setting
     * they depend on changes (param_changed). */
    if (!args->series && !(args->series = load_series(args, error)))
        return FALSE;
    if (!series_correction_compute_progress(args->series, NULL, NULL,
                                            with_progress ? &progress : NULL,
                                            &args->correction, error)) {
        series_correction_clear(&args->correction);
        return FALSE;
    }
    args->computed = TRUE;
    return TRUE;
}

/* The marker that keeps a corrected channel out of the frames of a later
 * run (frame_ids), as the command line's output carries it. */
static void
mark_corrected(GwyContainer *data, gint id)
{
    gwy_container_set_const_string_by_name(localscan_channel_meta(data, id, TRUE),
                                           SERIES_CORRECTED_META_KEY,
                                           (const guchar*)SERIES_CORRECTED_BY_DIALOG
                                           ", line by line");
}

/* A corrected frame as a new channel: titled after its source, with its
 * palette and metadata, a mask where no data exists. */
static gint
add_corrected_channel(SeriesArgs *args, gint k, GwyDataField *result,
                      GwyDataField *mask)
{
    GwyContainer *data = args->data;
    gint source = args->series->frames[k].channel_id, newid;
    gchar *title, *text;

    newid = gwy_app_data_browser_add_data_field(result, data, TRUE);
    title = gwy_app_get_data_field_title(data, source);
    text = g_strdup_printf(_("%s (drift corrected)"), title);
    gwy_container_set_string(data, gwy_app_get_data_title_key_for_id(newid),
                             (const guchar*)text);
    g_free(title);
    gwy_app_sync_data_items(data, data, source, newid, FALSE,
                            GWY_DATA_ITEM_GRADIENT, GWY_DATA_ITEM_MASK_COLOR,
                            GWY_DATA_ITEM_META, GWY_DATA_ITEM_REAL_SQUARE, 0);
    mark_corrected(data, newid);
    if (mask && gwy_data_field_get_max(mask) > 0.0)
        gwy_container_set_object(data, gwy_app_get_mask_key_for_id(newid),
                                 mask);
    gwy_app_channel_log_add(data, source, newid, NULL, NULL);
    return newid;
}

/* Every frame corrected (with Gwyddion's wait dialog, which can cancel),
 * then added, cropped to the common area when asked. */
static gboolean
create_outputs(SeriesArgs *args, gboolean show_progress, gdouble from,
               GError **error)
{
    gint n = args->series->n_frames, k, area[4];
    GwyDataField **results = g_new0(GwyDataField*, n);
    GwyDataField **masks = g_new0(GwyDataField*, n);
    gboolean ok = TRUE, crop = gwy_params_get_boolean(args->params, PARAM_CROP);
    GwyInterpolationType interpolation = gwy_params_get_enum(args->params,
                                                             PARAM_INTERPOLATION);

    for (k = 0; k < n && ok; k++) {
        GwyDataField *field = args->series->frames[k].field;

        results[k] = gwy_data_field_new_alike(field, FALSE);
        masks[k] = gwy_data_field_new_alike(field, FALSE);
        ok = series_correction_correct_frame(&args->correction, args->series,
                                             k, interpolation, results[k],
                                             masks[k], error);
        if (ok && show_progress
            && !gwy_app_wait_set_fraction(from + (1.0 - from)*(k + 1.0)/n))
            ok = FALSE;
    }
    if (ok && crop && !series_correction_trusted_area(&args->correction, masks, n, area)) {
        g_set_error(error, SERIES_CORRECTION_ERROR,
                    SERIES_CORRECTION_ERROR_COMPENSATE,
                    _("No part of the area is covered by every frame not flagged."));
        ok = FALSE;
    }
    for (k = 0; k < n && ok; k++) {
        if (crop) {
            GwyDataField *part = series_correction_crop_to_area(results[k], area);
            GwyDataField *mask_part = series_correction_crop_to_area(masks[k], area);

            /* Only a flagged frame may lack pixels in the area. */
            add_corrected_channel(args, k, part,
                                  gwy_data_field_get_max(mask_part) > 0.0 ? mask_part : NULL);
            g_object_unref(part);
            g_object_unref(mask_part);
        }
        else
            add_corrected_channel(args, k, results[k], masks[k]);
    }
    for (k = 0; k < n; k++) {
        if (results[k])
            g_object_unref(results[k]);
        if (masks[k])
            g_object_unref(masks[k]);
    }
    g_free(results);
    g_free(masks);
    return ok;
}

static void
add_graph(SeriesArgs *args)
{
    GwyGraphModel *gmodel = series_graph_new(&args->correction, args->series);

    gwy_app_data_browser_add_graph_model(gmodel, args->data, TRUE);
    g_object_unref(gmodel);
}

/* The fitted effect in words, with its parameters: the velocity alone is
 * the constant part, which beside a settling or an acceleration is not the
 * slope the graph shows. */
static void
describe_effect(GString *text, const DriftFit *fit)
{
    DriftFitParameters p;

    drift_fit_parameters(fit, &p);
    switch (fit->type) {
        case DRIFT_MODEL_SETTLING:
        g_string_append_printf(text, _("settling drift: time constant %.3g s, "
                                       "initial excess velocity (%.3g, %.3g) nm/s, "
                                       "final velocity (%.3g, %.3g) nm/s"),
                               p.tau_s, p.u_nm_per_s[0], p.u_nm_per_s[1],
                               p.velocity_nm_per_s[0], p.velocity_nm_per_s[1]);
        break;

        case DRIFT_MODEL_OSCILLATION:
        g_string_append_printf(text, _("oscillating drift: period %.3g s, "
                                       "amplitude (%.3g, %.3g) nm, mean velocity "
                                       "(%.3g, %.3g) nm/s"),
                               p.period_s, p.amplitude_nm[0], p.amplitude_nm[1],
                               p.velocity_nm_per_s[0], p.velocity_nm_per_s[1]);
        break;

        case DRIFT_MODEL_JUMP:
        g_string_append_printf(text, _("a jump of (%.3g, %.3g) nm at %.4g s on "
                                       "a velocity of (%.3g, %.3g) nm/s"),
                               p.step_nm[0], p.step_nm[1], p.t_s,
                               p.velocity_nm_per_s[0], p.velocity_nm_per_s[1]);
        break;

        case DRIFT_MODEL_ACCELERATION:
        g_string_append_printf(text, _("accelerating drift: (%.3g, %.3g) nm/s², "
                                       "starting at (%.3g, %.3g) nm/s"),
                               p.accel_nm_per_s2[0], p.accel_nm_per_s2[1],
                               p.velocity_nm_per_s[0], p.velocity_nm_per_s[1]);
        break;

        default:
        g_string_append_printf(text, _("constant drift of (%.3g, %.3g) nm/s"),
                               p.velocity_nm_per_s[0], p.velocity_nm_per_s[1]);
        break;
    }
}

static gboolean
direction_from_setting(const FrameSeries *series)
{
    gint k;

    for (k = 0; k < series->n_frames; k++) {
        if (series->frames[k].direction_source == FRAME_TIME_OPTION)
            return TRUE;
    }
    return FALSE;
}

/* The fit, the flagged frames and the warnings, in one text. */
static gchar*
describe_result(const SeriesArgs *args)
{
    const SeriesCorrection *c = &args->correction;
    GString *text = g_string_new(NULL);
    gint k, flagged = 0;
    guint i;

    describe_effect(text, c->fit.fits + c->fit.chosen);
    g_string_append_printf(text, _("; %d frames, typical residual %.2f px."),
                           args->series->n_frames, c->typical_px);
    for (k = 0; k < args->series->n_frames; k++) {
        if (!c->frames[k].flagged)
            continue;
        g_string_append_printf(text, _("\nFrame %d (%s) flagged: %s."), k,
                               args->series->frames[k].label,
                               c->frames[k].reason);
        flagged++;
    }
    if (!flagged)
        g_string_append(text, _("\nNo frame flagged."));
    if (args->timing_assumed)
        g_string_append_printf(text, _("\nTiming from the settings (the file's "
                                       "metadata: %s)."),
                               args->timing_reason ? args->timing_reason : _("none"));
    else if (direction_from_setting(args->series))
        g_string_append(text, _("\nTiming from the file's metadata, the slow-scan "
                                "direction from the setting (the file does not say)."));
    else
        g_string_append(text, _("\nTiming from the file's metadata (the "
                                "settings are not used)."));
    for (i = 0; i < c->warnings->len; i++)
        g_string_append_printf(text, "\n%s",
                               (const gchar*)g_ptr_array_index(c->warnings, i));
    return g_string_free(text, FALSE);
}

static void
report_error(SeriesArgs *args, const GError *error)
{
    GtkWidget *main_window = gwy_app_main_window_get(), *dialog;

    if (!main_window) {
        localscan_run_error_set(args->data, error);
        g_printerr("%s: %s\n", LOCALSCAN_SERIES_FUNCTION_NAME, error->message);
        return;
    }
    dialog = gtk_message_dialog_new(GTK_WINDOW(main_window),
                                    GTK_DIALOG_DESTROY_WITH_PARENT,
                                    GTK_MESSAGE_ERROR, GTK_BUTTONS_OK, "%s",
                                    _("Series drift correction failed."));
    gtk_message_dialog_format_secondary_text(GTK_MESSAGE_DIALOG(dialog), "%s",
                                             error->message);
    gtk_dialog_run(GTK_DIALOG(dialog));
    gtk_widget_destroy(dialog);
}

/* The dialog's preview: the series measured and fitted, the trajectory
 * drawn and the verdicts written (on request: it takes seconds). */
static void
preview(gpointer user_data)
{
    SeriesGUI *gui = (SeriesGUI*)user_data;
    GwyGraphModel *gmodel;
    GError *error = NULL;
    gboolean ok;
    gchar *text;

    gwy_app_wait_start(GTK_WINDOW(gui->dialog), _("Measuring the series..."));
    ok = execute(gui->args, TRUE, 0.0, 1.0, &error);
    gwy_app_wait_finish();
    if (ok) {
        gmodel = series_graph_new(&gui->args->correction, gui->args->series);
        gwy_graph_model_remove_all_curves(gui->gmodel);
        gwy_graph_model_append_curves(gui->gmodel, gmodel, 0);
        series_graph_place_legend(gui->gmodel);
        g_object_unref(gmodel);
        text = describe_result(gui->args);
        gwy_dialog_have_result(GWY_DIALOG(gui->dialog));
    }
    else if (g_error_matches(error, SERIES_CORRECTION_ERROR,
                             SERIES_CORRECTION_ERROR_CANCELLED)) {
        text = g_strdup(_("Measurement cancelled. Press Update to measure "
                          "the series."));
        g_clear_error(&error);
    }
    else {
        text = g_strdup(error->message);
        g_clear_error(&error);
    }
    gtk_label_set_text(GTK_LABEL(gui->summary), text);
    g_free(text);
}

/* What the file's metadata leaves to the settings: the frames read (not
 * measured) as the measurement will read them, and kept for it. */
static TimingUse
timing_use(SeriesArgs *args)
{
    if (!args->series && !(args->series = load_series(args, NULL)))
        return TIMING_USE_UNKNOWN;
    if (args->timing_assumed)
        return TIMING_USE_ALL;
    return direction_from_setting(args->series) ? TIMING_USE_DIRECTION : TIMING_USE_NONE;
}

/* The timing settings greyed where the file gives what they stand in for,
 * and a line that says which are used. */
static void
show_timing_use(SeriesGUI *gui)
{
    GwyParamTable *table = gui->table;
    TimingUse use = timing_use(gui->args);
    gboolean times_used = (use == TIMING_USE_ALL || use == TIMING_USE_UNKNOWN);
    gchar *text = NULL;

    gwy_param_table_set_sensitive(table, PARAM_LINE_TIME, times_used);
    gwy_param_table_set_sensitive(table, PARAM_FRAME_INTERVAL, times_used);
    gwy_param_table_set_sensitive(table, PARAM_DIRECTION, use != TIMING_USE_NONE);
    if (use == TIMING_USE_NONE)
        text = g_strdup(_("The file gives the timing: these settings are not used."));
    else if (use == TIMING_USE_DIRECTION)
        text = g_strdup(_("The file gives the timing but not the slow-scan "
                          "direction: only the direction is used."));
    else if (use == TIMING_USE_ALL)
        text = g_strdup_printf(_("The file lacks the timing (%s): these settings "
                                 "are used."), gui->args->timing_reason);
    else
        text = g_strdup(_("Used only if the file lacks them."));
    gtk_label_set_text(GTK_LABEL(gui->timing_use), text);
    g_free(text);
}

static GtkWidget*
create_timing_use_label(gpointer user_data)
{
    SeriesGUI *gui = user_data;

    gui->timing_use = gtk_label_new(NULL);
    gtk_misc_set_alignment(GTK_MISC(gui->timing_use), 0.0, 0.5);
    gtk_label_set_line_wrap(GTK_LABEL(gui->timing_use), TRUE);
    gtk_widget_set_size_request(gui->timing_use, TIMING_USE_WIDTH, -1);
    return gui->timing_use;
}

/* What was measured no longer holds: the series is read and measured
 * again, the old result is no longer shown, and OK and Update are greyed
 * while too few frames are checked (the summary says why). */
static void
drop_measurement(SeriesGUI *gui)
{
    gboolean too_few = too_few_checked(gui->args);

    series_args_reset(gui->args);
    gwy_graph_model_remove_all_curves(gui->gmodel);
    gtk_label_set_text(GTK_LABEL(gui->summary),
                       too_few ? too_few_checked_message()
                       : _("Press Update to measure the series."));
    gtk_dialog_set_response_sensitive(GTK_DIALOG(gui->dialog), GTK_RESPONSE_OK, !too_few);
    gtk_dialog_set_response_sensitive(GTK_DIALOG(gui->dialog), GWY_RESPONSE_UPDATE, !too_few);
}

/* Another set of frames: the series measured was of the old set, and OK
 * must not write it; the timing the new set's metadata gives may differ. */
static void
frames_changed(SeriesGUI *gui)
{
    drop_measurement(gui);
    gwy_dialog_invalidate(GWY_DIALOG(gui->dialog));
    show_timing_use(gui);
}

/* A click on a frame's checkbox; path is its row, the candidate's index. */
static void
frame_toggled(SeriesGUI *gui, const gchar *path)
{
    SeriesArgs *args = gui->args;
    GtkTreeIter iter;
    gint i = (gint)g_ascii_strtoll(path, NULL, 10);

    if (i < 0 || i >= (gint)args->candidates->len
        || !gtk_tree_model_get_iter_from_string(GTK_TREE_MODEL(gui->frames), &iter, path))
        return;
    args->checked[i] = !args->checked[i];
    gtk_list_store_set(gui->frames, &iter,
                       LOCALSCAN_SERIES_FRAME_COLUMN_CHECKED, args->checked[i], -1);
    frames_changed(gui);
}

/* Reset checks every frame again, as the dialog opens with all. */
static void
check_all_frames(SeriesGUI *gui)
{
    SeriesArgs *args = gui->args;
    GtkTreeIter iter;
    gboolean changed = FALSE;
    gint i;

    for (i = 0; i < (gint)args->candidates->len; i++) {
        if (args->checked[i])
            continue;
        args->checked[i] = changed = TRUE;
        if (gtk_tree_model_iter_nth_child(GTK_TREE_MODEL(gui->frames), &iter, NULL, i))
            gtk_list_store_set(gui->frames, &iter,
                               LOCALSCAN_SERIES_FRAME_COLUMN_CHECKED, TRUE, -1);
    }
    if (changed)
        frames_changed(gui);
}

static void
param_changed(SeriesGUI *gui, gint id)
{
    /* Only the fallback timing changes what is measured; the direction
     * also stands in where the file gives the rest of the timing. */
    if (id < 0 || id == PARAM_LINE_TIME || id == PARAM_FRAME_INTERVAL
        || id == PARAM_DIRECTION) {
        if (gui->args->timing_assumed || id < 0 || id == PARAM_DIRECTION)
            drop_measurement(gui);
        gwy_dialog_invalidate(GWY_DIALOG(gui->dialog));
    }
    if (id < 0)
        check_all_frames(gui);
}

/* Each candidate's start in seconds after the earliest given, as text;
 * empty where its metadata does not give it.  Returns whether any does. */
static gboolean
frame_start_texts(GwyContainer *data, GArray *ids, gchar **texts)
{
    gint n = ids->len, i;
    gdouble *t = g_new(gdouble, MAX(n, 1)), t0 = G_MAXDOUBLE;
    ScanMetaTiming timing;

    for (i = 0; i < n; i++) {
        gwy_clear(&timing, 1);
        t[i] = NAN;
        if (scan_timing_meta_read_channel(data, g_array_index(ids, gint, i), &timing)
            & SCAN_META_FRAME_START) {
            t[i] = timing.frame_start;
            t0 = MIN(t0, t[i]);
        }
    }
    for (i = 0; i < n; i++)
        texts[i] = isfinite(t[i]) ? g_strdup_printf("%g", t[i] - t0) : g_strdup("");
    g_free(t);
    return t0 < G_MAXDOUBLE;
}

/* The candidates as the chooser's rows, checked as args says. */
static GtkListStore*
frame_store_new(SeriesGUI *gui)
{
    SeriesArgs *args = gui->args;
    GtkListStore *store = gtk_list_store_new(LOCALSCAN_SERIES_FRAME_NCOLUMNS,
                                             G_TYPE_BOOLEAN, G_TYPE_INT, G_TYPE_STRING,
                                             G_TYPE_STRING, GDK_TYPE_PIXBUF);
    gchar **starts = g_new0(gchar*, args->candidates->len + 1), *title;
    gint i, id;

    gui->any_start = frame_start_texts(args->data, args->candidates, starts);
    for (i = 0; i < (gint)args->candidates->len; i++) {
        id = g_array_index(args->candidates, gint, i);
        title = gwy_app_get_data_field_title(args->data, id);
        gtk_list_store_insert_with_values(store, NULL, i,
                                          LOCALSCAN_SERIES_FRAME_COLUMN_CHECKED, args->checked[i],
                                          LOCALSCAN_SERIES_FRAME_COLUMN_ID, id,
                                          LOCALSCAN_SERIES_FRAME_COLUMN_TITLE, title,
                                          LOCALSCAN_SERIES_FRAME_COLUMN_START, starts[i],
                                          -1);
        g_free(title);
    }
    g_strfreev(starts);
    return store;
}

/* A row's thumbnail is made when the row is first drawn: a long series
 * shows few rows at a time. */
static void
render_thumbnail(G_GNUC_UNUSED GtkTreeViewColumn *column, GtkCellRenderer *renderer,
                 GtkTreeModel *model, GtkTreeIter *iter, gpointer user_data)
{
    SeriesGUI *gui = (SeriesGUI*)user_data;
    GdkPixbuf *pixbuf = NULL;
    gint id;

    gtk_tree_model_get(model, iter, LOCALSCAN_SERIES_FRAME_COLUMN_THUMBNAIL, &pixbuf,
                       LOCALSCAN_SERIES_FRAME_COLUMN_ID, &id, -1);
    if (!pixbuf
        && (pixbuf = gwy_app_get_channel_thumbnail(gui->args->data, id,
                                                   THUMBNAIL_SIZE, THUMBNAIL_SIZE)))
        gtk_list_store_set(GTK_LIST_STORE(model), iter,
                           LOCALSCAN_SERIES_FRAME_COLUMN_THUMBNAIL, pixbuf, -1);
    g_object_set(renderer, "pixbuf", pixbuf, NULL);
    if (pixbuf)
        g_object_unref(pixbuf);
}

static GtkTreeViewColumn*
add_text_column(GtkWidget *view, const gchar *title, gint column_id)
{
    GtkCellRenderer *renderer = gtk_cell_renderer_text_new();
    GtkTreeViewColumn *column;

    column = gtk_tree_view_column_new_with_attributes(title, renderer, "text", column_id, NULL);
    gtk_tree_view_append_column(GTK_TREE_VIEW(view), column);
    return column;
}

/* The frame chooser: per candidate a checkbox, a thumbnail, the channel id,
 * title and, where the metadata gives it, its start, the way Gwyddion's
 * own channel lists show channels. */
static GtkWidget*
create_frame_chooser(gpointer user_data)
{
    SeriesGUI *gui = (SeriesGUI*)user_data;
    GtkWidget *view = gtk_tree_view_new_with_model(GTK_TREE_MODEL(gui->frames)), *scroll;
    GtkTreeViewColumn *column;
    GtkCellRenderer *renderer;

    gtk_widget_set_name(view, LOCALSCAN_SERIES_FRAMES_WIDGET_NAME);
    gtk_widget_set_tooltip_text(view, _("The channels scanned like this one.  Uncheck a frame "
                                        "to leave it out of the series: it is neither "
                                        "measured nor corrected"));
    renderer = gtk_cell_renderer_toggle_new();
    g_signal_connect_swapped(renderer, "toggled", G_CALLBACK(frame_toggled), gui);
    column = gtk_tree_view_column_new_with_attributes(NULL, renderer, "active",
                                                      LOCALSCAN_SERIES_FRAME_COLUMN_CHECKED,
                                                      NULL);
    gtk_tree_view_append_column(GTK_TREE_VIEW(view), column);
    renderer = gtk_cell_renderer_pixbuf_new();
    column = gtk_tree_view_column_new();
    gtk_tree_view_column_pack_start(column, renderer, FALSE);
    gtk_tree_view_column_set_cell_data_func(column, renderer, render_thumbnail, gui, NULL);
    gtk_tree_view_append_column(GTK_TREE_VIEW(view), column);
    add_text_column(view, _("Id"), LOCALSCAN_SERIES_FRAME_COLUMN_ID);
    column = add_text_column(view, _("Title"), LOCALSCAN_SERIES_FRAME_COLUMN_TITLE);
    gtk_tree_view_column_set_expand(column, TRUE);
    column = add_text_column(view, _("Start (s)"), LOCALSCAN_SERIES_FRAME_COLUMN_START);
    gtk_tree_view_column_set_visible(column, gui->any_start);

    scroll = gtk_scrolled_window_new(NULL, NULL);
    gtk_scrolled_window_set_policy(GTK_SCROLLED_WINDOW(scroll), GTK_POLICY_NEVER,
                                   GTK_POLICY_AUTOMATIC);
    gtk_scrolled_window_set_shadow_type(GTK_SCROLLED_WINDOW(scroll), GTK_SHADOW_IN);
    gtk_widget_set_size_request(scroll, -1, FRAME_LIST_HEIGHT);
    gtk_container_add(GTK_CONTAINER(scroll), view);
    return scroll;
}

/* Curves appended from another model do not bring its units. */
static void
set_graph_units(GwyGraphModel *gmodel)
{
    GwySIUnit *unit = gwy_si_unit_new("s");

    g_object_set(gmodel, "si-unit-x", unit, NULL);
    g_object_unref(unit);
    unit = gwy_si_unit_new("m");
    g_object_set(gmodel, "si-unit-y", unit, NULL);
    g_object_unref(unit);
}

static GwyDialogOutcome
run_gui(SeriesArgs *args)
{
    SeriesGUI gui;
    GwyDialog *dialog;
    GwyParamTable *table;
    GtkWidget *hbox, *vbox, *graph;
    GwyDialogOutcome outcome;

    gwy_clear(&gui, 1);
    gui.args = args;
    gui.dialog = gwy_dialog_new(_("Local Scan Series Drift"));
    dialog = GWY_DIALOG(gui.dialog);
    gwy_dialog_add_buttons(dialog, GWY_RESPONSE_UPDATE, GWY_RESPONSE_RESET,
                           GTK_RESPONSE_CANCEL, GTK_RESPONSE_OK, 0);

    hbox = gwy_hbox_new(8);
    gtk_container_set_border_width(GTK_CONTAINER(hbox), 4);
    gwy_dialog_add_content(dialog, hbox, TRUE, TRUE, 0);
    vbox = gwy_vbox_new(4);
    gtk_box_pack_start(GTK_BOX(hbox), vbox, TRUE, TRUE, 0);
    gui.gmodel = gwy_graph_model_new();
    g_object_set(gui.gmodel, "title", _("Drift trajectory"),
                 "axis-label-bottom", "t", "axis-label-left", _("drift"), NULL);
    set_graph_units(gui.gmodel);
    graph = gwy_graph_new(gui.gmodel);
    gwy_graph_enable_user_input(GWY_GRAPH(graph), FALSE);
    gtk_widget_set_size_request(graph, GRAPH_WIDTH, GRAPH_HEIGHT);
    gtk_box_pack_start(GTK_BOX(vbox), graph, TRUE, TRUE, 0);
    gui.summary = gtk_label_new(_("Press Update to measure the series."));
    gtk_misc_set_alignment(GTK_MISC(gui.summary), 0.0, 0.0);
    gtk_label_set_line_wrap(GTK_LABEL(gui.summary), TRUE);
    gtk_label_set_selectable(GTK_LABEL(gui.summary), TRUE);
    gtk_widget_set_size_request(gui.summary, GRAPH_WIDTH, -1);
    gtk_box_pack_start(GTK_BOX(vbox), gui.summary, FALSE, FALSE, 0);

    table = gui.table = gwy_param_table_new(args->params);
    gui.frames = frame_store_new(&gui);
    gwy_param_table_append_header(table, -1, _("Frames"));
    gwy_param_table_append_foreign(table, WIDGET_FRAMES, create_frame_chooser, &gui, NULL);
    gwy_param_table_append_header(table, -1, _("Timing the file does not give"));
    gwy_param_table_append_entry(table, PARAM_LINE_TIME);
    gwy_param_table_set_unitstr(table, PARAM_LINE_TIME, "s");
    gwy_param_table_append_entry(table, PARAM_FRAME_INTERVAL);
    gwy_param_table_set_unitstr(table, PARAM_FRAME_INTERVAL, "s");
    gwy_param_table_append_combo(table, PARAM_DIRECTION);
    /* The fields look as if they mattered: say when they do. */
    gwy_param_table_append_foreign(table, INFO_TIMING_USE, create_timing_use_label, &gui, NULL);
    gwy_param_table_append_header(table, -1, _("Output"));
    gwy_param_table_append_combo(table, PARAM_INTERPOLATION);
    gwy_param_table_append_checkbox(table, PARAM_CROP);
    gwy_param_table_append_checkbox(table, PARAM_ADD_GRAPH);
    dialog_tooltips_add(gwy_param_table_widget(table), series_tooltips,
                        G_N_ELEMENTS(series_tooltips));
    gtk_box_pack_start(GTK_BOX(hbox), gwy_param_table_widget(table), FALSE,
                       FALSE, 0);
    gwy_dialog_add_param_table(dialog, table);
    show_timing_use(&gui);

    g_signal_connect_swapped(table, "param-changed", G_CALLBACK(param_changed),
                             &gui);
    gwy_dialog_set_preview_func(dialog, GWY_PREVIEW_UPON_REQUEST, preview,
                                &gui, NULL);
    outcome = gwy_dialog_run(dialog);
    g_object_unref(gui.gmodel);
    g_object_unref(gui.frames);
    return outcome;
}

static void
localscan_series(GwyContainer *data, GwyRunType runtype,
                 G_GNUC_UNUSED const gchar *name)
{
    GwyDialogOutcome outcome = GWY_DIALOG_PROCEED;
    GError *error = NULL;
    SeriesArgs args;
    gboolean ok, show_progress;
    gdouble share;
    gint k;

    g_return_if_fail(runtype & SERIES_RUN_MODES);
    gwy_clear(&args, 1);
    gwy_app_data_browser_get_current(GWY_APP_DATA_FIELD_ID, &args.id, 0);
    g_return_if_fail(args.id >= 0);
    args.data = data;
    args.params = gwy_params_new_from_settings(define_series_params());
    /* Every candidate is a frame until the dialog unchecks some.  The
     * choice is not kept with the settings: channel ids of this file mean
     * nothing in the next (Repeat last, pygwy), so those runs take all. */
    args.candidates = frame_ids(data, args.id);
    args.checked = g_new(gboolean, MAX(args.candidates->len, 1));
    for (k = 0; k < (gint)args.candidates->len; k++)
        args.checked[k] = TRUE;
    if (runtype == GWY_RUN_INTERACTIVE) {
        outcome = run_gui(&args);
        gwy_params_save_to_settings(args.params);
        if (outcome == GWY_DIALOG_CANCEL)
            goto end;
    }
    show_progress = (runtype == GWY_RUN_INTERACTIVE || gwy_app_main_window_get());
    if (show_progress)
        gwy_app_wait_start(gwy_app_find_window_for_channel(data, args.id),
                           _("Correcting the series..."));
    /* Measured already when the dialog's preview was up to date: the
     * frames' correction then takes the whole bar. */
    share = args.computed ? 0.0 : SERIES_MEASURE_SHARE;
    ok = (execute(&args, show_progress, 0.0, share, &error)
          && create_outputs(&args, show_progress, share, &error));
    if (show_progress)
        gwy_app_wait_finish();
    if (ok && gwy_params_get_boolean(args.params, PARAM_ADD_GRAPH))
        add_graph(&args);
    /* A run the user cancelled adds nothing and needs no word. */
    if (!ok && error && !g_error_matches(error, SERIES_CORRECTION_ERROR,
                                         SERIES_CORRECTION_ERROR_CANCELLED))
        report_error(&args, error);

end:
    g_clear_error(&error);
    series_args_reset(&args);
    g_array_free(args.candidates, TRUE);
    g_free(args.checked);
    g_object_unref(args.params);
}

void
localscan_series_register(void)
{
    gwy_process_func_register(LOCALSCAN_SERIES_FUNCTION_NAME,
                              &localscan_series,
                              N_("/_Distortion/Local Scan _Series Drift..."),
                              NULL, SERIES_RUN_MODES, GWY_MENU_FLAG_DATA,
                              N_("Correct a series of frames (the channels "
                                 "scanned like this one) from one fitted "
                                 "drift trajectory"));
}
