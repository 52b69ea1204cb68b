/*
 *  What the dialog tests on a (virtual) X display share: finding the
 *  dialog and its widgets, letting GTK draw, photographing a window,
 *  clicking a list's cell and counting a file's channels.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_GUI_WIDGETS_H
#define LOCALSCAN_GUI_WIDGETS_H

#include <gtk/gtk.h>
#include <libgwyddion/gwyddion.h>

GtkWidget* gui_find_visible_dialog(GType type);
/* The visible dialog with this title (of several open at once). */
GtkWidget* gui_find_titled_dialog (const gchar *title);
GtkWidget* gui_find_named_widget  (GtkWidget *widget,
                                   const gchar *name);
void       gui_flush_drawing      (void);
gboolean   gui_save_screenshot    (GtkWidget *widget,
                                   const gchar *filename,
                                   gint *width,
                                   gint *height);
gint       gui_count_channels     (GwyContainer *data);
/* A click of mouse button 1 on the cell of row and column, as the X
 * server delivers it; FALSE when the row is not shown or the click could
 * not be sent. */
gboolean   gui_click_tree_cell    (GtkTreeView *view,
                                   gint row,
                                   gint column);

#endif
