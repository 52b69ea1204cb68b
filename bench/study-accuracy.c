/*
 *  Accuracy study: particle-centre errors of paper mode and continuous mode
 *  on simscan's paper scenario and on stronger drift, over many seeds.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <glib.h>
#include "continuous-compensate.h"
#include "paper-compensate.h"
#include "stripe-geometry.h"
#include "simscan-run.h"
#include "simscan-presets.h"
#include "continuous-simscan-case.h"

/*
 * What is compared, and against which truth.
 *
 * Compensation can only show the sample as it was at some moment: paper
 * mode shows each stripe as it was at that stripe's local scan (its table
 * row is p(t_image) - p(t_local)); continuous mode shows the whole image as
 * it was at the earliest local scan (drift_trajectory_reference_time()).
 * simscan's own figure judges every image against the sample at the start
 * of the local scans.  The drift while the local scans run (2 s at
 * 0.08 nm/s on the paper scenario, 0.01 px) would otherwise count as an
 * error of the method, so each mode is judged against the moment it
 * claims to show: paper mode per particle at the t_local of the stripe
 * whose drift moved it, continuous mode at its reference time.  The
 * "simscan" column repeats paper mode against simscan's reference.
 *
 * Where continuous mode's error comes from, the "diagnosis" columns show:
 * the local scans' measurement error (dx_exact, dy_exact against what a
 * perfect local scan measures), continuous mode fed with those perfect
 * measurements, and continuous mode fed with the exact trajectory (so
 * only resampling and particle detection remain).
 */

typedef struct {
    const gchar *name;
    const gchar *description;
    DriftModelType type;
    gdouble v[2];          /* nm/s */
    gdouble u[2];          /* nm/s */
    gdouble tau;           /* s */
    gdouble a[2];          /* nm */
    gdouble period;        /* s */
    gdouble r_max;         /* nm, largest drift the local scans expect */
} Scenario;

static const Scenario scenarios[] = {
    {
        "paper", "simscan --preset paper: v = (0.08, 0.02) nm/s",
        DRIFT_MODEL_NONE, { 0.08, 0.02 }, { 0, 0 }, 1.0, { 0, 0 }, 1.0, 100.0,
    },
    {
        "settling", "settling: v = (0.08, 0.02), u = (1, -0.5) nm/s, "
        "tau = 60 s",
        DRIFT_MODEL_SETTLING, { 0.08, 0.02 }, { 1.0, -0.5 }, 60.0,
        { 0, 0 }, 1.0, 200.0,
    },
    {
        "oscillation", "oscillation: v = (0.08, 0.02) nm/s, "
        "a = (15, 8) nm, period 150 s",
        DRIFT_MODEL_OSCILLATION, { 0.08, 0.02 }, { 0, 0 }, 1.0,
        { 15.0, 8.0 }, 150.0, 200.0,
    },
    {
        "fast", "fast constant drift: v = (0.4, -0.3) nm/s",
        DRIFT_MODEL_NONE, { 0.4, -0.3 }, { 0, 0 }, 1.0, { 0, 0 }, 1.0,
        250.0,
    },
};

typedef struct {
    gint n;
    gdouble sum_rms[ACCURACY_NFIGURES];
    gdouble worst_rms[ACCURACY_NFIGURES];
    gdouble worst_max[ACCURACY_NFIGURES];
    gdouble sum_rms_nm[ACCURACY_NFIGURES];
    gdouble worst_max_nm[ACCURACY_NFIGURES];
    gdouble sum_meas, worst_meas, sum_disp, sum_act;
    gint continuous_better;
} Summary;

static void
configure(SimscanConfig *config, const Scenario *scenario, guint32 seed)
{
    simscan_config_init(config);
    simscan_preset_apply(config, SIMSCAN_PRESET_PAPER);
    config->seed = seed;
    config->quiet = TRUE;
    drift_model_init(&config->drift, scenario->type);
    config->drift.v[0] = 1e-9*scenario->v[0];
    config->drift.v[1] = 1e-9*scenario->v[1];
    config->drift.u[0] = 1e-9*scenario->u[0];
    config->drift.u[1] = 1e-9*scenario->u[1];
    config->drift.tau = scenario->tau;
    config->drift.a[0] = 1e-9*scenario->a[0];
    config->drift.a[1] = 1e-9*scenario->a[1];
    config->drift.period = scenario->period;
    config->drift.phase = 0.1*seed;
    config->local.r_max = 1e-9*scenario->r_max;
}

