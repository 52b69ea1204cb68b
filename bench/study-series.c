/*
 *  The series correction on simulated series (run by hand:
 *  bench/study-series [CASES [SEED]]): for each drift effect, with clean
 *  and with raw channels, and with a disturbed frame, how far the fitted
 *  trajectory and the corrected frames lie from the simulator's truth.
 *  Prints the table of docs/series.md.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <stdio.h>
#include <stdlib.h>
#include <math.h>
#include <libgwyddion/gwyddion.h>
#include <libprocess/gwyprocess.h>
#include "hidden-effect-cases.h"
#include "series-cases.h"

typedef struct {
    gint runs, failed, named, flagged_wrong, disturbed_found;
    gdouble rms_sum, rms_worst, traj_worst, stripe_worst, frame_worst;
    GArray *frame_errors;
} Tally;

static void
tally_add(Tally *t, const SeriesCaseResult *r, gboolean ok,
          const SeriesCaseOptions *o)
{
    t->runs++;
    if (!ok) {
        t->failed++;
        return;
    }
    t->named += r->effect_named;
    t->rms_sum += r->trajectory_rms_px;
    t->rms_worst = MAX(t->rms_worst, r->trajectory_rms_px);
    t->traj_worst = MAX(t->traj_worst, r->trajectory_worst_px);
    t->stripe_worst = MAX(t->stripe_worst, r->stripe_worst_px);
    t->frame_worst = MAX(t->frame_worst, r->frame_worst_px);
    g_array_append_val(t->frame_errors, r->stripe_worst_px);
    t->disturbed_found += r->disturbed_flagged;
    t->flagged_wrong += r->flagged - r->disturbed_flagged;
    (void)o;
}

static gint
compare(gconstpointer a, gconstpointer b)
{
    gdouble x = *(const gdouble*)a, y = *(const gdouble*)b;
    return (x > y) - (x < y);
}

static void
tally_print(const gchar *name, const gchar *variant, Tally *t)
{
    gdouble median = NAN;

    if (t->frame_errors->len) {
        g_array_sort(t->frame_errors, compare);
        median = g_array_index(t->frame_errors, gdouble, t->frame_errors->len/2);
    }
    printf("| %s | %s | %d | %d | %d | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f | %d | %d |\n",
           name, variant, t->runs, t->failed, t->named,
           t->rms_sum/MAX(t->runs - t->failed, 1), t->rms_worst, t->traj_worst,
           median, t->stripe_worst, t->frame_worst, t->disturbed_found,
           t->flagged_wrong);
}

int
main(int argc, char **argv)
{
    static const gchar *variants[] = { "clean", "raw", "disturbed" };
    gint cases = argc > 1 ? atoi(argv[1]) : 8;
    guint32 seed = argc > 2 ? (guint32)strtoul(argv[2], NULL, 10) : 1;
    gint e, v, c;

    gwy_process_type_init();
    printf("# series correction, %d cases per row, seed %u\n", cases, seed);
    printf("| effect | frames | runs | failed | named | traj rms mean (px) | "
           "traj rms worst | traj worst line | stripe median | stripe worst | "
           "frame vs truth worst | disturbed flagged | others flagged |\n");
    printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    for (e = 0; e < SERIES_CASE_EFFECTS; e++) {
        for (v = 0; v < 3; v++) {
            Tally t = { 0, 0, 0, 0, 0, 0.0, 0.0, 0.0, 0.0, 0.0, NULL };
            DriftModel model;

            t.frame_errors = g_array_new(FALSE, FALSE, sizeof(gdouble));
            for (c = 0; c < cases; c++) {
                gint i = e + SERIES_CASE_EFFECTS*c;
                SeriesCaseOptions o = { v == 1, v == 2 ? 1 + c % 3 : -1 };
                SeriesCaseResult r;
                GwyDataField **truth = NULL;
                FrameSeries *series;
                gboolean ok;
                gint k;

                hidden_case_draw(seed, i, &model);
                series = series_case_scan(seed, i, &model, &o, &truth);
                ok = series && series_case_judge(series, truth, &model, &o, &r);
                tally_add(&t, &r, ok, &o);
                for (k = 0; truth && k < 2*SERIES_CASE_FRAMES; k++)
                    g_object_unref(truth[k]);
                g_free(truth);
                frame_series_free(series);
                drift_model_clear(&model);
            }
            tally_print(drift_model_type_name(hidden_case_effect(e)), variants[v], &t);
            g_array_free(t.frame_errors, TRUE);
        }
    }
    return 0;
}
