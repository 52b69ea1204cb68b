/*
 *  The drift trajectory's CSV format (docs/cli.md, docs/benchmark.md):
 *  comment lines, the header frame,row,t_s,dx_px,dy_px, one line per scan
 *  line with p(t) - p(0) in pixels.  Written by the series correction and
 *  the benchmark, read by the benchmark's scorer.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_TRAJECTORY_CSV_H
#define LOCALSCAN_TRAJECTORY_CSV_H

#include <glib.h>

G_BEGIN_DECLS

#define TRAJECTORY_CSV_HEADER "frame,row,t_s,dx_px,dy_px"

/* The comment lines (what the values are, in pixels of xstep x ystep m;
 * `what` names the trajectory, e.g. "drift trajectory") and the header. */
void      trajectory_csv_begin  (GString *text,
                                 const gchar *what,
                                 gdouble xstep,
                                 gdouble ystep);
/* One scan line; dx, dy with `decimals` digits after the point. */
void      trajectory_csv_line   (GString *text,
                                 gint frame,
                                 gint row,
                                 gdouble t,
                                 gdouble dx,
                                 gdouble dy,
                                 gint decimals);

/* A trajectory read back: per frame and row (frame*yres + row) the time
 * and (dx, dy), have[] TRUE where the file gives that line. */
typedef struct {
    gint n_frames, yres;
    gdouble *t, *dx, *dy;
    gboolean *have;
} TrajectoryTable;

/* Parses text of a series of n_frames frames of yres rows strictly: the
 * header must come first after comments, every value must be a finite
 * number, frame and row within range, no line twice.  NULL on success,
 * else why (one line, "line N: ...", g_free it); table is filled either
 * way and freed with trajectory_table_free. */
gchar*    trajectory_csv_parse  (const gchar *text,
                                 gint n_frames,
                                 gint yres,
                                 TrajectoryTable *table);
void      trajectory_table_free (TrajectoryTable *table);

G_END_DECLS

#endif
