/*
 *  Independent tasks spread over the processor's cores.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_PARALLEL_RUN_H
#define LOCALSCAN_PARALLEL_RUN_H

#include <glib.h>

G_BEGIN_DECLS

typedef void (*ParallelTask)(gpointer data, gint index);

/* Runs task(data, index) for every index from first to end - 1 on up to
 * g_get_num_processors() threads (the caller's among them) and returns
 * when all are done.  Tasks must not depend on each other or on their
 * order: each should write only its own results. */
void parallel_run(gint first, gint end, ParallelTask task, gpointer data);

G_END_DECLS

#endif
