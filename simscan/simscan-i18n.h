/*
 *  Translation macros of simscan's messages: the project's gettext domain,
 *  after Gwyddion's headers (whose _() uses Gwyddion's own domain).
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef SIMSCAN_I18N_H
#define SIMSCAN_I18N_H

#include <libintl.h>
#include <libgwyddion/gwymacros.h>

#undef _
#define _(s) dgettext(GETTEXT_PACKAGE, s)
#ifndef N_
#define N_(s) (s)
#endif

#endif
