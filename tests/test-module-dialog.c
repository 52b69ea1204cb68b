/*
 *  Tests of the localscan_drift dialog on a real (virtual) X display: an
 *  unusable drift source disables OK and shows the parser's message; a good
 *  one gives the same new channel as an IMMEDIATE run.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <check.h>
#include <gtk/gtk.h>
#include <libgwyddion/gwyddion.h>
#include <libprocess/gwyprocess.h>
#include <libgwydgets/gwydgets.h>
#include <libgwymodule/gwymodule.h>
#include <app/gwyapp.h>
#include "localscan-channel.h"
#include "localscan-params.h"
#include "registration-frames.h"
#include "test-common.h"
#include "gui-widgets.h"
#include "worked-example.h"

#define RERUN_GUARD "LOCALSCAN_TEST_UNDER_XVFB"
#define MAX_TICKS 100

static guint32 test_seed;

/* What the timeout found in the dialog, and how it answered. */
typedef struct {
    const gchar *wait_for_text;
    gint response;
    gint ticks;
    gboolean found_dialog;
    gboolean found_text;
    gboolean ok_sensitive;
    gboolean answered;
    const gchar *also_text;      /* shown too when wait_for_text is */
    gboolean found_also;
} DialogProbe;

static GwyContainer*
make_container(const gchar *table_text)
{
    GwyDataField *field = gwy_data_field_new(4, 6, 4e-9, 6e-9, FALSE);
    GwyContainer *data = gwy_container_new();
    gdouble *d = gwy_data_field_get_data(field);
    gint i;

    for (i = 0; i < 24; i++)
        d[i] = i + 1;
    gwy_si_unit_set_from_string(gwy_data_field_get_si_unit_xy(field), "m");
    gwy_container_set_object(data, gwy_app_get_data_key_for_id(0), field);
    g_object_unref(field);
    gwy_container_set_const_string_by_name(data, "/0/data/title", (const guchar*)"Height");
    localscan_channel_store_table_text(data, 0, table_text);
    gwy_app_data_browser_add(data);
    gwy_app_data_browser_select_data_field(data, 0);
    return data;
}

static void
set_stored_table_settings(void)
{
    GwyContainer *settings = gwy_app_settings_get();

    gwy_container_set_int32_by_name(settings, LOCALSCAN_SETTINGS_KEY(SOURCE), 0);
    gwy_container_set_int32_by_name(settings, LOCALSCAN_SETTINGS_KEY(MODE), 0);
    gwy_container_set_int32_by_name(settings, LOCALSCAN_SETTINGS_KEY(FILL), 0);
    gwy_container_set_boolean_by_name(settings, LOCALSCAN_SETTINGS_KEY(ADD_MASK), TRUE);
    gwy_container_set_boolean_by_name(settings, LOCALSCAN_SETTINGS_KEY(PLOT_DRIFT), FALSE);
}

static gboolean
widget_shows_text(GtkWidget *widget, const gchar *text)
{
    GList *children, *l;
    gboolean found = FALSE;

    if (GTK_IS_LABEL(widget)) {
        const gchar *label = gtk_label_get_text(GTK_LABEL(widget));
        return label && strstr(label, text) && gtk_widget_get_visible(widget);
    }
    if (!GTK_IS_CONTAINER(widget))
        return FALSE;
    children = gtk_container_get_children(GTK_CONTAINER(widget));
    for (l = children; l && !found; l = g_list_next(l))
        found = widget_shows_text(GTK_WIDGET(l->data), text);
    g_list_free(children);
    return found;
}

