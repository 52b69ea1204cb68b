/*
 *  Where the scan lines put a jump (modules/core/jump-votes.h), on line
 *  evidence drawn at random (seeded) in the shape the series correction
 *  meets: lines that cut particles cost little under their right drift and
 *  much under the wrong one, featureless lines cost the noise under
 *  either, and a featureless line at a particle's edge may cost a few
 *  times the typical match under its right drift and nothing under the
 *  wrong one.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <math.h>
#include <check.h>
#include "jump-votes.h"
#include "test-common.h"

/* Draws per run of each test. */
#define N_DRAWS 25

static guint32 base_seed;

/* A line seen under both drifts with these mismatches. */
static void
two_sided(LineEvidence *ev, gdouble before, gdouble after)
{
    ev->before = before;
    ev->after = after;
    ev->two_sided = TRUE;
    ev->control = ev->texture = ev->nearby = ev->unrelated = NAN;
    ev->frame_edge = FALSE;
}

/* A line cutting particles: about the typical match m (a few times the
 * noise) under its right drift, contrast times it under the wrong one,
 * contrast drawn from 5 to 60 (a line that cuts a particle's edge only)
 * or from 10 to 100. */
static void
textured_line(LineEvidence *ev, GRand *rng, gdouble m, gboolean is_after,
              gboolean faint)
{
    gdouble right = m*g_rand_double_range(rng, 0.5, 2.0);
    gdouble wrong = m*(faint ? g_rand_double_range(rng, 5.0, 60.0)
                       : g_rand_double_range(rng, 10.0, 100.0));

    two_sided(ev, is_after ? wrong : right, is_after ? right : wrong);
}

/* A featureless line: noise under either drift, one side (lean > 0:
 * after the jump) by the factor 1 + |lean| cheaper: interpolation smooths
 * the other frame's noise by its sub-pixel phase, which differs between
 * the two drifts but hardly between neighbouring lines. */
static void
featureless_line(LineEvidence *ev, GRand *rng, gdouble noise, gdouble lean)
{
    gdouble cost = noise*g_rand_double_range(rng, 0.5, 2.0);

    if (lean > 0.0)
        two_sided(ev, cost*(1.0 + lean), cost);
    else
        two_sided(ev, cost, cost*(1.0 - lean));
}

/* Lines a .. b-1 of a clear jump at split j: textured before j, after it
 * from j on. */
static void
textured_run(LineEvidence *ev, GRand *rng, gdouble m, gint a, gint b, gint j,
             gboolean faint)
{
    gint i;

    for (i = a; i < b; i++)
        textured_line(ev + i, rng, m, i >= j, faint);
}

/* Lines that all cut particles: the split falls exactly at the jump. */
START_TEST(test_clear_jump_to_the_line)
{
    GRand *rng = test_rand_salted(base_seed, 1);
    LineEvidence ev[48];
    gint frame[48] = { 0 }, d, n, j, first, last;
    gdouble noise, m;

    for (d = 0; d < N_DRAWS; d++) {
        n = g_rand_int_range(rng, 12, 49);
        j = g_rand_int_range(rng, 1, n);
        noise = 1e-19*g_rand_double_range(rng, 0.5, 2.0);
        m = noise*g_rand_double_range(rng, 5.0, 40.0);
        textured_run(ev, rng, m, 0, n, j, FALSE);
        ck_assert_msg(jump_votes_split(ev, frame, n, &first, &last),
                      "seed %u draw %d: no split", base_seed, d);
        ck_assert_msg(first == j && last == j,
                      "seed %u draw %d: split %d..%d, the jump at %d",
                      base_seed, d, first, last, j);
    }
    g_rand_free(rng);
}
END_TEST

/* A run of featureless lines holds the jump, and the first line after it
 * that the other frames show a particle's edge on is nearly featureless
 * itself: under the right drift (after the jump) the other frame shows
 * the edge a fraction of a pixel off, 1 to 2 times a textured line's
 * typical match (1.3 times in seed 370001572);
 * under the wrong drift the step moves the particle away and the line
 * matches to the noise.  Textured lines are at least two thirds of the
 * window, as around a jump in a sample with particles.  The featureless
 * lines tell nothing of the jump, but all lean to one side: leaning after
 * the jump, the split must go to the start of the run, where the edge
 * line's weak evidence, counted alone, moved it past the run's end;
 * leaning before it, the split goes to the run's end, the edge line on
 * either side of it.  Counted by itself, that line moved a
 * jump 7 lines late (test-series-correction seed 370001572). */
