/*
 *  simscan's command line: options in user units (nm, um, s) into a
 *  SimscanConfig, presets first so that later options override them.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef SIMSCAN_OPTIONS_H
#define SIMSCAN_OPTIONS_H

#include <glib.h>
#include "simscan-config.h"

G_BEGIN_DECLS

/* Parses argv (argv[0] the command's name) into config, which must have
 * been initialised.  extra (may be NULL) are the subcommand's own options,
 * parsed along.  On a bad option returns FALSE with a one-line message.
 * --help prints every option and exits with status 0. */
gboolean  simscan_options_parse  (gint argc,
                                  gchar **argv,
                                  const gchar *usage,
                                  const GOptionEntry *extra,
                                  SimscanConfig *config,
                                  GError **error);

G_END_DECLS

#endif
