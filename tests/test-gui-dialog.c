/*
 *  The localscan_drift dialog as a user meets it, on a real (virtual) X
 *  display: Gwyddion's application environment, the data window open, the
 *  dialog found among the toplevels, photographed to tests/gui-dialog.png,
 *  answered with OK; and the same dialog in German.
 *  Run by tests/test-gui-dialog.sh under xvfb-run.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <check.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <gtk/gtk.h>
#include <libgwyddion/gwyddion.h>
#include <libprocess/gwyprocess.h>
#include <libgwydgets/gwydgets.h>
#include <libgwymodule/gwymodule.h>
#include <app/gwyapp.h>
#include "drift-table.h"
#include "localscan-channel.h"
#include "localscan-params.h"
#include "paper-compensate.h"
#include "test-common.h"
#include "gui-widgets.h"
#include "series-process.h"
#include "frame-series.h"
#include "series-correction.h"

#define SCREENSHOT TEST_BUILDDIR "/tests/gui-dialog.png"
#define SCREENSHOT_DE TEST_BUILDDIR "/tests/gui-dialog-de.png"
#define SCREENSHOT_AGAIN TEST_BUILDDIR "/tests/gui-compensate-again.png"
#define SCREENSHOT_REFERENCE TEST_BUILDDIR "/tests/gui-reference.png"
#define SCREENSHOT_LARGE TEST_BUILDDIR "/tests/gui-large-preview.png"
#define SCREENSHOT_WAIT TEST_BUILDDIR "/tests/gui-cancel-wait.png"
#define SCREENSHOT_SERIES TEST_BUILDDIR "/tests/gui-series-dialog.png"
#define SCREENSHOT_FRAMES TEST_BUILDDIR "/tests/gui-series-frames.png"
#define SCREENSHOT_TOO_FEW TEST_BUILDDIR "/tests/gui-series-too-few.png"
/* A large image: previewed on a reduced copy, made in the wait dialog. */
#define LARGE_RES 2048
#define TEST_LOCALEDIR TEST_BUILDDIR "/tests/locale"
#define TICK_MS 50
#define MAX_TICKS 200
#define XRES 120
#define YRES 90
#define N_STRIPES 9

static guint32 seed;

/* What the timeout saw in the dialog and did with it. */
typedef struct {
    const gchar *ready_text;     /* the preview's status line to wait for */
    const gchar *screenshot;
    gint ticks;
    GtkWidget *dialog;
    gchar *title;
    GString *texts;              /* every visible label, one per line */
    gboolean ready;
    gboolean ok_sensitive;
    gboolean saved;
    gint width, height;
    gint response;
    gboolean keep_reference;     /* keep the reference chooser's model */
    GtkTreeModel *reference_model;
    gchar *reference_active;     /* its preselected label */
    GString *missing_tooltips;   /* when set: settings without a tooltip */
    gint sensitive_entries;      /* text entries the user can type into */
    GString *frame_starts;       /* when set: the series frame chooser's
                                    start column (describe_frame_starts) */
} DialogProbe;

/************************************************************************
 * The application environment
 ************************************************************************/

/* What gwyddion itself does before it opens windows (gwyddion.c): GTK,
 * widget types, styles, i18n, stock items, resources, settings; modules
 * are only ours, from LOCALSCAN_MODULE. */
static void
init_application(void)
{
    const gchar *module = g_getenv("LOCALSCAN_MODULE");
    GError *error = NULL;

    ck_assert_msg(module && *module, "LOCALSCAN_MODULE is not set");
    ck_assert_msg(gtk_init_check(NULL, NULL), "cannot open the X display %s", g_getenv("DISPLAY"));
    gwy_app_init_common(&error, NULL);
    g_clear_error(&error);
    ck_assert_msg(gwy_module_register_module(module, &error),
                  "cannot register %s: %s", module, error ? error->message : "?");
    ck_assert(gwy_process_func_exists(LOCALSCAN_FUNCTION_NAME));
}

static void
set_batch_like_settings(void)
{
    GwyContainer *settings = gwy_app_settings_get();

    gwy_container_set_int32_by_name(settings, LOCALSCAN_SETTINGS_KEY(SOURCE), LOCALSCAN_SOURCE_STORED);
    gwy_container_set_int32_by_name(settings, LOCALSCAN_SETTINGS_KEY(MODE), LOCALSCAN_MODE_PAPER);
    gwy_container_set_int32_by_name(settings, LOCALSCAN_SETTINGS_KEY(FILL), LOCALSCAN_FILL_MEAN);
    gwy_container_set_boolean_by_name(settings, LOCALSCAN_SETTINGS_KEY(ADD_MASK), TRUE);
    gwy_container_set_boolean_by_name(settings, LOCALSCAN_SETTINGS_KEY(PLOT_DRIFT), FALSE);
}

/* A smooth random surface (so the preview shows something recognisable)
 * with a stored table whose shifts grow down the image, like the paper's
 * Figure 6. */
static GwyContainer*
make_data(DriftTable **table)
{
    GRand *rng = g_rand_new_with_seed(seed);
    GwyDataField *field = gwy_data_field_new(XRES, YRES, XRES*2e-9, YRES*2e-9, FALSE);
    GwyContainer *data = gwy_container_new();
    gdouble *d = gwy_data_field_get_data(field);
    gchar *text;
    gint i, s;

    for (i = 0; i < XRES*YRES; i++)
        d[i] = g_rand_double_range(rng, 0.0, 1e-9);
    gwy_data_field_filter_gaussian(field, 3.0);
    gwy_si_unit_set_from_string(gwy_data_field_get_si_unit_xy(field), "m");
    gwy_si_unit_set_from_string(gwy_data_field_get_si_unit_z(field), "m");
    gwy_container_set_object(data, gwy_app_get_data_key_for_id(0), field);
    gwy_container_set_const_string_by_name(data, "/0/data/title", (const guchar*)"Topography");

    *table = drift_table_new(N_STRIPES, DRIFT_UNIT_PX);
    for (s = 0; s < N_STRIPES; s++) {
        (*table)->rows[s].has_drift = (s != 4);
        if (s != 4) {
            (*table)->rows[s].dx = -(s + 1) - g_rand_int_range(rng, 0, 3);
            (*table)->rows[s].dy = -s/3;
        }
    }
    text = drift_table_to_string(*table);
    localscan_channel_store_table_text(data, 0, text);
    g_free(text);
    g_object_unref(field);
    g_rand_free(rng);
    return data;
}

/************************************************************************
 * Looking at the dialog
 ************************************************************************/

static void
collect_texts(GtkWidget *widget, GString *texts)
{
    GList *children, *l;
    const gchar *text;

    if (!gtk_widget_get_visible(widget))
        return;
    if (GTK_IS_LABEL(widget) && (text = gtk_label_get_text(GTK_LABEL(widget))) && *text) {
        g_string_append(texts, text);
        g_string_append_c(texts, '\n');
    }
    if (!GTK_IS_CONTAINER(widget))
        return;
    children = gtk_container_get_children(GTK_CONTAINER(widget));
    for (l = children; l; l = g_list_next(l))
        collect_texts(GTK_WIDGET(l->data), texts);
    g_list_free(children);
}

static void
inspect_reference(GtkWidget *dialog, DialogProbe *probe)
{
    GtkWidget *chooser = gui_find_named_widget(dialog, LOCALSCAN_REFERENCE_WIDGET_NAME);
    GtkTreeIter iter;

    if (!chooser || !GTK_IS_COMBO_BOX(chooser))
        return;
    probe->reference_model = g_object_ref(gtk_combo_box_get_model(GTK_COMBO_BOX(chooser)));
    if (gtk_combo_box_get_active_iter(GTK_COMBO_BOX(chooser), &iter))
        gtk_tree_model_get(probe->reference_model, &iter,
                           LOCALSCAN_REFERENCE_COLUMN_LABEL, &probe->reference_active, -1);
}

