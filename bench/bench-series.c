/*
 *  The series correction's speed against the rigid frame-to-frame
 *  correction peers use (bench/rigid-baseline.h), on the same synthetic
 *  series in the same run (bench/bench-series [FRAMES], default 1000):
 *  time per frame of each, their ratio, and how far each lies from the
 *  true drift line by line.  Prints figures, asserts nothing.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <math.h>
#include <libgwyddion/gwyddion.h>
#include <libprocess/gwyprocess.h>
#include "frame-series.h"
#include "series-correction.h"
#include "sim-random.h"
#include "rigid-baseline.h"

#define RES 256
#define FIELD 2e-6              /* m, so a pixel is 7.8 nm */
#define LINE_TIME 0.01          /* s */
#define DEFAULT_FRAMES 1000
/* The surface is periodic on a canvas much larger than a frame, so any
 * drift over any number of frames samples it without running off an edge,
 * and no two frames closer than CANVAS px of drift see the same copy. */
#define CANVAS 1024
#define N_BUMPS 6000
#define SEED 20260101
/* True drift p(t) = v t + a (sin, cos)(2 pi t / period), px: about 0.8 px
 * per frame, so each frame is skewed by what a rigid shift cannot undo. */
#define VX 0.30                 /* px/s */
#define VY 0.20                 /* px/s */
#define OSC_AMPLITUDE 0.3       /* px */
#define OSC_PERIOD 5.0          /* s, about two frames */
#define NOISE 0.03              /* of the surface's RMS */
#define MAX_BLOCKS 64

static void
true_drift(gdouble t, gdouble *px, gdouble *py)
{
    gdouble phase = 2.0*G_PI*t/OSC_PERIOD;

    *px = VX*t + OSC_AMPLITUDE*sin(phase);
    *py = VY*t + OSC_AMPLITUDE*cos(phase);
}

/* One Gaussian bump added to the periodic canvas within 4 sigma. */
static void
add_bump(gdouble *canvas, gdouble x0, gdouble y0, gdouble sigma, gdouble height)
{
    gint r = (gint)ceil(4.0*sigma), i, j;
    gint ic = (gint)floor(y0), jc = (gint)floor(x0);

    for (i = ic - r; i <= ic + r; i++) {
        gdouble wy = exp(-0.5*(i - y0)*(i - y0)/(sigma*sigma));
        gint ii = ((i % CANVAS) + CANVAS) % CANVAS;

        for (j = jc - r; j <= jc + r; j++) {
            gint jj = ((j % CANVAS) + CANVAS) % CANVAS;

            canvas[ii*CANVAS + jj] += height*wy*exp(-0.5*(j - x0)*(j - x0)/(sigma*sigma));
        }
    }
}

/* A random smooth surface: many small bumps for texture every block can
 * register, a few broad ones for the long-wavelength background. */
static gdouble*
make_surface(SimRandom *rng)
{
    gdouble *canvas = g_new0(gdouble, CANVAS*CANVAS);
    gint k;

    for (k = 0; k < N_BUMPS; k++) {
        gboolean broad = (k % 100 == 0);
        gdouble sigma = broad ? 20.0 + 20.0*sim_random_uniform(rng) : 2.0 + 4.0*sim_random_uniform(rng);
        gdouble height = (broad ? 3.0 : 1.0)*(sim_random_uniform(rng) - 0.3);

        add_bump(canvas, CANVAS*sim_random_uniform(rng), CANVAS*sim_random_uniform(rng), sigma, height);
    }
    return canvas;
}

static gdouble
surface_rms(const gdouble *canvas)
{
    gdouble s = 0.0, s2 = 0.0;
    gint i, n = CANVAS*CANVAS;

    for (i = 0; i < n; i++) {
        s += canvas[i];
        s2 += canvas[i]*canvas[i];
    }
    return sqrt(MAX(s2/n - (s/n)*(s/n), 0.0));
}

/* Bilinear sample of the periodic canvas at (x, y), canvas pixels. */
static gdouble
sample(const gdouble *canvas, gdouble x, gdouble y)
{
    gint j = (gint)floor(x), i = (gint)floor(y);
    gdouble fx = x - j, fy = y - i;
    gint j0 = ((j % CANVAS) + CANVAS) % CANVAS, i0 = ((i % CANVAS) + CANVAS) % CANVAS;
    gint j1 = (j0 + 1) % CANVAS, i1 = (i0 + 1) % CANVAS;

    return (1.0 - fy)*((1.0 - fx)*canvas[i0*CANVAS + j0] + fx*canvas[i0*CANVAS + j1])
           + fy*((1.0 - fx)*canvas[i1*CANVAS + j0] + fx*canvas[i1*CANVAS + j1]);
}

