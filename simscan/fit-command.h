/*
 *  `simscan fit`: the command line over the core's fit of a frame
 *  series (modules/core/fit-report.h).
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef SIMSCAN_FIT_COMMAND_H
#define SIMSCAN_FIT_COMMAND_H

#include <glib.h>
#include "fit-report.h"

G_BEGIN_DECLS

/* The subcommand; argv[0] is "fit".  Returns the exit status. */
int       simscan_fit_main    (int argc, char **argv);

G_END_DECLS

#endif
