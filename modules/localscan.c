/*
 *  Gwyddion process module "localscan_drift": removes thermal drift from an
 *  image by the local-scan method, from a per-stripe drift table.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <string.h>
#include <math.h>
#include <libintl.h>
#include <gtk/gtk.h>
#include <libgwyddion/gwymacros.h>
#include <libprocess/arithmetic.h>
#include <libgwydgets/gwydgets.h>
#include <libgwymodule/gwymodule-process.h>
#include <app/gwyapp.h>
#include <app/gwymoduleutils.h>
#include "localscan-channel.h"
#include "localscan-params.h"
#include "stripe-registration.h"
#include "compensation-marker.h"
#include "reference-choice.h"
#include "run-description.h"
#include "preview-field.h"
#include "series-process.h"
#include "dialog-tooltips.h"

/* Our strings live in our own domain, not in Gwyddion's. */
#undef _
#define _(s) dgettext(GETTEXT_PACKAGE, s)

#define RUN_MODES (GWY_RUN_INTERACTIVE | GWY_RUN_IMMEDIATE)
#define PREVIEW_SIZE 480
#define DRIFT_GRAPH_HEIGHT 170
/* How long the stripe count must rest before it is registered. */
#define STRIPES_SETTLE_MS 400

enum {
    PARAM_SOURCE,
    PARAM_TABLE_FILE,
    PARAM_REFERENCE,
    PARAM_STRIPES,
    PARAM_MODE,
    PARAM_INTERPOLATION,
    PARAM_DIRECTION,
    PARAM_LINE_TIME,
    PARAM_FRAME_START,
    PARAM_FILL,
    PARAM_ADD_MASK,
    PARAM_PLOT_DRIFT,
    PARAM_MASK_COLOR,
    PARAM_REFERENCE_CHANNEL,
    PARAM_FORCE,
    PARAM_ALL_CHANNELS,
    PARAM_MASKING,
    WIDGET_TABLE_FILE,
    WIDGET_REFERENCE,
    MESSAGE_STATUS,
};

/* The drift measured against a reference (whole table or the error), kept
 * because registration is slow on large images and depends only on the
 * reference and the stripe count. */
typedef struct {
    gboolean valid;
    GwyAppDataId reference;
    gint stripes;
    GwyMaskingType masking;
    DriftTable *table;     /* px, exact (not rounded) */
    StripeRegistrationSupport support;
    GError *error;
} MeasuredDrift;

typedef struct {
    GwyParams *params;
    GwyContainer *data;
    gint id;
    GwyDataField *field;
    GwyDataField *result;
    GwyDataField *mask;
    DriftTable *table;
    LocalscanApplied applied;
    ScanTiming timing;                /* what continuous mode used */
    LocalscanTimingFound timing_found;
    gint batch_reference;     /* reference-channel of an IMMEDIATE run, or -1 */
    MeasuredDrift measured;
    GArray *siblings;         /* SiblingResult: the scan's other channels */
    gboolean result_has_mask; /* the new channel gets args->mask */
    gboolean show_progress;   /* the final run in Gwyddion's wait dialog */
    gboolean cancelled;       /* the user cancelled it there */
} ModuleArgs;

/* One more channel of the scan compensated like the image. */
typedef struct {
    gint id;
    GwyDataField *result;
    GwyDataField *mask;       /* filled pixels and the channel's own mask */
    gboolean has_mask;
} SiblingResult;

typedef struct {
    ModuleArgs *args;
    GtkWidget *dialog;
    GwyParamTable *table;
    GtkWidget *file_button;
    GwyContainer *data;
    GwyGraphModel *drift_gmodel;
    GtkWidget *reference_combo;
    GtkWidget *preview_status;   /* under the drift graph: what a registration
                                    measured */
    GtkWidget *export_button;
    GtkListStore *references;
    LocalscanTimingFound timing_in_meta;
    guint stripes_settle_id;
    /* A large image is previewed on a reduced copy (preview-field.h), and
     * so is its reference, registered against it. */
    PreviewField *preview;
    PreviewField *preview_reference;
    GwyAppDataId preview_reference_id;
    MeasuredDrift preview_measured;
    LocalscanApplied preview_applied;
} ModuleGUI;

static gboolean         module_register     (void);
static GwyParamDef*     define_module_params(void);
static void             localscan_drift     (GwyContainer *data,
                                             GwyRunType runtype,
                                             const gchar *name);
static void             use_reference_channel_setting(ModuleArgs *args,
                                                      GwyRunType runtype);
static gboolean         check_not_compensated(ModuleArgs *args,
                                              GwyRunType runtype);
static void             remember_reference_channel   (ModuleArgs *args);
static gboolean         execute             (ModuleArgs *args,
                                             GError **error);
static gboolean         execute_preview     (ModuleGUI *gui,
                                             GError **error);
static DriftTable*      load_drift_table    (ModuleArgs *args,
                                             GError **error);
static gboolean         progress_stage      (ModuleArgs *args,
                                             const gchar *message);
static gboolean         compensate_siblings (ModuleArgs *args,
                                             GError **error);
static void             siblings_clear      (ModuleArgs *args);
static void             create_outputs      (ModuleArgs *args);
static void             add_drift_graph     (ModuleArgs *args);
static void             report_error        (ModuleArgs *args,
                                             const GError *error);
static GwyDialogOutcome run_gui             (ModuleArgs *args);
static GtkWidget*       create_drift_graph  (ModuleGUI *gui);
static GtkWidget*       create_export_button(ModuleGUI *gui);
static GtkWidget*       create_file_chooser (gpointer user_data);
static void             table_file_chosen   (ModuleGUI *gui);
static GtkWidget*       create_reference_chooser(gpointer user_data);
static gboolean         reference_filter    (GwyContainer *data,
                                             gint id,
                                             gpointer user_data);
static void             param_changed       (ModuleGUI *gui,
                                             gint id);
static void             preview             (gpointer user_data);
static gboolean         stripes_settled     (gpointer user_data);
static void             measured_drift_clear(MeasuredDrift *measured);

static GwyModuleInfo module_info = {
    GWY_MODULE_ABI_VERSION,
    &module_register,
    N_("Compensates thermal drift by the local-scan method: shifts image stripes back by a "
       "measured per-stripe drift table."),
    "The gwy-localscan authors",
    PACKAGE_VERSION,
    "The gwy-localscan authors",
    "2026",
};

GWY_MODULE_QUERY(module_info)

static gboolean
module_register(void)
{
    bindtextdomain(GETTEXT_PACKAGE, LOCALEDIR);
    bind_textdomain_codeset(GETTEXT_PACKAGE, "UTF-8");
    gwy_process_func_register(LOCALSCAN_FUNCTION_NAME,
                              &localscan_drift,
                              N_("/_Distortion/_Local Scan Drift..."),
                              NULL,
                              RUN_MODES,
                              GWY_MENU_FLAG_DATA,
                              N_("Compensate drift by the local-scan method"));
    localscan_series_register();
    return TRUE;
}

/* GwyParamTable translates enum labels in Gwyddion's domain, so the labels
 * are translated here, in ours, once. */
static const GwyEnum*
translate_enum(const GwyEnum *values, gint n)
{
    GwyEnum *translated = g_new(GwyEnum, n);
    gint i;

    for (i = 0; i < n; i++) {
        translated[i].name = _(values[i].name);
        translated[i].value = values[i].value;
    }
    return translated;
}

