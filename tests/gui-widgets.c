/*
 *  What the dialog tests on a (virtual) X display share: finding the
 *  dialog and its widgets, letting GTK draw, photographing a window,
 *  clicking a list's cell and counting a file's channels.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <stdio.h>
#include <app/gwyapp.h>
#include "gui-widgets.h"

/* The last visible toplevel dialog of the type (GtkDialog or a subtype). */
GtkWidget*
gui_find_visible_dialog(GType type)
{
    GList *toplevels = gtk_window_list_toplevels(), *l;
    GtkWidget *dialog = NULL;

    for (l = toplevels; l; l = g_list_next(l)) {
        if (G_TYPE_CHECK_INSTANCE_TYPE(l->data, type)
            && gtk_widget_get_visible(GTK_WIDGET(l->data)))
            dialog = GTK_WIDGET(l->data);
    }
    g_list_free(toplevels);
    return dialog;
}

GtkWidget*
gui_find_titled_dialog(const gchar *title)
{
    GList *toplevels = gtk_window_list_toplevels(), *l;
    GtkWidget *dialog = NULL;

    for (l = toplevels; l && !dialog; l = g_list_next(l)) {
        if (GTK_IS_DIALOG(l->data) && gtk_widget_get_visible(GTK_WIDGET(l->data))
            && !g_strcmp0(gtk_window_get_title(GTK_WINDOW(l->data)), title))
            dialog = GTK_WIDGET(l->data);
    }
    g_list_free(toplevels);
    return dialog;
}

/* The widget itself or the first one below it with the name. */
GtkWidget*
gui_find_named_widget(GtkWidget *widget, const gchar *name)
{
    GList *children, *l;
    GtkWidget *found = NULL;

    if (!g_strcmp0(gtk_widget_get_name(widget), name))
        return widget;
    if (!GTK_IS_CONTAINER(widget))
        return NULL;
    children = gtk_container_get_children(GTK_CONTAINER(widget));
    for (l = children; l && !found; l = g_list_next(l))
        found = gui_find_named_widget(GTK_WIDGET(l->data), name);
    g_list_free(children);
    return found;
}

/* Lets pending events run (a bounded number: a preview may keep adding
 * them) and the windows draw, so that a photograph shows them. */
void
gui_flush_drawing(void)
{
    gint i;

    for (i = 0; i < 50 && gtk_events_pending(); i++)
        gtk_main_iteration_do(FALSE);
    gdk_window_process_all_updates();
    gdk_flush();
}

/* Photographs the widget's window, raised and drawn, to the PNG filename;
 * its size in width and height. */
gboolean
gui_save_screenshot(GtkWidget *widget, const gchar *filename,
                    gint *width, gint *height)
{
    GdkWindow *window = gtk_widget_get_window(widget);
    GdkPixbuf *pixbuf;
    GError *error = NULL;
    gboolean ok;

    gdk_window_raise(window);
    gui_flush_drawing();
    gdk_drawable_get_size(GDK_DRAWABLE(window), width, height);
    pixbuf = gdk_pixbuf_get_from_drawable(NULL, GDK_DRAWABLE(window), NULL,
                                          0, 0, 0, 0, *width, *height);
    if (!pixbuf)
        return FALSE;
    ok = gdk_pixbuf_save(pixbuf, filename, "png", &error, NULL);
    if (!ok)
        fprintf(stderr, "cannot save %s: %s\n", filename, error->message);
    g_clear_error(&error);
    g_object_unref(pixbuf);
    return ok;
}

gint
gui_count_channels(GwyContainer *data)
{
    gint *ids = gwy_app_data_browser_get_data_ids(data), n = 0;

    while (ids[n] >= 0)
        n++;
    g_free(ids);
    return n;
}

/* The row scrolled into view and drawn first: a click lands where the
 * cell is shown, in the view's bin window. */
gboolean
gui_click_tree_cell(GtkTreeView *view, gint row, gint column)
{
    GtkTreePath *path = gtk_tree_path_new_from_indices(row, -1);
    GtkTreeViewColumn *col = gtk_tree_view_get_column(view, column);
    GdkWindow *bin = gtk_tree_view_get_bin_window(view);
    GdkRectangle cell;
    gboolean ok = FALSE;
    gint x, y;

    if (col && bin) {
        gtk_tree_view_scroll_to_cell(view, path, NULL, FALSE, 0.0, 0.0);
        gui_flush_drawing();
        gtk_tree_view_get_cell_area(view, path, col, &cell);
        x = cell.x + cell.width/2;
        y = cell.y + cell.height/2;
        ok = (cell.height > 0
              && gdk_test_simulate_button(bin, x, y, 1, 0, GDK_BUTTON_PRESS)
              && gdk_test_simulate_button(bin, x, y, 1, 0, GDK_BUTTON_RELEASE));
        gui_flush_drawing();
    }
    gtk_tree_path_free(path);
    return ok;
}