/* Frame k: each line sees the surface displaced by the drift at its centre
 * time (a feature at X appears at X + p(t), docs/conventions.md). */
static GwyDataField*
make_frame(const gdouble *canvas, const ScanTiming *timing, gdouble noise, SimRandom *rng)
{
    GwyDataField *field = gwy_data_field_new(RES, RES, FIELD, FIELD, FALSE);
    gdouble *data = gwy_data_field_get_data(field);
    gint r, c;

    gwy_si_unit_set_from_string(gwy_data_field_get_si_unit_xy(field), "m");
    gwy_si_unit_set_from_string(gwy_data_field_get_si_unit_z(field), "m");
    for (r = 0; r < RES; r++) {
        gdouble px, py;

        true_drift(scan_timing_rows_time(timing, r, r + 1), &px, &py);
        for (c = 0; c < RES; c++)
            data[r*RES + c] = 1e-9*(sample(canvas, c - px, r - py) + noise*sim_random_gaussian(rng));
    }
    return field;
}

static FrameSeries*
make_series(gint n_frames)
{
    FrameSeries *series = frame_series_new();
    SimRandom rng;
    gdouble *canvas;
    gdouble noise;
    gint k;

    sim_random_init(&rng, SEED, 0);
    canvas = make_surface(&rng);
    noise = NOISE*surface_rms(canvas);
    for (k = 0; k < n_frames; k++) {
        ScanTiming timing;
        GwyDataField *field;
        gchar *label = g_strdup_printf("frame%d", k);

        /* Frames back to back: frame k starts when frame k - 1 ends. */
        scan_timing_init(&timing, RES, RES, k*RES*LINE_TIME, LINE_TIME, SCAN_DIRECTION_DOWN);
        field = make_frame(canvas, &timing, noise, &rng);
        frame_series_append(series, field, label, &timing);
        g_object_unref(field);
        g_free(label);
    }
    g_free(canvas);
    return series;
}

/* The truth every method is judged against: p(t) - p(0) at each line's
 * centre time, px. */
static void
true_relative(gdouble t, gdouble *x, gdouble *y)
{
    gdouble x0, y0;

    true_drift(0.0, &x0, &y0);
    true_drift(t, x, y);
    *x -= x0;
    *y -= y0;
}

/* A trajectory's drift (px) at time t, within frame k. */
typedef void (*TrajectoryEval)(gconstpointer trajectory, gint k, gdouble t,
                               gdouble *x, gdouble *y);

/* RMS over every line of the series of |estimate - truth|. */
static gdouble
trajectory_rms(TrajectoryEval eval, gconstpointer trajectory, const FrameSeries *series)
{
    gdouble sum = 0.0;
    gint k, r;

    for (k = 0; k < series->n_frames; k++) {
        for (r = 0; r < RES; r++) {
            gdouble t = scan_timing_rows_time(&series->frames[k].timing, r, r + 1);
            gdouble ex, ey, tx, ty;

            eval(trajectory, k, t, &ex, &ey);
            true_relative(t, &tx, &ty);
            sum += (ex - tx)*(ex - tx) + (ey - ty)*(ey - ty);
        }
    }
    return sqrt(sum/((gdouble)series->n_frames*RES));
}

static void
ours_eval(gconstpointer trajectory, G_GNUC_UNUSED gint k, gdouble t, gdouble *x, gdouble *y)
{
    series_correction_eval(trajectory, t, x, y);
}

static gdouble
ours_rms(const SeriesCorrection *correction, const FrameSeries *series)
{
    return trajectory_rms(ours_eval, correction, series);
}

/* Rigid shifts, one per frame, with an offset added to every one. */
typedef struct {
    const gdouble *dx;
    const gdouble *dy;
    gdouble offx;
    gdouble offy;
} RigidTrajectory;

static void
rigid_eval(gconstpointer trajectory, gint k, G_GNUC_UNUSED gdouble t, gdouble *x, gdouble *y)
{
    const RigidTrajectory *rigid = trajectory;

    *x = rigid->dx[k] + rigid->offx;
    *y = rigid->dy[k] + rigid->offy;
}

/* The same for the rigid shifts.  offset (px) is added to every shift: 0
 * judges it against p(t) - p(0) like ours; the mean error judges it against
 * the best moment a rigid correction could stand for. */
static gdouble
rigid_rms(const gdouble *dx, const gdouble *dy, const FrameSeries *series,
          gdouble offx, gdouble offy)
{
    RigidTrajectory rigid = { dx, dy, offx, offy };

    return trajectory_rms(rigid_eval, &rigid, series);
}