static GwyParamDef*
define_module_params(void)
{
    static const GwyEnum sources[] = {
        { N_("Table stored with the image"), LOCALSCAN_SOURCE_STORED,    },
        { N_("Table file (CSV)"),            LOCALSCAN_SOURCE_FILE,      },
        { N_("Registration to a reference"), LOCALSCAN_SOURCE_REFERENCE, },
    };
    static const GwyEnum modes[] = {
        { N_("Paper (whole-pixel stripes)"), LOCALSCAN_MODE_PAPER,      },
        { N_("Continuous (line by line)"),   LOCALSCAN_MODE_CONTINUOUS, },
    };
    static const GwyEnum directions[] = {
        { N_("Down"), SCAN_DIRECTION_DOWN, },
        { N_("Up"),   SCAN_DIRECTION_UP,   },
    };
    static const GwyEnum fills[] = {
        { N_("Image mean"), LOCALSCAN_FILL_MEAN,    },
        { N_("Zero"),       LOCALSCAN_FILL_ZERO,    },
        { N_("Minimum"),    LOCALSCAN_FILL_MINIMUM, },
        { N_("Maximum"),    LOCALSCAN_FILL_MAXIMUM, },
    };
    static GwyParamDef *paramdef = NULL;

    if (paramdef)
        return paramdef;

    paramdef = gwy_param_def_new();
    gwy_param_def_set_function_name(paramdef, LOCALSCAN_FUNCTION_NAME);
    gwy_param_def_add_gwyenum(paramdef, PARAM_SOURCE, LOCALSCAN_KEY_SOURCE, _("Drift source"),
                              translate_enum(sources, G_N_ELEMENTS(sources)),
                              G_N_ELEMENTS(sources), LOCALSCAN_DEFAULT_SOURCE);
    gwy_param_def_add_string(paramdef, PARAM_TABLE_FILE, LOCALSCAN_KEY_TABLE_FILE, _("Table _file"),
                             GWY_PARAM_STRING_NULL_IS_EMPTY, NULL, "");
    gwy_param_def_add_image_id(paramdef, PARAM_REFERENCE, LOCALSCAN_KEY_REFERENCE,
                               _("_Reference image"));
    gwy_param_def_add_int(paramdef, PARAM_STRIPES, LOCALSCAN_KEY_STRIPES, _("_Stripes"),
                          LOCALSCAN_STRIPES_MIN, LOCALSCAN_STRIPES_MAX, LOCALSCAN_STRIPES_DEFAULT);
    gwy_param_def_add_gwyenum(paramdef, PARAM_MODE, LOCALSCAN_KEY_MODE, _("Mode"),
                              translate_enum(modes, G_N_ELEMENTS(modes)),
                              G_N_ELEMENTS(modes), LOCALSCAN_DEFAULT_MODE);
    gwy_param_def_add_enum(paramdef, PARAM_INTERPOLATION, LOCALSCAN_KEY_INTERPOLATION,
                           _("_Interpolation"),
                           GWY_TYPE_INTERPOLATION_TYPE, LOCALSCAN_DEFAULT_INTERPOLATION);
    gwy_param_def_add_gwyenum(paramdef, PARAM_DIRECTION, LOCALSCAN_KEY_DIRECTION,
                              _("Slow scan _direction"),
                              translate_enum(directions, G_N_ELEMENTS(directions)),
                              G_N_ELEMENTS(directions), LOCALSCAN_DEFAULT_DIRECTION);
    gwy_param_def_add_double(paramdef, PARAM_LINE_TIME, LOCALSCAN_KEY_LINE_TIME, _("_Line time"),
                             LOCALSCAN_LINE_TIME_MIN, LOCALSCAN_LINE_TIME_MAX,
                             LOCALSCAN_LINE_TIME_DEFAULT);
    gwy_param_def_add_double(paramdef, PARAM_FRAME_START, LOCALSCAN_KEY_FRAME_START,
                             _("Frame _start"),
                             LOCALSCAN_FRAME_START_MIN, LOCALSCAN_FRAME_START_MAX,
                             LOCALSCAN_FRAME_START_DEFAULT);
    gwy_param_def_add_gwyenum(paramdef, PARAM_FILL, LOCALSCAN_KEY_FILL, _("_Fill value"),
                              translate_enum(fills, G_N_ELEMENTS(fills)),
                              G_N_ELEMENTS(fills), LOCALSCAN_DEFAULT_FILL);
    gwy_param_def_add_boolean(paramdef, PARAM_ADD_MASK, LOCALSCAN_KEY_ADD_MASK,
                              _("_Mask filled pixels"), LOCALSCAN_DEFAULT_ADD_MASK);
    gwy_param_def_add_boolean(paramdef, PARAM_PLOT_DRIFT, LOCALSCAN_KEY_PLOT_DRIFT,
                              _("_Plot drift graph"), LOCALSCAN_DEFAULT_PLOT_DRIFT);
    gwy_param_def_add_mask_color(paramdef, PARAM_MASK_COLOR, NULL, NULL);
    /* The reference by its channel id in the image's own file, for batch
     * callers: an image id parameter is remembered only in the running
     * session's memory, never in the settings. */
    gwy_param_def_add_int(paramdef, PARAM_REFERENCE_CHANNEL, LOCALSCAN_KEY_REFERENCE_CHANNEL, NULL,
                          LOCALSCAN_REFERENCE_CHANNEL_NONE, G_MAXINT32,
                          LOCALSCAN_REFERENCE_CHANNEL_NONE);
    /* Batch callers only (gwy-localscan --force): the dialog asks instead. */
    gwy_param_def_add_boolean(paramdef, PARAM_FORCE, LOCALSCAN_KEY_FORCE, NULL,
                              LOCALSCAN_DEFAULT_FORCE);
    gwy_param_def_add_boolean(paramdef, PARAM_ALL_CHANNELS, LOCALSCAN_KEY_ALL_CHANNELS,
                              _("_All channels of the scan"), LOCALSCAN_DEFAULT_ALL_CHANNELS);
    gwy_param_def_add_enum(paramdef, PARAM_MASKING, LOCALSCAN_KEY_MASKING, _("Mas_ks in registration"),
                           GWY_TYPE_MASKING_TYPE, LOCALSCAN_DEFAULT_MASKING);
    return paramdef;
}

static void
localscan_drift(GwyContainer *data, GwyRunType runtype, G_GNUC_UNUSED const gchar *name)
{
    GwyDialogOutcome outcome = GWY_DIALOG_PROCEED;
    GError *error = NULL;
    ModuleArgs args;
    gboolean ok;

    g_return_if_fail(runtype & RUN_MODES);
    gwy_clear(&args, 1);
    gwy_app_data_browser_get_current(GWY_APP_DATA_FIELD, &args.field,
                                     GWY_APP_DATA_FIELD_ID, &args.id,
                                     0);
    g_return_if_fail(args.field);
    args.data = data;
    /* Compensation writes every pixel of both. */
    args.result = gwy_data_field_new_alike(args.field, FALSE);
    args.mask = gwy_data_field_new_alike(args.field, FALSE);
    args.params = gwy_params_new_from_settings(define_module_params());
    use_reference_channel_setting(&args, runtype);
    if (!check_not_compensated(&args, runtype))
        goto end;

    if (runtype == GWY_RUN_INTERACTIVE) {
        outcome = run_gui(&args);
        remember_reference_channel(&args);
        gwy_params_save_to_settings(args.params);
        if (outcome == GWY_DIALOG_CANCEL)
            goto end;
    }
    /* Computed again after a preview, which may have been of a reduced
     * copy, so that the GUI and IMMEDIATE runs take exactly the same path to
     * the result.  A registration of the whole image is reused when the
     * reference and the stripe count are still those it was measured with.
     * With a GUI the run shows Gwyddion's wait dialog; cancelled, it adds
     * nothing. */
    args.show_progress = (runtype == GWY_RUN_INTERACTIVE || gwy_app_main_window_get());
    if (args.show_progress)
        gwy_app_wait_start(gwy_app_find_window_for_channel(data, args.id),
                           _("Local-scan drift compensation..."));
    ok = execute(&args, &error);
    args.result_has_mask = (gwy_params_get_boolean(args.params, PARAM_ADD_MASK)
                            && args.applied.n_filled > 0);
    if (ok && gwy_params_get_boolean(args.params, PARAM_ALL_CHANNELS))
        ok = compensate_siblings(&args, &error);
    ok = ok && progress_stage(&args, _("Creating the channels..."));
    if (args.show_progress)
        gwy_app_wait_finish();
    if (ok)
        create_outputs(&args);
    else if (!args.cancelled)
        report_error(&args, error);
    siblings_clear(&args);

end:
    g_clear_error(&error);
    if (args.table)
        drift_table_free(args.table);
    localscan_applied_clear(&args.applied);
    measured_drift_clear(&args.measured);
    g_object_unref(args.mask);
    g_object_unref(args.result);
    g_object_unref(args.params);
}

/* A reference given as reference-channel (batch callers) names a channel of
 * the image's own file and is used as given: a bad one is reported.  In the
 * dialog it only preselects the chooser, and only a channel it offers. */
static void
use_reference_channel_setting(ModuleArgs *args, GwyRunType runtype)
{
    static const GwyAppDataId none = GWY_APP_DATA_ID_NONE;
    gint channel = gwy_params_get_int(args->params, PARAM_REFERENCE_CHANNEL);
    GwyAppDataId refid;

    args->batch_reference = -1;
    if (channel < 0)
        return;
    if (runtype == GWY_RUN_INTERACTIVE && !reference_filter(args->data, channel, args))
        return;
    refid.datano = gwy_app_data_browser_get_number(args->data);
    refid.id = channel;
    if (runtype != GWY_RUN_INTERACTIVE) {
        args->batch_reference = channel;
        /* Never the session's remembered choice instead of a missing one. */
        if (!gwy_app_data_id_verify_channel(&refid))
            refid = none;
    }
    gwy_params_set_image_id(args->params, PARAM_REFERENCE, refid);
}

/* A compensated channel carries the drift table it was made with, so
 * nothing else would stop Repeat last from applying the drift twice. */
static gboolean
ask_compensate_again(ModuleArgs *args)
{
    GtkWindow *parent = gwy_app_find_window_for_channel(args->data, args->id);
    GtkWidget *dialog;
    gint response;

    dialog = gtk_message_dialog_new(parent, GTK_DIALOG_MODAL | GTK_DIALOG_DESTROY_WITH_PARENT,
                                    GTK_MESSAGE_QUESTION, GTK_BUTTONS_NONE,
                                    "%s", _("This channel is already local-scan compensated."));
    gtk_message_dialog_format_secondary_text(GTK_MESSAGE_DIALOG(dialog), "%s",
                                             _("Compensating it again applies the drift a second "
                                               "time.  Compensate it anyway?"));
    gtk_dialog_add_buttons(GTK_DIALOG(dialog),
                           GTK_STOCK_CANCEL, GTK_RESPONSE_CANCEL,
                           _("Compensate _Again"), GTK_RESPONSE_YES,
                           NULL);
    gtk_dialog_set_default_response(GTK_DIALOG(dialog), GTK_RESPONSE_CANCEL);
    response = gtk_dialog_run(GTK_DIALOG(dialog));
    gtk_widget_destroy(dialog);
    return response == GTK_RESPONSE_YES;
}

static gboolean
check_not_compensated(ModuleArgs *args, GwyRunType runtype)
{
    GError *error = NULL;
    gchar *name;
    gboolean ok;

    if (!compensation_marker_get(args->data, args->id))
        return TRUE;
    /* Repeat last in Gwyddion (IMMEDIATE with a main window) asks too,
     * whatever a script left in the force parameter; only batch callers,
     * which cannot answer, need it. */
    if (runtype == GWY_RUN_INTERACTIVE || gwy_app_main_window_get())
        return ask_compensate_again(args);
    name = g_strdup_printf(_("channel %d"), args->id);
    ok = compensation_marker_check(args->data, args->id, name,
                                   gwy_params_get_boolean(args->params, PARAM_FORCE),
                                   _("set the parameter force to do it anyway"), &error);
    g_free(name);
    if (!ok)
        report_error(args, error);
    g_clear_error(&error);
    return ok;
}

