/*
 *  Where the scan lines put a jump: each line's mismatch under the drift
 *  without the step and with it, weighed into a vote, and the split of
 *  the lines (in scan order) that the votes favour.  docs/series.md, step 5.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_JUMP_VOTES_H
#define LOCALSCAN_JUMP_VOTES_H

#include <glib.h>

G_BEGIN_DECLS

/* What the frames near a line tell of which side of the jump it lies on:
 * its mean mismatch (each the lowest within half a pixel of the place the
 * fitted drift predicts) under the drift without the step and with it
 * over the frames that show its content under both (two_sided), else over those
 * that show it under one of them only (a line at a frame's edge, whose
 * content the step takes out of every other frame), with the mismatch of
 * that one side's content displaced by the step once more (control): what
 * being a step off costs this line's content. */
typedef struct {
    gdouble before, after;   /* mean mismatches; NAN where not seen */
    gboolean two_sided;
    gdouble control;         /* one-sided only; NAN where not seen */
    gdouble texture;         /* one-sided only: the line's mean square after
                                its quadratic over the pixels its one
                                drift predicts; NAN otherwise */
    gdouble nearby;          /* one-sided only: the lowest mismatch of its
                                content a pixel off the best place its one
                                drift predicts (left, right, up or down); NAN
                                where not seen */
    gdouble unrelated;       /* one-sided only: what content unrelated to the
                                line would cost, its texture plus that of
                                the content its one drift predicts; NAN
                                otherwise */
    gboolean frame_edge;     /* the first or last line its frame scanned */
} LineEvidence;

/* The best splits of lines 0 .. n-1, in the order they were scanned (frame
 * gives each line's frame): split i puts lines 0 .. i-1 before the jump
 * and i .. n-1 after it, and every split from first to last is equally
 * good.  FALSE when the lines do not place the jump (fewer than two, or
 * all on one side). */
gboolean     jump_votes_split     (const LineEvidence *evidence,
                                   const gint *frame,
                                   gint n,
                                   gint *first,
                                   gint *last);

/* The same, and the splits loose_first .. loose_last that differ from the
 * best only by lines whose evidence is weak (below a tenth of a typical
 * line's) or unsure (a frame's edge line seen under one drift only): where
 * the data leaves the jump, whatever the split chosen. */
gboolean     jump_votes_split_loose(const LineEvidence *evidence,
                                    const gint *frame,
                                    gint n,
                                    gint *first,
                                    gint *last,
                                    gint *loose_first,
                                    gint *loose_last);

G_END_DECLS

#endif