static void collect_missing_tooltips(GtkWidget *widget, GString *missing);
static void describe_frame_starts(GtkWidget *dialog, GString *starts);

static gint
count_sensitive_entries(GtkWidget *widget)
{
    GList *children, *l;
    gint n = 0;

    if (!gtk_widget_get_visible(widget))
        return 0;
    if (GTK_IS_ENTRY(widget))
        return gtk_widget_is_sensitive(widget);
    if (!GTK_IS_CONTAINER(widget))
        return 0;
    children = gtk_container_get_children(GTK_CONTAINER(widget));
    for (l = children; l; l = g_list_next(l))
        n += count_sensitive_entries(GTK_WIDGET(l->data));
    g_list_free(children);
    return n;
}

/* Waits until the preview has computed (its status line is up), then
 * records what the dialog shows, photographs it and answers. */
static gboolean
probe_dialog(gpointer user_data)
{
    DialogProbe *probe = (DialogProbe*)user_data;
    GtkWidget *dialog = gui_find_visible_dialog(GTK_TYPE_DIALOG), *ok_button;

    probe->ticks++;
    if (!dialog)
        return probe->ticks < MAX_TICKS;
    g_string_truncate(probe->texts, 0);
    collect_texts(dialog, probe->texts);
    probe->ready = !!strstr(probe->texts->str, probe->ready_text);
    if (!probe->ready && probe->ticks < MAX_TICKS)
        return TRUE;

    probe->dialog = dialog;
    probe->title = g_strdup(gtk_window_get_title(GTK_WINDOW(dialog)));
    ok_button = gtk_dialog_get_widget_for_response(GTK_DIALOG(dialog), GTK_RESPONSE_OK);
    probe->ok_sensitive = ok_button && gtk_widget_is_sensitive(ok_button);
    if (probe->keep_reference)
        inspect_reference(dialog, probe);
    if (probe->missing_tooltips)
        collect_missing_tooltips(dialog, probe->missing_tooltips);
    probe->sensitive_entries = count_sensitive_entries(dialog);
    if (probe->frame_starts)
        describe_frame_starts(dialog, probe->frame_starts);
    probe->saved = probe->screenshot
                   && gui_save_screenshot(dialog, probe->screenshot, &probe->width, &probe->height);
    gtk_dialog_response(GTK_DIALOG(dialog), probe->response);
    return FALSE;
}

/* Runs the dialog of the process function func on channel id. */
static void
run_function_dialog_on(const gchar *func, GwyContainer *data, gint id, DialogProbe *probe)
{
    guint timeout;

    gwy_app_data_browser_select_data_field(data, id);
    probe->texts = g_string_new(NULL);
    timeout = g_timeout_add(TICK_MS, probe_dialog, probe);
    gwy_process_func_run(func, data, GWY_RUN_INTERACTIVE);
    /* The timeout is gone once it answered; a dialog that never came or
     * never got ready leaves it behind. */
    if (!probe->dialog)
        g_source_remove(timeout);
}

static void
run_dialog_on(GwyContainer *data, gint id, DialogProbe *probe)
{
    run_function_dialog_on(LOCALSCAN_FUNCTION_NAME, data, id, probe);
}

/* A probe that waits for ready_text, photographs the dialog to
 * screenshot and answers with response. */
static void
probe_init(DialogProbe *probe, const gchar *ready_text, const gchar *screenshot, gint response)
{
    gwy_clear(probe, 1);
    probe->ready_text = ready_text;
    probe->screenshot = screenshot;
    probe->response = response;
}

/* What the probe collected from every dialog. */
static void
probe_clear(DialogProbe *probe)
{
    g_string_free(probe->texts, TRUE);
    g_free(probe->title);
}

static void
run_dialog(GwyContainer *data, DialogProbe *probe)
{
    gwy_app_data_browser_add(data);
    run_dialog_on(data, 0, probe);
}

static gint
count_filled(const DriftTable *table, GwyDataField *source, gdouble *want, gdouble *want_mask)
{
    gint dx[N_STRIPES], dy[N_STRIPES], s, i, n = 0;
    gdouble *px = g_new(gdouble, N_STRIPES), *py = g_new(gdouble, N_STRIPES);
    const gdouble *a = gwy_data_field_get_data_const(source);

    ck_assert(drift_table_to_pixels(table, YRES, 2e-9, 2e-9, TRUE, px, py, NULL));
    for (s = 0; s < N_STRIPES; s++) {
        dx[s] = (gint)px[s];
        dy[s] = (gint)py[s];
    }
    paper_compensate(a, XRES, YRES, N_STRIPES, dx, dy, paper_image_mean(a, XRES, YRES), want, want_mask);
    for (i = 0; i < XRES*YRES; i++)
        n += (want_mask[i] > 0.0);
    g_free(px);
    g_free(py);
    return n;
}

/************************************************************************
 * Tests (each in its own process: one X connection, one GTK per test)
 ************************************************************************/

START_TEST(test_dialog_ok_makes_channel)
{
    gdouble *want = g_new(gdouble, XRES*YRES), *want_mask = g_new(gdouble, XRES*YRES);
    GwyDataField *source, *result = NULL, *mask = NULL;
    DialogProbe probe;
    DriftTable *table;
    GwyContainer *data;
    const guchar *title = NULL;
    gchar *ready;
    gint n_filled;

    init_application();
    set_batch_like_settings();
    data = make_data(&table);
    source = gwy_container_get_object(data, gwy_app_get_data_key_for_id(0));
    n_filled = count_filled(table, source, want, want_mask);
    ready = g_strdup_printf("%d stripes, %d filled pixels.", N_STRIPES, n_filled);
    probe_init(&probe, ready, SCREENSHOT, GTK_RESPONSE_OK);
    run_dialog(data, &probe);

    ck_assert_msg(probe.dialog, "no dialog appeared in %d ms", MAX_TICKS*TICK_MS);
    ck_assert_msg(probe.ready, "the dialog never showed \"%s\"; it shows:\n%s", ready, probe.texts->str);
    ck_assert_str_eq(probe.title, "Local Scan Drift");
    ck_assert(probe.ok_sensitive);
    ck_assert_msg(probe.saved, "no screenshot");
    printf("test-gui-dialog: screenshot of the dialog (%d x %d) in %s\n", probe.width, probe.height, SCREENSHOT);
    printf("test-gui-dialog: the dialog shows:\n%s", probe.texts->str);

    ck_assert(gwy_container_gis_object_by_name(data, "/1/data", &result));
    ck_assert_msg(!memcmp(gwy_data_field_get_data_const(result), want, XRES*YRES*sizeof(gdouble)),
                  "the channel made by OK differs from paper_compensate() (seed %u)", seed);
    ck_assert(gwy_container_gis_object_by_name(data, "/1/mask", &mask));
    ck_assert(!memcmp(gwy_data_field_get_data_const(mask), want_mask, XRES*YRES*sizeof(gdouble)));
    ck_assert(gwy_container_gis_string_by_name(data, "/1/data/title", &title));
    ck_assert_str_eq((const gchar*)title, "Topography (local-scan compensated)");

    gwy_app_data_browser_remove(data);
    g_object_unref(data);
    drift_table_free(table);
    probe_clear(&probe);
    g_free(ready);
    g_free(want);
    g_free(want_mask);
}
END_TEST

/* A German user: the catalogue built from po/de.po, LANGUAGE=de.  The
 * module binds its domain to LOCALEDIR when it registers; the test points
 * it at the build's catalogue afterwards, as an installed one would be. */
