/*
 *  Translatable messages of the GTK-free core: _() and N_() in the
 *  project's own gettext domain (GETTEXT_PACKAGE), as the module and the
 *  tools translate theirs.  Include it after every other header (Gwyddion's
 *  gwymacros.h defines _() for Gwyddion's domain).
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_INTL_H
#define LOCALSCAN_INTL_H

#include <libintl.h>
#include <glib.h>

/* dgettext, not g_dgettext: GLib's turns all translation off when the
 * program's default domain (Gwyddion's) has no catalogue for a
 * non-English locale, and the core's messages would then stay English
 * beside the tool's and the module's translated ones. */
#undef _
#undef N_
#define _(s) dgettext(GETTEXT_PACKAGE, s)
#define N_(s) (s)

#endif
