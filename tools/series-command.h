/*
 *  `gwy-localscan series`: a frame series corrected from one fitted drift
 *  trajectory (docs/series.md).
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_SERIES_COMMAND_H
#define LOCALSCAN_SERIES_COMMAND_H

/* argv[0] is "series"; returns the exit status. */
int series_command_main(int argc, char **argv);

#endif