static void
rigid_mean_error(const gdouble *dx, const gdouble *dy, const FrameSeries *series,
                 gdouble *mx, gdouble *my)
{
    gint k, r;

    *mx = *my = 0.0;
    for (k = 0; k < series->n_frames; k++) {
        for (r = 0; r < RES; r++) {
            gdouble t = scan_timing_rows_time(&series->frames[k].timing, r, r + 1);
            gdouble tx, ty;

            true_relative(t, &tx, &ty);
            *mx += tx - dx[k];
            *my += ty - dy[k];
        }
    }
    *mx /= (gdouble)series->n_frames*RES;
    *my /= (gdouble)series->n_frames*RES;
}

static gdouble
seconds_since(gint64 start)
{
    return (g_get_monotonic_time() - start)/1e6;
}

/* (a) The series correction: compute, then every frame corrected. */
static gboolean
run_ours(const FrameSeries *series, SeriesCorrection *correction,
         gdouble *t_compute, gdouble *t_correct)
{
    GwyDataField *result = gwy_data_field_new_alike(series->frames[0].field, FALSE);
    GwyDataField *mask = gwy_data_field_new_alike(series->frames[0].field, FALSE);
    GError *error = NULL;
    gint64 start = g_get_monotonic_time();
    gint k, failed = 0;

    if (!series_correction_compute(series, NULL, NULL, correction, &error)) {
        fprintf(stderr, "series_correction_compute: %s\n", error->message);
        g_clear_error(&error);
        g_object_unref(result);
        g_object_unref(mask);
        return FALSE;
    }
    *t_compute = seconds_since(start);
    start = g_get_monotonic_time();
    for (k = 0; k < series->n_frames; k++) {
        if (!series_correction_correct_frame(correction, series, k, GWY_INTERPOLATION_BSPLINE,
                                             result, mask, &error)) {
            if (!failed++)
                fprintf(stderr, "series_correction_correct_frame(%d): %s\n", k, error->message);
            g_clear_error(&error);
        }
    }
    *t_correct = seconds_since(start);
    if (failed)
        printf("series correction: %d frames failed to correct\n", failed);
    g_object_unref(result);
    g_object_unref(mask);
    return TRUE;
}

/* (b) The rigid baseline: shifts, then every frame moved back. */
static void
run_rigid(const FrameSeries *series, gdouble *dx, gdouble *dy,
          gdouble *t_shifts, gdouble *t_correct)
{
    GwyDataField *result = gwy_data_field_new_alike(series->frames[0].field, FALSE);
    gint64 start = g_get_monotonic_time();
    gint k;

    rigid_baseline_shifts(series, dx, dy);
    *t_shifts = seconds_since(start);
    start = g_get_monotonic_time();
    for (k = 0; k < series->n_frames; k++)
        rigid_baseline_correct(series->frames[k].field, dx[k], dy[k], result);
    *t_correct = seconds_since(start);
    g_object_unref(result);
}

static void
print_time(const gchar *name, gdouble first, const gchar *first_name,
           gdouble second, gint n)
{
    gdouble total = first + second;

    printf("%-18s %8.2f s total  %8.2f ms/frame  (%s %.2f s, correcting %.2f s)\n",
           name, total, 1e3*total/n, first_name, first, second);
}

/* The mean error of the measurements of each block position (px against
 * the true drift at their times), and the worst of them: a bias of one
 * block position that the pairs share becomes a velocity error of the
 * fit, which a long series integrates. */
static void
print_block_bias(const SeriesCorrection *correction, const FrameSeries *series)
{
    gdouble sum[2][MAX_BLOCKS], count[MAX_BLOCKS], worst = 0.0;
    gdouble xstep = frame_series_dx(series), ystep = frame_series_dy(series);
    gint i, g, worst_g = -1;

    memset(sum, 0, sizeof(sum));
    memset(count, 0, sizeof(count));
    for (i = 0; i < correction->fit.n_meas; i++) {
        const DriftMeasurement *m = correction->fit.meas + i;
        gdouble xa, ya, xb, yb;

        if (!(m->weight > 0.0) || m->group < 0 || m->group >= MAX_BLOCKS)
            continue;
        true_drift(m->t_a, &xa, &ya);
        true_drift(m->t_b, &xb, &yb);
        sum[0][m->group] += m->dx/xstep - (xa - xb);
        sum[1][m->group] += m->dy/ystep - (ya - yb);
        count[m->group]++;
    }
    for (g = 0; g < MAX_BLOCKS; g++) {
        gdouble e = count[g] ? hypot(sum[0][g], sum[1][g])/count[g] : 0.0;

        if (e > worst) {
            worst = e;
            worst_g = g;
        }
    }
    if (worst_g >= 0)
        printf("  worst block position: %d, mean error (%.4f, %.4f) px over %.0f fitted measurements\n",
               worst_g, sum[0][worst_g]/count[worst_g], sum[1][worst_g]/count[worst_g], count[worst_g]);
}

