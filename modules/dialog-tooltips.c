/*
 *  Tooltips for the settings of a Gwyddion parameter table.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <string.h>
#include <libgwyddion/gwyddion.h>
#include "localscan-intl.h"
#include "dialog-tooltips.h"

/* A label's or button's text as the user reads it: no mnemonic
 * underscore, no colon the parameter table appends. */
static gchar*
plain_label(const gchar *text)
{
    GString *plain = g_string_new(NULL);
    const gchar *p;

    for (p = text; *p; p++) {
        if (*p != '_')
            g_string_append_c(plain, *p);
    }
    if (plain->len && plain->str[plain->len - 1] == ':')
        g_string_truncate(plain, plain->len - 1);
    return g_string_free(plain, FALSE);
}

static const gchar*
find_tooltip(const gchar *text, const DialogTooltip *tips, guint n)
{
    gboolean found;
    gchar *label;
    guint i;

    for (i = 0; i < n; i++) {
        label = plain_label(_(tips[i].label));
        found = gwy_strequal(label, text);
        g_free(label);
        if (found)
            return _(tips[i].tooltip);
    }
    return NULL;
}

void
dialog_tooltips_add(GtkWidget *widget, const DialogTooltip *tips, guint n)
{
    const gchar *text = NULL, *tooltip;
    GtkWidget *target;
    GList *children, *l;
    gchar *plain;

    if (GTK_IS_LABEL(widget))
        text = gtk_label_get_label(GTK_LABEL(widget));
    else if (GTK_IS_BUTTON(widget))
        text = gtk_button_get_label(GTK_BUTTON(widget));
    if (text) {
        plain = plain_label(text);
        if ((tooltip = find_tooltip(plain, tips, n))) {
            gtk_widget_set_tooltip_text(widget, tooltip);
            if (GTK_IS_LABEL(widget)
                && (target = gtk_label_get_mnemonic_widget(GTK_LABEL(widget))))
                gtk_widget_set_tooltip_text(target, tooltip);
        }
        g_free(plain);
    }
    if (!GTK_IS_CONTAINER(widget))
        return;
    children = gtk_container_get_children(GTK_CONTAINER(widget));
    for (l = children; l; l = g_list_next(l))
        dialog_tooltips_add(GTK_WIDGET(l->data), tips, n);
    g_list_free(children);
}
