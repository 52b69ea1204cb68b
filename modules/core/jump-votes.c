/*
 *  Where the scan lines put a jump: from each line's evidence to the split
 *  of the lines that the evidence favours.  docs/series.md, step 5.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <math.h>
#include <libgwyddion/gwyddion.h>
#include "jump-votes.h"
#include "median.h"

/* A one-sided line's cost is placed on the scale from the typical cost of
 * a line under its right drift (match: noise and interpolation) to its
 * control, the cost of its content a step off.  Under the right drift the
 * cost is about the match level and the control a step's displacement;
 * under the wrong one the cost is a step's displacement and the control
 * two, which costs at most four times as much (displacements small beside
 * the content's features cost as their square): above a fifth of the
 * scale the side is wrong.  Below it the line lies on its side only where
 * its content sits exactly where that drift puts it: its cost is lower
 * than a pixel off in any direction (nearby; both measured from the best
 * place within half a pixel of the drift's, series-correction.c).  The
 * scale alone does not tell: lines after a jump cost 0.12 and 0.15 of it
 * (their content at the frame's edge, seeds 560100016 and 560100232 of
 * test-series-correction), lines before one 0.10 and 0.14 (content that
 * merely resembles what lies a step away, seeds 572000020 and 572000004),
 * but the first were minima (1.3-1.5 times lower than a pixel off) and the
 * second not (0.6-1.0; these figures measured at the exact place): a
 * step off, a line meets other content, whose mismatch does not rise on
 * every side.  A line below a fifth that is no minimum, or no match at
 * all (ONE_SIDED_RELATED), tells nothing.
 * And only a line whose own texture and control both stand well above the
 * match level is judged at all: a featureless line, or one whose features
 * a step hardly moves, costs about the same under either drift, and a
 * featureless line matches featureless content a step off as well as its
 * own while its control may meet a particle (seed 21).  A line matching
 * better than the match level is judged where its control stands that
 * far above its own cost (and above the match level): the match level is
 * the median line's, and the lines after a jump 1.5 s before a frame's
 * end matched five times better (6.3e-19 against 3.3e-18) with a control
 * only 6.5 times the level; told nothing, they let the jump go 2 s late,
 * 5.3 px on a textured line (test-series-correction seed 20000352, case
 * 504). */
#define ONE_SIDED_MISMATCH 0.2
#define ONE_SIDED_CONTRAST 8.0
/* A minimum means something only where the line resembles the content its
 * drift predicts: below this fraction of what unrelated content costs
 * (the two textures summed).  A textured line whose content that drift
 * puts on featureless lines costs its own texture there, and a pixel off
 * just the same: noise made it a "minimum", 0.98 of unrelated, and a line
 * before a jump voted after it (test-series-correction seed 1603438049,
 * case 809).  True matches of 600 drawn end-of-frame jumps cost at most
 * 0.57 of unrelated, 0.24 at the 99th percentile. */
#define ONE_SIDED_RELATED 0.75
/* A line that resembles its predicted content this closely is where that
 * drift puts it even where a pixel off costs less: the fitted drift is a
 * fraction of a pixel off there (a jump placed late leaves the step and
 * the velocity slightly wrong).  12 % of the true matches of 600 drawn
 * end-of-frame jumps were no minimum; 255 of those 365 cost below 0.05 of
 * unrelated content (median 0.036), lines on the wrong side 0.063 and up
 * (minima by a mirror image) or 0.26 and up (no minimum).  Without it the
 * lines after a jump 5.5 lines before a frame's end, 1.2 and 0.7 times
 * as costly as a pixel off, told nothing, and the jump went 4 lines late
 * (5.8 px on a textured line; test-series-correction seed 740000384). */
#define ONE_SIDED_CLOSE 0.05

/* Whether a one-sided line is nearly featureless beside the content its
 * one drift predicts (that content's texture above ONE_SIDED_CONTRAST
 * times its own) and matches that content no better than unrelated
 * content: the drift is wrong, whatever the match level of textured lines
 * says (a featureless line's right match costs its noise, its texture).
 * Judged by the match level only, the featureless lines just before a
 * jump, which the drift after it puts on a particle (their cost 0.95 of
 * unrelated, 17 times their texture), told nothing, and two featureless
 * lines 8 lines earlier that leaned after it by noise placed the jump
 * there: 4.3 px on the textured lines between (test-series-correction
 * seed 40100081, case 634).  Nor may its content a step further off (its
 * control) match better: a featureless line after a jump whose right
 * drift, a fraction of a pixel off, puts it on a particle's edge costs
 * 0.93 of unrelated content too, but its control, on the particle, four
 * times more, and it lies where that drift puts it (seed 62000007,
 * case 1119: voted before the jump, the jump's lines went unreported). */