static const gchar *german_texts[] = {
    "Kompensation", "Ausgabe", "Driftquelle", "Mit dem Bild gespeicherte Tabelle",
};
static const gchar *english_texts[] = {
    "Compensation", "Output", "Drift source", "Table stored with the image",
};

START_TEST(test_dialog_in_german)
{
    DialogProbe probe;
    DriftTable *table;
    GwyContainer *data;
    gchar *mo;
    guint i;

    mo = g_build_filename(TEST_LOCALEDIR, "de", "LC_MESSAGES", GETTEXT_PACKAGE ".mo", NULL);
    ck_assert_msg(g_file_test(mo, G_FILE_TEST_IS_REGULAR), "the German catalogue %s is not built", mo);
    g_free(mo);
    g_setenv("LC_ALL", "C.UTF-8", TRUE);
    g_setenv("LANGUAGE", "de", TRUE);
    init_application();
    bindtextdomain(GETTEXT_PACKAGE, TEST_LOCALEDIR);
    set_batch_like_settings();
    data = make_data(&table);
    probe_init(&probe, "Streifen", SCREENSHOT_DE, GTK_RESPONSE_CANCEL);
    run_dialog(data, &probe);

    ck_assert_msg(probe.dialog, "no dialog appeared");
    ck_assert_msg(probe.ready, "no German status line; the dialog shows:\n%s", probe.texts->str);
    printf("test-gui-dialog: German dialog \"%s\" (%s):\n%s", probe.title, SCREENSHOT_DE, probe.texts->str);
    ck_assert_str_ne(probe.title, "Local Scan Drift");
    for (i = 0; i < G_N_ELEMENTS(german_texts); i++) {
        ck_assert_msg(strstr(probe.texts->str, german_texts[i]),
                      "\"%s\" is not in the German dialog:\n%s", german_texts[i], probe.texts->str);
        ck_assert_msg(!strstr(probe.texts->str, english_texts[i]),
                      "\"%s\" is still English in the German dialog", english_texts[i]);
    }
    ck_assert(!gwy_container_contains_by_name(data, "/1/data"));

    gwy_app_data_browser_remove(data);
    g_object_unref(data);
    drift_table_free(table);
    probe_clear(&probe);
}
END_TEST

/* Every widget a user sets something with says what it does. */
static void
collect_missing_tooltips(GtkWidget *widget, GString *missing)
{
    GList *children, *l;
    gboolean settable;
    gchar *tip;

    if (!gtk_widget_get_visible(widget))
        return;
    settable = (GTK_IS_TOGGLE_BUTTON(widget) || GTK_IS_COMBO_BOX(widget) || GTK_IS_TREE_VIEW(widget)
                || GTK_IS_SPIN_BUTTON(widget) || GTK_IS_FILE_CHOOSER_BUTTON(widget)
                || GWY_IS_COLOR_BUTTON(widget) || (GTK_IS_ENTRY(widget)
                                                   && !GTK_IS_SPIN_BUTTON(widget)));
    /* A combo box's or file button's inner widgets share its tooltip. */
    if (settable && !(tip = gtk_widget_get_tooltip_text(widget))) {
        GtkWidget *parent = gtk_widget_get_parent(widget);

        if (!parent || !(tip = gtk_widget_get_tooltip_text(parent)))
            g_string_append_printf(missing, "%s \"%s\"; ", G_OBJECT_TYPE_NAME(widget),
                                   GTK_IS_BUTTON(widget) && gtk_button_get_label(GTK_BUTTON(widget))
                                   ? gtk_button_get_label(GTK_BUTTON(widget)) : "");
        else
            g_free(tip);
    }
    else if (settable)
        g_free(tip);
    if (!GTK_IS_CONTAINER(widget) || GTK_IS_COMBO_BOX(widget) || GTK_IS_FILE_CHOOSER_BUTTON(widget))
        return;
    children = gtk_container_get_children(GTK_CONTAINER(widget));
    for (l = children; l; l = g_list_next(l))
        collect_missing_tooltips(GTK_WIDGET(l->data), missing);
    g_list_free(children);
}

/* Repeat last (an IMMEDIATE run with the last settings) on the result
 * must not compensate it again; the dialog on the result asks first, and
 * its Cancel adds nothing. */
START_TEST(test_no_double_correction)
{
    DialogProbe probe;
    DriftTable *table;
    GwyContainer *data;
    gint n;

    init_application();
    set_batch_like_settings();
    data = make_data(&table);
    probe_init(&probe, "filled pixels.", SCREENSHOT, GTK_RESPONSE_OK);
    run_dialog(data, &probe);
    ck_assert_msg(probe.ready, "the first dialog never got ready:\n%s", probe.texts->str);
    ck_assert_int_eq(gui_count_channels(data), 2);
    probe_clear(&probe);

    /* Repeat last on the new channel 1. */
    gwy_app_data_browser_select_data_field(data, 1);
    gwy_process_func_run(LOCALSCAN_FUNCTION_NAME, data, GWY_RUN_IMMEDIATE);
    n = gui_count_channels(data);
    printf("test-gui-dialog: Repeat last on the result: %d channels (2 before)\n", n);
    ck_assert_int_eq(n, 2);

    /* The dialog on the result asks; Cancel leaves it at that. */
    probe_init(&probe, "already local-scan compensated", SCREENSHOT_AGAIN, GTK_RESPONSE_CANCEL);
    run_dialog_on(data, 1, &probe);
    ck_assert_msg(probe.ready, "no question on the compensated channel; shown:\n%s", probe.texts->str);
    ck_assert_msg(probe.saved, "no screenshot");
    printf("test-gui-dialog: the question on the result (%s):\n%s", SCREENSHOT_AGAIN, probe.texts->str);
    ck_assert_int_eq(gui_count_channels(data), 2);

    gwy_app_data_browser_remove(data);
    g_object_unref(data);
    drift_table_free(table);
    probe_clear(&probe);
}
END_TEST

/* Two files: scan-a.gwy with Topography (the image) and its Amplitude
 * (same scan), scan-b.gwy with a Topography of the same area scanned
 * later, and scan-c.gwy with an image of another size.  The chooser names
 * "file — channel", offers the two fitting channels, never the image, and
 * preselects the other scan. */
START_TEST(test_reference_chooser)
{
    GwyContainer *a, *b, *c;
    GwyDataField *field, *other;
    GtkTreeModel *model;
    GtkTreeIter iter;
    DialogProbe probe;
    DriftTable *table;
    GString *labels = g_string_new(NULL);
    gchar *label, *active = NULL;
    gboolean more;

    init_application();
    set_batch_like_settings();
    gwy_container_set_int32_by_name(gwy_app_settings_get(), LOCALSCAN_SETTINGS_KEY(SOURCE),
                                    LOCALSCAN_SOURCE_REFERENCE);
    a = make_data(&table);
    drift_table_free(table);
    b = make_data(&table);
    drift_table_free(table);
    gwy_container_set_const_string_by_name(a, "/filename", (const guchar*)"/data/scan-a.gwy");
    gwy_container_set_const_string_by_name(b, "/filename", (const guchar*)"/data/scan-b.gwy");
    field = gwy_container_get_object(a, gwy_app_get_data_key_for_id(0));
    other = gwy_data_field_duplicate(field);
    gwy_container_set_object(a, gwy_app_get_data_key_for_id(1), other);
    gwy_container_set_const_string_by_name(a, "/1/data/title", (const guchar*)"Amplitude");
    g_object_unref(other);
    c = gwy_container_new();
    other = gwy_data_field_new(XRES/2, YRES, XRES*1e-9, YRES*2e-9, TRUE);
    gwy_container_set_object(c, gwy_app_get_data_key_for_id(0), other);
    g_object_unref(other);
    gwy_app_data_browser_add(b);
    gwy_app_data_browser_add(c);
    gwy_app_data_browser_add(a);

    probe_init(&probe, "Registered", SCREENSHOT_REFERENCE, GTK_RESPONSE_CANCEL);
    probe.keep_reference = TRUE;
    run_dialog_on(a, 0, &probe);
    ck_assert_msg(probe.dialog, "no dialog");
    ck_assert_msg(probe.reference_model, "no reference chooser");
    model = probe.reference_model;
    for (more = gtk_tree_model_get_iter_first(model, &iter); more;
         more = gtk_tree_model_iter_next(model, &iter)) {
        gtk_tree_model_get(model, &iter, LOCALSCAN_REFERENCE_COLUMN_LABEL, &label, -1);
        g_string_append_printf(labels, "%s\n", label);
        g_free(label);
    }
    active = probe.reference_active;
    printf("test-gui-dialog: the reference chooser (%s) offers:\n%sand preselects: %s\n",
           SCREENSHOT_REFERENCE, labels->str, active);
    ck_assert_str_eq(labels->str, "scan-a.gwy \342\200\224 Amplitude (same scan)\n"
                                  "scan-b.gwy \342\200\224 Topography\n");
    ck_assert_str_eq(active, "scan-b.gwy \342\200\224 Topography");

    g_object_unref(probe.reference_model);
    g_free(active);
    g_string_free(labels, TRUE);
    gwy_app_data_browser_remove(a);
    gwy_app_data_browser_remove(b);
    gwy_app_data_browser_remove(c);
    g_object_unref(a);
    g_object_unref(b);
    g_object_unref(c);
    probe_clear(&probe);
}
END_TEST

