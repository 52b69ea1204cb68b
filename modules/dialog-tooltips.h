/*
 *  Tooltips for the settings of a Gwyddion parameter table, which offers
 *  none of its own: found by the labels' text.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_DIALOG_TOOLTIPS_H
#define LOCALSCAN_DIALOG_TOOLTIPS_H

#include <gtk/gtk.h>

G_BEGIN_DECLS

/* A setting's label (as the parameter definition gives it, untranslated,
 * mnemonic underscores and a trailing colon not counting) and its
 * tooltip. */
typedef struct {
    const gchar *label;
    const gchar *tooltip;
} DialogTooltip;

/* Gives every label and button below widget whose text is one of the n
 * labels its tooltip, and a label's tooltip to the widget it names too. */
void     dialog_tooltips_add      (GtkWidget *widget,
                                   const DialogTooltip *tips,
                                   guint n);

G_END_DECLS

#endif