/* So that the settings (and the log, which records them) name the chosen
 * reference, and a repeated IMMEDIATE run uses it; a reference in another
 * file cannot be named there. */
static void
remember_reference_channel(ModuleArgs *args)
{
    GwyAppDataId refid = gwy_params_get_data_id(args->params, PARAM_REFERENCE);
    gint channel = -1;

    if (refid.id >= 0 && refid.datano == gwy_app_data_browser_get_number(args->data))
        channel = refid.id;
    gwy_params_set_int(args->params, PARAM_REFERENCE_CHANNEL, channel);
}

/* The chosen reference, checked to be another scan of the image's area
 * that the stripe count fits. */
static GwyDataField*
find_reference(ModuleArgs *args, GwyAppDataId *refid, GError **error)
{
    GwyDataField *reference;
    gchar *image_name, *reference_name;
    gboolean ok;

    *refid = gwy_params_get_data_id(args->params, PARAM_REFERENCE);
    if (refid->id < 0 && args->batch_reference >= 0) {
        g_set_error(error, LOCALSCAN_CHANNEL_ERROR, LOCALSCAN_CHANNEL_ERROR_REFERENCE,
                    _("The reference channel %d does not exist."), args->batch_reference);
        return NULL;
    }
    if (refid->id < 0) {
        g_set_error(error, LOCALSCAN_CHANNEL_ERROR, LOCALSCAN_CHANNEL_ERROR_REFERENCE, "%s",
                    _("No reference image is chosen (another channel of the same pixel and "
                      "physical size)."));
        return NULL;
    }
    if (!(reference = gwy_params_get_image(args->params, PARAM_REFERENCE))) {
        g_set_error(error, LOCALSCAN_CHANNEL_ERROR, LOCALSCAN_CHANNEL_ERROR_REFERENCE,
                    _("The reference channel %d does not exist."), refid->id);
        return NULL;
    }
    if (reference == args->field) {
        g_set_error(error, LOCALSCAN_CHANNEL_ERROR, LOCALSCAN_CHANNEL_ERROR_REFERENCE, "%s",
                    _("The reference must be another channel than the image itself."));
        return NULL;
    }
    image_name = g_strdup_printf(_("channel %d"), args->id);
    reference_name = g_strdup_printf(_("channel %d"), refid->id);
    ok = localscan_reference_check(args->field, image_name, reference, reference_name,
                                   gwy_params_get_int(args->params, PARAM_STRIPES), error);
    g_free(reference_name);
    g_free(image_name);
    return ok ? reference : NULL;
}

static void
measured_drift_clear(MeasuredDrift *measured)
{
    if (measured->table)
        drift_table_free(measured->table);
    g_clear_error(&measured->error);
    gwy_clear(measured, 1);
}

/* A registration that measured too few of the stripes it could measure
 * cannot support a result: it is an unusable drift source, in the dialog
 * (its reason shown, OK insensitive) as in a batch run (one line). */
static void
refuse_unsupported(MeasuredDrift *measured)
{
    gchar *why;

    if (!measured->table || !(why = stripe_registration_support_message(&measured->support)))
        return;
    g_set_error(&measured->error, STRIPE_REGISTRATION_ERROR, STRIPE_REGISTRATION_ERROR_NO_MATCH,
                _("The registration does not support a result: %s."), why);
    g_free(why);
    drift_table_free(measured->table);
    measured->table = NULL;
}

/* What the registration measured, for the dialog; NULL when the drift does
 * not come from one. */
static gchar*
format_registration_status(const MeasuredDrift *measured)
{
    const StripeRegistrationSupport *support = &measured->support;

    if (!measured->valid || !measured->table)
        return NULL;
    return g_strdup_printf(_("Registration: %d of the %d stripes whose content lies in the reference "
                             "measured, median score %.2f."),
                           support->measured, support->in_reference, support->median_score);
}

/* A channel's mask, or NULL. */
static GwyDataField*
channel_mask(GwyContainer *data, gint id)
{
    return (data && id >= 0) ? localscan_channel_mask(data, id) : NULL;
}

/* Whether the last registration had this reference, stripe count and
 * masking.  The masks themselves are not compared: they cannot change
 * while the dialog, which is modal, is open. */
static gboolean
measured_drift_current(const MeasuredDrift *measured, GwyAppDataId refid, gint n,
                       GwyMaskingType masking)
{
    return (measured->valid && measured->stripes == n && measured->masking == masking
            && measured->reference.datano == refid.datano && measured->reference.id == refid.id);
}

/* The exact table registering image against reference measured, from the
 * last registration when it is current (its failure is kept just as
 * well).  The masks are the image's and the reference's, in their pixels
 * (either may be NULL). */
static const DriftTable*
measure_drift(MeasuredDrift *measured, GwyDataField *image, GwyDataField *image_mask,
              GwyDataField *reference, GwyDataField *reference_mask, GwyAppDataId refid, gint n,
              GwyMaskingType masking, GError **error)
{
    StripeRegistrationOptions options;

    if (!measured_drift_current(measured, refid, n, masking)) {
        measured_drift_clear(measured);
        g_debug("%s: registering %d stripes against channel %d (%d x %d px)",
                LOCALSCAN_FUNCTION_NAME, n, refid.id,
                gwy_data_field_get_xres(image), gwy_data_field_get_yres(image));
        stripe_registration_options_init(&options);
        options.image_mask = image_mask;
        options.reference_mask = reference_mask;
        options.masking = masking;
        measured->table = stripe_registration_table_for_fields(image, reference, n, &options, FALSE,
                                                               &measured->support, &measured->error);
        refuse_unsupported(measured);
        measured->valid = TRUE;
        measured->reference = refid;
        measured->stripes = n;
        measured->masking = masking;
    }
    if (measured->error) {
        g_propagate_error(error, g_error_copy(measured->error));
        return NULL;
    }
    return measured->table;
}

static const DriftTable*
measure_reference_drift(ModuleArgs *args, GError **error)
{
    GwyDataField *reference;
    GwyAppDataId refid;

    if (!(reference = find_reference(args, &refid, error)))
        return NULL;
    return measure_drift(&args->measured, args->field, channel_mask(args->data, args->id), reference,
                         channel_mask(gwy_app_data_browser_get(refid.datano), refid.id), refid,
                         gwy_params_get_int(args->params, PARAM_STRIPES),
                         gwy_params_get_enum(args->params, PARAM_MASKING), error);
}

/* Paper mode shifts by whole pixels; the exact columns stay for continuous
 * mode and for the record. */
static DriftTable*
reference_drift_table(ModuleArgs *args, GError **error)
{
    const DriftTable *measured;

    if (!(measured = measure_reference_drift(args, error)))
        return NULL;
    if (gwy_params_get_enum(args->params, PARAM_MODE) == LOCALSCAN_MODE_PAPER)
        return localscan_table_round_px(measured);
    return drift_table_copy(measured);
}

static DriftTable*
load_drift_table(ModuleArgs *args, GError **error)
{
    LocalscanSource source = gwy_params_get_enum(args->params, PARAM_SOURCE);
    const gchar *filename;

    if (source == LOCALSCAN_SOURCE_STORED)
        return localscan_channel_stored_table(args->data, args->id, error);
    if (source == LOCALSCAN_SOURCE_FILE) {
        filename = gwy_params_get_string(args->params, PARAM_TABLE_FILE);
        if (!filename || !*filename) {
            g_set_error(error, LOCALSCAN_CHANNEL_ERROR, LOCALSCAN_CHANNEL_ERROR_NO_TABLE,
                        "%s", _("No drift table file is chosen."));
            return NULL;
        }
        return drift_table_load(filename, error);
    }
    return reference_drift_table(args, error);
}

/* Between the stages of a run in the wait dialog: FALSE when the user
 * cancelled it. */
static gboolean
progress_stage(ModuleArgs *args, const gchar *message)
{
    if (!args->show_progress || args->cancelled)
        return !args->cancelled;
    args->cancelled = !gwy_app_wait_set_message(message);
    return !args->cancelled;
}

/* The options of the run: the timing settings are only the fallbacks for
 * files that do not say how they were scanned. */
static void
gather_options(ModuleArgs *args, LocalscanOptions *options)
{
    GwyParams *params = args->params;

    args->timing_found
        = localscan_channel_scan_timing_fallback(args->data, args->id,
                                                 gwy_params_get_double(params, PARAM_LINE_TIME),
                                                 gwy_params_get_enum(params, PARAM_DIRECTION),
                                                 gwy_params_get_double(params, PARAM_FRAME_START),
                                                 &args->timing);
    options->mode = gwy_params_get_enum(params, PARAM_MODE);
    options->fill = gwy_params_get_enum(params, PARAM_FILL);
    options->interpolation = gwy_params_get_enum(params, PARAM_INTERPOLATION);
    options->line_time = args->timing.line_time;
    options->direction = args->timing.direction;
    options->frame_start = args->timing.frame_start;
}

static gboolean
execute(ModuleArgs *args, GError **error)
{
    LocalscanOptions options;

    if (args->table)
        drift_table_free(args->table);
    args->table = NULL;
    localscan_applied_clear(&args->applied);
    if (!progress_stage(args, _("Reading the drift...")))
        return FALSE;
    if (!(args->table = load_drift_table(args, error)))
        return FALSE;
    if (!progress_stage(args, _("Compensating...")))
        return FALSE;
    gather_options(args, &options);
    return localscan_compensate_field(args->field, args->table, &options, args->result, args->mask,
                                      &args->applied, error);
}

/* How the reference is named everywhere: "file — channel". */
static gchar*
reference_label(GwyContainer *data, gint id)
{
    gchar *untitled = g_strdup_printf(_("Untitled %d"), gwy_app_data_browser_get_number(data));
    gchar *label = reference_choice_label(data, id, untitled);

    g_free(untitled);
    return label;
}