/* The wait dialog of the final run: photographed once it says it is
 * compensating, then cancelled (the run sees the cancel when it next
 * reports, before it would create the channels). */
typedef struct {
    gboolean seen;
    gboolean cancelled;
    gboolean saved;
    gint width, height;
    GString *texts;
} WaitProbe;

static gboolean
probe_wait_dialog(gpointer user_data)
{
    WaitProbe *probe = (WaitProbe*)user_data;
    GtkWidget *dialog = gui_find_visible_dialog(GTK_TYPE_DIALOG);

    if (!dialog || g_strcmp0(gtk_window_get_title(GTK_WINDOW(dialog)), "Please wait"))
        return TRUE;
    probe->seen = TRUE;
    g_string_truncate(probe->texts, 0);
    collect_texts(dialog, probe->texts);
    if (!strstr(probe->texts->str, "Compensating"))
        return TRUE;
    probe->saved = gui_save_screenshot(dialog, SCREENSHOT_WAIT, &probe->width, &probe->height);
    gtk_dialog_response(GTK_DIALOG(dialog), GTK_RESPONSE_CANCEL);
    probe->cancelled = TRUE;
    return FALSE;
}

/* A large image: the dialog previews a reduced copy; OK runs the whole
 * compensation in Gwyddion's wait dialog, whose Cancel leaves no channel. */
START_TEST(test_cancel_large_image)
{
    GwyContainer *data = gwy_container_new();
    GwyDataField *field = gwy_data_field_new(LARGE_RES, LARGE_RES, LARGE_RES*1e-9, LARGE_RES*1e-9,
                                             FALSE);
    WaitProbe wait;
    DialogProbe probe;
    GString *missing = g_string_new(NULL);
    GRand *rng;
    gint64 start;
    guint timeout;

    init_application();
    set_batch_like_settings();
    rng = g_rand_new_with_seed(seed);
    gwy_data_field_synth_gaussian_displacement(field, 40.0, 1.0, rng);
    g_rand_free(rng);
    gwy_si_unit_set_from_string(gwy_data_field_get_si_unit_xy(field), "m");
    gwy_container_set_object(data, gwy_app_get_data_key_for_id(0), field);
    gwy_container_set_const_string_by_name(data, "/0/data/title", (const guchar*)"Large");
    localscan_channel_store_table_text(data, 0, "stripe,dx,dy\n0,-3,0\n1,-6,-1\n2,-9,-2\n");
    gwy_clear(&probe, 1);
    gwy_clear(&wait, 1);
    wait.texts = g_string_new(NULL);
    probe.ready_text = "Preview of a";
    probe.screenshot = SCREENSHOT_LARGE;
    probe.response = GTK_RESPONSE_OK;
    probe.missing_tooltips = missing;
    timeout = g_timeout_add(1, probe_wait_dialog, &wait);
    start = g_get_monotonic_time();
    run_dialog(data, &probe);
    if (!wait.cancelled)
        g_source_remove(timeout);
    printf("test-gui-dialog: %d x %d image: dialog, OK and cancel took %.2f s; the dialog shows:\n%s",
           LARGE_RES, LARGE_RES, (g_get_monotonic_time() - start)/1e6, probe.texts->str);
    ck_assert_msg(probe.ready, "no reduced preview; the dialog shows:\n%s", probe.texts->str);
    ck_assert_msg(!missing->len, "settings without a tooltip: %s", missing->str);
    ck_assert_msg(wait.seen, "no wait dialog during the final run");
    ck_assert_msg(wait.cancelled, "the wait dialog never said it was compensating: %s",
                  wait.texts->str);
    printf("test-gui-dialog: the wait dialog (%s, %d x %d) said:\n%s", SCREENSHOT_WAIT,
           wait.width, wait.height, wait.texts->str);
    ck_assert_int_eq(gui_count_channels(data), 1);

    gwy_app_data_browser_remove(data);
    g_object_unref(data);
    g_object_unref(field);
    g_string_free(wait.texts, TRUE);
    g_string_free(missing, TRUE);
    probe_clear(&probe);
}
END_TEST

/* Three frames "Height 0..2" of the series dialog; with timing, each
 * with the metadata of a frame of line_time s per line scanned down,
 * one after another. */
static GwyContainer*
make_series_data(gdouble line_time)
{
    GwyContainer *data = gwy_container_new(), *meta;
    GRand *rng = g_rand_new_with_seed(seed);
    gchar text[32];
    gint k;

    for (k = 0; k < 3; k++) {
        GwyDataField *field = gwy_data_field_new(XRES, YRES, XRES*1e-9, YRES*1e-9, FALSE);

        gwy_data_field_synth_gaussian_displacement(field, 3.0, 1.0, rng);
        gwy_si_unit_set_from_string(gwy_data_field_get_si_unit_xy(field), "m");
        gwy_container_set_object(data, gwy_app_get_data_key_for_id(k), field);
        g_snprintf(text, sizeof(text), "Height %d", k);
        gwy_container_set_const_string(data, gwy_app_get_data_title_key_for_id(k),
                                       (const guchar*)text);
        g_object_unref(field);
        if (line_time <= 0.0)
            continue;
        meta = gwy_container_new();
        g_snprintf(text, sizeof(text), "%g s", line_time);
        gwy_container_set_const_string_by_name(meta, "Line time", (const guchar*)text);
        g_snprintf(text, sizeof(text), "%g", k*YRES*line_time);
        gwy_container_set_const_string_by_name(meta, "Frame start (s)", (const guchar*)text);
        gwy_container_set_const_string_by_name(meta, "Slow scan", (const guchar*)"down");
        g_snprintf(text, sizeof(text), "/%d/meta", k);
        gwy_container_set_object_by_name(data, text, meta);
        g_object_unref(meta);
    }
    g_rand_free(rng);
    return data;
}

/* The series dialog, too, says what each of its settings does (it had no
 * tooltip at all; its frame chooser too), and that the timing settings
 * are used when the file lacks the timing (all of them sensitive), where
 * the chooser has no start to show; Cancel adds nothing. */
