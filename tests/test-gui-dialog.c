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

#define SCREENSHOT TEST_BUILDDIR "/tests/gui-dialog.png"
#define SCREENSHOT_DE TEST_BUILDDIR "/tests/gui-dialog-de.png"
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

static GtkWidget*
find_dialog(void)
{
    GList *toplevels = gtk_window_list_toplevels(), *l;
    GtkWidget *dialog = NULL;

    for (l = toplevels; l; l = g_list_next(l)) {
        if (GTK_IS_DIALOG(l->data) && gtk_widget_get_visible(GTK_WIDGET(l->data)))
            dialog = GTK_WIDGET(l->data);
    }
    g_list_free(toplevels);
    return dialog;
}

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
flush_drawing(void)
{
    gint i;

    for (i = 0; i < 50 && gtk_events_pending(); i++)
        gtk_main_iteration_do(FALSE);
    gdk_window_process_all_updates();
    gdk_flush();
}

static gboolean
save_screenshot(GtkWidget *dialog, const gchar *filename, gint *width, gint *height)
{
    GdkWindow *window = gtk_widget_get_window(dialog);
    GdkPixbuf *pixbuf;
    GError *error = NULL;
    gboolean ok;

    gdk_window_raise(window);
    flush_drawing();
    gdk_drawable_get_size(GDK_DRAWABLE(window), width, height);
    pixbuf = gdk_pixbuf_get_from_drawable(NULL, GDK_DRAWABLE(window), NULL, 0, 0, 0, 0, *width, *height);
    if (!pixbuf)
        return FALSE;
    ok = gdk_pixbuf_save(pixbuf, filename, "png", &error, NULL);
    if (!ok)
        fprintf(stderr, "cannot save %s: %s\n", filename, error->message);
    g_clear_error(&error);
    g_object_unref(pixbuf);
    return ok;
}

/* Waits until the preview has computed (its status line is up), then
 * records what the dialog shows, photographs it and answers. */
static gboolean
probe_dialog(gpointer user_data)
{
    DialogProbe *probe = (DialogProbe*)user_data;
    GtkWidget *dialog = find_dialog(), *ok_button;

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
    probe->saved = save_screenshot(dialog, probe->screenshot, &probe->width, &probe->height);
    gtk_dialog_response(GTK_DIALOG(dialog), probe->response);
    return FALSE;
}

static void
run_dialog(GwyContainer *data, DialogProbe *probe)
{
    guint timeout;

    gwy_app_data_browser_add(data);
    gwy_app_data_browser_select_data_field(data, 0);
    probe->texts = g_string_new(NULL);
    timeout = g_timeout_add(TICK_MS, probe_dialog, probe);
    gwy_process_func_run(LOCALSCAN_FUNCTION_NAME, data, GWY_RUN_INTERACTIVE);
    /* The timeout is gone once it answered; a dialog that never came or
     * never got ready leaves it behind. */
    if (!probe->dialog)
        g_source_remove(timeout);
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
    gwy_clear(&probe, 1);
    probe.ready_text = ready;
    probe.screenshot = SCREENSHOT;
    probe.response = GTK_RESPONSE_OK;
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
    g_string_free(probe.texts, TRUE);
    g_free(probe.title);
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
    gwy_clear(&probe, 1);
    probe.ready_text = "Streifen";
    probe.screenshot = SCREENSHOT_DE;
    probe.response = GTK_RESPONSE_CANCEL;
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
    g_string_free(probe.texts, TRUE);
    g_free(probe.title);
}
END_TEST

int
main(void)
{
    const gchar *seed_env = g_getenv("LOCALSCAN_TEST_SEED");
    Suite *suite;
    TCase *tc;
    SRunner *sr;
    gint failed;

    if (!g_getenv("DISPLAY") || !*g_getenv("DISPLAY")) {
        printf("test-gui-dialog: SKIPPED: no X display (run it through tests/test-gui-dialog.sh)\n");
        return 77;
    }
    seed = seed_env ? (guint32)g_ascii_strtoull(seed_env, NULL, 10) : (guint32)g_random_int();
    printf("test-gui-dialog: seed %u (set LOCALSCAN_TEST_SEED to repeat)\n", seed);
    fflush(stdout);

    suite = suite_create("gui-dialog");
    tc = tcase_create("dialog");
    tcase_set_timeout(tc, 60);
    tcase_add_test(tc, test_dialog_ok_makes_channel);
    tcase_add_test(tc, test_dialog_in_german);
    suite_add_tcase(suite, tc);
    sr = srunner_create(suite);
    srunner_run_all(sr, CK_NORMAL);
    failed = srunner_ntests_failed(sr);
    srunner_free(sr);
    return failed ? 1 : 0;
}