/* Waits for the preview to put the expected text up, then answers. */
static gboolean
probe_dialog(gpointer user_data)
{
    DialogProbe *probe = (DialogProbe*)user_data;
    GtkWidget *dialog = gui_find_visible_dialog(GWY_TYPE_DIALOG), *ok_button;

    if (!dialog)
        return TRUE;
    probe->ticks++;
    probe->found_dialog = TRUE;
    probe->found_text = widget_shows_text(dialog, probe->wait_for_text);
    if (!probe->found_text && probe->ticks < MAX_TICKS)
        return TRUE;
    ok_button = gtk_dialog_get_widget_for_response(GTK_DIALOG(dialog), GTK_RESPONSE_OK);
    probe->ok_sensitive = ok_button && gtk_widget_is_sensitive(ok_button);
    probe->found_also = probe->also_text && widget_shows_text(dialog, probe->also_text);
    gtk_dialog_response(GTK_DIALOG(dialog), probe->response);
    probe->answered = TRUE;
    return FALSE;
}

static void
run_dialog(GwyContainer *data, DialogProbe *probe)
{
    guint timeout = g_timeout_add(50, probe_dialog, probe);

    gwy_process_func_run(LOCALSCAN_FUNCTION_NAME, data, GWY_RUN_INTERACTIVE);
    if (!probe->answered)
        g_source_remove(timeout);
}

START_TEST(test_bad_table_disables_ok)
{
    GwyContainer *data = make_container("stripe,dx,dy\n0,abc,1\n");
    DialogProbe probe = { "channel 0 drift table:2", GTK_RESPONSE_CANCEL, 0, FALSE, FALSE, TRUE, FALSE, NULL, FALSE };

    set_stored_table_settings();
    run_dialog(data, &probe);
    ck_assert(probe.found_dialog);
    ck_assert_msg(probe.found_text, "the dialog does not show the parser's message");
    ck_assert(!probe.ok_sensitive);
    ck_assert_int_eq(gui_count_channels(data), 1);
    gwy_app_data_browser_remove(data);
    g_object_unref(data);
}
END_TEST

START_TEST(test_good_table_ok_makes_channel)
{
    GwyContainer *data = make_container(worked_table);
    DialogProbe probe = { "3 stripes, 5 filled pixels.", GTK_RESPONSE_OK, 0, FALSE, FALSE, FALSE, FALSE, NULL, FALSE };
    GwyDataField *result = NULL, *mask = NULL;
    const guchar *title = NULL;
    gint i;

    set_stored_table_settings();
    run_dialog(data, &probe);
    ck_assert(probe.found_dialog);
    ck_assert_msg(probe.found_text, "the dialog does not show the stripe summary");
    ck_assert(probe.ok_sensitive);
    ck_assert_int_eq(gui_count_channels(data), 2);
    ck_assert(gwy_container_gis_object_by_name(data, "/1/data", &result));
    for (i = 0; i < 24; i++)
        ck_assert(gwy_data_field_get_data_const(result)[i] == worked_c[i]);
    ck_assert(gwy_container_gis_object_by_name(data, "/1/mask", &mask));
    ck_assert_int_eq((gint)gwy_data_field_get_sum(mask), 5);
    ck_assert(gwy_container_gis_string_by_name(data, "/1/data/title", &title));
    ck_assert_str_eq((const gchar*)title, "Height (local-scan compensated)");
    gwy_app_data_browser_remove(data);
    g_object_unref(data);
}
END_TEST

/* Continuous mode names the stripe whose local scan it leaves out as a
 * gross error (6-20 px in a random direction on a random stripe of a
 * smooth drift), as gwy-localscan does. */