START_TEST(test_series_dialog_tooltips)
{
    GwyContainer *data = make_series_data(0.0);
    GString *missing = g_string_new(NULL);
    DialogProbe probe;

    init_application();
    probe_init(&probe, "Interpolation", SCREENSHOT_SERIES, GTK_RESPONSE_CANCEL);
    probe.missing_tooltips = missing;
    probe.frame_starts = g_string_new(NULL);
    gwy_app_data_browser_add(data);
    run_function_dialog_on(LOCALSCAN_SERIES_FUNCTION_NAME, data, 0, &probe);
    ck_assert_str_eq(probe.frame_starts->str, "Start (s) shown: no\n0: \n1: \n2: \n");
    g_string_free(probe.frame_starts, TRUE);
    printf("test-gui-dialog: the series dialog shows:\n%s", probe.texts->str);
    ck_assert_msg(probe.ready, "no series dialog; it shows:\n%s", probe.texts->str);
    ck_assert_msg(!missing->len, "series settings without a tooltip: %s", missing->str);
    ck_assert_msg(strstr(probe.texts->str, "these settings are used"),
                  "the dialog does not say the timing settings are used:\n%s",
                  probe.texts->str);
    ck_assert_int_eq(probe.sensitive_entries, 2);
    ck_assert_int_eq(gui_count_channels(data), 3);
    gwy_app_data_browser_remove(data);
    g_object_unref(data);
    g_string_free(missing, TRUE);
    probe_clear(&probe);
}
END_TEST

/* Frames whose metadata gives the timing: the dialog says the timing
 * settings are not used and greys their entries (they looked as if they
 * mattered); the frame chooser shows each frame's start (1.8 s apart). */
START_TEST(test_series_dialog_timing_from_file)
{
    GwyContainer *data = make_series_data(0.02);
    DialogProbe probe;

    init_application();
    probe_init(&probe, "Interpolation", NULL, GTK_RESPONSE_CANCEL);
    probe.frame_starts = g_string_new(NULL);
    gwy_app_data_browser_add(data);
    run_function_dialog_on(LOCALSCAN_SERIES_FUNCTION_NAME, data, 0, &probe);
    ck_assert_msg(probe.ready, "no series dialog; it shows:\n%s", probe.texts->str);
    ck_assert_msg(strstr(probe.texts->str, "The file gives the timing: these settings are not used."),
                  "the dialog does not say the file gives the timing:\n%s", probe.texts->str);
    ck_assert_int_eq(probe.sensitive_entries, 0);
    printf("test-gui-dialog: the frame chooser of frames the metadata times:\n%s",
           probe.frame_starts->str);
    ck_assert_str_eq(probe.frame_starts->str, "Start (s) shown: yes\n0: 0\n1: 1.8\n2: 3.6\n");
    g_string_free(probe.frame_starts, TRUE);
    gwy_app_data_browser_remove(data);
    g_object_unref(data);
    probe_clear(&probe);
}
END_TEST

/* A movie of n frames "Height 0.." of res x res px, each a window one
 * pixel further along x and half a pixel along y on one surface. */
static GwyContainer*
make_movie_data(gint n, gint res)
{
    GwyContainer *data = gwy_container_new();
    GwyDataField *surface = gwy_data_field_new(res + n + 8, res + n/2 + 8,
                                               (res + n + 8)*1e-9, (res + n/2 + 8)*1e-9, FALSE);
    GRand *rng = g_rand_new_with_seed(seed);
    gchar title[32];
    gint k;

    gwy_data_field_synth_gaussian_displacement(surface, 3.0, 1.0, rng);
    g_rand_free(rng);
    for (k = 0; k < n; k++) {
        GwyDataField *field = gwy_data_field_area_extract(surface, k, k/2, res, res);

        gwy_data_field_set_xreal(field, res*1e-9);
        gwy_data_field_set_yreal(field, res*1e-9);
        gwy_si_unit_set_from_string(gwy_data_field_get_si_unit_xy(field), "m");
        gwy_container_set_object(data, gwy_app_get_data_key_for_id(k), field);
        g_snprintf(title, sizeof(title), "Height %d", k);
        gwy_container_set_const_string(data, gwy_app_get_data_title_key_for_id(k),
                                       (const guchar*)title);
        g_object_unref(field);
    }
    g_object_unref(surface);
    return data;
}

/* The measurement's wait dialog, cancelled once it says it measures. */
static gboolean
cancel_measuring(gpointer user_data)
{
    WaitProbe *probe = (WaitProbe*)user_data;
    GtkWidget *dialog = gui_find_titled_dialog("Please wait");

    if (!dialog)
        return TRUE;
    probe->seen = TRUE;
    g_string_truncate(probe->texts, 0);
    collect_texts(dialog, probe->texts);
    if (!strstr(probe->texts->str, "Measuring the series"))
        return TRUE;
    gtk_dialog_response(GTK_DIALOG(dialog), GTK_RESPONSE_CANCEL);
    probe->cancelled = TRUE;
    return FALSE;
}

/* The series dialog ready: Update pressed (its wait dialog cancelled by
 * cancel_measuring; the dialog measures when it next idles), then, once
 * its summary has changed, what it says recorded and the dialog
 * cancelled, again at each tick while it stays: GwyDialog dropped the
 * first Cancel right after such a preview in 7 of 8 runs under load (the
 * dialog stayed up for good), and took the second, a tick later. */
typedef struct {
    DialogProbe dialog;
    WaitProbe wait;
    GString *after;
    gboolean updating;
    gboolean answered;
    gboolean stopped;            /* its timeout source is gone */
    gint cancels;                /* Cancel answers until the dialog went */
} UpdateProbe;

static gboolean
update_then_cancel(gpointer user_data)
{
    UpdateProbe *probe = (UpdateProbe*)user_data;
    GtkWidget *dialog = gui_find_titled_dialog("Local Scan Series Drift");

    probe->dialog.ticks++;
    if (!dialog)
        return (probe->stopped = (probe->dialog.ticks >= MAX_TICKS)) == FALSE;
    if (!probe->updating) {
        probe->dialog.ready = TRUE;
        probe->dialog.dialog = dialog;
        probe->updating = TRUE;
        g_timeout_add(1, cancel_measuring, &probe->wait);
        gtk_dialog_response(GTK_DIALOG(dialog), GWY_RESPONSE_UPDATE);
        return TRUE;
    }
    if (!probe->answered) {
        g_string_truncate(probe->after, 0);
        collect_texts(dialog, probe->after);
        if (g_str_has_prefix(probe->after->str, "Press Update to measure the series.")
            && probe->dialog.ticks < MAX_TICKS)
            return TRUE;
        probe->answered = TRUE;
    }
    gtk_dialog_response(GTK_DIALOG(dialog), GTK_RESPONSE_CANCEL);
    probe->cancels++;
    return (probe->stopped = (probe->dialog.ticks >= 2*MAX_TICKS)) == FALSE;
}

/* Update measures a long series in Gwyddion's wait dialog, whose Cancel
 * stops the measurement: the dialog says so, and nothing is added (the
 * measurement of a thousand frames takes seconds, and could not be
 * stopped). */
START_TEST(test_series_update_cancelled)
{
    GwyContainer *data = make_movie_data(48, 96);
    UpdateProbe probe;
    guint timeout;

    init_application();
    gwy_clear(&probe, 1);
    probe.wait.texts = g_string_new(NULL);
    probe.after = g_string_new(NULL);
    gwy_app_data_browser_add(data);
    gwy_app_data_browser_select_data_field(data, 0);
    timeout = g_timeout_add(TICK_MS, update_then_cancel, &probe);
    gwy_process_func_run(LOCALSCAN_SERIES_FUNCTION_NAME, data, GWY_RUN_INTERACTIVE);
    if (!probe.stopped)
        g_source_remove(timeout);
    printf("test-gui-dialog: the series dialog after a cancelled Update (closed by the "
           "Cancel answer number %d) shows:\n%s", probe.cancels, probe.after->str);
    fflush(stdout);
    ck_assert_msg(probe.dialog.ready, "no series dialog");
    ck_assert_msg(probe.wait.cancelled, "no measuring wait dialog (it said: %s)", probe.wait.texts->str);
    ck_assert_msg(strstr(probe.after->str, "Measurement cancelled."),
                  "the dialog does not say the measurement was cancelled:\n%s", probe.after->str);
    ck_assert_int_eq(gui_count_channels(data), 48);
    gwy_app_data_browser_remove(data);
    g_object_unref(data);
    g_string_free(probe.wait.texts, TRUE);
    g_string_free(probe.after, TRUE);
}
END_TEST

