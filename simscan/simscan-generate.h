/*
 *  The main simscan command: simulate, measure by local scans, write.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef SIMSCAN_GENERATE_H
#define SIMSCAN_GENERATE_H

#include <glib.h>

G_BEGIN_DECLS

int  simscan_generate_main  (int argc, char **argv);

G_END_DECLS

#endif