START_TEST(test_status_names_left_out_stripe)
{
    GRand *rng = test_rand_salted(test_seed, 7400);
    GwyDataField *field = gwy_data_field_new(32, 48, 32e-9, 48e-9, FALSE);
    GwyContainer *data = gwy_container_new();
    GString *table = g_string_new("stripe,dx,dy\n");
    gint bad = g_rand_int_range(rng, 0, 12), s;
    gdouble size = g_rand_double_range(rng, 6.0, 20.0), angle = g_rand_double_range(rng, 0.0, 2.0*G_PI);
    gchar *expected;
    DialogProbe probe = { NULL, GTK_RESPONSE_CANCEL, 0, FALSE, FALSE, FALSE, FALSE, NULL, FALSE };

    for (s = 0; s < 32*48; s++)
        gwy_data_field_get_data(field)[s] = 1e-9*g_rand_double(rng);
    for (s = 0; s < 12; s++) {
        gdouble dx = 0.5 + 0.05*s, dy = -0.3 + 0.02*s;

        if (s == bad) {
            dx += size*cos(angle);
            dy += size*sin(angle);
        }
        g_string_append_printf(table, "%d,%.4f,%.4f\n", s, dx, dy);
    }
    gwy_si_unit_set_from_string(gwy_data_field_get_si_unit_xy(field), "m");
    gwy_container_set_object(data, gwy_app_get_data_key_for_id(0), field);
    gwy_container_set_const_string_by_name(data, "/0/data/title", (const guchar*)"Height");
    localscan_channel_store_table_text(data, 0, table->str);
    gwy_app_data_browser_add(data);
    gwy_app_data_browser_select_data_field(data, 0);
    set_stored_table_settings();
    gwy_container_set_int32_by_name(gwy_app_settings_get(), LOCALSCAN_SETTINGS_KEY(MODE), 1);
    expected = g_strdup_printf("Stripe %d lies far from the others' drift: left out.", bad);
    probe.wait_for_text = expected;
    run_dialog(data, &probe);
    ck_assert(probe.found_dialog);
    ck_assert_msg(probe.found_text, "seed %u: the dialog does not name stripe %d (%.1f px off)",
                  test_seed, bad, size);
    gwy_app_data_browser_remove(data);
    g_object_unref(data);
    g_object_unref(field);
    g_string_free(table, TRUE);
    g_free(expected);
    g_rand_free(rng);
}
END_TEST

/* Continuous mode says where each part of the scan timing came from. */
START_TEST(test_status_names_timing_source)
{
    static const gchar gentle_table[] = "stripe,dx,dy\n0,0,0\n1,0.5,0\n2,1,0\n";
    DialogProbe with_meta = { "frame start 2.5 s (metadata).", GTK_RESPONSE_CANCEL, 0, FALSE, FALSE, FALSE, FALSE,
                              "Line time 1.5 s (metadata),\nslow scan up (metadata),\n", FALSE };
    DialogProbe without = { "frame start 0 s (setting).", GTK_RESPONSE_CANCEL, 0, FALSE, FALSE, FALSE, FALSE,
                            "Line time 1 s (setting),\nslow scan down (setting),\n", FALSE };
    DialogProbe set = { "frame start 3 s (setting).", GTK_RESPONSE_CANCEL, 0, FALSE, FALSE, FALSE, FALSE,
                        "Line time 0.25 s (setting),\nslow scan up (setting),\n", FALSE };
    DialogProbe overridden = { "frame start 2.5 s (metadata).", GTK_RESPONSE_CANCEL, 0, FALSE, FALSE, FALSE, FALSE,
                               "Line time 0.25 s (setting),\nslow scan down (metadata),\n", FALSE };
    GwyContainer *settings = gwy_app_settings_get(), *data, *meta;

    set_stored_table_settings();
    gwy_container_set_int32_by_name(settings, LOCALSCAN_SETTINGS_KEY(MODE), 1);
    gwy_container_set_int32_by_name(settings, LOCALSCAN_SETTINGS_KEY(DIRECTION), 0);
    data = make_container(gentle_table);
    run_dialog(data, &without);
    ck_assert_msg(without.found_text && without.found_also, "no timing source shown without metadata");
    gwy_app_data_browser_remove(data);
    g_object_unref(data);

    /* The timing settings stand in for what the metadata does not say. */
    gwy_container_set_double_by_name(settings, LOCALSCAN_SETTINGS_KEY(LINE_TIME), 0.25);
    gwy_container_set_int32_by_name(settings, LOCALSCAN_SETTINGS_KEY(DIRECTION), SCAN_DIRECTION_UP);
    gwy_container_set_double_by_name(settings, LOCALSCAN_SETTINGS_KEY(FRAME_START), 3.0);
    data = make_container(gentle_table);
    run_dialog(data, &set);
    ck_assert_msg(set.found_text && set.found_also, "the timing settings are not used");
    gwy_app_data_browser_remove(data);
    g_object_unref(data);

    data = make_container(gentle_table);
    ck_assert(gwy_container_gis_object_by_name(data, "/0/meta", &meta));
    gwy_container_set_const_string_by_name(meta, "Slow scan", (const guchar*)"down");
    gwy_container_set_const_string_by_name(meta, "Frame start (s)", (const guchar*)"2.5");
    run_dialog(data, &overridden);
    ck_assert_msg(overridden.found_text && overridden.found_also, "the metadata does not win over the settings");
    gwy_app_data_browser_remove(data);
    g_object_unref(data);

    data = make_container(gentle_table);
    ck_assert(gwy_container_gis_object_by_name(data, "/0/meta", &meta));
    gwy_container_set_const_string_by_name(meta, "Line time (s)", (const guchar*)"1.5");
    gwy_container_set_const_string_by_name(meta, "Slow scan", (const guchar*)"up");
    gwy_container_set_const_string_by_name(meta, "Frame start (s)", (const guchar*)"2.5");
    run_dialog(data, &with_meta);
    ck_assert_msg(with_meta.found_text && with_meta.found_also, "the timing from metadata is not shown");
    gwy_app_data_browser_remove(data);
    g_object_unref(data);
}
END_TEST