/* The settings that made the result, by name. */
static gchar*
describe_run(ModuleArgs *args)
{
    GwyParams *params = args->params;
    GwyAppDataId refid = gwy_params_get_data_id(params, PARAM_REFERENCE);
    GwyContainer *refdata = refid.id >= 0 ? gwy_app_data_browser_get(refid.datano) : NULL;
    RunDescription run;
    gchar *reference = NULL, *text;

    run.source = gwy_params_get_enum(params, PARAM_SOURCE);
    run.table_file = gwy_params_get_string(params, PARAM_TABLE_FILE);
    if (run.source == LOCALSCAN_SOURCE_REFERENCE && refdata)
        reference = reference_label(refdata, refid.id);
    run.reference = reference;
    run.stripes = gwy_params_get_int(params, PARAM_STRIPES);
    run.masking = gwy_params_get_enum(params, PARAM_MASKING);
    run.mode = gwy_params_get_enum(params, PARAM_MODE);
    run.interpolation = gwy_params_get_enum(params, PARAM_INTERPOLATION);
    run.fill = gwy_params_get_enum(params, PARAM_FILL);
    text = run_description_format(&run);
    g_free(reference);
    return text;
}

/* Gwyddion's own log entry would list the stored settings as numbers; the
 * entry is written with their names instead, in the same form
 * (function(args)@time), after the source's log is copied. */
static void
log_run(GwyContainer *data, gint id, gint newid, const gchar *description)
{
    GwyStringList *log = NULL;
    GDateTime *now;
    gchar key[40], *stamp;

    if (!gwy_log_get_enabled())
        return;
    gwy_app_channel_log_add(data, id, newid, NULL, NULL);
    g_snprintf(key, sizeof(key), "/%d/data/log", newid);
    if (!gwy_container_gis_object_by_name(data, key, &log)) {
        log = gwy_string_list_new();
        gwy_container_set_object_by_name(data, key, log);
        g_object_unref(log);
    }
    now = g_date_time_new_now_local();
    stamp = g_date_time_format(now, "%Y-%m-%d %H:%M:%S");
    gwy_string_list_append_take(log, g_strdup_printf("proc::%s(%s)@%s", LOCALSCAN_FUNCTION_NAME,
                                                     description, stamp));
    g_free(stamp);
    g_date_time_unref(now);
}

/* A new channel made from channel id: titled after it, with its palette,
 * range and metadata, the table used, the compensation marker and a log
 * entry by name. */
static gint
add_result_channel(ModuleArgs *args, gint id, GwyDataField *result, GwyDataField *mask,
                   const gchar *description)
{
    GwyContainer *data = args->data;
    gchar *title;
    gint newid;

    newid = gwy_app_data_browser_add_data_field(result, data, TRUE);
    title = gwy_app_get_data_field_title(data, id);
    gwy_container_set_string(data, gwy_app_get_data_title_key_for_id(newid),
                             (const guchar*)localscan_channel_result_title(title));
    g_free(title);
    gwy_app_sync_data_items(data, data, id, newid, FALSE,
                            GWY_DATA_ITEM_GRADIENT,
                            GWY_DATA_ITEM_RANGE,
                            GWY_DATA_ITEM_RANGE_TYPE,
                            GWY_DATA_ITEM_MASK_COLOR,
                            GWY_DATA_ITEM_META,
                            GWY_DATA_ITEM_REAL_SQUARE,
                            0);
    if (mask)
        gwy_container_set_object(data, gwy_app_get_mask_key_for_id(newid), mask);
    /* The table as read, so the new channel can be compensated or inspected
     * again; the applied per-stripe values follow from it and the image. */
    localscan_channel_store_table(data, newid, args->table);
    localscan_channel_drop_source_meta(data, newid);
    compensation_marker_set(data, newid, description, args->table);
    log_run(data, id, newid, description);
    return newid;
}

/* The source channels are never touched: adding the new channels is the
 * whole (undoable) change. */
static void
create_outputs(ModuleArgs *args)
{
    gchar *description = describe_run(args);
    SiblingResult *sibling;
    guint i;

    add_result_channel(args, args->id, args->result, args->result_has_mask ? args->mask : NULL,
                       description);
    for (i = 0; args->siblings && i < args->siblings->len; i++) {
        sibling = &g_array_index(args->siblings, SiblingResult, i);
        add_result_channel(args, sibling->id, sibling->result,
                           sibling->has_mask ? sibling->mask : NULL, description);
    }
    g_free(description);
    if (gwy_params_get_boolean(args->params, PARAM_PLOT_DRIFT))
        add_drift_graph(args);
}

/* The other channels of the image's scan: its own file, its pixels and
 * physical size, its scan time (reference-choice.h's siblings), not
 * compensated already. */
static gint*
find_siblings(ModuleArgs *args)
{
    gint *ids = gwy_app_data_browser_get_data_ids(args->data), i, n = 0;

    for (i = 0; ids[i] >= 0; i++) {
        if (reference_choice_rank(args->data, args->id, args->data, ids[i])
            == REFERENCE_RANK_SIBLING
            && !compensation_marker_get(args->data, ids[i]))
            ids[n++] = ids[i];
    }
    ids[n] = -1;
    return ids;
}

/* A mask moves with its channel: compensated with the nearest pixel, so it
 * stays a mask, and joined with the filled pixels when those are masked. */
static gboolean
compensate_own_mask(ModuleArgs *args, gint id, const LocalscanOptions *options,
                    SiblingResult *sibling, GError **error)
{
    GwyDataField *own = NULL, *moved, *filled;
    LocalscanOptions mask_options = *options;
    gboolean ok;

    /* Anything else stored as its mask (another size, no field) is none. */
    if (!(own = localscan_channel_mask(args->data, id)))
        return TRUE;
    mask_options.interpolation = GWY_INTERPOLATION_ROUND;
    mask_options.fill = LOCALSCAN_FILL_ZERO;
    moved = gwy_data_field_new_alike(own, FALSE);
    filled = gwy_data_field_new_alike(own, FALSE);
    ok = localscan_compensate_field(own, args->table, &mask_options, moved, filled, NULL, error);
    if (ok) {
        if (sibling->has_mask)
            gwy_data_field_max_of_fields(sibling->mask, sibling->mask, moved);
        else
            gwy_data_field_assign(sibling->mask, moved);
        sibling->has_mask = TRUE;
    }
    g_object_unref(filled);
    g_object_unref(moved);
    return ok;
}

static gboolean
compensate_sibling(ModuleArgs *args, gint id, const LocalscanOptions *options, GError **error)
{
    GwyDataField *field = gwy_container_get_object(args->data, gwy_app_get_data_key_for_id(id));
    LocalscanApplied applied;
    SiblingResult sibling;

    sibling.id = id;
    sibling.result = gwy_data_field_new_alike(field, FALSE);
    sibling.mask = gwy_data_field_new_alike(field, FALSE);
    if (!localscan_compensate_field(field, args->table, options, sibling.result, sibling.mask,
                                    &applied, error)) {
        /* Said of the image, the refusal blamed a channel that is fine. */
        g_prefix_error(error, _("the other channel %d of the scan: "), id);
        g_object_unref(sibling.result);
        g_object_unref(sibling.mask);
        return FALSE;
    }
    sibling.has_mask = (gwy_params_get_boolean(args->params, PARAM_ADD_MASK)
                        && applied.n_filled > 0);
    localscan_applied_clear(&applied);
    g_array_append_val(args->siblings, sibling);
    return compensate_own_mask(args, id, options,
                               &g_array_index(args->siblings, SiblingResult,
                                              args->siblings->len - 1), error);
}

/* The image's drift applied to every other channel of its scan, as
 * Gwyddion's own drift compensation offers; the image's own mask moves
 * too.  Nothing is added until all are made. */
static gboolean
compensate_siblings(ModuleArgs *args, GError **error)
{
    gint *ids = find_siblings(args), i;
    LocalscanOptions options;
    SiblingResult main_mask;
    gboolean ok = TRUE;

    args->siblings = g_array_new(FALSE, FALSE, sizeof(SiblingResult));
    gather_options(args, &options);
    for (i = 0; ok && ids[i] >= 0; i++) {
        ok = (progress_stage(args, _("Compensating the other channels..."))
              && compensate_sibling(args, ids[i], &options, error));
    }
    g_free(ids);
    if (!ok)
        return FALSE;
    main_mask.mask = args->mask;
    main_mask.has_mask = args->result_has_mask;
    if (!compensate_own_mask(args, args->id, &options, &main_mask, error))
        return FALSE;
    args->result_has_mask = main_mask.has_mask;
    return TRUE;
}

static void
siblings_clear(ModuleArgs *args)
{
    SiblingResult *sibling;
    guint i;

    for (i = 0; args->siblings && i < args->siblings->len; i++) {
        sibling = &g_array_index(args->siblings, SiblingResult, i);
        g_object_unref(sibling->result);
        g_object_unref(sibling->mask);
    }
    if (args->siblings)
        g_array_free(args->siblings, TRUE);
    args->siblings = NULL;
}

/* The two curves, dx and dy over the stripes' y positions, in the image's
 * lateral unit. */
static GwyGraphModel*
new_drift_graph_model(GwyDataField *field)
{
    static const gchar *names[2] = { "dx", "dy" };
    GwySIUnit *unit = gwy_data_field_get_si_unit_xy(field);
    GwyGraphCurveModel *gcmodel;
    GwyGraphModel *gmodel;
    gint i;

    gmodel = gwy_graph_model_new();
    g_object_set(gmodel,
                 "axis-label-bottom", "y",
                 "axis-label-left", _("drift"),
                 "si-unit-x", unit,
                 "si-unit-y", unit,
                 NULL);
    for (i = 0; i < 2; i++) {
        gcmodel = gwy_graph_curve_model_new();
        g_object_set(gcmodel,
                     "description", names[i],
                     "mode", GWY_GRAPH_CURVE_LINE_POINTS,
                     "color", gwy_graph_get_preset_color(i),
                     NULL);
        gwy_graph_model_add_curve(gmodel, gcmodel);
        g_object_unref(gcmodel);
    }
    return gmodel;
}

