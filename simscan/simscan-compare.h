/*
 *  `simscan compare FILE.gwy`: particle-centre errors of a simulator file
 *  after another tool (gwy-localscan) compensated it, and PNG pictures of
 *  the contaminated, compensated and true channels.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef SIMSCAN_COMPARE_H
#define SIMSCAN_COMPARE_H

#include <glib.h>

G_BEGIN_DECLS

int  simscan_compare_main  (int argc, char **argv);

G_END_DECLS

#endif