/************************************************************************
 * The reference source in the dialog
 ************************************************************************/

#define REF_SIZE 256
#define REF_STEP 4e-9
#define SCREENSHOT TEST_BUILDDIR "/tests/module-dialog-reference.png"

/* What the reference dialog run saw, step by step. */
typedef enum {
    STEP_REGISTERED,      /* first preview: 16 stripes registered */
    STEP_CONTINUOUS,      /* mode switched: the measured table reused */
    STEP_EIGHT_STRIPES,   /* stripe count moved 12, 10, 8: measured once */
    STEP_DONE,
} ReferenceStep;

typedef struct {
    ReferenceStep step;
    gint ticks;
    gint registrations[STEP_DONE];
    gint registrations_while_moving;  /* before the stripe count rested */
    gint offered;             /* channels the reference chooser offers */
    gboolean offers_other_size;
    gboolean offers_other_real;
    gboolean offers_itself;
    gint chosen;              /* the chooser's channel */
    gboolean ok_sensitive;
    gint graph_points;        /* dx points in the dialog's drift graph */
    gboolean saved;
    gboolean answered;
    GwyContainer *data;
} ReferenceProbe;

static gint registrations;

/* The module says when it registers (g_debug); the cache is seen here. */
static void
count_registrations(G_GNUC_UNUSED const gchar *domain, G_GNUC_UNUSED GLogLevelFlags level,
                    const gchar *message, G_GNUC_UNUSED gpointer user_data)
{
    if (strstr(message, "registering"))
        registrations++;
}

static GtkWidget*
find_widget(GtkWidget *widget, GType type, const gchar *button_label)
{
    GList *children, *l;
    GtkWidget *found = NULL;

    if (G_TYPE_CHECK_INSTANCE_TYPE(widget, type)
        && (!button_label || !g_strcmp0(gtk_button_get_label(GTK_BUTTON(widget)), button_label)))
        return widget;
    if (!GTK_IS_CONTAINER(widget))
        return NULL;
    children = gtk_container_get_children(GTK_CONTAINER(widget));
    for (l = children; l && !found; l = g_list_next(l))
        found = find_widget(GTK_WIDGET(l->data), type, button_label);
    g_list_free(children);
    return found;
}

/* The spin button of the labelled slider. */
static GtkWidget*
find_labelled_spin(GtkWidget *widget, const gchar *label_text)
{
    GList *children, *l;
    GtkWidget *found = NULL, *target;

    if (GTK_IS_LABEL(widget) && !g_strcmp0(gtk_label_get_text(GTK_LABEL(widget)), label_text)) {
        target = gtk_label_get_mnemonic_widget(GTK_LABEL(widget));
        return GTK_IS_SPIN_BUTTON(target) ? target : NULL;
    }
    if (!GTK_IS_CONTAINER(widget))
        return NULL;
    children = gtk_container_get_children(GTK_CONTAINER(widget));
    for (l = children; l && !found; l = g_list_next(l))
        found = find_labelled_spin(GTK_WIDGET(l->data), label_text);
    g_list_free(children);
    return found;
}