static void
summary_add(Summary *summary, const AccuracyCase *c)
{
    gint k;

    summary->n++;
    for (k = 0; k < ACCURACY_NFIGURES; k++) {
        summary->sum_rms[k] += c->error[k].rms_px;
        summary->sum_rms_nm[k] += c->error[k].rms_nm;
        summary->worst_rms[k] = fmax(summary->worst_rms[k],
                                     c->error[k].rms_px);
        summary->worst_max[k] = fmax(summary->worst_max[k],
                                     c->error[k].max_px);
        summary->worst_max_nm[k] = fmax(summary->worst_max_nm[k],
                                        c->error[k].max_nm);
    }
    summary->sum_meas += c->measurement_rms_px;
    summary->worst_meas = fmax(summary->worst_meas, c->measurement_rms_px);
    summary->sum_disp += c->displayed_rms_px;
    summary->sum_act += c->actual_rms_px;
    if (c->error[ACCURACY_CONTINUOUS].rms_px
        < c->error[ACCURACY_PAPER].rms_px)
        summary->continuous_better++;
}

static void
print_header(void)
{
    printf("%5s %5s | %-13s | %-13s | %-13s | %-13s || %-20s | %-13s "
           "| %-13s | %-13s\n",
           "seed", "found", "before", "paper", "continuous", "paper/simscan",
           "meas (disp, act)", "cont/true-tab", "cont/exact", "truth image");
    printf("%5s %5s | %6s %6s | %6s %6s | %6s %6s | %6s %6s || %6s %6s %6s | "
           "%6s %6s | %6s %6s | %6s %6s\n",
           "", "", "rms", "max", "rms", "max", "rms", "max", "rms", "max",
           "rms", "rms", "rms", "rms", "max", "rms", "max", "rms", "max");
}

static void
print_case(guint32 seed, const AccuracyCase *c)
{
    static const gint order[] = {
        ACCURACY_BEFORE, ACCURACY_PAPER, ACCURACY_CONTINUOUS,
        ACCURACY_PAPER_SIMSCAN_REF,
    };
    guint k;

    printf("%5u %2d/%-2d |", seed,
           c->error[ACCURACY_CONTINUOUS].n_matched,
           c->error[ACCURACY_CONTINUOUS].n_expected);
    for (k = 0; k < G_N_ELEMENTS(order); k++) {
        printf(" %6.3f %6.3f |", c->error[order[k]].rms_px,
               c->error[order[k]].max_px);
    }
    printf("| %6.3f %6.3f %6.3f | %6.3f %6.3f | %6.3f %6.3f | %6.3f %6.3f\n",
           c->measurement_rms_px, c->displayed_rms_px, c->actual_rms_px,
           c->error[ACCURACY_CONTINUOUS_TRUE_TABLE].rms_px,
           c->error[ACCURACY_CONTINUOUS_TRUE_TABLE].max_px,
           c->error[ACCURACY_CONTINUOUS_EXACT].rms_px,
           c->error[ACCURACY_CONTINUOUS_EXACT].max_px,
           c->error[ACCURACY_TRUTH].rms_px, c->error[ACCURACY_TRUTH].max_px);
}

