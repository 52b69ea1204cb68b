/*
 *  Independent tasks spread over the processor's cores.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include "parallel-run.h"

typedef struct {
    ParallelTask task;
    gpointer data;
    gint next;
    gint end;
} ParallelRun;

/* Takes the next index until none is left: tasks of unequal cost keep
 * every thread busy. */
static gpointer
parallel_worker(gpointer data)
{
    ParallelRun *run = data;
    gint index;

    while ((index = g_atomic_int_add(&run->next, 1)) < run->end)
        run->task(run->data, index);
    return NULL;
}

void
parallel_run(gint first, gint end, ParallelTask task, gpointer data)
{
    ParallelRun run = { task, data, first, end };
    gint n_threads = MIN((gint)g_get_num_processors(), end - first), t;
    GThread **threads;

    if (n_threads <= 1) {
        parallel_worker(&run);
        return;
    }
    threads = g_new(GThread*, n_threads - 1);
    for (t = 0; t < n_threads - 1; t++)
        threads[t] = g_thread_new("localscan-worker", parallel_worker, &run);
    parallel_worker(&run);
    for (t = 0; t < n_threads - 1; t++)
        g_thread_join(threads[t]);
    g_free(threads);
}