static gboolean
chooser_offers(GtkTreeModel *model, gint datano, gint id)
{
    GtkTreeIter iter;
    gboolean more;
    gint d, i;

    for (more = gtk_tree_model_get_iter_first(model, &iter); more;
         more = gtk_tree_model_iter_next(model, &iter)) {
        gtk_tree_model_get(model, &iter, LOCALSCAN_REFERENCE_COLUMN_DATANO, &d,
                           LOCALSCAN_REFERENCE_COLUMN_ID, &i, -1);
        if (d == datano && i == id)
            return TRUE;
    }
    return FALSE;
}

static void
inspect_reference_chooser(GtkWidget *dialog, ReferenceProbe *probe)
{
    GtkWidget *chooser = gui_find_named_widget(dialog, LOCALSCAN_REFERENCE_WIDGET_NAME);
    gint datano = gwy_app_data_browser_get_number(probe->data);
    GtkTreeModel *model;
    GtkTreeIter iter;

    ck_assert_msg(chooser && GTK_IS_COMBO_BOX(chooser), "no reference chooser in the dialog");
    model = gtk_combo_box_get_model(GTK_COMBO_BOX(chooser));
    probe->offered = gtk_tree_model_iter_n_children(model, NULL);
    probe->chosen = -1;
    if (gtk_combo_box_get_active_iter(GTK_COMBO_BOX(chooser), &iter))
        gtk_tree_model_get(model, &iter, LOCALSCAN_REFERENCE_COLUMN_ID, &probe->chosen, -1);
    probe->offers_other_size = chooser_offers(model, datano, 2);
    probe->offers_other_real = chooser_offers(model, datano, 3);
    probe->offers_itself = chooser_offers(model, datano, 1);
}

static gint
graph_points(GtkWidget *dialog)
{
    GtkWidget *graph = find_widget(dialog, GWY_TYPE_GRAPH, NULL);
    GwyGraphModel *gmodel;

    if (!graph || !(gmodel = gwy_graph_get_model(GWY_GRAPH(graph))) || gwy_graph_model_get_n_curves(gmodel) < 1)
        return -1;
    return gwy_graph_curve_model_get_ndata(gwy_graph_model_get_curve(gmodel, 0));
}

static gboolean
save_screenshot(GtkWidget *dialog, const gchar *filename)
{
    gint width, height;
    gboolean ok = gui_save_screenshot(dialog, filename, &width, &height);

    printf("test-module-dialog: the reference dialog (%d x %d) in %s\n", width, height, filename);
    return ok;
}

/* As a dragged slider passes values: the main loop runs between them (an
 * immediate preview would register each), but for far less time than the
 * count must rest. */
static void
move_stripes(GtkWidget *spin, ReferenceProbe *probe)
{
    static const gint values[] = { 12, 10, 8 };
    guint i, k;

    for (i = 0; i < G_N_ELEMENTS(values); i++) {
        gtk_spin_button_set_value(GTK_SPIN_BUTTON(spin), values[i]);
        for (k = 0; k < 100 && gtk_events_pending(); k++)
            gtk_main_iteration_do(FALSE);
    }
    probe->registrations_while_moving = registrations;
}

/* Each step waits for the preview's status line, records, and makes the
 * next change; the last answers OK. */
