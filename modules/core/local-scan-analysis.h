/*
 *  What the lines of a local scan tell (the paper's Figure 1): the chords
 *  where a sampled line crosses the particle's threshold, their midpoints,
 *  which chord belongs to the particle, and the drift table the particles'
 *  displayed minus actual centres make.  The scanning itself (which lines,
 *  on which instrument) is the caller's: simscan/local-scan.c runs it on
 *  the simulator.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_LOCAL_SCAN_ANALYSIS_H
#define LOCALSCAN_LOCAL_SCAN_ANALYSIS_H

#include <glib.h>
#include "drift-table.h"

G_BEGIN_DECLS

/* One particle's local scan.  Pixel coordinates as in particle-detect.h. */
typedef struct {
    gboolean found;
    gint lines;                /* lines scanned, also when not found */
    gdouble x_disp, y_disp;    /* displayed centre, px */
    gdouble x_act, y_act;      /* actual centre at the local scan, px */
    gdouble y_line;            /* row of the line along x that found it, px */
    gdouble dx, dy;            /* displayed - actual, px */
    gdouble t_image;           /* when the displayed centre was scanned, s */
    gdouble t_local;           /* middle of the particle's local scan, s */
    gdouble t_start, t_end;    /* its first line's start, last line's end */
} LocalScanParticle;

/* The chords of a line of n >= 2 heights sampled evenly over length:
 * runs above threshold, their end points interpolated linearly between
 * samples.  Their midpoints (position along the line, relative to its
 * centre) replace the contents of mids (a GArray of gdouble).  Runs cut by
 * the line's ends are incomplete chords and never used. */
void         local_scan_chord_midpoints (const gdouble *heights,
                                         gint n,
                                         gdouble length,
                                         gdouble threshold,
                                         GArray *mids);

/* The midpoint in mids nearest to expect, skipping those already taken
 * (marked NaN) and those farther than limit from 0; it is marked taken.
 * FALSE when none is left. */
gboolean     local_scan_take_nearest_chord(GArray *mids,
                                           gdouble expect,
                                           gdouble limit,
                                           gdouble *mid);

/* Row s of a px drift table from particle r's local scan (NULL: the stripe
 * had no particle): dx, dy displayed minus actual rounded to whole pixels,
 * blank when the particle was not found; extra columns dx_exact, dy_exact,
 * t_image, t_local, x, y, lines, every one set on every row so the columns
 * keep their order and blank stripes get blank cells. */
void         local_scan_table_set_row   (DriftTable *table,
                                         gint s,
                                         const LocalScanParticle *r);

G_END_DECLS

#endif