/************************************************************************
 * The series dialog's frame chooser
 ************************************************************************/

/* Channels' pixels of make_movie_data()'s frames, and the line time the
 * frame chooser's tests set (the frames carry no timing). */
#define MOVIE_RES 96
#define MOVIE_LINE_TIME 0.5

/* GLib criticals (a failed g_return_if_fail) seen while a test runs. */
static gint criticals_seen = 0;

static void
count_criticals(const gchar *domain, GLogLevelFlags level, const gchar *message,
                gpointer user_data)
{
    if (level & G_LOG_LEVEL_CRITICAL)
        criticals_seen++;
    g_log_default_handler(domain, level, message, user_data);
}

static void
watch_criticals(void)
{
    static const gchar *domains[] = {
        "GLib", "GLib-GObject", "Gtk", "Gdk", "GdkPixbuf",
        "Gwyddion", "GwyProcess", "GwyDraw", "GwyDgets", "GwyApp", "GwyModule",
    };
    guint i;

    criticals_seen = 0;
    g_log_set_default_handler(count_criticals, NULL);
    for (i = 0; i < G_N_ELEMENTS(domains); i++)
        g_log_set_handler(domains[i], G_LOG_LEVEL_CRITICAL | G_LOG_FLAG_FATAL
                          | G_LOG_FLAG_RECURSION, count_criticals, NULL);
}

/* The timing the frames lack, given by the settings as a user types it;
 * the trajectory graph added, no crop, B-spline interpolation. */
static void
set_series_settings(void)
{
    GwyContainer *settings = gwy_app_settings_get();

    gwy_container_set_double_by_name(settings, "/module/localscan_series/line_time",
                                     MOVIE_LINE_TIME);
    gwy_container_set_double_by_name(settings, "/module/localscan_series/frame_interval", 0.0);
    gwy_container_set_boolean_by_name(settings, "/module/localscan_series/add_graph", TRUE);
    gwy_container_set_boolean_by_name(settings, "/module/localscan_series/crop", FALSE);
    gwy_container_set_enum_by_name(settings, "/module/localscan_series/interpolation",
                                   GWY_INTERPOLATION_BSPLINE);
}

static GtkTreeView*
find_frame_chooser(GtkWidget *dialog)
{
    GtkWidget *widget = gui_find_named_widget(dialog, LOCALSCAN_SERIES_FRAMES_WIDGET_NAME);

    return (widget && GTK_IS_TREE_VIEW(widget)) ? GTK_TREE_VIEW(widget) : NULL;
}

/* The chooser's rows, "[x] ID TITLE" (checked) or "[ ] ID TITLE" a line. */
static void
describe_frames(GtkTreeView *view, GString *rows)
{
    GtkTreeModel *model = gtk_tree_view_get_model(view);
    GtkTreeIter iter;
    gboolean more, checked;
    gchar *title;
    gint id;

    g_string_truncate(rows, 0);
    for (more = gtk_tree_model_get_iter_first(model, &iter); more;
         more = gtk_tree_model_iter_next(model, &iter)) {
        gtk_tree_model_get(model, &iter, LOCALSCAN_SERIES_FRAME_COLUMN_CHECKED, &checked,
                           LOCALSCAN_SERIES_FRAME_COLUMN_ID, &id,
                           LOCALSCAN_SERIES_FRAME_COLUMN_TITLE, &title, -1);
        g_string_append_printf(rows, "[%c] %d %s\n", checked ? 'x' : ' ', id, title);
        g_free(title);
    }
}

/* Whether the chooser shows its start column, then "ID: START" a row. */
static void
describe_frame_starts(GtkWidget *dialog, GString *starts)
{
    GtkTreeView *view = find_frame_chooser(dialog);
    GtkTreeViewColumn *column;
    GtkTreeModel *model;
    GtkTreeIter iter;
    gboolean more;
    gchar *start;
    gint id;

    if (!view)
        return;
    column = gtk_tree_view_get_column(view, 4);
    g_string_append_printf(starts, "%s shown: %s\n",
                           column ? gtk_tree_view_column_get_title(column) : "no column",
                           column && gtk_tree_view_column_get_visible(column) ? "yes" : "no");
    model = gtk_tree_view_get_model(view);
    for (more = gtk_tree_model_get_iter_first(model, &iter); more;
         more = gtk_tree_model_iter_next(model, &iter)) {
        gtk_tree_model_get(model, &iter, LOCALSCAN_SERIES_FRAME_COLUMN_ID, &id,
                           LOCALSCAN_SERIES_FRAME_COLUMN_START, &start, -1);
        g_string_append_printf(starts, "%d: %s\n", id, start);
        g_free(start);
    }
}

/* Clicks the checkbox of each row (ended by -1); FALSE unless each click
 * got through and unchecked its frame. */
static gboolean
uncheck_frames(GtkTreeView *view, const gint *rows)
{
    GtkTreeModel *model = gtk_tree_view_get_model(view);
    GtkTreeIter iter;
    gboolean checked = TRUE;
    gint i;

    for (i = 0; rows[i] >= 0; i++) {
        if (!gui_click_tree_cell(view, rows[i], 0)
            || !gtk_tree_model_iter_nth_child(model, &iter, NULL, rows[i]))
            return FALSE;
        gtk_tree_model_get(model, &iter, LOCALSCAN_SERIES_FRAME_COLUMN_CHECKED, &checked, -1);
        if (checked)
            return FALSE;
    }
    return TRUE;
}

static gboolean
response_sensitive(GtkWidget *dialog, gint response)
{
    GtkWidget *button = gtk_dialog_get_widget_for_response(GTK_DIALOG(dialog), response);

    return button && gtk_widget_is_sensitive(button);
}

/* The step of a frame chooser's test that answers OK until the dialog
 * goes. */
#define STEP_OK 99

/* What a frame chooser's test saw at each of its steps. */
typedef struct {
    gint step;
    gint ticks;
    gboolean stopped;            /* its timeout source is gone */
    const gint *uncheck;         /* the rows to uncheck, ended by -1 */
    GString *texts;              /* every visible label of the dialog */
    GString *opened;             /* the chooser's rows as the dialog opened */
    GString *measured;           /* the labels after Update */
    GString *rows;               /* the chooser's rows after the clicks */
    GString *after;              /* the labels after the clicks */
    GString *updated;            /* the labels after an Update with too few */
    GString *reset;              /* the chooser's rows after Reset */
    gboolean clicked;
    gboolean ok_sensitive, update_sensitive;
    gboolean ok_sensitive_reset;
    gboolean saved;
    gint width, height;
} FrameProbe;

static void
frame_probe_init(FrameProbe *probe, const gint *uncheck)
{
    gwy_clear(probe, 1);
    probe->uncheck = uncheck;
    probe->texts = g_string_new(NULL);
    probe->opened = g_string_new(NULL);
    probe->measured = g_string_new(NULL);
    probe->rows = g_string_new(NULL);
    probe->after = g_string_new(NULL);
    probe->updated = g_string_new(NULL);
    probe->reset = g_string_new(NULL);
}