static void
set_drift_curves(GwyGraphModel *gmodel, const gdouble *ypos, const gdouble *dx, const gdouble *dy,
                 gint n)
{
    gwy_graph_curve_model_set_data(gwy_graph_model_get_curve(gmodel, 0), ypos, dx, n);
    gwy_graph_curve_model_set_data(gwy_graph_model_get_curve(gmodel, 1), ypos, dy, n);
}

static void
add_drift_graph(ModuleArgs *args)
{
    GwyAppDataId target = GWY_APP_DATA_ID_NONE;
    gint n = args->applied.n_stripes;
    GwyGraphModel *gmodel = new_drift_graph_model(args->field);
    gdouble *ypos = g_new(gdouble, 3*n), *dx = ypos + n, *dy = dx + n;
    gchar *title, *gtitle;

    localscan_applied_to_physical(&args->applied, args->field, ypos, dx, dy);
    set_drift_curves(gmodel, ypos, dx, dy, n);
    title = gwy_app_get_data_field_title(args->data, args->id);
    gtitle = g_strdup_printf(_("Local-scan drift of %s"), title);
    g_object_set(gmodel, "title", gtitle, NULL);
    g_free(gtitle);
    g_free(title);
    gwy_app_add_graph_or_curves(gmodel, args->data, &target, 1);
    g_object_unref(gmodel);
    g_free(ypos);
}

/* Without a GUI (batch, pygwy, the command-line tool) the error goes with
 * the data to the caller (localscan_run_error_take()) and is the one line
 * on stderr a script shows; with a GUI, a message box. */
static void
report_error(ModuleArgs *args, const GError *error)
{
    GtkWidget *main_window = gwy_app_main_window_get(), *dialog;
    GtkWindow *parent;

    if (!main_window) {
        localscan_run_error_set(args->data, error);
        g_printerr("%s: %s\n", LOCALSCAN_FUNCTION_NAME, error->message);
        return;
    }
    parent = gwy_app_find_window_for_channel(args->data, args->id);
    dialog = gtk_message_dialog_new(parent ? parent : GTK_WINDOW(main_window),
                                    GTK_DIALOG_DESTROY_WITH_PARENT, GTK_MESSAGE_ERROR,
                                    GTK_BUTTONS_OK,
                                    "%s", _("Local-scan drift compensation failed."));
    gtk_message_dialog_format_secondary_text(GTK_MESSAGE_DIALOG(dialog), "%s", error->message);
    gtk_dialog_run(GTK_DIALOG(dialog));
    gtk_widget_destroy(dialog);
}

/* The tooltip of every setting, keyed by the labels of
 * define_module_params(). */
static const DialogTooltip localscan_tooltips[] = {
    { N_("Table stored with the image"),
      N_("The drift table in the channel's metadata (item 'Local-scan drift table'), as "
         "simscan and the local-scan measurement store it") },
    { N_("Table file (CSV)"),
      N_("A drift table file: stripe,dx,dy per row, in px, nm, um or m") },
    { N_("Registration to a reference"),
      N_("Measure the drift of every stripe by registering it against another scan of "
         "the same area, made without (or with other) drift") },
    { N_("Table file"), N_("The CSV drift table to apply") },
    { N_("Stripes"),
      N_("How many stripes along the slow axis are registered against the reference") },
    { N_("Masks in registration"),
      N_("What the image's and the reference's masks mean to the registration: Exclude "
         "leaves masked pixels out (Gwyddion's importers mask the pixels a file lacks), "
         "Include uses only masked pixels, Ignore uses every pixel") },
    { N_("Paper (whole-pixel stripes)"),
      N_("Shift every stripe by whole pixels, exactly as the paper does") },
    { N_("Continuous (line by line)"),
      N_("Move every scan line back by the drift at its own scan time, from a drift "
         "trajectory through the stripe measurements") },
    { N_("Interpolation"),
      N_("How continuous mode resamples: Round (nearest pixel, the default) keeps "
         "heights exactly; the sub-pixel kernels place features more exactly but "
         "change the peaks of small particles (see docs/heights.md)") },
    { N_("Slow scan direction"),
      N_("Whether the image was scanned top to bottom or bottom to top; used only when "
         "the metadata does not say") },
    { N_("Line time"),
      N_("Seconds per scan line, trace and retrace; used only when the metadata does "
         "not say") },
    { N_("Frame start"),
      N_("When the frame started, in the clock of the table's t_image and t_local "
         "columns; used only when the metadata does not say") },
    { N_("Fill value"),
      N_("The value of pixels that no stripe covers after the shift (the paper uses "
         "the image mean)") },
    { N_("Mask filled pixels"),
      N_("Add a mask over the filled pixels to the new channel") },
    { N_("Plot drift graph"),
      N_("Add a graph of the drift of every stripe (dx and dy against the stripe's "
         "position) to the file") },
    { N_("Mask color"), N_("The colour of the mask in the preview and the new channel") },
    { N_("All channels of the scan"),
      N_("Apply the same correction, from this channel's drift, to every other channel "
         "of the same scan (Height, Amplitude, Phase...; same pixels and physical size, "
         "same file, same scan time) and to their masks") },
};


static GwyDialogOutcome
run_gui(ModuleArgs *args)
{
    GwyDialogOutcome outcome;
    GwyParamTable *table;
    GtkWidget *hbox, *vbox, *alignment, *dataview;
    GwyDialog *dialog;
    ModuleGUI gui;

    gwy_clear(&gui, 1);
    gui.args = args;
    gui.data = gwy_container_new();
    gui.preview = preview_field_new(args->field, PREVIEW_FIELD_SIZE);
    if (!preview_field_is_reduced(gui.preview)) {
        /* Previewed exactly: the preview shows the result itself. */
        preview_field_free(gui.preview);
        gui.preview = preview_field_new_with_result(args->field, args->result, args->mask);
    }
    gwy_container_set_object_by_name(gui.data, "/0/data", preview_field_result(gui.preview));
    gwy_container_set_object_by_name(gui.data, "/0/mask", preview_field_mask(gui.preview));
    gwy_app_sync_data_items(args->data, gui.data, args->id, 0, FALSE,
                            GWY_DATA_ITEM_GRADIENT,
                            GWY_DATA_ITEM_RANGE_TYPE,
                            GWY_DATA_ITEM_REAL_SQUARE,
                            0);

    gui.timing_in_meta = localscan_channel_scan_timing(args->data, args->id, SCAN_DIRECTION_DOWN,
                                                       &args->timing);
    gui.dialog = gwy_dialog_new(_("Local Scan Drift"));
    dialog = GWY_DIALOG(gui.dialog);
    gwy_dialog_add_buttons(dialog, GWY_RESPONSE_RESET, GTK_RESPONSE_CANCEL, GTK_RESPONSE_OK, 0);

    /* The usual preview box, with the drift graph under the preview. */
    hbox = gwy_hbox_new(8);
    gtk_container_set_border_width(GTK_CONTAINER(hbox), 4);
    gwy_dialog_add_content(dialog, hbox, FALSE, FALSE, 0);
    vbox = gwy_vbox_new(4);
    gtk_box_pack_start(GTK_BOX(hbox), vbox, FALSE, FALSE, 0);
    dataview = gwy_create_preview(gui.data, 0, PREVIEW_SIZE, TRUE);
    alignment = gtk_alignment_new(0.0, 0.0, 0.0, 0.0);
    gtk_widget_set_size_request(alignment, PREVIEW_SIZE, -1);
    gtk_container_add(GTK_CONTAINER(alignment), dataview);
    gtk_box_pack_start(GTK_BOX(vbox), alignment, FALSE, FALSE, 0);
    gtk_box_pack_start(GTK_BOX(vbox), create_drift_graph(&gui), TRUE, TRUE, 0);
    /* What the drift source says about itself (registration: stripes
     * measured, their scores, warnings) belongs here, beside the preview
     * and the graph of the same drift. */
    gui.preview_status = gtk_label_new(NULL);
    gtk_misc_set_alignment(GTK_MISC(gui.preview_status), 0.0, 0.5);
    gtk_label_set_line_wrap(GTK_LABEL(gui.preview_status), TRUE);
    gtk_widget_set_no_show_all(gui.preview_status, TRUE);
    gtk_box_pack_start(GTK_BOX(vbox), gui.preview_status, FALSE, FALSE, 0);
    gtk_box_pack_start(GTK_BOX(vbox), create_export_button(&gui), FALSE, FALSE, 0);

    table = gui.table = gwy_param_table_new(args->params);
    gwy_param_table_append_header(table, -1, _("Drift"));
    gwy_param_table_append_radio(table, PARAM_SOURCE);
    gwy_param_table_append_foreign(table, WIDGET_TABLE_FILE, create_file_chooser, &gui, NULL);
    gwy_param_table_append_foreign(table, WIDGET_REFERENCE, create_reference_chooser, &gui, NULL);
    gwy_param_table_append_slider(table, PARAM_STRIPES);
    /* A stripe needs two rows to be registered (localscan_reference_check). */
    gwy_param_table_slider_restrict_range(table, PARAM_STRIPES, LOCALSCAN_STRIPES_MIN,
                                          MAX(LOCALSCAN_STRIPES_MIN,
                                              MIN(LOCALSCAN_STRIPES_MAX,
                                                  gwy_data_field_get_yres(args->field)/2)));
    gwy_param_table_append_combo(table, PARAM_MASKING);
    gwy_param_table_append_header(table, -1, _("Compensation"));
    gwy_param_table_append_radio(table, PARAM_MODE);
    gwy_param_table_append_combo(table, PARAM_INTERPOLATION);
    gwy_param_table_append_combo(table, PARAM_DIRECTION);
    gwy_param_table_append_entry(table, PARAM_LINE_TIME);
    gwy_param_table_set_unitstr(table, PARAM_LINE_TIME, "s");
    gwy_param_table_append_entry(table, PARAM_FRAME_START);
    gwy_param_table_set_unitstr(table, PARAM_FRAME_START, "s");
    gwy_param_table_append_combo(table, PARAM_FILL);
    gwy_param_table_append_header(table, -1, _("Output"));
    gwy_param_table_append_checkbox(table, PARAM_ADD_MASK);
    gwy_param_table_append_mask_color(table, PARAM_MASK_COLOR, gui.data, 0, args->data, args->id);
    gwy_param_table_append_checkbox(table, PARAM_PLOT_DRIFT);
    gwy_param_table_append_checkbox(table, PARAM_ALL_CHANNELS);
    gwy_param_table_append_message(table, MESSAGE_STATUS, NULL);

    dialog_tooltips_add(gwy_param_table_widget(table), localscan_tooltips,
                        G_N_ELEMENTS(localscan_tooltips));
    gtk_box_pack_start(GTK_BOX(hbox), gwy_param_table_widget(table), TRUE, TRUE, 0);
    gwy_dialog_add_param_table(dialog, table);

    g_signal_connect_swapped(table, "param-changed", G_CALLBACK(param_changed), &gui);
    gwy_dialog_set_preview_func(dialog, GWY_PREVIEW_IMMEDIATE, preview, &gui, NULL);

    outcome = gwy_dialog_run(dialog);
    if (gui.stripes_settle_id)
        g_source_remove(gui.stripes_settle_id);
    g_object_unref(gui.drift_gmodel);
    g_object_unref(gui.data);
    preview_field_free(gui.preview);
    preview_field_free(gui.preview_reference);
    measured_drift_clear(&gui.preview_measured);
    localscan_applied_clear(&gui.preview_applied);

    return outcome;
}