static gboolean
featureless_on_texture(const LineEvidence *ev, gdouble cost)
{
    return (!isnan(ev->unrelated) && !isnan(cost) && !isnan(ev->control)
            && ev->unrelated - ev->texture > ONE_SIDED_CONTRAST*ev->texture
            && cost >= ONE_SIDED_RELATED*ev->unrelated && cost >= ev->control);
}

/* Costs without and with the step of each line, as steady_votes() weighs
 * them (0 and 0: no evidence).  A line seen under one drift only is given
 * a cost under the other: where its content matches, that of a step off
 * (its control); where it does not, the typical match of the two-sided
 * lines.  Without this, the lines after a jump of a few rows at the end of
 * a frame followed by a flagged one, whose content the step takes out of
 * every later frame, told nothing, and the jump was placed in the flagged
 * frame: 5.4 px on those lines (test-series-correction seed 310000476).
 * Judged against unrelated content instead of the control, a line 3 px
 * off matched well enough to pull a jump out of the flagged frame into
 * the end of the one before (seed 350000212).  Without two-sided lines
 * there is no match level and no one-sided line is judged; a line that
 * some frames show under one drift only and others under the other only
 * is not judged either (its two costs come from different frames). */
static gdouble
evidence_costs(const LineEvidence *ev, gint n, gdouble *before, gdouble *after)
{
    gdouble *right = g_new(gdouble, MAX(n, 1)), match, cost, other, q;
    gint i, m = 0;

    for (i = 0; i < n; i++) {
        if (ev[i].two_sided)
            right[m++] = MIN(ev[i].before, ev[i].after);
    }
    match = m ? median_in_place(right, m) : NAN;
    g_free(right);
    for (i = 0; i < n; i++) {
        before[i] = after[i] = 0.0;
        if (ev[i].two_sided) {
            before[i] = ev[i].before;
            after[i] = ev[i].after;
            continue;
        }
        cost = isnan(ev[i].before) ? ev[i].after : ev[i].before;
        if (featureless_on_texture(ev + i, cost)) {
            before[i] = isnan(ev[i].before) ? ev[i].texture : cost;
            after[i] = isnan(ev[i].before) ? cost : ev[i].texture;
            continue;
        }
        if (!m || isnan(ev[i].control)
            || !(ev[i].control > ONE_SIDED_CONTRAST*match
                 || (cost < match && ev[i].control > match
                     && ev[i].control > ONE_SIDED_CONTRAST*cost))
            || !(2.0*ev[i].texture > ONE_SIDED_CONTRAST*match))
            continue;
        q = (cost - match)/(ev[i].control - match);
        if (q >= ONE_SIDED_MISMATCH)
            other = match;
        else if ((cost < ev[i].nearby
                  && cost < ONE_SIDED_RELATED*ev[i].unrelated)
                 || cost < ONE_SIDED_CLOSE*ev[i].unrelated)
            other = ev[i].control;
        else
            continue;
        before[i] = isnan(ev[i].before) ? other : cost;
        after[i] = isnan(ev[i].before) ? cost : other;
    }
    return match;
}

/* Evidence below this fraction of a typical line's is weak; so is that of
 * a line whose worse cost stays below this many times the match level. */
#define JUMP_WEAK_EVIDENCE 0.1
#define JUMP_CLEAR_CONTRAST 4.0

/* The median of the vote of line i and its neighbours in the same frame.
 * A frame's first or last line has one neighbour: the two count only when
 * they agree, by the weaker of them. */
static gdouble
median_vote(const gdouble *raw, const gint *frame, gint n, gint i)
{
    gdouble v[3];
    gint j, m = 0;

    for (j = MAX(i - 1, 0); j <= MIN(i + 1, n - 1); j++) {
        if (frame[j] == frame[i])
            v[m++] = raw[j];
    }
    if (m == 3)
        return median_in_place(v, 3);
    if (m == 2)
        return (v[0]*v[1] > 0.0) ? (fabs(v[0]) < fabs(v[1]) ? v[0] : v[1]) : 0.0;
    return v[0];
}