START_TEST(test_edge_line_needs_its_neighbours)
{
    GRand *rng = test_rand_salted(base_seed, 2);
    LineEvidence ev[80];
    gint frame[80] = { 0 }, d, i, n_before, n_flat, n_after, edge, n;
    gint first, last, textured;
    gdouble noise, m, lean;

    for (d = 0; d < N_DRAWS; d++) {
        n_flat = g_rand_int_range(rng, 3, 11);
        n_before = g_rand_int_range(rng, 6, 21);
        textured = 2*(n_flat + 1);
        n_after = g_rand_int_range(rng, MAX(textured - n_before, 6), 21);
        noise = 1e-19*g_rand_double_range(rng, 0.5, 2.0);
        m = noise*g_rand_double_range(rng, 10.0, 40.0);
        lean = g_rand_double_range(rng, 0.2, 1.0)*(g_rand_boolean(rng) ? 1.0 : -1.0);
        textured_run(ev, rng, m, 0, n_before, n_before, TRUE);
        for (i = n_before; i < n_before + n_flat; i++)
            featureless_line(ev + i, rng, noise, lean);
        edge = n_before + n_flat;
        two_sided(ev + edge, noise*g_rand_double_range(rng, 0.8, 1.2),
                  m*g_rand_double_range(rng, 1.0, 2.0));
        n = edge + 1 + n_after;
        textured_run(ev, rng, m, edge + 1, n, edge + 1, TRUE);
        ck_assert_msg(jump_votes_split(ev, frame, n, &first, &last),
                      "seed %u draw %d: no split", base_seed, d);
        if (lean > 0.0)
            ck_assert_msg(first == n_before && last == n_before,
                          "seed %u draw %d: split %d..%d, featureless lines "
                          "%d..%d leaning after the jump", base_seed, d,
                          first, last, n_before, edge - 1);
        else
            ck_assert_msg(first >= edge && last <= edge + 1,
                          "seed %u draw %d: split %d..%d, featureless lines "
                          "%d..%d leaning before the jump", base_seed, d,
                          first, last, n_before, edge - 1);
    }
    g_rand_free(rng);
}
END_TEST

/* A line seen under one drift only (its content out of every other frame
 * under the other): cost under it, control, texture, nearby cost and
 * what unrelated content costs. */
static void
one_sided(LineEvidence *ev, gboolean seen_after, gdouble cost,
          gdouble control, gdouble texture, gdouble nearby, gdouble unrelated)
{
    ev->two_sided = FALSE;
    ev->before = seen_after ? NAN : cost;
    ev->after = seen_after ? cost : NAN;
    ev->control = control;
    ev->texture = texture;
    ev->nearby = nearby;
    ev->unrelated = unrelated;
    ev->frame_edge = FALSE;
}

/* Between textured lines before the jump and after it, a line cutting
 * particles seen under one drift only.  Its cost below a fifth of its
 * scale (match level to control) puts it on that drift's side only where
 * its content sits exactly there, costing less than a pixel off; no
 * minimum, it tells nothing (the split ties on either side of it); above
 * a fifth it lies on the other side whatever lies nearby.  Lines before a
 * jump cost 0.10 and 0.14 of the scale against content that merely
 * resembled theirs (seeds 572000020 and 572000004 of
 * test-series-correction), lines after one 0.12 and 0.15 (seeds
 * 560100016, 560100232): the scale alone placed them wrong.  Nor does a
 * minimum tell where the line costs about what unrelated content would:
 * a textured line against featureless content is a "minimum" by noise
 * (seed 1603438049 of test-series-correction, 0.98 of unrelated).  But a
 * line as close to its content as true matches are (below 0.05 of
 * unrelated) is a match even where a pixel off costs less: the drift is
 * a fraction of a pixel off there (seed 740000384). */
