/*
 *  Accuracy study of the stripe registration: our method, a plain phase
 *  correlation of stripe against stripe, and Gwyddion's own drift estimate,
 *  on the same seeded synthetic frame pairs.  Prints tables; not a test.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <complex.h>
#include <fftw3.h>
#include <libgwyddion/gwyddion.h>
#include <libprocess/gwyprocess.h>
#include <libgwymodule/gwymodule.h>
#include <libdraw/gwydraw.h>
#include <libgwydgets/gwydgets.h>
#include <app/gwyapp.h>
#include "stripe-registration.h"
#include "stripe-geometry.h"
#include "registration-frames.h"
#include "gwyddion-drift-baseline.h"

typedef struct {
    const gchar *name;
    gdouble sum_sq;        /* of |error| over stripes */
    gdouble sum_sq_x;
    gdouble max_error;
    gint off_by_pixel;     /* stripes with |error| > 1 px */
    gint rejected;
    gint stripes;
    gdouble seconds;
    gint frames;
} Tally;

/* Plain phase correlation of each image stripe against the same rows of
 * the reference, as image libraries offer it: Hann window, normalised cross
 * power spectrum, peak with a 5x5 weighted centroid. */
typedef struct {
    gint rows, cols;
    gdouble *real_in;
    fftw_complex *image_spec, *ref_spec;
    gdouble *surface;
    gdouble *hann;
    fftw_plan image_forward, ref_forward, backward;
} PhaseCorrelation;

static void
tally_add(Tally *tally, gdouble ex, gdouble ey, gboolean rejected)
{
    gdouble e = sqrt(ex*ex + ey*ey);

    tally->sum_sq += e*e;
    tally->sum_sq_x += ex*ex;
    tally->max_error = MAX(tally->max_error, e);
    tally->off_by_pixel += (e > 1.0);
    tally->rejected += !!rejected;
    tally->stripes++;
}

static void
tally_print(const Tally *tally, gboolean x_only)
{
    gchar rms[32];

    if (!tally->stripes) {
        printf("%-38s (no stripe: nothing was accepted)\n", tally->name);
        return;
    }
    if (x_only)
        g_snprintf(rms, sizeof(rms), "%9s", "-");
    else
        g_snprintf(rms, sizeof(rms), "%9.4f", sqrt(tally->sum_sq/tally->stripes));
    printf("%-38s %s %9.4f %9.4f %9.4f %8.2f%% %8.2f%% %9.2f\n",
           tally->name, rms, sqrt(tally->sum_sq_x/tally->stripes), tally->max_error,
           tally->max_error, 100.0*tally->off_by_pixel/tally->stripes,
           100.0*tally->rejected/tally->stripes, 1e3*tally->seconds/tally->frames);
}

static PhaseCorrelation*
phase_correlation_new(gint rows, gint cols)
{
    PhaseCorrelation *pc = g_new0(PhaseCorrelation, 1);
    gint i, j;

    pc->rows = rows;
    pc->cols = cols;
    pc->real_in = fftw_alloc_real(rows*cols);
    pc->surface = fftw_alloc_real(rows*cols);
    pc->image_spec = fftw_alloc_complex(rows*(cols/2 + 1));
    pc->ref_spec = fftw_alloc_complex(rows*(cols/2 + 1));
    pc->hann = g_new(gdouble, rows*cols);
    for (i = 0; i < rows; i++) {
        for (j = 0; j < cols; j++)
            pc->hann[i*cols + j] = ((1.0 - cos(2.0*G_PI*i/rows))*(1.0 - cos(2.0*G_PI*j/cols))/4.0);
    }
    pc->image_forward = fftw_plan_dft_r2c_2d(rows, cols, pc->real_in, pc->image_spec, FFTW_ESTIMATE);
    pc->ref_forward = fftw_plan_dft_r2c_2d(rows, cols, pc->real_in, pc->ref_spec, FFTW_ESTIMATE);
    pc->backward = fftw_plan_dft_c2r_2d(rows, cols, pc->image_spec, pc->surface, FFTW_ESTIMATE);
    return pc;
}

static void
phase_correlation_free(PhaseCorrelation *pc)
{
    fftw_destroy_plan(pc->image_forward);
    fftw_destroy_plan(pc->ref_forward);
    fftw_destroy_plan(pc->backward);
    fftw_free(pc->real_in);
    fftw_free(pc->surface);
    fftw_free(pc->image_spec);
    fftw_free(pc->ref_spec);
    g_free(pc->hann);
    g_free(pc);
}

static void
load_windowed(PhaseCorrelation *pc, const gdouble *rows)
{
    gint k, count = pc->rows*pc->cols;

    for (k = 0; k < count; k++)
        pc->real_in[k] = rows[k]*pc->hann[k];
}

static gint
wrap_index(gint i, gint res)
{
    return ((i % res) + res) % res;
}

/* Shift of the image stripe against the reference stripe: peak of
 * ifft(I conj(R)/|I conj(R)|). */