/* The drift each stripe of the table states (measured, for a reference),
 * in the lateral unit; stripes without a drift have no point. */
/* The drift each stripe of the table states (measured, for a reference),
 * in the lateral unit; stripes without a drift have no point. */
static GtkWidget*
create_drift_graph(ModuleGUI *gui)
{
    GtkWidget *graph;

    gui->drift_gmodel = new_drift_graph_model(gui->args->field);
    graph = gwy_graph_new(gui->drift_gmodel);
    gwy_graph_enable_user_input(GWY_GRAPH(graph), FALSE);
    gtk_widget_set_size_request(graph, PREVIEW_SIZE, DRIFT_GRAPH_HEIGHT);
    return graph;
}

/* Fills ypos, dx, dy (physical) with the stated drift; returns the count. */
static gint
stated_drift(ModuleArgs *args, gdouble *ypos, gdouble *dx, gdouble *dy)
{
    GwyDataField *field = args->field;
    gint n = args->table->n_stripes, count, k;
    gint *stripes = g_new(gint, n);

    count = localscan_table_stated_px(args->table, field, stripes, dx, dy, NULL);
    for (k = 0; k < count; k++) {
        ypos[k] = localscan_stripe_centre_y(field, stripes[k], n);
        dx[k] *= gwy_data_field_get_dx(field);
        dy[k] *= gwy_data_field_get_dy(field);
    }
    g_free(stripes);
    return MAX(count, 0);
}

static void
update_drift_graph(ModuleGUI *gui, gboolean ok)
{
    ModuleArgs *args = gui->args;
    gint n = ok ? args->table->n_stripes : 0, count = 0;
    gdouble *ypos = g_new(gdouble, 3*MAX(n, 1)), *dx = ypos + n, *dy = dx + n;

    if (ok)
        count = stated_drift(args, ypos, dx, dy);
    set_drift_curves(gui->drift_gmodel, ypos, dx, dy, count);
    g_free(ypos);
}

/* The table the result will be made with (of the whole image, even when
 * the preview is of a reduced copy), to a CSV file of the user's choice. */
static void
export_drift_table(ModuleGUI *gui)
{
    ModuleArgs *args = gui->args;
    GtkWidget *chooser;
    GError *error = NULL;
    DriftTable *table;
    gchar *filename = NULL;

    chooser = gtk_file_chooser_dialog_new(_("Export Drift Table"), GTK_WINDOW(gui->dialog),
                                          GTK_FILE_CHOOSER_ACTION_SAVE,
                                          GTK_STOCK_CANCEL, GTK_RESPONSE_CANCEL,
                                          GTK_STOCK_SAVE, GTK_RESPONSE_ACCEPT,
                                          NULL);
    gtk_file_chooser_set_do_overwrite_confirmation(GTK_FILE_CHOOSER(chooser), TRUE);
    gtk_file_chooser_set_current_name(GTK_FILE_CHOOSER(chooser), "drift.csv");
    if (gtk_dialog_run(GTK_DIALOG(chooser)) == GTK_RESPONSE_ACCEPT)
        filename = gtk_file_chooser_get_filename(GTK_FILE_CHOOSER(chooser));
    gtk_widget_destroy(chooser);
    if (!filename)
        return;
    gwy_app_wait_cursor_start(GTK_WINDOW(gui->dialog));
    table = load_drift_table(args, &error);
    gwy_app_wait_cursor_finish(GTK_WINDOW(gui->dialog));
    if (!table || !drift_table_save(table, filename, &error)) {
        gwy_param_table_message_set_type(gui->table, MESSAGE_STATUS, GTK_MESSAGE_ERROR);
        gwy_param_table_set_label(gui->table, MESSAGE_STATUS, error->message);
        g_clear_error(&error);
    }
    if (table)
        drift_table_free(table);
    g_free(filename);
}

static GtkWidget*
create_export_button(ModuleGUI *gui)
{
    GtkWidget *hbox = gtk_hbox_new(FALSE, 6);

    gui->export_button = gtk_button_new_with_mnemonic(_("_Export Drift Table..."));
    gtk_widget_set_tooltip_text(gui->export_button,
                                _("Save the drift table the result is made with (stripe,dx,dy "
                                  "and the measurement's extra columns) as CSV"));
    g_signal_connect_swapped(gui->export_button, "clicked", G_CALLBACK(export_drift_table), gui);
    gtk_box_pack_end(GTK_BOX(hbox), gui->export_button, FALSE, FALSE, 0);
    return hbox;
}

static GtkWidget*
create_file_chooser(gpointer user_data)
{
    ModuleGUI *gui = (ModuleGUI*)user_data;
    const gchar *filename = gwy_params_get_string(gui->args->params, PARAM_TABLE_FILE);
    GtkFileFilter *filter;
    GtkWidget *hbox, *label;

    hbox = gtk_hbox_new(FALSE, 6);
    label = gtk_label_new_with_mnemonic(_("Table _file:"));
    gtk_box_pack_start(GTK_BOX(hbox), label, FALSE, FALSE, 0);

    gui->file_button = gtk_file_chooser_button_new(_("Drift Table"), GTK_FILE_CHOOSER_ACTION_OPEN);
    gtk_label_set_mnemonic_widget(GTK_LABEL(label), gui->file_button);
    filter = gtk_file_filter_new();
    gtk_file_filter_set_name(filter, _("Drift tables (*.csv)"));
    gtk_file_filter_add_pattern(filter, "*.csv");
    gtk_file_filter_add_pattern(filter, "*.CSV");
    gtk_file_chooser_add_filter(GTK_FILE_CHOOSER(gui->file_button), filter);
    filter = gtk_file_filter_new();
    gtk_file_filter_set_name(filter, _("All files"));
    gtk_file_filter_add_pattern(filter, "*");
    gtk_file_chooser_add_filter(GTK_FILE_CHOOSER(gui->file_button), filter);
    if (filename && *filename)
        gtk_file_chooser_set_filename(GTK_FILE_CHOOSER(gui->file_button), filename);
    gtk_box_pack_start(GTK_BOX(hbox), gui->file_button, TRUE, TRUE, 0);
    g_signal_connect_swapped(gui->file_button, "file-set", G_CALLBACK(table_file_chosen), gui);

    return hbox;
}

static void
table_file_chosen(ModuleGUI *gui)
{
    gchar *filename = gtk_file_chooser_get_filename(GTK_FILE_CHOOSER(gui->file_button));

    gwy_params_set_string(gui->args->params, PARAM_TABLE_FILE, filename ? filename : "");
    g_free(filename);
    gwy_param_table_param_changed(gui->table, PARAM_TABLE_FILE);
}

/* Registration compares the image with another scan of the same area, so
 * only images of the same pixel and physical size qualify, never the image
 * itself. */
static gboolean
reference_filter(GwyContainer *data, gint id, gpointer user_data)
{
    ModuleArgs *args = (ModuleArgs*)user_data;

    return reference_choice_rank(args->data, args->id, data, id) != REFERENCE_RANK_UNFIT;
}