static gboolean
probe_reference_dialog(gpointer user_data)
{
    static const gchar *wait_for[STEP_DONE] = {
        "Registered ", "Line time", "of 8 stripes",
    };
    ReferenceProbe *probe = (ReferenceProbe*)user_data;
    GtkWidget *dialog = gui_find_visible_dialog(GWY_TYPE_DIALOG), *ok_button, *widget;

    if (!dialog)
        return TRUE;
    if (!widget_shows_text(dialog, wait_for[probe->step]) && ++probe->ticks < MAX_TICKS)
        return TRUE;
    probe->ticks = 0;
    probe->registrations[probe->step] = registrations;
    if (probe->step == STEP_REGISTERED) {
        inspect_reference_chooser(dialog, probe);
        ok_button = gtk_dialog_get_widget_for_response(GTK_DIALOG(dialog), GTK_RESPONSE_OK);
        probe->ok_sensitive = ok_button && gtk_widget_is_sensitive(ok_button);
        probe->graph_points = graph_points(dialog);
        widget = find_widget(dialog, GTK_TYPE_RADIO_BUTTON, "Continuous (line by line)");
        ck_assert_msg(widget, "no Continuous radio button");
        gtk_toggle_button_set_active(GTK_TOGGLE_BUTTON(widget), TRUE);
    }
    else if (probe->step == STEP_CONTINUOUS) {
        /* The longest status: registration and scan timing. */
        probe->saved = save_screenshot(dialog, SCREENSHOT);
        widget = find_labelled_spin(dialog, "Stripes:");
        ck_assert_msg(widget, "no stripes slider");
        move_stripes(widget, probe);
    }
    else {
        gtk_dialog_response(GTK_DIALOG(dialog), GTK_RESPONSE_OK);
        probe->answered = TRUE;
        return FALSE;
    }
    probe->step++;
    return TRUE;
}

/* Channel 0 the reference, 1 the drifting image (selected), 2 another
 * pixel size, 3 the same pixels but another physical size. */
static GwyContainer*
make_reference_container(void)
{
    FramePairSpec spec;
    FramePair *pair;
    GwyContainer *data = gwy_container_new();
    GwyDataField *field;
    const gdouble *values[2];
    gint i;

    frame_pair_spec_init(&spec);
    spec.xres = spec.yres = REF_SIZE;
    pair = frame_pair_generate(&spec, test_seed);
    values[0] = pair->reference;
    values[1] = pair->image;
    for (i = 0; i < 4; i++) {
        field = gwy_data_field_new(i == 2 ? REF_SIZE/2 : REF_SIZE, REF_SIZE,
                                   (i == 3 ? 2 : 1)*REF_SIZE*REF_STEP, REF_SIZE*REF_STEP, TRUE);
        if (i < 2)
            memcpy(gwy_data_field_get_data(field), values[i], REF_SIZE*REF_SIZE*sizeof(gdouble));
        gwy_si_unit_set_from_string(gwy_data_field_get_si_unit_xy(field), "m");
        gwy_container_set_object(data, gwy_app_get_data_key_for_id(i), field);
        g_object_unref(field);
    }
    gwy_container_set_const_string_by_name(data, "/0/data/title", (const guchar*)"Reference");
    gwy_container_set_const_string_by_name(data, "/1/data/title", (const guchar*)"Height");
    gwy_container_set_const_string_by_name(data, "/1/base/palette", (const guchar*)"Gray");
    gwy_app_data_browser_add(data);
    gwy_app_data_browser_select_data_field(data, 1);
    frame_pair_free(pair);
    return data;
}