static void
phase_correlation_shift(PhaseCorrelation *pc, const gdouble *image_rows, const gdouble *ref_rows,
                        gdouble *dy, gdouble *dx)
{
    gint rows = pc->rows, cols = pc->cols, nspec = rows*(cols/2 + 1);
    gint k, i, j, bi = 0, bj = 0;
    gdouble best = -G_MAXDOUBLE, s = 0.0, sy = 0.0, sx = 0.0;

    load_windowed(pc, image_rows);
    fftw_execute(pc->image_forward);
    load_windowed(pc, ref_rows);
    fftw_execute(pc->ref_forward);
    for (k = 0; k < nspec; k++) {
        fftw_complex c = pc->image_spec[k]*conj(pc->ref_spec[k]);
        gdouble a = cabs(c);

        pc->image_spec[k] = (a > 1e-300) ? c/a : 0.0;
    }
    fftw_execute(pc->backward);
    for (i = 0; i < rows; i++) {
        for (j = 0; j < cols; j++) {
            if (pc->surface[i*cols + j] > best) {
                best = pc->surface[i*cols + j];
                bi = i;
                bj = j;
            }
        }
    }
    for (i = -2; i <= 2; i++) {
        for (j = -2; j <= 2; j++) {
            gdouble v = pc->surface[wrap_index(bi + i, rows)*cols + wrap_index(bj + j, cols)];

            s += v;
            sy += v*i;
            sx += v*j;
        }
    }
    *dy = (bi > rows/2 ? bi - rows : bi) + (s > 0.0 ? sy/s : 0.0);
    *dx = (bj > cols/2 ? bj - cols : bj) + (s > 0.0 ? sx/s : 0.0);
}

static void
run_phase_correlation(const FramePair *pair, gint n, const gdouble *tx, const gdouble *ty, Tally *tally)
{
    gint s, first, h;
    gdouble dy, dx;
    gint64 start = g_get_monotonic_time();
    PhaseCorrelation *pc = NULL;

    for (s = 0; s < n; s++) {
        first = stripe_first_row(s, n, pair->yres);
        h = stripe_end_row(s, n, pair->yres) - first;
        if (!pc || pc->rows != h) {
            if (pc)
                phase_correlation_free(pc);
            pc = phase_correlation_new(h, pair->xres);
        }
        phase_correlation_shift(pc, pair->image + first*pair->xres, pair->reference + first*pair->xres,
                                &dy, &dx);
        if (g_getenv("STUDY_DEBUG"))
            printf("pc s=%d truth %.3f %.3f pc %.3f %.3f\n", s, tx[s], ty[s], dx, dy);
        tally_add(tally, dx - tx[s], dy - ty[s], FALSE);
    }
    phase_correlation_free(pc);
    tally->seconds += (g_get_monotonic_time() - start)/1e6;
    tally->frames++;
}

static void
run_ours(const FramePair *pair, gint n, gdouble max_shift, const gdouble *tx, const gdouble *ty,
         Tally *raw, Tally *filled, gdouble *score_hist)
{
    StripeShift *shifts = g_new(StripeShift, n);
    gboolean *has = g_new(gboolean, n);
    gdouble *dx = g_new(gdouble, n), *dy = g_new(gdouble, n);
    StripeRegistrationOptions options;
    GError *error = NULL;
    gint64 start = g_get_monotonic_time();
    gint s;

    stripe_registration_options_init(&options);
    options.search_x = options.search_y = max_shift;
    if (!stripe_registration_measure(pair->image, pair->reference, pair->xres, pair->yres, n, &options, shifts, &error))
        g_error("registration failed: %s", error->message);
    raw->seconds += (g_get_monotonic_time() - start)/1e6;
    raw->frames++;
    for (s = 0; s < n; s++) {
        tally_add(raw, shifts[s].dx - tx[s], shifts[s].dy - ty[s], !shifts[s].accepted);
        has[s] = shifts[s].accepted;
        dx[s] = shifts[s].dx;
        dy[s] = shifts[s].dy;
        score_hist[MIN((gint)(10.0*shifts[s].score), 9)] += 1.0;
    }
    if (stripe_drift_fill_missing(n, has, dx, dy)) {
        for (s = 0; s < n; s++)
            tally_add(filled, dx[s] - tx[s], dy[s] - ty[s], !has[s]);
    }
    filled->seconds = raw->seconds;
    filled->frames = raw->frames;
    g_free(shifts);
    g_free(has);
    g_free(dx);
    g_free(dy);
}

/* Gwyddion's estimate is relative (median removed), so it is compared after
 * removing its best constant offset from the truth, per frame; ours is not. */
static void
run_gwyddion(const FramePair *pair, gint n, const gdouble *tx, Tally *tally)
{
    gdouble *row_drift = g_new(gdouble, pair->yres);
    gdouble *sx = g_new(gdouble, n);
    gdouble offset = 0.0, seconds;
    gint s, r, first, end;

    if (!gwyddion_drift_estimate(pair->image, pair->xres, pair->yres, row_drift, &seconds))
        g_error("Gwyddion's drift function did not produce a drift graph");
    tally->seconds += seconds;
    tally->frames++;
    for (s = 0; s < n; s++) {
        first = stripe_first_row(s, n, pair->yres);
        end = stripe_end_row(s, n, pair->yres);
        sx[s] = 0.0;
        for (r = first; r < end; r++)
            sx[s] += row_drift[r];
        sx[s] /= end - first;
        offset += (sx[s] - tx[s])/n;
    }
    for (s = 0; s < n; s++) {
        if (g_getenv("STUDY_DEBUG"))
            printf("gwy s=%d truth %.3f gwy %.3f\n", s, tx[s], sx[s] - offset);
        tally_add(tally, sx[s] - offset - tx[s], 0.0, FALSE);
    }
    g_free(sx);
    g_free(row_drift);
}

