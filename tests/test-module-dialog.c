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

#define FUNC_NAME "localscan_drift"
#define SETTINGS_PREFIX "/module/localscan_drift/"
#define RERUN_GUARD "LOCALSCAN_TEST_UNDER_XVFB"
#define MAX_TICKS 100

static const gchar worked_table[] = "stripe,dx,dy\n0,1,1\n1,-1,0\n2,0,-1\n";
static const gdouble worked_c[6*4] = {
    6.0,  7.0,  8.0,  12.5,
    12.5, 9.0,  10.0, 11.0,
    12.5, 9.0,  10.0, 11.0,
    12.5, 13.0, 14.0, 15.0,
    12.5, 13.0, 14.0, 15.0,
    17.0, 18.0, 19.0, 20.0,
};

/* What the timeout found in the dialog, and how it answered. */
typedef struct {
    const gchar *wait_for_text;
    gint response;
    gint ticks;
    gboolean found_dialog;
    gboolean found_text;
    gboolean ok_sensitive;
    gboolean answered;
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

    gwy_container_set_int32_by_name(settings, SETTINGS_PREFIX "source", 0);
    gwy_container_set_int32_by_name(settings, SETTINGS_PREFIX "mode", 0);
    gwy_container_set_int32_by_name(settings, SETTINGS_PREFIX "fill", 0);
    gwy_container_set_boolean_by_name(settings, SETTINGS_PREFIX "add-mask", TRUE);
    gwy_container_set_boolean_by_name(settings, SETTINGS_PREFIX "plot-drift", FALSE);
}

static GtkWidget*
find_module_dialog(void)
{
    GList *toplevels = gtk_window_list_toplevels(), *l;
    GtkWidget *dialog = NULL;

    for (l = toplevels; l; l = g_list_next(l)) {
        if (GWY_IS_DIALOG(l->data) && gtk_widget_get_visible(GTK_WIDGET(l->data)))
            dialog = GTK_WIDGET(l->data);
    }
    g_list_free(toplevels);
    return dialog;
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
    GtkWidget *dialog = find_module_dialog(), *ok_button;

    if (!dialog)
        return TRUE;
    probe->ticks++;
    probe->found_dialog = TRUE;
    probe->found_text = widget_shows_text(dialog, probe->wait_for_text);
    if (!probe->found_text && probe->ticks < MAX_TICKS)
        return TRUE;
    ok_button = gtk_dialog_get_widget_for_response(GTK_DIALOG(dialog), GTK_RESPONSE_OK);
    probe->ok_sensitive = ok_button && gtk_widget_is_sensitive(ok_button);
    gtk_dialog_response(GTK_DIALOG(dialog), probe->response);
    probe->answered = TRUE;
    return FALSE;
}

static gint
count_channels(GwyContainer *data)
{
    gint *ids = gwy_app_data_browser_get_data_ids(data), n = 0;

    while (ids[n] != -1)
        n++;
    g_free(ids);
    return n;
}

static void
run_dialog(GwyContainer *data, DialogProbe *probe)
{
    guint timeout = g_timeout_add(50, probe_dialog, probe);

    gwy_process_func_run(FUNC_NAME, data, GWY_RUN_INTERACTIVE);
    if (!probe->answered)
        g_source_remove(timeout);
}

START_TEST(test_bad_table_disables_ok)
{
    GwyContainer *data = make_container("stripe,dx,dy\n0,abc,1\n");
    DialogProbe probe = { "channel 0 drift table:2", GTK_RESPONSE_CANCEL, 0, FALSE, FALSE, TRUE, FALSE };

    set_stored_table_settings();
    run_dialog(data, &probe);
    ck_assert(probe.found_dialog);
    ck_assert_msg(probe.found_text, "the dialog does not show the parser's message");
    ck_assert(!probe.ok_sensitive);
    ck_assert_int_eq(count_channels(data), 1);
    gwy_app_data_browser_remove(data);
    g_object_unref(data);
}
END_TEST

START_TEST(test_good_table_ok_makes_channel)
{
    GwyContainer *data = make_container(worked_table);
    DialogProbe probe = { "3 stripes, 5 filled pixels.", GTK_RESPONSE_OK, 0, FALSE, FALSE, FALSE, FALSE };
    GwyDataField *result = NULL, *mask = NULL;
    const guchar *title = NULL;
    gint i;

    set_stored_table_settings();
    run_dialog(data, &probe);
    ck_assert(probe.found_dialog);
    ck_assert_msg(probe.found_text, "the dialog does not show the stripe summary");
    ck_assert(probe.ok_sensitive);
    ck_assert_int_eq(count_channels(data), 2);
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

/* Without a display the test starts itself again under xvfb-run, once. */
static void
ensure_display(gchar **argv)
{
    if (g_getenv("DISPLAY") && *g_getenv("DISPLAY"))
        return;
    if (g_getenv(RERUN_GUARD) || !g_find_program_in_path("xvfb-run")) {
        printf("test-module-dialog: SKIPPED: no X display and no xvfb-run\n");
        exit(77);
    }
    g_setenv(RERUN_GUARD, "1", TRUE);
    execlp("xvfb-run", "xvfb-run", "-a", argv[0], (gchar*)NULL);
    printf("test-module-dialog: SKIPPED: cannot run xvfb-run\n");
    exit(77);
}

int
main(int argc, char **argv)
{
    const gchar *path = g_getenv("LOCALSCAN_MODULE");
    GError *error = NULL;
    Suite *suite;
    TCase *tc;
    SRunner *sr;
    gint failed;

    ensure_display(argv);
    if (!path) {
        fprintf(stderr, "test-module-dialog: LOCALSCAN_MODULE is not set.\n");
        return 1;
    }
    gtk_init(&argc, &argv);
    gwy_app_init_nongui("enable-threads", FALSE, NULL);
    gwy_stock_register_stock_items();
    if (!gwy_module_register_module(path, &error)) {
        fprintf(stderr, "test-module-dialog: cannot load %s: %s\n", path, error->message);
        return 1;
    }

    suite = suite_create("module-dialog");
    tc = tcase_create("dialog");
    tcase_add_test(tc, test_bad_table_disables_ok);
    tcase_add_test(tc, test_good_table_ok_makes_channel);
    suite_add_tcase(suite, tc);
    sr = srunner_create(suite);
    /* One X connection, one process. */
    srunner_set_fork_status(sr, CK_NOFORK);
    srunner_run_all(sr, CK_NORMAL);
    failed = srunner_ntests_failed(sr);
    srunner_free(sr);
    return failed ? EXIT_FAILURE : EXIT_SUCCESS;
}