START_TEST(test_reference_chooser_and_cache)
{
    GwyContainer *settings = gwy_app_settings_get();
    ReferenceProbe probe;
    DriftTable *table;
    guint timeout, handler;
    gint32 channel = -2;

    gwy_clear(&probe, 1);
    probe.data = make_reference_container();
    set_stored_table_settings();
    gwy_container_set_int32_by_name(settings, LOCALSCAN_SETTINGS_KEY(SOURCE), 2);
    gwy_container_set_int32_by_name(settings, LOCALSCAN_SETTINGS_KEY(STRIPES), 16);
    gwy_container_set_int32_by_name(settings, LOCALSCAN_SETTINGS_KEY(REFERENCE_CHANNEL), -1);
    registrations = 0;
    handler = g_log_set_handler(NULL, G_LOG_LEVEL_DEBUG, count_registrations, NULL);
    timeout = g_timeout_add(50, probe_reference_dialog, &probe);
    gwy_process_func_run(LOCALSCAN_FUNCTION_NAME, probe.data, GWY_RUN_INTERACTIVE);
    if (!probe.answered)
        g_source_remove(timeout);
    g_log_remove_handler(NULL, handler);

    printf("test-module-dialog: chooser offers %d channel(s), chose %d; registrations after each step: "
           "%d, %d, (stripes moving %d) %d, after OK %d; drift graph %d points\n",
           probe.offered, probe.chosen, probe.registrations[0], probe.registrations[1],
           probe.registrations_while_moving, probe.registrations[2], registrations, probe.graph_points);
    ck_assert_msg(probe.answered, "the dialog never reached step %d", probe.step);
    ck_assert_int_eq(probe.offered, 1);
    ck_assert_int_eq(probe.chosen, 0);
    ck_assert(!probe.offers_other_size && !probe.offers_other_real && !probe.offers_itself);
    ck_assert(probe.ok_sensitive);
    ck_assert_int_ge(probe.graph_points, 12);
    ck_assert_int_le(probe.graph_points, 16);
    ck_assert(probe.saved);
    /* Registered once for 16 stripes, not again for the mode, once more
     * for 8 stripes, and OK's final run reused that. */
    ck_assert_int_eq(probe.registrations[STEP_REGISTERED], 1);
    ck_assert_int_eq(probe.registrations[STEP_CONTINUOUS], 1);
    ck_assert_int_eq(probe.registrations_while_moving, 1);
    ck_assert_int_eq(probe.registrations[STEP_EIGHT_STRIPES], 2);
    ck_assert_int_eq(registrations, 2);

    ck_assert_int_eq(gui_count_channels(probe.data), 5);
    table = localscan_channel_stored_table(probe.data, 4, NULL);
    ck_assert(table);
    ck_assert_int_eq(table->n_stripes, 8);
    drift_table_free(table);
    ck_assert(gwy_container_gis_int32_by_name(settings, LOCALSCAN_SETTINGS_KEY(REFERENCE_CHANNEL), &channel));
    ck_assert_int_eq(channel, 0);

    gwy_app_data_browser_remove(probe.data);
    g_object_unref(probe.data);
}
END_TEST

/* Without a display the test starts itself again under xvfb-run, once. */
static void
ensure_display(gchar **argv)
{
    if (g_getenv("DISPLAY") && *g_getenv("DISPLAY"))
        return;
    if (g_getenv(RERUN_GUARD) || !g_find_program_in_path("xvfb-run")) {
        exit(test_skip_all("test-module-dialog", "no X display and no xvfb-run"));
    }
    g_setenv(RERUN_GUARD, "1", TRUE);
    execlp("xvfb-run", "xvfb-run", "-a", "-s", "-screen 0 1280x1024x24", argv[0], (gchar*)NULL);
    exit(test_skip_all("test-module-dialog", "cannot run xvfb-run"));
}

int
main(int argc, char **argv)
{
    const gchar *path = g_getenv("LOCALSCAN_MODULE");
    GError *error = NULL;
    Suite *suite;
    TCase *tc;

    ensure_display(argv);
    if (!path) {
        fprintf(stderr, "test-module-dialog: LOCALSCAN_MODULE is not set.\n");
        return 1;
    }
    test_seed = test_seed_from_env("test-module-dialog");
    gtk_init(&argc, &argv);
    gwy_app_init_nongui("enable-threads", FALSE, NULL);
    gwy_stock_register_stock_items();
    if (!gwy_module_register_module(path, &error)) {
        fprintf(stderr, "test-module-dialog: cannot load %s: %s\n", path, error->message);
        return 1;
    }

    suite = test_suite_new("module-dialog", "dialog", &tc);
    tcase_add_test(tc, test_bad_table_disables_ok);
    tcase_add_test(tc, test_good_table_ok_makes_channel);
    tcase_add_test(tc, test_status_names_timing_source);
    tcase_add_test(tc, test_status_names_left_out_stripe);
    tcase_add_test(tc, test_reference_chooser_and_cache);
    /* One X connection, one process. */
    return test_run_suite_forking(suite, FALSE);
}
