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

#define SCREENSHOT TEST_BUILDDIR "/tests/gui-dialog.png"
#define SCREENSHOT_DE TEST_BUILDDIR "/tests/gui-dialog-de.png"
#define SCREENSHOT_AGAIN TEST_BUILDDIR "/tests/gui-compensate-again.png"
#define SCREENSHOT_REFERENCE TEST_BUILDDIR "/tests/gui-reference.png"
#define SCREENSHOT_LARGE TEST_BUILDDIR "/tests/gui-large-preview.png"
#define SCREENSHOT_WAIT TEST_BUILDDIR "/tests/gui-cancel-wait.png"
#define SCREENSHOT_SERIES TEST_BUILDDIR "/tests/gui-series-dialog.png"
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
    settable = (GTK_IS_TOGGLE_BUTTON(widget) || GTK_IS_COMBO_BOX(widget)
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
 * tooltip at all), and that the timing settings are used when the file
 * lacks the timing (all of them sensitive); Cancel adds nothing. */
START_TEST(test_series_dialog_tooltips)
{
    GwyContainer *data = make_series_data(0.0);
    GString *missing = g_string_new(NULL);
    DialogProbe probe;

    init_application();
    probe_init(&probe, "Interpolation", SCREENSHOT_SERIES, GTK_RESPONSE_CANCEL);
    probe.missing_tooltips = missing;
    gwy_app_data_browser_add(data);
    run_function_dialog_on(LOCALSCAN_SERIES_FUNCTION_NAME, data, 0, &probe);
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
 * mattered). */
START_TEST(test_series_dialog_timing_from_file)
{
    GwyContainer *data = make_series_data(0.02);
    DialogProbe probe;

    init_application();
    probe_init(&probe, "Interpolation", NULL, GTK_RESPONSE_CANCEL);
    gwy_app_data_browser_add(data);
    run_function_dialog_on(LOCALSCAN_SERIES_FUNCTION_NAME, data, 0, &probe);
    ck_assert_msg(probe.ready, "no series dialog; it shows:\n%s", probe.texts->str);
    ck_assert_msg(strstr(probe.texts->str, "The file gives the timing: these settings are not used."),
                  "the dialog does not say the file gives the timing:\n%s", probe.texts->str);
    ck_assert_int_eq(probe.sensitive_entries, 0);
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
    return test_run_suite(suite);
}
