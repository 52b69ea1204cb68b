/*
 *  Output rows as weighted sums of a few rows, written past the caches.
 *  Internal to the core.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_ROW_COMBINE_H
#define LOCALSCAN_ROW_COMBINE_H

#include <glib.h>

G_BEGIN_DECLS

/* dest = src. */
void     row_copy_streamed      (const gdouble *restrict src,
                                 gint n,
                                 gdouble *restrict dest);
/* dest = sum of w[k] rows[k], k = 0 .. 3; the outer rows are not read (and
 * may be NULL) when both their weights are zero. */
void     row_combine_streamed   (const gdouble **rows,
                                 const gdouble *w,
                                 gint n,
                                 gdouble *restrict dest);
/* Call once after the last streamed row, before the rows are used. */
void     row_stream_finish      (void);

G_END_DECLS

#endif
