/*
 *  Local Scan Series Drift, the module's second process function
 *  (docs/series.md).
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_SERIES_PROCESS_H
#define LOCALSCAN_SERIES_PROCESS_H

#define LOCALSCAN_SERIES_FUNCTION_NAME "localscan_series"

/* Registers the process function (from the module's registration). */
void localscan_series_register(void);

#endif