START_TEST(test_one_sided_line_needs_a_minimum)
{
    GRand *rng = test_rand_salted(base_seed, 3);
    LineEvidence ev[40];
    gint frame[40] = { 0 }, d, n_before, n_after, mid, n, kind, want_first, want_last;
    gint first, last;
    gdouble m, control, q, cost, nearby, unrelated, texture;
    gboolean seen_after;

    for (d = 0; d < N_DRAWS; d++) {
        n_before = g_rand_int_range(rng, 6, 16);
        n_after = g_rand_int_range(rng, 6, 16);
        m = 1e-19*g_rand_double_range(rng, 5.0, 40.0);
        textured_run(ev, rng, m, 0, n_before, n_before, FALSE);
        mid = n_before;
        n = mid + 1 + n_after;
        textured_run(ev, rng, m, mid + 1, n, mid + 1, FALSE);
        seen_after = g_rand_boolean(rng);
        /* 0: a match, a minimum; 1: as low, no minimum, resembling its
         * predicted content no more than loosely (0.1-0.6 of what
         * unrelated content costs); 2: a mismatch; 3: as low, a minimum
         * by noise, but as costly as unrelated content: a textured line
         * against featureless content costs its own texture (well above
         * the match level) and unrelated content that texture and the
         * little the featureless content has; 4: no minimum, but as
         * close to its predicted content as a true match (below 0.05 of
         * unrelated), the drift a fraction of a pixel off there. */
        kind = g_rand_int_range(rng, 0, 5);
        control = m*((kind == 3) ? g_rand_double_range(rng, 40.0, 60.0)
                     : g_rand_double_range(rng, 15.0, 60.0));
        q = (kind == 2) ? g_rand_double_range(rng, 0.25, 0.9)
            : (kind == 3) ? g_rand_double_range(rng, 0.1, 0.19)
            : g_rand_double_range(rng, 0.0, 0.19);
        cost = m + q*(control - m);
        nearby = cost*((kind == 1 || kind == 4) ? g_rand_double_range(rng, 0.5, 1.0)
                       : (kind == 3) ? g_rand_double_range(rng, 1.0, 1.05)
                       : g_rand_double_range(rng, 1.1, 10.0));
        texture = (kind == 3) ? cost*g_rand_double_range(rng, 0.95, 1.0)
                              : control*g_rand_double_range(rng, 0.6, 1.0);
        unrelated = (kind == 3) ? texture + m*g_rand_double_range(rng, 0.0, 0.5)
                    : (kind == 1) ? cost/g_rand_double_range(rng, 0.1, 0.6)
                    : (kind == 4) ? cost/g_rand_double_range(rng, 0.001, 0.045)
                    : cost/g_rand_double_range(rng, 0.0, 0.6);
        one_sided(ev + mid, seen_after, cost, control, texture, nearby, unrelated);
        if (kind == 1 || kind == 3) {
            want_first = mid;
            want_last = mid + 1;
        }
        else
            want_first = want_last = ((kind == 0 || kind == 4) == seen_after) ? mid : mid + 1;
        ck_assert_msg(jump_votes_split(ev, frame, n, &first, &last),
                      "seed %u draw %d: no split", base_seed, d);
        ck_assert_msg(first == want_first && last == want_last,
                      "seed %u draw %d: split %d..%d, not %d..%d (line %d seen "
                      "%s the jump, %.2f of its scale, %s)", base_seed, d,
                      first, last, want_first, want_last, mid,
                      seen_after ? "after" : "before", q,
                      kind == 1 ? "no minimum" : kind == 3 ? "unrelated"
                      : kind == 4 ? "close, no minimum" : "a minimum");
    }
    g_rand_free(rng);
}
END_TEST

/* 6-20 textured lines before a jump, then 2-8 featureless ones, whose
 * leanings are noise (10-40 times below the textured lines' match);
 * returns that match level. */
static gdouble
flat_run_after_texture(LineEvidence *ev, GRand *rng, gint *n_before, gint *n_flat)
{
    gdouble noise, m;
    gint i;

    *n_before = g_rand_int_range(rng, 6, 21);
    *n_flat = g_rand_int_range(rng, 2, 9);
    noise = 1e-19*g_rand_double_range(rng, 0.5, 2.0);
    m = noise*g_rand_double_range(rng, 10.0, 40.0);
    textured_run(ev, rng, m, 0, *n_before, *n_before, FALSE);
    for (i = *n_before; i < *n_before + *n_flat; i++)
        featureless_line(ev + i, rng, noise, g_rand_double_range(rng, -0.3, 0.3));
    return m;
}

/* A run of featureless lines between textured lines before and after a
 * jump: their leanings are noise, a hundredth of a textured line's
 * evidence and less, and whatever split they choose, the loose splits
 * span the whole run (the series correction reports that window). */
