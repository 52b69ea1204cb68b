/*
 *  Steps through a regular layout that visit every position of it alike:
 *  the least step of at least some size that shares no factor with the
 *  layout's period.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_COPRIME_STEP_H
#define LOCALSCAN_COPRIME_STEP_H

#include <glib.h>

G_BEGIN_DECLS

/* The least step >= least (at least 1) sharing no factor with period:
 * stepping through items laid out with that period, it takes every
 * position in turn (a step of 2 through lines of 256 columns samples
 * even columns only).  A period of 0 or 1 has no factor to avoid. */
gsize        coprime_step         (gsize least,
                                   gsize period);

G_END_DECLS

#endif