static void
frame_probe_clear(FrameProbe *probe)
{
    g_string_free(probe->texts, TRUE);
    g_string_free(probe->opened, TRUE);
    g_string_free(probe->measured, TRUE);
    g_string_free(probe->rows, TRUE);
    g_string_free(probe->after, TRUE);
    g_string_free(probe->updated, TRUE);
    g_string_free(probe->reset, TRUE);
}

/* OK until the dialog takes it: sent while GwyDialog is between two runs
 * of its loop (its wait cursor put away after a preview lets the probe
 * run), the answer is dropped, as update_then_cancel() found for Cancel. */
static gboolean
answer_ok_until_gone(FrameProbe *probe)
{
    GtkWidget *dialog = gui_find_titled_dialog("Local Scan Series Drift");

    if (!dialog || ++probe->ticks >= 2*MAX_TICKS) {
        probe->stopped = TRUE;
        return FALSE;
    }
    gtk_dialog_response(GTK_DIALOG(dialog), GTK_RESPONSE_OK);
    return TRUE;
}

/* The series dialog at rest (no wait dialog over it), its labels in
 * probe->texts; NULL while it is not, and the dialog cancelled (the probe
 * stopped) when it never got where the test waits for. */
static GtkWidget*
series_dialog_at_rest(FrameProbe *probe)
{
    GtkWidget *dialog = gui_find_titled_dialog("Local Scan Series Drift");

    if (++probe->ticks >= MAX_TICKS) {
        if (dialog)
            gtk_dialog_response(GTK_DIALOG(dialog), GTK_RESPONSE_CANCEL);
        probe->stopped = TRUE;
        return NULL;
    }
    if (!dialog || gui_find_titled_dialog("Please wait"))
        return NULL;
    g_string_truncate(probe->texts, 0);
    collect_texts(dialog, probe->texts);
    return dialog;
}

/* The series dialog at rest and its frame chooser; NULL until the dialog
 * is at rest, and NULL with the dialog cancelled and the probe stopped
 * when it has no chooser. */
static GtkTreeView*
frame_chooser_at_rest(FrameProbe *probe, GtkWidget **dialog)
{
    GtkTreeView *view;

    if (!(*dialog = series_dialog_at_rest(probe)))
        return NULL;
    if (!(view = find_frame_chooser(*dialog))) {
        gtk_dialog_response(GTK_DIALOG(*dialog), GTK_RESPONSE_CANCEL);
        probe->stopped = TRUE;
    }
    return view;
}

/* Update on every frame, then one frame unchecked after the measurement,
 * then OK. */
static gboolean
measure_then_leave_out(gpointer user_data)
{
    FrameProbe *probe = (FrameProbe*)user_data;
    GtkWidget *dialog;
    GtkTreeView *view;

    if (probe->step == STEP_OK)
        return answer_ok_until_gone(probe);
    if (!(view = frame_chooser_at_rest(probe, &dialog)))
        return !probe->stopped;
    if (probe->step == 0) {
        describe_frames(view, probe->opened);
        probe->step++;
        gtk_dialog_response(GTK_DIALOG(dialog), GWY_RESPONSE_UPDATE);
        return TRUE;
    }
    if (!strstr(probe->texts->str, " frames, typical residual"))
        return TRUE;
    g_string_assign(probe->measured, probe->texts->str);
    probe->clicked = uncheck_frames(view, probe->uncheck);
    describe_frames(view, probe->rows);
    collect_texts(dialog, probe->after);
    probe->ok_sensitive = response_sensitive(dialog, GTK_RESPONSE_OK);
    probe->saved = gui_save_screenshot(dialog, SCREENSHOT_FRAMES, &probe->width, &probe->height);
    probe->step = STEP_OK;
    return answer_ok_until_gone(probe);
}

/* The core's correction of channels ids[] of data (n of them) against the
 * channels from first_new on, which OK made: their titles and every value.
 * The frames carry no timing: MOVIE_LINE_TIME s per line and the frames
 * back to back, each in its place among all candidates (places[]), which
 * is gwy-localscan series --channels IDS --line-time 0.5 --frame-times
 * PLACE*48,... */
static void
assert_core_correction(GwyContainer *data, const gint *ids, const gint *places, gint n,
                       gint first_new)
{
    gdouble *times = g_new(gdouble, n);
    gchar *name = (gchar*)"Untitled";
    FrameSeriesOptions options;
    SeriesCorrection correction;
    FrameSeries *series;
    GError *error = NULL;
    gint k;

    for (k = 0; k < n; k++)
        times[k] = places[k]*MOVIE_RES*MOVIE_LINE_TIME;
    frame_series_options_init(&options);
    options.channel_ids = ids;
    options.n_channel_ids = n;
    options.line_time = MOVIE_LINE_TIME;
    options.direction = SCAN_DIRECTION_DOWN;
    options.frame_times = times;
    options.n_frame_times = n;
    series = frame_series_from_files(&data, &name, 1, &options, &error);
    ck_assert_msg(series, "the core cannot read the frames: %s", error ? error->message : "?");
    ck_assert_int_eq(series->n_frames, n);
    ck_assert(series_correction_compute(series, NULL, NULL, &correction, NULL));
    for (k = 0; k < n; k++) {
        GwyDataField *want = gwy_data_field_new_alike(series->frames[k].field, FALSE);
        GwyDataField *mask = gwy_data_field_new_alike(want, FALSE), *made = NULL;
        gchar *title = g_strdup_printf("Height %d (drift corrected)", ids[k]);
        const guchar *made_title = NULL;

        ck_assert(series_correction_correct_frame(&correction, series, k,
                                                  GWY_INTERPOLATION_BSPLINE, want, mask, NULL));
        ck_assert(gwy_container_gis_string(data, gwy_app_get_data_title_key_for_id(first_new + k),
                                           &made_title));
        ck_assert_str_eq((const gchar*)made_title, title);
        ck_assert(gwy_container_gis_object(data, gwy_app_get_data_key_for_id(first_new + k),
                                           &made));
        gwy_data_field_subtract_fields(want, want, made);
        ck_assert_msg(gwy_data_field_get_max(want) < 1e-15 && gwy_data_field_get_min(want) > -1e-15,
                      "channel %d differs from the core's correction of channel %d (seed %u)",
                      first_new + k, ids[k], seed);
        g_object_unref(want);
        g_object_unref(mask);
        g_free(title);
    }
    series_correction_clear(&correction);
    frame_series_free(series);
    g_free(times);
}

/* The series dialog on channel 0 of data, added to the data browser, run
 * interactively with drive stepping it every TICK_MS; the frames in
 * uncheck (-1 terminated) are to be unchecked. */
static void
run_series_dialog(GwyContainer *data, FrameProbe *probe, const gint *uncheck, GSourceFunc drive)
{
    guint timeout;

    init_application();
    watch_criticals();
    set_series_settings();
    frame_probe_init(probe, uncheck);
    gwy_app_data_browser_add(data);
    gwy_app_data_browser_select_data_field(data, 0);
    timeout = g_timeout_add(TICK_MS, drive, probe);
    gwy_process_func_run(LOCALSCAN_SERIES_FUNCTION_NAME, data, GWY_RUN_INTERACTIVE);
    if (!probe->stopped)
        g_source_remove(timeout);
}

/* Five frames measured with Update, then frame 2 (a disturbed frame, say)
 * unchecked and OK: the measurement of five frames is dropped, and the
 * result is the four checked frames corrected as the core corrects them,
 * frame 2 still taking its time in the series' clock.  Repeat last then
 * takes all five again: the choice is not kept. */
