/*
 *  Progress of a long computation told to whoever waits for it (a wait
 *  dialog), which may stop it.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_PROGRESS_H
#define LOCALSCAN_PROGRESS_H

#include <glib.h>

G_BEGIN_DECLS

/* How far the computation has come, 0 to 1; returns FALSE to stop it.
 * Called from the thread that started the computation only. */
typedef gboolean (*ProgressFunc)(gdouble fraction, gpointer user_data);

/* A part of a computation: its own fractions 0 to 1 are reported as
 * from .. to of the whole.  func NULL: nothing is reported, nothing
 * stops. */
typedef struct {
    ProgressFunc func;
    gpointer user_data;
    gdouble from, to;
} Progress;

/* The part from .. to (fractions of the whole) of progress whole (NULL:
 * none). */
static inline Progress
progress_part(const Progress *whole, gdouble from, gdouble to)
{
    Progress part = { NULL, NULL, 0.0, 1.0 };

    if (whole && whole->func) {
        part = *whole;
        part.from = whole->from + from*(whole->to - whole->from);
        part.to = whole->from + to*(whole->to - whole->from);
    }
    return part;
}

/* Reports fraction of the part; FALSE when the computation is to stop. */
static inline gboolean
progress_report(const Progress *progress, gdouble fraction)
{
    if (!progress || !progress->func)
        return TRUE;
    fraction = CLAMP(fraction, 0.0, 1.0);
    return progress->func(progress->from + fraction*(progress->to - progress->from),
                          progress->user_data);
}

G_END_DECLS

#endif