static void
print_summary(const Scenario *scenario, const Summary *s, gdouble px_nm)
{
    static const struct {
        gint figure;
        const gchar *name;
    } rows[] = {
        { ACCURACY_BEFORE, "before (contaminated)" },
        { ACCURACY_PAPER, "paper mode" },
        { ACCURACY_CONTINUOUS, "continuous mode (B-spline)" },
        { ACCURACY_PAPER_SIMSCAN_REF, "paper mode, simscan's reference" },
        { ACCURACY_CONTINUOUS_TRUE_TABLE, "continuous, perfect local scans" },
        { ACCURACY_CONTINUOUS_EXACT, "continuous, exact trajectory" },
        { ACCURACY_TRUTH, "drift-free scan at t_ref (floor)" },
    };
    guint k;

    printf("\nSummary '%s' over %d seeds (1 px = %.2f nm)\n",
           scenario->name, s->n, px_nm);
    printf("| %-32s | mean RMS px | worst RMS px | worst max px "
           "| mean RMS nm | worst max nm |\n", "");
    printf("|%s|-------------|--------------|--------------"
           "|-------------|--------------|\n",
           "----------------------------------");
    for (k = 0; k < G_N_ELEMENTS(rows); k++) {
        gint f = rows[k].figure;

        printf("| %-32s | %11.3f | %12.3f | %12.3f | %11.2f | %12.2f |\n",
               rows[k].name, s->sum_rms[f]/s->n, s->worst_rms[f],
               s->worst_max[f], s->sum_rms_nm[f]/s->n, s->worst_max_nm[f]);
    }
    printf("local-scan measurement error (dx_exact, dy_exact): mean RMS "
           "%.3f px, worst %.3f px;\n  of it the displayed centre found in "
           "the image %.3f px, the actual centre\n  found by the local scan "
           "%.3f px (mean RMS)\n", s->sum_meas/s->n, s->worst_meas,
           s->sum_disp/s->n, s->sum_act/s->n);
    printf("continuous mode better than paper mode in %d of %d seeds\n",
           s->continuous_better, s->n);
}

static void
usage(void)
{
    printf("Usage: study-accuracy [SEEDS [SCENARIO]]\n"
           "Runs simscan's paper scenario (256x256 px over 5 um, 50 nm "
           "particles, N = 16,\n300 s, local scans after the frame) with "
           "seeds 1..SEEDS (default 20) and\ncompares the particle-centre "
           "errors of paper mode and continuous mode.\nSCENARIO: ");
    for (guint k = 0; k < G_N_ELEMENTS(scenarios); k++)
        printf("%s%s", k ? ", " : "", scenarios[k].name);
    printf(" (default: all).\n");
}

int
main(int argc, char **argv)
{
    gint n_seeds = 20, failures = 0;
    const gchar *only = NULL, *kernel_name;
    GwyInterpolationType kernel = GWY_INTERPOLATION_BSPLINE;
    gdouble px_nm = 0.0;
    guint k;

    if (argc > 1 && (!strcmp(argv[1], "--help") || !strcmp(argv[1], "-h"))) {
        usage();
        return EXIT_SUCCESS;
    }
    if (argc > 1)
        n_seeds = atoi(argv[1]);
    if (argc > 2)
        only = argv[2];
    /* Another kernel for continuous mode, for comparisons. */
    if ((kernel_name = g_getenv("STUDY_KERNEL")))
        kernel = atoi(kernel_name);
    if (n_seeds < 1 || argc > 3) {
        usage();
        return EXIT_FAILURE;
    }

    printf("Particle-centre errors, px.  Each mode is judged against the "
           "sample at the\nmoment it shows: paper mode per stripe at that "
           "stripe's local scan, continuous\nmode at the earliest local "
           "scan; 'paper/simscan' is paper mode against\nsimscan's "
           "reference (the start of the local scans).  'meas' is the RMS "
           "error of\nthe local scans' dx_exact, dy_exact against a perfect "
           "local scan; 'cont/true-tab'\nfeeds continuous mode perfect "
           "local scans; 'cont/exact' the exact trajectory.\n");
    for (k = 0; k < G_N_ELEMENTS(scenarios); k++) {
        const Scenario *scenario = scenarios + k;
        Summary summary;
        guint32 seed;

        if (only && strcmp(only, scenario->name))
            continue;
        memset(&summary, 0, sizeof(summary));
        printf("\n== %s\n", scenario->description);
        print_header();
        for (seed = 1; seed <= (guint32)n_seeds; seed++) {
            SimscanConfig config;
            AccuracyCase c;
            GError *error = NULL;

            configure(&config, scenario, seed);
            if (!accuracy_case_run(&config, kernel,
                                   &c, &error)) {
                printf("%5u  failed: %s\n", seed, error->message);
                g_clear_error(&error);
                failures++;
            }
            else {
                print_case(seed, &c);
                summary_add(&summary, &c);
                px_nm = 1e9*config.xreal/config.xres;
            }
            simscan_config_clear(&config);
            fflush(stdout);
        }
        if (summary.n)
            print_summary(scenario, &summary, px_nm);
    }
    return failures ? EXIT_FAILURE : EXIT_SUCCESS;
}