static void
print_header(void)
{
    printf("%-38s %9s %9s %9s %9s %9s %9s %9s\n",
           "method", "rms|e|", "rms(ex)", "max|e|", "max", ">1px", "rejected", "ms/frame");
}

static void
run_study(const gchar *title, const FramePairSpec *spec, gint pairs, guint32 seed0, gint n,
          gdouble max_shift, gboolean with_gwyddion)
{
    Tally ours = { "ours (ZNCC, stripe vs whole frame)", 0, 0, 0, 0, 0, 0, 0, 0 };
    Tally filled = { "ours, rejected filled (nearest stripe)", 0, 0, 0, 0, 0, 0, 0, 0 };
    Tally plain = { "plain phase correlation, stripe/stripe", 0, 0, 0, 0, 0, 0, 0, 0 };
    Tally gwy = { "Gwyddion drift (x only, offset fitted)", 0, 0, 0, 0, 0, 0, 0, 0 };
    gdouble hist[10] = { 0 };
    gdouble *tx = g_new(gdouble, n), *ty = g_new(gdouble, n);
    gchar limit[32];
    gint i, k;

    if (max_shift > 0.0)
        g_snprintf(limit, sizeof(limit), "%g px", max_shift);
    else
        g_snprintf(limit, sizeof(limit), "default (1/4 side)");
    printf("\n== %s: %d pairs %dx%d, N = %d, seeds %u..%u, noise %g, max_shift %s\n",
           title, pairs, spec->xres, spec->yres, n, seed0, seed0 + pairs - 1, spec->noise, limit);
    for (i = 0; i < pairs; i++) {
        FramePair *pair = frame_pair_generate(spec, seed0 + i);

        frame_pair_stripe_truth(pair, n, tx, ty);
        run_ours(pair, n, max_shift, tx, ty, &ours, &filled, hist);
        run_phase_correlation(pair, n, tx, ty, &plain);
        if (with_gwyddion)
            run_gwyddion(pair, n, tx, &gwy);
        frame_pair_free(pair);
    }
    print_header();
    tally_print(&ours, FALSE);
    tally_print(&filled, FALSE);
    tally_print(&plain, FALSE);
    if (with_gwyddion)
        tally_print(&gwy, TRUE);
    printf("our scores (0.0-0.1 ... 0.9-1.0):");
    for (k = 0; k < 10; k++)
        printf(" %.0f", hist[k]);
    printf("\n");
    g_free(tx);
    g_free(ty);
}

int
main(int argc, char *argv[])
{
    FramePairSpec spec;
    gint pairs = (argc > 1) ? atoi(argv[1]) : 120;
    guint32 seed0 = (argc > 2) ? (guint32)strtoul(argv[2], NULL, 10) : 1;
    gboolean with_gwyddion = !g_getenv("STUDY_NO_GWYDDION");

    if (pairs < 1) {
        fprintf(stderr, "usage: %s [PAIRS [FIRST_SEED]]\n", argv[0]);
        return 2;
    }
    if (with_gwyddion && !gwyddion_drift_init())
        return 1;

    frame_pair_spec_init(&spec);
    run_study("random drift (up to ~10 px), particles + roughness + noise", &spec, pairs, seed0, 16, 0.0,
              with_gwyddion);
    run_study("the same, search limited to 16 px", &spec, pairs, seed0, 16, 16.0, FALSE);
    spec.drift_scale = 0.3;
    run_study("small drift (scale 0.3, up to ~3 px)", &spec, pairs, seed0, 16, 0.0, FALSE);
    spec.drift_scale = 1.0;
    spec.noise = 0.2;
    run_study("strong noise (0.2)", &spec, pairs, seed0, 16, 0.0, with_gwyddion);
    spec.noise = 0.05;
    spec.lattice = 0.3;
    run_study("periodic lattice (0.3, period 12 px) under the particles", &spec, pairs, seed0, 16, 0.0,
              FALSE);
    spec.lattice = 1.0;
    spec.particle_density = 1.0/20000.0;
    spec.roughness = 0.02;
    run_study("strong lattice, few particles: most stripes ambiguous", &spec, MAX(pairs/4, 1), seed0, 16, 0.0,
              FALSE);
    frame_pair_spec_init(&spec);
    spec.xres = 320;
    spec.yres = 200;
    run_study("non-square 320x200, N = 12", &spec, MAX(pairs/4, 1), seed0, 12, 0.0, FALSE);

    if (with_gwyddion)
        gwyddion_drift_finish();
    fftw_cleanup();
    return 0;
}