START_TEST(test_loose_splits_span_featureless_run)
{
    GRand *rng = test_rand_salted(base_seed, 5);
    LineEvidence ev[60];
    gint frame[60] = { 0 }, d, n_before, n_flat, n, first, last, lo, hi;
    gdouble m;

    for (d = 0; d < N_DRAWS; d++) {
        m = flat_run_after_texture(ev, rng, &n_before, &n_flat);
        n = n_before + n_flat + g_rand_int_range(rng, 6, 21);
        textured_run(ev, rng, m, n_before + n_flat, n, n_before + n_flat, FALSE);
        ck_assert(jump_votes_split_loose(ev, frame, n, &first, &last, &lo, &hi));
        ck_assert_msg(first >= n_before && last <= n_before + n_flat,
                      "seed %u draw %d: split %d..%d outside the run %d..%d",
                      base_seed, d, first, last, n_before, n_before + n_flat);
        ck_assert_msg(lo == n_before && hi == n_before + n_flat,
                      "seed %u draw %d: loose splits %d..%d, the run %d..%d",
                      base_seed, d, lo, hi, n_before, n_before + n_flat);
    }
    g_rand_free(rng);
}
END_TEST

/* The jump in the featureless last lines of a frame, then (a flagged
 * frame left out) the next frame, whose first line is seen under the
 * drift without the step only and matches there, a minimum: a mirror
 * image of itself a step away, a round particle's row across its centre.
 * It may decide the split, but the loose splits reach back over it and
 * the featureless run (seeds 700000014 and 810000003 of
 * test-series-correction: without this, no word of the open window). */
START_TEST(test_edge_line_seen_on_one_side_leaves_jump_open)
{
    GRand *rng = test_rand_salted(base_seed, 6);
    LineEvidence ev[60];
    gint frame[60], d, i, n_before, n_flat, edge, n, first, last, lo, hi;
    gdouble m, cost, control;

    for (d = 0; d < N_DRAWS; d++) {
        m = flat_run_after_texture(ev, rng, &n_before, &n_flat);
        edge = n_before + n_flat;
        for (i = 0; i < edge; i++)
            frame[i] = 0;
        control = m*g_rand_double_range(rng, 15.0, 60.0);
        cost = m*g_rand_double_range(rng, 0.5, 2.0);
        one_sided(ev + edge, FALSE, cost, control, control*g_rand_double_range(rng, 0.3, 1.0),
                  cost*g_rand_double_range(rng, 1.1, 4.0), cost/g_rand_double_range(rng, 0.05, 0.5));
        ev[edge].frame_edge = TRUE;
        n = edge + 1 + g_rand_int_range(rng, 6, 21);
        textured_run(ev, rng, m, edge + 1, n, edge + 1, FALSE);
        for (i = edge; i < n; i++)
            frame[i] = 2;
        ck_assert(jump_votes_split_loose(ev, frame, n, &first, &last, &lo, &hi));
        ck_assert_msg(lo <= n_before && hi >= edge + 1,
                      "seed %u draw %d: loose splits %d..%d, not from %d to %d or beyond "
                      "(split %d..%d)", base_seed, d, lo, hi, n_before, edge + 1, first, last);
        ck_assert_msg(lo == n_before && hi == edge + 1,
                      "seed %u draw %d: loose splits %d..%d reach past the featureless run "
                      "and the edge line, %d..%d", base_seed, d, lo, hi, n_before, edge + 1);
    }
    g_rand_free(rng);
}
END_TEST

/* Lines all on one side, or fewer than two, place no jump. */
START_TEST(test_no_jump_without_both_sides)
{
    GRand *rng = test_rand_salted(base_seed, 4);
    LineEvidence ev[24];
    gint frame[24] = { 0 }, first, last;

    textured_run(ev, rng, 1e-18, 0, 24, 24, FALSE);
    ck_assert(!jump_votes_split(ev, frame, 24, &first, &last));
    textured_run(ev, rng, 1e-18, 0, 24, 0, FALSE);
    ck_assert(!jump_votes_split(ev, frame, 24, &first, &last));
    ck_assert(!jump_votes_split(ev, frame, 1, &first, &last));
    g_rand_free(rng);
}
END_TEST

int
main(void)
{
    TCase *tc;
    Suite *s = test_suite_new("jump-votes", "split", &tc);

    base_seed = test_seed_from_env("test-jump-votes");
    tcase_add_test(tc, test_clear_jump_to_the_line);
    tcase_add_test(tc, test_edge_line_needs_its_neighbours);
    tcase_add_test(tc, test_one_sided_line_needs_a_minimum);
    tcase_add_test(tc, test_loose_splits_span_featureless_run);
    tcase_add_test(tc, test_edge_line_seen_on_one_side_leaves_jump_open);
    tcase_add_test(tc, test_no_jump_without_both_sides);
    return test_run_suite(s);
}