static void
add_reference_candidates(GwyContainer *data, gpointer user_data)
{
    ModuleGUI *gui = (ModuleGUI*)user_data;
    ModuleArgs *args = gui->args;
    gint *ids = gwy_app_data_browser_get_data_ids(data);
    gint datano = gwy_app_data_browser_get_number(data), i;
    ReferenceRank rank;
    gchar *label, *shown;

    for (i = 0; ids[i] >= 0; i++) {
        if (!(rank = reference_choice_rank(args->data, args->id, data, ids[i])))
            continue;
        label = reference_label(data, ids[i]);
        /* A sibling shares the image's drift and registers to zero. */
        shown = (rank == REFERENCE_RANK_SIBLING
                 ? g_strdup_printf(_("%s (same scan)"), label) : g_strdup(label));
        gtk_list_store_insert_with_values(gui->references, NULL, G_MAXINT,
                                          LOCALSCAN_REFERENCE_COLUMN_LABEL, shown,
                                          LOCALSCAN_REFERENCE_COLUMN_DATANO, datano,
                                          LOCALSCAN_REFERENCE_COLUMN_ID, ids[i],
                                          LOCALSCAN_REFERENCE_COLUMN_RANK, rank,
                                          -1);
        g_free(shown);
        g_free(label);
    }
    g_free(ids);
}

/* The remembered reference if it is as good as the best offered, else the
 * best (the first of the highest rank); -1 when nothing is offered. */
static gint
preferred_reference(ModuleGUI *gui)
{
    GtkTreeModel *model = GTK_TREE_MODEL(gui->references);
    GwyAppDataId remembered = gwy_params_get_data_id(gui->args->params, PARAM_REFERENCE);
    gint best = -1, best_rank = 0, kept = -1, kept_rank = 0, n = 0, datano, id, rank;
    GtkTreeIter iter;
    gboolean more;

    for (more = gtk_tree_model_get_iter_first(model, &iter); more;
         more = gtk_tree_model_iter_next(model, &iter), n++) {
        gtk_tree_model_get(model, &iter, LOCALSCAN_REFERENCE_COLUMN_DATANO, &datano,
                           LOCALSCAN_REFERENCE_COLUMN_ID, &id, LOCALSCAN_REFERENCE_COLUMN_RANK, &rank, -1);
        if (rank > best_rank) {
            best = n;
            best_rank = rank;
        }
        if (datano == remembered.datano && id == remembered.id) {
            kept = n;
            kept_rank = rank;
        }
    }
    return (kept >= 0 && kept_rank == best_rank) ? kept : best;
}

static void
set_reference_from_chooser(ModuleGUI *gui)
{
    GwyAppDataId refid = GWY_APP_DATA_ID_NONE;
    GtkTreeIter iter;

    if (gtk_combo_box_get_active_iter(GTK_COMBO_BOX(gui->reference_combo), &iter)) {
        gtk_tree_model_get(GTK_TREE_MODEL(gui->references), &iter,
                           LOCALSCAN_REFERENCE_COLUMN_DATANO, &refid.datano,
                           LOCALSCAN_REFERENCE_COLUMN_ID, &refid.id, -1);
    }
    gwy_params_set_image_id(gui->args->params, PARAM_REFERENCE, refid);
}

static void
reference_chosen(ModuleGUI *gui)
{
    set_reference_from_chooser(gui);
    gwy_param_table_param_changed(gui->table, PARAM_REFERENCE);
}

/* Gwyddion's image chooser names channels without their files and offers
 * the image's own siblings first; this one names "file — channel", offers
 * only compatible channels and preselects a scan made at another time. */
static GtkWidget*
create_reference_chooser(gpointer user_data)
{
    ModuleGUI *gui = (ModuleGUI*)user_data;
    GtkCellRenderer *renderer;
    GtkWidget *hbox, *label;

    gui->references = gtk_list_store_new(LOCALSCAN_REFERENCE_NCOLUMNS,
                                         G_TYPE_STRING, G_TYPE_INT, G_TYPE_INT, G_TYPE_INT);
    gwy_app_data_browser_foreach(add_reference_candidates, gui);

    hbox = gtk_hbox_new(FALSE, 6);
    label = gtk_label_new_with_mnemonic(_("_Reference:"));
    gtk_box_pack_start(GTK_BOX(hbox), label, FALSE, FALSE, 0);
    gui->reference_combo = gtk_combo_box_new_with_model(GTK_TREE_MODEL(gui->references));
    gtk_widget_set_name(gui->reference_combo, LOCALSCAN_REFERENCE_WIDGET_NAME);
    g_object_unref(gui->references);
    renderer = gtk_cell_renderer_text_new();
    g_object_set(renderer, "ellipsize", PANGO_ELLIPSIZE_MIDDLE, "width-chars", 28, NULL);
    gtk_cell_layout_pack_start(GTK_CELL_LAYOUT(gui->reference_combo), renderer, TRUE);
    gtk_cell_layout_add_attribute(GTK_CELL_LAYOUT(gui->reference_combo), renderer,
                                  "text", LOCALSCAN_REFERENCE_COLUMN_LABEL);
    gtk_label_set_mnemonic_widget(GTK_LABEL(label), gui->reference_combo);
    gtk_widget_set_tooltip_text(gui->reference_combo,
                                _("Another scan of the same area (same pixels and physical "
                                  "size) against which every stripe is registered; scans made "
                                  "at another time are listed first-choice, channels of the "
                                  "same scan share its drift"));
    gtk_combo_box_set_active(GTK_COMBO_BOX(gui->reference_combo), preferred_reference(gui));
    set_reference_from_chooser(gui);
    g_signal_connect_swapped(gui->reference_combo, "changed", G_CALLBACK(reference_chosen), gui);
    gtk_box_pack_start(GTK_BOX(hbox), gui->reference_combo, TRUE, TRUE, 0);
    return hbox;
}

static void
param_changed(ModuleGUI *gui, gint id)
{
    GwyParams *params = gui->args->params;
    GwyParamTable *table = gui->table;
    LocalscanSource source = gwy_params_get_enum(params, PARAM_SOURCE);
    LocalscanMode mode = gwy_params_get_enum(params, PARAM_MODE);

    if (id < 0 || id == PARAM_SOURCE) {
        gwy_param_table_set_sensitive(table, WIDGET_TABLE_FILE, source == LOCALSCAN_SOURCE_FILE);
        gwy_param_table_set_sensitive(table, WIDGET_REFERENCE, source == LOCALSCAN_SOURCE_REFERENCE);
        gwy_param_table_set_sensitive(table, PARAM_STRIPES, source == LOCALSCAN_SOURCE_REFERENCE);
        gwy_param_table_set_sensitive(table, PARAM_MASKING, source == LOCALSCAN_SOURCE_REFERENCE);
    }
    if (id < 0 || id == PARAM_MODE) {
        gwy_param_table_set_sensitive(table, PARAM_INTERPOLATION,
                                      mode == LOCALSCAN_MODE_CONTINUOUS);
        /* The settings stand in only for what the metadata does not say. */
        gwy_param_table_set_sensitive(table, PARAM_DIRECTION,
                                      mode == LOCALSCAN_MODE_CONTINUOUS
                                      && !(gui->timing_in_meta & LOCALSCAN_TIMING_DIRECTION));
        gwy_param_table_set_sensitive(table, PARAM_LINE_TIME,
                                      mode == LOCALSCAN_MODE_CONTINUOUS
                                      && !(gui->timing_in_meta & LOCALSCAN_TIMING_LINE_TIME));
        gwy_param_table_set_sensitive(table, PARAM_FRAME_START,
                                      mode == LOCALSCAN_MODE_CONTINUOUS
                                      && !(gui->timing_in_meta & LOCALSCAN_TIMING_FRAME_START));
    }
    if (id == PARAM_ADD_MASK || id == PARAM_PLOT_DRIFT || id == PARAM_MASK_COLOR)
        return;
    if (gui->stripes_settle_id)
        g_source_remove(gui->stripes_settle_id);
    gui->stripes_settle_id = 0;
    /* Registration takes about a second on a large image: a dragged stripe
     * count is measured once it rests, not at every value it passes. */
    if (id == PARAM_STRIPES)
        gui->stripes_settle_id = g_timeout_add(STRIPES_SETTLE_MS, stripes_settled, gui);
    else
        gwy_dialog_invalidate(GWY_DIALOG(gui->dialog));
}

static gboolean
stripes_settled(gpointer user_data)
{
    ModuleGUI *gui = (ModuleGUI*)user_data;

    gui->stripes_settle_id = 0;
    gwy_dialog_invalidate(GWY_DIALOG(gui->dialog));
    return G_SOURCE_REMOVE;
}

/* What registration found: stripes accepted and the range of their drift. */
static void
append_registration(GString *status, ModuleArgs *args)
{
    const DriftTable *table = args->table;
    gint n = table->n_stripes, count, k;
    gint *stripes = g_new(gint, n);
    gdouble *dx = g_new(gdouble, 2*n), *dy = dx + n;
    gdouble xmin = G_MAXDOUBLE, xmax = -G_MAXDOUBLE, ymin = G_MAXDOUBLE, ymax = -G_MAXDOUBLE;

    count = localscan_table_stated_px(table, args->field, stripes, dx, dy, NULL);
    for (k = 0; k < count; k++) {
        xmin = fmin(xmin, dx[k]);
        xmax = fmax(xmax, dx[k]);
        ymin = fmin(ymin, dy[k]);
        ymax = fmax(ymax, dy[k]);
    }
    g_string_append_printf(status, _("Registered %d of %d stripes,"), count, n);
    g_string_append_c(status, '\n');
    g_string_append_printf(status, _("dx %.2f to %.2f px, dy %.2f to %.2f px."),
                           xmin, xmax, ymin, ymax);
    g_string_append_c(status, '\n');
    g_string_append_printf(status, _("%d filled pixels."), args->applied.n_filled);
    g_free(stripes);
    g_free(dx);
}