static void
print_verdicts(const SeriesCorrection *correction)
{
    gint k, flagged = 0;
    guint w;

    for (k = 0; k < correction->n_frames; k++)
        flagged += correction->frames[k].flagged;
    printf("series correction: model %s, %d frames flagged, typical pair residual %.3f px\n",
           correction->fit.chosen >= 0
           ? drift_model_type_name(correction->fit.fits[correction->fit.chosen].type) : "(none)",
           flagged, correction->typical_px);
    if (correction->fit.chosen >= 0) {
        const DriftFit *fit = correction->fit.fits + correction->fit.chosen;
        gdouble nm_x = 1e9*correction->xstep, nm_y = 1e9*correction->ystep;

        /* The fit's own numbers beside the truth, so that an error of the
         * trajectory can be told from a wrong model or period. */
        printf("  fitted velocity (%.4f, %.4f) px/s (true %.2f, %.2f), nonlinear parameter %.4f s "
               "(true period %.1f s), residual %.4f px; trajectory from the %s\n",
               fit->coef[0][0]/nm_x, fit->coef[1][0]/nm_y, VX, VY, fit->nonlinear, OSC_PERIOD,
               fit->rms_nm/nm_x, correction->use_smooth ? "flexible fit" : "model");
    }
    for (w = 0; correction->warnings && w < MIN(correction->warnings->len, 5); w++)
        printf("  warning: %s\n", (const gchar*)g_ptr_array_index(correction->warnings, w));
}

static void
print_rigid_accuracy(const gdouble *dx, const gdouble *dy, const FrameSeries *series)
{
    gdouble mx, my;
    gint col, row, width, height;

    rigid_mean_error(dx, dy, series, &mx, &my);
    printf("rigid trajectory RMS error         %.3f px (vs p(t) - p(0)); %.3f px with its mean "
           "offset (%.2f, %.2f) px removed\n",
           rigid_rms(dx, dy, series, 0.0, 0.0), rigid_rms(dx, dy, series, mx, my), mx, my);
    if (rigid_baseline_crop(dx, dy, series->n_frames, RES, RES, &col, &row, &width, &height))
        printf("rigid common crop                  %d x %d px at (%d, %d)\n", width, height, col, row);
    else
        printf("rigid common crop                  none (the frames share no pixel)\n");
}

int
main(int argc, char *argv[])
{
    gint n_frames = argc > 1 ? atoi(argv[1]) : DEFAULT_FRAMES;
    SeriesCorrection correction;
    FrameSeries *series;
    gdouble *dx, *dy, t_compute = 0.0, t_ours = 0.0, t_shifts, t_rigid;
    gboolean ok;
    gint64 start;

    gwy_process_type_init();
    if (n_frames < 2) {
        fprintf(stderr, "usage: %s [FRAMES >= 2]\n", argv[0]);
        return 1;
    }
    start = g_get_monotonic_time();
    series = make_series(n_frames);
    printf("frames %d of %d x %d px, line time %g s, %d CPU cores "
           "(series made in %.2f s)\n",
           n_frames, RES, RES, LINE_TIME, g_get_num_processors(), seconds_since(start));
    printf("target: a 1000-frame 256 x 256 series corrected in at most 10 s on a 2-core machine\n");
    ok = run_ours(series, &correction, &t_compute, &t_ours);
    dx = g_new(gdouble, n_frames);
    dy = g_new(gdouble, n_frames);
    run_rigid(series, dx, dy, &t_shifts, &t_rigid);
    if (ok)
        print_time("series correction", t_compute, "compute", t_ours, n_frames);
    print_time("rigid baseline", t_shifts, "shifts", t_rigid, n_frames);
    if (ok) {
        printf("ratio ours/rigid                   %.2f\n",
               (t_compute + t_ours)/(t_shifts + t_rigid));
        printf("series trajectory RMS error        %.3f px (vs p(t) - p(0))\n",
               ours_rms(&correction, series));
        print_verdicts(&correction);
        print_block_bias(&correction, series);
        series_correction_clear(&correction);
    }
    print_rigid_accuracy(dx, dy, series);
    g_free(dx);
    g_free(dy);
    frame_series_free(series);
    return 0;
}