START_TEST(test_series_frame_left_out)
{
    static const gint uncheck[] = { 2, -1 };
    static const gint ids[] = { 0, 1, 3, 4 };
    GwyContainer *data = make_movie_data(5, MOVIE_RES);
    FrameProbe probe;
    GError *error;

    run_series_dialog(data, &probe, uncheck, measure_then_leave_out);
    printf("test-gui-dialog: the frame chooser as the series dialog opened:\n%s"
           "after Update on them:\n%sand after frame 2 was unchecked (%s, %d x %d):\n%s%s",
           probe.opened->str, probe.measured->str, SCREENSHOT_FRAMES, probe.width, probe.height,
           probe.rows->str, probe.after->str);
    fflush(stdout);
    ck_assert_str_eq(probe.opened->str, "[x] 0 Height 0\n[x] 1 Height 1\n[x] 2 Height 2\n"
                                        "[x] 3 Height 3\n[x] 4 Height 4\n");
    ck_assert_msg(strstr(probe.measured->str, "; 5 frames,"),
                  "Update did not measure five frames:\n%s", probe.measured->str);
    ck_assert_msg(probe.clicked, "the click did not uncheck frame 2:\n%s", probe.rows->str);
    ck_assert_str_eq(probe.rows->str, "[x] 0 Height 0\n[x] 1 Height 1\n[ ] 2 Height 2\n"
                                      "[x] 3 Height 3\n[x] 4 Height 4\n");
    ck_assert_msg(strstr(probe.after->str, "Press Update to measure the series.")
                  && !strstr(probe.after->str, " frames, typical residual"),
                  "the five frames' result is still shown:\n%s", probe.after->str);
    ck_assert(probe.ok_sensitive);
    ck_assert_msg(probe.saved, "no screenshot");
    /* On a 1280 px screen with room to spare: the unwrapped line saying
     * why the timing settings are used made it 1378 px, OK off screen. */
    ck_assert_msg(probe.width <= 1024, "the dialog is %d px wide", probe.width);
    error = localscan_run_error_take(data);
    ck_assert_msg(!error, "the run failed: %s", error ? error->message : "");
    ck_assert_int_eq(gui_count_channels(data), 5 + G_N_ELEMENTS(ids));
    assert_core_correction(data, ids, ids, G_N_ELEMENTS(ids), 5);
    ck_assert(gwy_container_contains_by_name(data, "/0/graph/graph/1"));

    gwy_app_data_browser_select_data_field(data, 0);
    gwy_process_func_run(LOCALSCAN_SERIES_FUNCTION_NAME, data, GWY_RUN_IMMEDIATE);
    error = localscan_run_error_take(data);
    ck_assert_msg(!error, "Repeat last failed: %s", error ? error->message : "");
    ck_assert_int_eq(gui_count_channels(data), 5 + G_N_ELEMENTS(ids) + 5);
    ck_assert_int_eq(criticals_seen, 0);
    gwy_app_data_browser_remove(data);
    g_object_unref(data);
    frame_probe_clear(&probe);
}
END_TEST

/* Two of three frames unchecked: the summary says it, OK and Update are
 * greyed; Update all the same says it again; Reset checks them all; two
 * unchecked again and OK all the same: the run says it and adds nothing. */
static gboolean
leave_too_few(gpointer user_data)
{
    FrameProbe *probe = (FrameProbe*)user_data;
    GtkWidget *dialog;
    GtkTreeView *view;

    if (probe->step == STEP_OK)
        return answer_ok_until_gone(probe);
    if (!(view = frame_chooser_at_rest(probe, &dialog)))
        return !probe->stopped;
    if (probe->step == 0) {
        describe_frames(view, probe->opened);
        probe->clicked = uncheck_frames(view, probe->uncheck);
        describe_frames(view, probe->rows);
        collect_texts(dialog, probe->after);
        probe->ok_sensitive = response_sensitive(dialog, GTK_RESPONSE_OK);
        probe->update_sensitive = response_sensitive(dialog, GWY_RESPONSE_UPDATE);
        probe->saved = gui_save_screenshot(dialog, SCREENSHOT_TOO_FEW, &probe->width,
                                           &probe->height);
        probe->step++;
        gtk_dialog_response(GTK_DIALOG(dialog), GWY_RESPONSE_UPDATE);
        return TRUE;
    }
    if (probe->step == 1) {
        g_string_assign(probe->updated, probe->texts->str);
        probe->step++;
        gtk_dialog_response(GTK_DIALOG(dialog), GWY_RESPONSE_RESET);
        return TRUE;
    }
    describe_frames(view, probe->reset);
    probe->ok_sensitive_reset = response_sensitive(dialog, GTK_RESPONSE_OK);
    probe->clicked = probe->clicked && uncheck_frames(view, probe->uncheck);
    probe->step = STEP_OK;
    return answer_ok_until_gone(probe);
}

START_TEST(test_series_too_few_frames)
{
    static const gint uncheck[] = { 1, 2, -1 };
    static const gchar *too_few = "Fewer than two frames are checked: check at least two "
                                  "to measure the series.";
    GwyContainer *data = make_movie_data(3, MOVIE_RES);
    FrameProbe probe;
    GError *error;

    run_series_dialog(data, &probe, uncheck, leave_too_few);
    printf("test-gui-dialog: one frame of three checked (%s, %d x %d):\n%s%s",
           SCREENSHOT_TOO_FEW, probe.width, probe.height, probe.rows->str, probe.after->str);
    fflush(stdout);
    ck_assert_msg(probe.clicked, "the clicks did not uncheck frames 1 and 2:\n%s", probe.rows->str);
    ck_assert_str_eq(probe.rows->str, "[x] 0 Height 0\n[ ] 1 Height 1\n[ ] 2 Height 2\n");
    ck_assert_msg(strstr(probe.after->str, too_few), "the dialog does not say too few frames "
                  "are checked:\n%s", probe.after->str);
    ck_assert_msg(!probe.ok_sensitive && !probe.update_sensitive,
                  "OK or Update can be pressed with one frame checked");
    ck_assert_msg(probe.saved, "no screenshot");
    ck_assert_msg(strstr(probe.updated->str, too_few), "Update with one frame does not say "
                  "why it measures nothing:\n%s", probe.updated->str);
    ck_assert_str_eq(probe.reset->str, "[x] 0 Height 0\n[x] 1 Height 1\n[x] 2 Height 2\n");
    ck_assert_msg(probe.ok_sensitive_reset, "OK stays greyed after Reset checked every frame");
    error = localscan_run_error_take(data);
    ck_assert_msg(error, "OK with one frame checked did not fail");
    printf("test-gui-dialog: OK with one frame checked: %s\n", error->message);
    ck_assert_str_eq(error->message, too_few);
    g_error_free(error);
    ck_assert_int_eq(gui_count_channels(data), 3);
    ck_assert_int_eq(criticals_seen, 0);
    gwy_app_data_browser_remove(data);
    g_object_unref(data);
    frame_probe_clear(&probe);
}
END_TEST

int
main(void)
{
    Suite *suite;
    TCase *tc;

    if (!g_getenv("DISPLAY") || !*g_getenv("DISPLAY")) {
        return test_skip_all("test-gui-dialog",
                             "no X display (run it through tests/test-gui-dialog.sh)");
    }
    seed = test_seed_from_env("test-gui-dialog");

    suite = test_suite_new("gui-dialog", "dialog", &tc);
    tcase_set_timeout(tc, 60);
    tcase_add_test(tc, test_dialog_ok_makes_channel);
    tcase_add_test(tc, test_dialog_in_german);
    tcase_add_test(tc, test_no_double_correction);
    tcase_add_test(tc, test_reference_chooser);
    tcase_add_test(tc, test_cancel_large_image);
    tcase_add_test(tc, test_series_dialog_tooltips);
    tcase_add_test(tc, test_series_dialog_timing_from_file);
    tcase_add_test(tc, test_series_update_cancelled);
    tcase_add_test(tc, test_series_frame_left_out);
    tcase_add_test(tc, test_series_too_few_frames);
    return test_run_suite(suite);
}