/* The evidence of each line, its cost without the step minus its cost
 * with it (positive: the line lies after the jump); returns the level
 * below which a line's evidence is weak.  A line with the
 * evidence of a typical line (a tenth of the median over the lines with
 * any) speaks for itself: the one line after a jump before a frame's
 * unseen last lines must count (seed 5000182).  A weak line, nearly
 * featureless, counts by the median of itself and its neighbours in the
 * frame: alone against the lines around it, it must not move a jump
 * across a frame boundary (seed 3000021), while a run of weak lines that
 * agree still counts (seed 2000427).  So does a line seen under both
 * drifts whose costs both lie within the reach of a right match (below
 * JUMP_CLEAR_CONTRAST times the match level; a one-sided line was judged
 * against its control already, and its made-up other cost is no such
 * measure): a nearly featureless line at a particle's edge, which the
 * other frame shows a fraction of a pixel off under the right drift,
 * costs twice the match level there and nothing under the wrong drift
 * that moves the particle away; counted by itself, against a run of
 * featureless lines that leaned the other way, it moved a jump 7 lines
 * late (test-series-correction seed 370001572, case 3: 4.4 px on those
 * lines). */
static gdouble
steady_votes(const gdouble *before, const gdouble *after,
             const LineEvidence *ev, const gint *frame, gint n, gdouble match,
             gdouble *votes)
{
    gdouble *raw = g_new(gdouble, 2*MAX(n, 1)), *strength = raw + MAX(n, 1);
    gdouble strong;
    gint i, m = 0;

    for (i = 0; i < n; i++) {
        raw[i] = before[i] - after[i];
        if (before[i] + after[i] > 0.0)
            strength[m++] = fabs(raw[i]);
    }
    strong = m ? JUMP_WEAK_EVIDENCE*median_in_place(strength, m) : 0.0;
    for (i = 0; i < n; i++) {
        if (fabs(raw[i]) >= strong
            && !(ev[i].two_sided
                 && MAX(before[i], after[i]) <= JUMP_CLEAR_CONTRAST*match))
            votes[i] = raw[i];
        else
            votes[i] = median_vote(raw, frame, n, i);
    }
    g_free(raw);
    return strong;
}

/* Split i: lines 0 .. i-1 before the jump, i .. n-1 after it; the best
 * splits are first .. last.  Costs are in the data's squared units: splits
 * tie within a tiny fraction of all of them. */
static void
best_split(const gdouble *votes, gint n, gint *first, gint *last)
{
    gdouble total = 0.0, lowest = 0.0, tie = 0.0;
    gint i;

    for (i = 0; i < n; i++)
        tie += fabs(votes[i]);
    tie *= 1e-9;
    *first = *last = 0;
    for (i = 0; i < n; i++) {
        total += votes[i];
        if (total < lowest - tie) {
            lowest = total;
            *first = *last = i + 1;
        }
        else if (total <= lowest + tie && *last == i)
            *last = i + 1;
    }
}

gboolean
jump_votes_split(const LineEvidence *evidence, const gint *frame, gint n,
                 gint *first, gint *last)
{
    gint loose_first, loose_last;

    return jump_votes_split_loose(evidence, frame, n, first, last,
                                  &loose_first, &loose_last);
}

/* Whether line i's vote leaves where the jump lies open: a weak one, or
 * that of a frame's edge line seen under one drift only.  The other
 * drift puts such a line's content a fraction of a pixel past the other
 * frames' edge, and the one it is seen under may match a mirror image of
 * it: a round particle's rows either side of its centre are alike.  The
 * first line of the frame after a flagged one so matched the rows a step
 * away and put a jump that lay in the featureless end of the frame
 * before the flagged one there, with no word (test-series-correction
 * seeds 700000014 and 810000003). */
static gboolean
vote_leaves_open(const LineEvidence *ev, const gdouble *votes, gint i,
                 gdouble strong)
{
    return fabs(votes[i]) < strong || (ev[i].frame_edge && !ev[i].two_sided);
}

/* The tied splits widened over the votes that leave the jump open on
 * either side: featureless lines vote by noise, and a split they decide is
 * no better placed than a tie (a jump in frame 0's last featureless lines
 * before a flagged frame was put four lines early by votes a hundred times
 * below a typical line's, with no word: seed 575000436 of
 * test-series-correction). */
gboolean
jump_votes_split_loose(const LineEvidence *evidence, const gint *frame,
                       gint n, gint *first, gint *last, gint *loose_first,
                       gint *loose_last)
{
    gdouble *costs = g_new(gdouble, 3*MAX(n, 1)), *before = costs;
    gdouble *after = costs + MAX(n, 1), *votes = after + MAX(n, 1), match;
    gdouble strong;

    match = evidence_costs(evidence, n, before, after);
    strong = steady_votes(before, after, evidence, frame, n, match, votes);
    best_split(votes, n, first, last);
    *loose_first = *first;
    *loose_last = *last;
    while (*loose_first > 0 && vote_leaves_open(evidence, votes, *loose_first - 1, strong))
        (*loose_first)--;
    while (*loose_last < n && vote_leaves_open(evidence, votes, *loose_last, strong))
        (*loose_last)++;
    g_free(costs);
    return n >= 2 && *last > 0 && *first < n;
}