/* Where each part of the scan timing came from, in three short lines. */
static void
append_timing(GString *status, const ScanTiming *timing, LocalscanTimingFound found)
{
    const gchar *from_meta = _("metadata"), *setting = _("setting");

    g_string_append_printf(status, _("Line time %g s (%s),"), timing->line_time,
                           (found & LOCALSCAN_TIMING_LINE_TIME) ? from_meta : setting);
    g_string_append_c(status, '\n');
    g_string_append_printf(status,
                           (timing->direction == SCAN_DIRECTION_UP
                            ? _("slow scan up (%s),") : _("slow scan down (%s),")),
                           (found & LOCALSCAN_TIMING_DIRECTION) ? from_meta : setting);
    g_string_append_c(status, '\n');
    g_string_append_printf(status, _("frame start %g s (%s)."), timing->frame_start,
                           (found & LOCALSCAN_TIMING_FRAME_START) ? from_meta : setting);
}

/* Local scans the line-by-line trajectory leaves out as gross errors
 * (localscan_continuous_left_out), named by stripe: the result does not
 * follow them, as the command line says too.  At most LEFT_OUT_LISTED are
 * listed (the line must not widen the dialog); a registration of a
 * reduced preview is not judged (its scatter, scaled to the image, is not
 * the full registration's). */
#define LEFT_OUT_LISTED 4

static void
append_left_out(GString *status, ModuleGUI *gui)
{
    ModuleArgs *args = gui->args;
    LocalscanOptions options;
    GString *list;
    gint *stripes, n, i;

    if (!args->table
        || (preview_field_is_reduced(gui->preview)
            && gwy_params_get_enum(args->params, PARAM_SOURCE) == LOCALSCAN_SOURCE_REFERENCE))
        return;
    stripes = g_new(gint, MAX(args->table->n_stripes, 1));
    gather_options(args, &options);
    n = localscan_continuous_left_out(args->field, args->table, &options, stripes, NULL, NULL);
    if (n > 0) {
        list = g_string_new(NULL);
        for (i = 0; i < MIN(n, LEFT_OUT_LISTED); i++)
            g_string_append_printf(list, i ? ", %d" : "%d", stripes[i]);
        if (n > LEFT_OUT_LISTED)
            g_string_append(list, ", ...");
        g_string_append_c(status, '\n');
        g_string_append_printf(status,
                               dngettext(GETTEXT_PACKAGE,
                                         "Stripe %s lies far from the others' drift: left out.",
                                         "Stripes %s lie far from the others' drift: left out.", n),
                               list->str);
        g_string_free(list, TRUE);
    }
    g_free(stripes);
}

/* Short lines: the message must not widen the dialog.  A reduced preview
 * says so; its filled pixels are counted on it and scaled to the image. */
static gchar*
format_status(ModuleGUI *gui)
{
    ModuleArgs *args = gui->args;
    GString *status = g_string_new(NULL);

    if (preview_field_is_reduced(gui->preview)) {
        g_string_append_printf(status, _("Preview of a %d x %d copy (the result is computed "
                                         "in full):"),
                               preview_field_xres(gui->preview), preview_field_yres(gui->preview));
        g_string_append_c(status, '\n');
    }

    if (gwy_params_get_enum(args->params, PARAM_SOURCE) == LOCALSCAN_SOURCE_REFERENCE)
        append_registration(status, args);
    else {
        g_string_append_printf(status, _("%d stripes, %d filled pixels."),
                               args->applied.n_stripes, args->applied.n_filled);
    }
    if (gwy_params_get_enum(args->params, PARAM_MODE) != LOCALSCAN_MODE_CONTINUOUS)
        return g_string_free(status, FALSE);
    g_string_append_c(status, '\n');
    append_timing(status, &args->timing, args->timing_found);
    append_left_out(status, gui);
    return g_string_free(status, FALSE);
}

/* The drift for a reduced preview: a table of the image (stored, file), or
 * measured by registering the reduced copy against a reduced copy of the
 * reference, in the copy's pixels; the registration is cached like the
 * full one. */
static DriftTable*
preview_drift_table(ModuleGUI *gui, gboolean *in_preview_px, GError **error)
{
    ModuleArgs *args = gui->args;
    gint n = gwy_params_get_int(args->params, PARAM_STRIPES);
    const DriftTable *measured;
    GwyDataField *reference, *image_mask = NULL, *reference_mask = NULL;
    GwyMaskingType masking;
    GwyAppDataId refid;

    *in_preview_px = FALSE;
    if (gwy_params_get_enum(args->params, PARAM_SOURCE) != LOCALSCAN_SOURCE_REFERENCE)
        return load_drift_table(args, error);
    if (!(reference = find_reference(args, &refid, error)))
        return NULL;
    /* Stripes of one row of the copy cannot be registered: only the image
     * can tell. */
    if (n > preview_field_yres(gui->preview)/2)
        return load_drift_table(args, error);
    if (!gui->preview_reference || gui->preview_reference_id.datano != refid.datano
        || gui->preview_reference_id.id != refid.id) {
        preview_field_free(gui->preview_reference);
        gui->preview_reference = preview_field_new(reference, PREVIEW_FIELD_SIZE);
        gui->preview_reference_id = refid;
    }
    /* The masks are reduced with the copies only for a new registration
     * (a 4096 x 4096 mask takes longer than the rest of a refresh). */
    masking = gwy_params_get_enum(args->params, PARAM_MASKING);
    if (!measured_drift_current(&gui->preview_measured, refid, n, masking)) {
        image_mask = preview_field_reduce_mask(gui->preview, channel_mask(args->data, args->id));
        reference_mask = preview_field_reduce_mask(gui->preview_reference,
                                                   channel_mask(gwy_app_data_browser_get(refid.datano),
                                                                refid.id));
    }
    measured = measure_drift(&gui->preview_measured, preview_field_source(gui->preview), image_mask,
                             preview_field_source(gui->preview_reference), reference_mask, refid, n,
                             masking, error);
    g_clear_object(&image_mask);
    g_clear_object(&reference_mask);
    if (!measured)
        return NULL;
    *in_preview_px = TRUE;
    if (gwy_params_get_enum(args->params, PARAM_MODE) == LOCALSCAN_MODE_PAPER)
        return localscan_table_round_px(measured);
    return drift_table_copy(measured);
}

/* A change of a setting on a large image: the reduced copy is compensated;
 * args->table and args->applied describe it in the image's pixels, for the
 * status and the drift graph. */
static gboolean
execute_preview(ModuleGUI *gui, GError **error)
{
    ModuleArgs *args = gui->args;
    gdouble image_pixels, preview_pixels;
    LocalscanOptions options;
    gboolean in_preview_px, ok;
    DriftTable *table;

    if (args->table)
        drift_table_free(args->table);
    args->table = NULL;
    localscan_applied_clear(&args->applied);
    localscan_applied_clear(&gui->preview_applied);
    if (!(table = preview_drift_table(gui, &in_preview_px, error)))
        return FALSE;
    gather_options(args, &options);
    ok = preview_field_compensate(gui->preview, table, in_preview_px, &options,
                                  &gui->preview_applied, error);
    args->table = in_preview_px ? preview_field_table_to_image(gui->preview, table) : table;
    if (in_preview_px)
        drift_table_free(table);
    image_pixels = (gdouble)gwy_data_field_get_xres(args->field)*gwy_data_field_get_yres(args->field);
    preview_pixels = (gdouble)preview_field_xres(gui->preview)*preview_field_yres(gui->preview);
    args->applied.n_stripes = gui->preview_applied.n_stripes;
    args->applied.n_filled = GWY_ROUND(gui->preview_applied.n_filled*image_pixels/preview_pixels);
    return ok;
}

static void
update_registration_status(ModuleGUI *gui, gboolean ok)
{
    ModuleArgs *args = gui->args;
    const MeasuredDrift *measured = (preview_field_is_reduced(gui->preview)
                                     ? &gui->preview_measured : &args->measured);
    gchar *text = NULL;

    if (ok && gwy_params_get_enum(args->params, PARAM_SOURCE) == LOCALSCAN_SOURCE_REFERENCE)
        text = format_registration_status(measured);
    gtk_label_set_text(GTK_LABEL(gui->preview_status), text ? text : "");
    gtk_widget_set_visible(gui->preview_status, text != NULL);
    g_free(text);
}

/* An unusable drift source leaves the source image in the preview, the
 * parser's own message in the dialog and OK insensitive. */
static void
preview(gpointer user_data)
{
    ModuleGUI *gui = (ModuleGUI*)user_data;
    ModuleArgs *args = gui->args;
    GError *error = NULL;
    gboolean ok;
    gchar *text;

    gwy_app_wait_cursor_start(GTK_WINDOW(gui->dialog));
    if (preview_field_is_reduced(gui->preview))
        ok = execute_preview(gui, &error);
    else
        ok = execute(args, &error);
    gwy_app_wait_cursor_finish(GTK_WINDOW(gui->dialog));
    update_drift_graph(gui, ok);
    if (ok) {
        text = format_status(gui);
        gwy_param_table_message_set_type(gui->table, MESSAGE_STATUS, GTK_MESSAGE_INFO);
    }
    else {
        text = g_markup_escape_text(error->message, -1);
        gwy_param_table_message_set_type(gui->table, MESSAGE_STATUS, GTK_MESSAGE_ERROR);
        gwy_data_field_assign(preview_field_result(gui->preview),
                              preview_field_source(gui->preview));
        gwy_data_field_clear(preview_field_mask(gui->preview));
        g_clear_error(&error);
    }
    gwy_param_table_set_label(gui->table, MESSAGE_STATUS, text);
    g_free(text);
    gtk_dialog_set_response_sensitive(GTK_DIALOG(gui->dialog), GTK_RESPONSE_OK, ok);
    gtk_widget_set_sensitive(gui->export_button, ok);
    update_registration_status(gui, ok);
    gwy_data_field_data_changed(preview_field_result(gui->preview));
    gwy_data_field_data_changed(preview_field_mask(gui->preview));
    if (ok)
        gwy_dialog_have_result(GWY_DIALOG(gui->dialog));
}
