/*
 *  Fitting drift trajectories to displacement measurements; model choice.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <string.h>
#include <math.h>
#include <libgwyddion/gwymath.h>
#include "drift-fit.h"
#include "parallel-run.h"
#include "median.h"

#define MAX_BASIS 4
#define GOLDEN_STEPS 40
#define MAX_GRID 6000
/* Local minima of an oscillation's grid refined besides the best. */
#define REFINED_MINIMA 12
/* Distinct measured times a jump leaves on either side at least. */
#define JUMP_MIN_SIDE 3
/* Measurements a jump must lie within, and measurements it must not, at
 * least (see jump_separable). */
#define JUMP_MIN_SPLIT 3
/* Oscillation periods whose cycles mostly cancel between the frames are not
 * searched (see oscillation_visibility). */
#define MIN_VISIBILITY 0.25

/* Measurements in nm and s, weights normalised to mean 1 over those used. */
typedef struct {
    gint n;
    gdouble *ta, *tb, *d[2], *w;
    gdouble *half;         /* half the span of each measurement */
    gint n_used;
    gdouble t_min;         /* earliest time */
    gdouble t_max;         /* latest time */
    gdouble t_resolution;  /* typical spacing of distinct times */
    gdouble longest_gap;   /* longest stretch without a measured time */
    gdouble longest_run;   /* longest stretch with no step above half the
                              longest gap */
    gboolean periods_given; /* the observable periods are period_range, */
    gdouble period_range[2]; /* those of the whole series (a training fold) */
} Prepared;

/* What is fitted: a DriftModelType, or a creep form after them. */
typedef gint FitKind;

#define KIND_ACCELERATION (DRIFT_MODEL_NTYPES + DRIFT_FIT_CREEP_ACCELERATION)
#define KIND_LOG_CREEP (DRIFT_MODEL_NTYPES + DRIFT_FIT_CREEP_LOGARITHMIC)

static FitKind
fit_kind(const DriftFit *fit)
{
    if (fit->creep != DRIFT_FIT_CREEP_NONE)
        return DRIFT_MODEL_NTYPES + fit->creep;
    return fit->type;
}

static const DriftModelType candidate_types[] = {
    DRIFT_MODEL_NONE, DRIFT_MODEL_SETTLING, DRIFT_MODEL_OSCILLATION,
    DRIFT_MODEL_JUMP, DRIFT_MODEL_ACCELERATION,
};

const DriftModelType*
drift_fit_candidates(gint *n)
{
    *n = G_N_ELEMENTS(candidate_types);
    return candidate_types;
}

void
drift_fit_options_init(DriftFitOptions *options)
{
    memset(options, 0, sizeof(DriftFitOptions));
    options->n_folds = 5;
    options->bic_margin = 20.0;
    options->cv_gain = 0.1;
    options->min_explained = 1.5;
    options->outlier_floor_nm = 0.0;
    options->outlier_sigmas = 5.0;
    options->min_cycles = 1.5;
}

/* The options given, or the defaults in *defaults. */
static const DriftFitOptions*
options_or_defaults(const DriftFitOptions *options, DriftFitOptions *defaults)
{
    if (options)
        return options;
    drift_fit_options_init(defaults);
    return defaults;
}

gdouble
drift_fit_min_period(gdouble line_time, gint lines, gint n_blocks)
{
    return 3.0*line_time*lines/MAX(n_blocks, 1);
}

/* sinh(x)/x and sin(x)/x, exact near 0. */
static gdouble
sinhc(gdouble x)
{
    return fabs(x) < 1e-4 ? 1.0 + x*x/6.0 : sinh(x)/x;
}

static gdouble
sinc(gdouble x)
{
    return fabs(x) < 1e-4 ? 1.0 - x*x/6.0 : sin(x)/x;
}

/* What averaging over [t - h, t + h] leaves of an oscillation of period
 * theta. */
static gdouble
oscillation_span_factor(gdouble theta, gdouble h)
{
    return (h > 0.0) ? sinc(2.0*G_PI*h/theta) : 1.0;
}

/* The oscillation's basis at t, its sine and cosine scaled by w. */
static gint
oscillation_basis(gdouble theta, gdouble t, gdouble w, gdouble *f)
{
    f[0] = t;
    f[1] = w*sin(2.0*G_PI*t/theta);
    f[2] = w*cos(2.0*G_PI*t/theta);
    return 3;
}

/* Basis functions of the trajectory for nonlinear parameter theta,
 * averaged over [t - h, t + h] (h = 0: at t). */
static gint
model_basis_mean(FitKind kind, gdouble theta, gdouble t, gdouble h,
                 gdouble *f)
{
    gdouble w;

    f[0] = t;
    switch (kind) {
        case DRIFT_MODEL_SETTLING:
        /* The mean of exp(-s/theta) is exp(-t/theta) sinh(h/theta)/(h/theta);
         * so long a span that it overflows averages nothing (the basis is
         * then the point value). */
        w = sinhc(h/theta);
        f[1] = isfinite(w) ? theta*(1.0 - exp(-t/theta)*w)
                           : -theta*expm1(-t/theta);
        return 2;

        case DRIFT_MODEL_OSCILLATION:
        return oscillation_basis(theta, t, oscillation_span_factor(theta, h), f);

        case DRIFT_MODEL_JUMP:
        if (h > 0.0)
            f[1] = CLAMP((t + h - theta)/(2.0*h), 0.0, 1.0);
        else
            f[1] = (t >= theta) ? 1.0 : 0.0;
        return 2;

        case DRIFT_MODEL_ACCELERATION:
        case KIND_ACCELERATION:
        f[1] = t*t + h*h/3.0;
        return 2;

        case KIND_LOG_CREEP:
        f[1] = theta*log1p(t/theta);
        return 2;

        default:
        return 1;
    }
}


static gboolean
model_has_nonlinear(FitKind kind)
{
    return (kind == DRIFT_MODEL_SETTLING || kind == DRIFT_MODEL_OSCILLATION
            || kind == DRIFT_MODEL_JUMP || kind == KIND_LOG_CREEP);
}

/* The sorted distinct times of the measurements; returns their count. */
static gint
distinct_times(const Prepared *pm, gdouble **times)
{
    gdouble *t = g_new(gdouble, 2*pm->n + 1);
    gint i, m = 0, k;

    for (i = 0; i < pm->n; i++) {
        if (pm->w[i] <= 0.0)
            continue;
        t[m++] = pm->ta[i];
        t[m++] = pm->tb[i];
    }
    gwy_math_sort(m, t);
    for (i = k = 0; i < m; i++) {
        if (!k || t[i] - t[k-1] > 1e-9*(1.0 + fabs(t[i])))
            t[k++] = t[i];
    }
    *times = t;
    return k;
}

/* The longest stretch of the sorted distinct times with no step longer
 * than max_step. */
static gdouble
longest_run(const gdouble *times, gint nt, gdouble max_step)
{
    gdouble run = 0.0;
    gint i, start = 0;

    for (i = 1; i <= nt; i++) {
        if (i == nt || times[i] - times[i-1] > max_step) {
            run = MAX(run, times[i-1] - times[start]);
            start = i;
        }
    }
    return run;
}

static void
prepared_free(Prepared *pm)
{
    g_free(pm->ta);
    g_free(pm->tb);
    g_free(pm->d[0]);
    g_free(pm->d[1]);
    g_free(pm->w);
    g_free(pm->half);
}

/* mask: when not NULL, measurements with mask[i] FALSE are left out. */
static void
prepare(const DriftMeasurement *meas, gint n, const gboolean *mask,
        Prepared *pm)
{
    gdouble wsum = 0.0, *times, *gaps;
    gint i, nt;

    pm->n = n;
    pm->ta = g_new(gdouble, n);
    pm->tb = g_new(gdouble, n);
    pm->d[0] = g_new(gdouble, n);
    pm->d[1] = g_new(gdouble, n);
    pm->w = g_new(gdouble, n);
    pm->half = g_new(gdouble, n);
    pm->n_used = 0;
    pm->periods_given = FALSE;
    pm->t_min = G_MAXDOUBLE;
    pm->t_max = 0.0;
    for (i = 0; i < n; i++) {
        const DriftMeasurement *m = meas + i;
        /* Content seen again no later than it was first scanned means
         * frames overlapping in time (wrong timing): no drift to read. */
        gboolean usable = (m->weight > 0.0 && isfinite(m->weight)
                           && isfinite(m->dx) && isfinite(m->dy)
                           && isfinite(m->t_a) && isfinite(m->t_b)
                           && m->t_a > m->t_b
                           && (!mask || mask[i]));

        pm->ta[i] = m->t_a;
        pm->tb[i] = m->t_b;
        pm->half[i] = (m->span > 0.0 && isfinite(m->span)) ? 0.5*m->span : 0.0;
        pm->d[0][i] = usable ? 1e9*m->dx : 0.0;
        pm->d[1][i] = usable ? 1e9*m->dy : 0.0;
        pm->w[i] = usable ? m->weight : 0.0;
        if (usable) {
            wsum += m->weight;
            pm->n_used++;
            pm->t_min = MIN(pm->t_min, MIN(m->t_a, m->t_b));
            pm->t_max = MAX(pm->t_max, MAX(m->t_a, m->t_b));
        }
    }
    for (i = 0; i < n; i++)
        pm->w[i] *= (wsum > 0.0) ? pm->n_used/wsum : 0.0;

    if (!pm->n_used)
        pm->t_min = 0.0;
    nt = distinct_times(pm, &times);
    pm->t_resolution = pm->t_max/MAX(nt, 1);
    pm->longest_gap = pm->t_max - pm->t_min;
    if (nt > 2) {
        gaps = g_new(gdouble, nt - 1);
        for (i = 0; i+1 < nt; i++)
            gaps[i] = times[i+1] - times[i];
        gwy_math_sort(nt - 1, gaps);
        pm->t_resolution = MAX(gaps[(nt - 1)/2], 1e-9);
        pm->longest_gap = gaps[nt - 2];
        g_free(gaps);
    }
    pm->longest_run = longest_run(times, nt, 0.5*pm->longest_gap);
    g_free(times);
}

/* Solves the k x k system a x = b (a, b destroyed) by Gaussian elimination
 * with partial pivoting; a vanishing pivot gives a zero coefficient.  Not
 * gwy_math_lin_solve(): it refuses singular systems, and an effect whose
 * basis no measurement sees (zero everywhere) must still fit the velocity,
 * with a zero effect. */
static void
solve_small(gdouble *a, gdouble *b, gint k, gdouble *x)
{
    gint i, j, r, p;
    gdouble scale = 0.0;

    for (i = 0; i < k; i++)
        scale = MAX(scale, fabs(a[i*k + i]));
    for (i = 0; i < k; i++) {
        p = i;
        for (r = i+1; r < k; r++) {
            if (fabs(a[r*k + i]) > fabs(a[p*k + i]))
                p = r;
        }
        if (p != i) {
            for (j = 0; j < k; j++) {
                gdouble tmp = a[i*k + j];
                a[i*k + j] = a[p*k + j];
                a[p*k + j] = tmp;
            }
            gdouble tmp = b[i];
            b[i] = b[p];
            b[p] = tmp;
        }
        if (fabs(a[i*k + i]) <= 1e-13*scale) {
            a[i*k + i] = 1.0;
            for (j = i+1; j < k; j++)
                a[i*k + j] = 0.0;
            b[i] = 0.0;
        }
        for (r = i+1; r < k; r++) {
            gdouble f = a[r*k + i]/a[i*k + i];
            for (j = i; j < k; j++)
                a[r*k + j] -= f*a[i*k + j];
            b[r] -= f*b[i];
        }
    }
    for (i = k-1; i >= 0; i--) {
        gdouble s = b[i];
        for (j = i+1; j < k; j++)
            s -= a[i*k + j]*x[j];
        x[i] = s/a[i*k + i];
    }
}

/* The least-squares coefficients of both axes from the normal equations
 * (ata k x k, atb per axis) and the weighted residual sum of squares, from
 * sdd, the weighted d.d of each axis; NAN when ata is not finite. */
static gdouble
solve_normal(const gdouble *ata, gdouble atb[2][MAX_BASIS],
             const gdouble *sdd, gint k, gdouble coef[2][MAX_BASIS])
{
    gdouble a[MAX_BASIS*MAX_BASIS], row[MAX_BASIS], rss = 0.0;
    gint j, ax;

    for (j = 0; j < k*k; j++) {
        if (!isfinite(ata[j]))
            return NAN;
    }
    /* The residual sum of squares of a least-squares solution is
     * d.d - coef.(A^T d): no second pass over the measurements (the grid
     * searches call this thousands of times). */
    for (ax = 0; ax < 2; ax++) {
        memcpy(a, ata, k*k*sizeof(gdouble));
        memcpy(row, atb[ax], k*sizeof(gdouble));
        solve_small(a, row, k, coef[ax]);
        rss += sdd[ax];
        for (j = 0; j < k; j++)
            rss -= coef[ax][j]*atb[ax][j];
    }
    return MAX(rss, 0.0);
}

/* Whether a jump that lies within `spanned` of the n_used measurements
 * can be told from the velocity.  Its step adds to exactly the
 * measurements it lies within, so without JUMP_MIN_SPLIT measurements on
 * each side of that split the step is the velocity times the spanned
 * measurements' nearly equal baselines over again: any step fits, read
 * from the baselines' spread of a few percent (one pair of frames with a
 * featureless frame between, every block spanning a jump placed between
 * them: a step of 168 nm in 64 nm frames, the drift read 26 px off;
 * test-series-correction seed 19386928). */
static gboolean
jump_separable(gint spanned, gint n_used)
{
    return spanned >= JUMP_MIN_SPLIT && n_used - spanned >= JUMP_MIN_SPLIT;
}

/* Whether a measurement whose step basis (its share of the step, 0 to 1
 * over its span) is this counts as spanning the jump. */
static gboolean
spans_jump(gdouble step_basis)
{
    return fabs(step_basis) >= 0.5;
}

/* Weighted least squares for a fixed nonlinear parameter; returns the
 * weighted residual sum of squares (nm^2) over both axes; NAN for a jump
 * that cannot be told from the velocity. */
static gdouble
solve_fixed(const Prepared *pm, FitKind kind, gdouble theta,
            gdouble coef[2][MAX_BASIS], gint *n_basis)
{
    gdouble ata[MAX_BASIS*MAX_BASIS], atb[2][MAX_BASIS], fa[MAX_BASIS],
            fb[MAX_BASIS], row[MAX_BASIS];
    gdouble sdd[2] = { 0.0, 0.0 }, half = NAN, w = 1.0;
    gint i, j, l, k = 1, spanned = 0;

    memset(ata, 0, sizeof(ata));
    memset(atb, 0, sizeof(atb));
    memset(coef, 0, 2*MAX_BASIS*sizeof(gdouble));
    /* Callers read the basis size even when the fit is refused below. */
    *n_basis = k;
    for (i = 0; i < pm->n; i++) {
        if (pm->w[i] <= 0.0)
            continue;
        if (kind == DRIFT_MODEL_OSCILLATION) {
            /* The span factor, a sine, depends on the span alone: blocks of
             * one height share it (the golden search of the period calls
             * this hundreds of times per fit). */
            if (pm->half[i] != half) {
                half = pm->half[i];
                w = oscillation_span_factor(theta, half);
            }
            k = oscillation_basis(theta, pm->ta[i], w, fa);
            oscillation_basis(theta, pm->tb[i], w, fb);
        }
        else {
            k = model_basis_mean(kind, theta, pm->ta[i], pm->half[i], fa);
            model_basis_mean(kind, theta, pm->tb[i], pm->half[i], fb);
        }
        for (j = 0; j < k; j++)
            row[j] = fa[j] - fb[j];
        if (kind == DRIFT_MODEL_JUMP)
            spanned += spans_jump(row[1]);
        for (j = 0; j < k; j++) {
            for (l = 0; l < k; l++)
                ata[j*k + l] += pm->w[i]*row[j]*row[l];
            atb[0][j] += pm->w[i]*row[j]*pm->d[0][i];
            atb[1][j] += pm->w[i]*row[j]*pm->d[1][i];
        }
        sdd[0] += pm->w[i]*pm->d[0][i]*pm->d[0][i];
        sdd[1] += pm->w[i]*pm->d[1][i]*pm->d[1][i];
    }
    *n_basis = k;
    if (kind == DRIFT_MODEL_JUMP && !jump_separable(spanned, pm->n_used))
        return NAN;
    return solve_normal(ata, atb, sdd, k, coef);
}

/* The periods an oscillation can be seen with in these measurements.  At
 * least min_cycles cycles must fit into the measured time span, or no
 * periodicity is seen: the fit merely bends the trajectory.  And a period
 * shorter than twice the longest stretch of time without measurements
 * aliases when the measurements are bursts shorter than the gaps between
 * them: the phase is free across the gap, so a whole comb of periods fits
 * alike (a frame series scanned in short bursts far apart cannot tell a fast
 * oscillation from a distortion repeated in every frame).  A gap shorter
 * than the measured stretches around it (blocks without particles in
 * contiguous frames) does not: the stretches follow the phase across it.
 * FALSE when no period is left. */
static gboolean
observable_periods(const Prepared *pm, const DriftFitOptions *options,
                   gdouble *shortest, gdouble *longest)
{
    gdouble cycles = (options->min_cycles > 0.0) ? options->min_cycles : 1.5;

    if (pm->periods_given) {
        *shortest = pm->period_range[0];
        *longest = pm->period_range[1];
        return pm->n_used >= 3 && *shortest < *longest;
    }
    *shortest = MAX(2.0*pm->t_resolution, options->min_period);
    if (pm->longest_gap > pm->longest_run)
        *shortest = MAX(*shortest, 2.0*pm->longest_gap);
    *longest = (pm->t_max - pm->t_min)/cycles;
    return pm->n_used >= 3 && *shortest < *longest;
}

/* How much of an oscillation of this period shows in the measurements: the
 * weighted mean of |exp(i w t_a) - exp(i w t_b)|^2/2 = 1 - cos(w (t_a - t_b)),
 * about 1 for a period unrelated to the frame timing, 0 when every
 * measurement spans a whole number of cycles.  Such an oscillation repeats
 * identically in every frame and cancels between frames; fitting it anyway
 * blows a small pattern tied to the position in the frame (a registration
 * bias of each block) up into a large amplitude. */
static gdouble
oscillation_visibility(const Prepared *pm, gdouble period)
{
    gdouble sum = 0.0, wsum = 0.0;
    gint i;

    for (i = 0; i < pm->n; i++) {
        if (pm->w[i] <= 0.0)
            continue;
        sum += pm->w[i]*(1.0 - cos(2.0*G_PI*(pm->ta[i] - pm->tb[i])/period));
        wsum += pm->w[i];
    }
    return (wsum > 0.0) ? sum/wsum : 0.0;
}

/* Recomputed exactly every this many frequencies, so that the rounding of
 * the rotations cannot build up. */
#define SCAN_RESEED 32

/* sin and cos of a phase, and of the step that takes it to the next
 * frequency. */
typedef struct {
    gdouble s, c, rs, rc;
} Phasor;

static void
phasor_set(Phasor *p, gdouble phase, gdouble step)
{
    p->s = sin(phase);
    p->c = cos(phase);
    p->rs = sin(step);
    p->rc = cos(step);
}

/* Angle addition: the phase one step on. */
static void
phasor_step(Phasor *p)
{
    gdouble s = p->s*p->rc + p->c*p->rs;

    p->c = p->c*p->rc - p->s*p->rs;
    p->s = s;
}

/* What a used measurement brings to every frequency of
 * oscillation_scan(), in the order they are summed: its weight, the
 * velocity's basis value (t_a - t_b) and its weighted product, its
 * displacements, and its span's half as a phase per unit frequency. */
typedef struct {
    gdouble w, r0, wr0, d0, d1, half_2pi;
} ScanTerm;

/* The sums of the velocity's basis alone: the same at every frequency. */
typedef struct {
    gdouble a00, b0[2], wsum;
} ScanFixed;

/* One frequency of oscillation_scan(): the normal equations (as
 * solve_fixed() sums them, product by product) and the visibility, from
 * the phasors of the used measurements at it, each stepped on to the next
 * frequency.  The velocity's own sums come from fixed. */
static gdouble
scan_frequency(const ScanTerm *terms, gint nu, const ScanFixed *fixed,
               gdouble f, Phasor *pa, Phasor *pb, Phasor *ph,
               const gdouble *sdd, gdouble *visibility)
{
    gdouble ata[MAX_BASIS*MAX_BASIS], atb[2][MAX_BASIS], coef[2][MAX_BASIS];
    gdouble a01 = 0.0, a02 = 0.0, a10 = 0.0, a11 = 0.0, a12 = 0.0;
    gdouble a20 = 0.0, a21 = 0.0, a22 = 0.0, bx1 = 0.0, bx2 = 0.0;
    gdouble by1 = 0.0, by2 = 0.0, x, w, r1, r2, wr1, wr2, vsum = 0.0, rss;
    gint u;

    for (u = 0; u < nu; u++) {
        const ScanTerm *t = terms + u;

        /* The basis averaged over the span (model_basis_mean). */
        x = t->half_2pi*f;
        w = (t->half_2pi > 0.0) ? (fabs(x) < 1e-4 ? 1.0 - x*x/6.0 : ph[u].s/x) : 1.0;
        r1 = w*(pa[u].s - pb[u].s);
        r2 = w*(pa[u].c - pb[u].c);
        wr1 = t->w*r1;
        wr2 = t->w*r2;
        a01 += t->wr0*r1;
        a02 += t->wr0*r2;
        a10 += wr1*t->r0;
        a11 += wr1*r1;
        a12 += wr1*r2;
        a20 += wr2*t->r0;
        a21 += wr2*r1;
        a22 += wr2*r2;
        bx1 += wr1*t->d0;
        by1 += wr1*t->d1;
        bx2 += wr2*t->d0;
        by2 += wr2*t->d1;
        /* 1 - cos(w (t_a - t_b)), as oscillation_visibility() sums it. */
        vsum += t->w*(1.0 - (pa[u].c*pb[u].c + pa[u].s*pb[u].s));
        phasor_step(pa + u);
        phasor_step(pb + u);
        phasor_step(ph + u);
    }
    {
        const gdouble a[9] = { fixed->a00, a01, a02, a10, a11, a12, a20, a21, a22 };
        const gdouble b[2][3] = { { fixed->b0[0], bx1, bx2 }, { fixed->b0[1], by1, by2 } };

        memcpy(ata, a, sizeof(a));
        memcpy(atb[0], b[0], sizeof(b[0]));
        memcpy(atb[1], b[1], sizeof(b[1]));
    }
    *visibility = (fixed->wsum > 0.0) ? vsum/fixed->wsum : 0.0;
    rss = solve_normal(ata, atb, sdd, 3, coef);
    return isfinite(rss) ? rss : G_MAXDOUBLE;
}

/* The oscillation's residual sum of squares and visibility at m
 * frequencies evenly from fmin to fmax in one pass: each measurement's
 * sines and cosines step from one frequency to the next by a rotation,
 * a few multiplications where sin and cos cost a hundred (the grid of a
 * long series is thousands of frequencies times thousands of
 * measurements, refitted after each outlier round and in each fold). */
static void
oscillation_scan(const Prepared *pm, gdouble fmin, gdouble fmax, gint m,
                 gdouble *rss, gdouble *visibility)
{
    gint n = MAX(pm->n, 1), *used = g_new(gint, n), nu = 0, i, j, u;
    ScanTerm *terms = g_new(ScanTerm, n);
    ScanFixed fixed = { 0.0, { 0.0, 0.0 }, 0.0 };
    Phasor *pa = g_new(Phasor, 3*n), *pb = pa + n, *ph = pb + n;
    gdouble df = (fmax - fmin)/(m - 1.0), f, sdd[2] = { 0.0, 0.0 };

    for (i = 0; i < pm->n; i++) {
        ScanTerm *t = terms + nu;

        if (pm->w[i] <= 0.0)
            continue;
        used[nu++] = i;
        sdd[0] += pm->w[i]*pm->d[0][i]*pm->d[0][i];
        sdd[1] += pm->w[i]*pm->d[1][i]*pm->d[1][i];
        t->w = pm->w[i];
        t->r0 = pm->ta[i] - pm->tb[i];
        t->wr0 = t->w*t->r0;
        t->d0 = pm->d[0][i];
        t->d1 = pm->d[1][i];
        t->half_2pi = 2.0*G_PI*pm->half[i];
        fixed.a00 += t->wr0*t->r0;
        fixed.b0[0] += t->wr0*t->d0;
        fixed.b0[1] += t->wr0*t->d1;
        fixed.wsum += t->w;
    }
    for (j = 0; j < m; j++) {
        f = fmin + (fmax - fmin)*j/(m - 1.0);
        for (u = 0; u < nu && j % SCAN_RESEED == 0; u++) {
            i = used[u];
            phasor_set(pa + u, 2.0*G_PI*pm->ta[i]*f, 2.0*G_PI*pm->ta[i]*df);
            phasor_set(pb + u, 2.0*G_PI*pm->tb[i]*f, 2.0*G_PI*pm->tb[i]*df);
            phasor_set(ph + u, 2.0*G_PI*pm->half[i]*f, 2.0*G_PI*pm->half[i]*df);
        }
        rss[j] = scan_frequency(terms, nu, &fixed, f, pa, pb, ph, sdd, visibility + j);
    }
    g_free(terms);
    g_free(pa);
    g_free(used);
}

/* The oscillation's grid, uniform in frequency from fmin to fmax (m
 * values), without the periods whose cycles cancel between the frames,
 * and the residual sums of squares at it; returns its size. */
static gint
oscillation_grid(const Prepared *pm, gdouble fmin, gdouble fmax, gint m,
                 gdouble **grid, gdouble **rss)
{
    gdouble *all = g_new(gdouble, 2*m), *visibility = all + m;
    gint i, nt = 0;

    oscillation_scan(pm, fmin, fmax, m, all, visibility);
    *grid = g_new(gdouble, m);
    *rss = g_new(gdouble, m);
    for (i = 0; i < m; i++) {
        if (visibility[i] >= MIN_VISIBILITY) {
            (*grid)[nt] = 1.0/(fmin + (fmax - fmin)*i/(m - 1.0));
            (*rss)[nt++] = all[i];
        }
    }
    g_free(all);
    if (!nt) {
        g_free(*grid);
        g_free(*rss);
        *grid = *rss = NULL;
    }
    return nt;
}

/* Candidate values of the nonlinear parameter; 0 when there are none.
 * *rss gets their residual sums of squares where the grid comes with them
 * (an oscillation's), else NULL. */
static gint
parameter_grid(const Prepared *pm, FitKind kind,
               const DriftFitOptions *options, gdouble **grid, gdouble **rss)
{
    gdouble tmin = MAX(2.0*pm->t_resolution, options->min_period);
    gdouble tmax = MAX(pm->t_max, 2.0*tmin), *g, *times;
    gdouble pshort, plong;
    gint i, m, nt;

    *rss = NULL;
    if (kind == DRIFT_MODEL_SETTLING || kind == KIND_LOG_CREEP) {
        m = 80;
        g = g_new(gdouble, m);
        for (i = 0; i < m; i++)
            g[i] = 0.5*tmin*pow(6.0*tmax/(0.5*tmin), i/(m - 1.0));
    }
    else if (kind == DRIFT_MODEL_OSCILLATION) {
        /* Uniform in frequency, fine enough that no alias is missed. */
        gdouble fmin, fmax, df = 0.125/tmax;

        if (!observable_periods(pm, options, &pshort, &plong)) {
            *grid = NULL;
            return 0;
        }
        fmin = 1.0/plong;
        fmax = 1.0/pshort;
        m = CLAMP((gint)ceil((fmax - fmin)/df) + 1, 8, MAX_GRID);
        m = oscillation_grid(pm, fmin, fmax, m, &g, rss);
    }
    else {
        /* A step between each pair of consecutive distinct times, with at
         * least JUMP_MIN_SIDE times on either side: a jump that sets apart
         * the last block or two explains a single failed registration
         * there, which the outlier cut then keeps (an acceleration read as
         * a jump in the last block, then as none).  At most MAX_GRID of
         * them, evenly spread (the series correction places a jump to the
         * line afterwards). */
        gint stride, first, last, span_i;

        nt = distinct_times(pm, &times);
        first = JUMP_MIN_SIDE - 1;
        last = nt - 1 - JUMP_MIN_SIDE;
        if (last < first) {
            first = 0;
            last = nt - 2;
        }
        span_i = MAX(last - first + 1, 1);
        stride = MAX((span_i + MAX_GRID - 1)/MAX_GRID, 1);
        m = MAX((span_i + stride - 1)/stride, 1);
        g = g_new(gdouble, m);
        for (i = 0; i < m && first + stride*i + 1 < nt; i++)
            g[i] = 0.5*(times[first + stride*i] + times[first + stride*i + 1]);
        if (nt < 2)
            g[0] = tmax;
        g_free(times);
    }
    *grid = g;
    return m;
}

static gdouble
refine_golden(const Prepared *pm, FitKind kind, gdouble lo, gdouble hi,
              gdouble best_theta, gdouble best_rss, gdouble *theta)
{
    const gdouble r = 0.5*(sqrt(5.0) - 1.0);
    gdouble coef[2][MAX_BASIS], a = lo, b = hi, x1, x2, f1, f2;
    gint i, k;

    x1 = b - r*(b - a);
    x2 = a + r*(b - a);
    f1 = solve_fixed(pm, kind, x1, coef, &k);
    f2 = solve_fixed(pm, kind, x2, coef, &k);
    for (i = 0; i < GOLDEN_STEPS; i++) {
        if (f1 < f2) {
            b = x2;
            x2 = x1;
            f2 = f1;
            x1 = b - r*(b - a);
            f1 = solve_fixed(pm, kind, x1, coef, &k);
        }
        else {
            a = x1;
            x1 = x2;
            f1 = f2;
            x2 = a + r*(b - a);
            f2 = solve_fixed(pm, kind, x2, coef, &k);
        }
    }
    if (MIN(f1, f2) < best_rss) {
        *theta = (f1 < f2) ? x1 : x2;
        return MIN(f1, f2);
    }
    *theta = best_theta;
    return best_rss;
}

/* Refines the grid value i between its neighbours; the refined value
 * must stay visible for an oscillation, else the grid value is kept. */
static gdouble
refine_grid_value(const Prepared *pm, FitKind kind, const gdouble *grid,
                  const gdouble *rss, gint m, gint i, gdouble *theta)
{
    gdouble best;

    *theta = grid[i];
    if (kind == DRIFT_MODEL_JUMP || m <= 2)
        return rss[i];
    best = refine_golden(pm, kind, grid[MAX(i - 1, 0)], grid[MIN(i + 1, m - 1)],
                         grid[i], rss[i], theta);
    if (kind == DRIFT_MODEL_OSCILLATION
        && oscillation_visibility(pm, *theta) < MIN_VISIBILITY) {
        *theta = grid[i];
        return rss[i];
    }
    return best;
}

/* The best nonlinear parameter (theta) and the index of the grid value it
 * was refined from.  An oscillation's residual has many narrow minima in
 * period (period and phase trade off over the long time span, and aliases
 * across the frame interval), so every local minimum of the grid is
 * refined, not just the lowest: a narrow true minimum can fall between grid
 * values and look worse there than a broad wrong one. */
static gint
search_grid(const Prepared *pm, FitKind kind, const gdouble *grid,
            const gdouble *rss, gint m, gdouble *theta)
{
    gdouble best, value, t;
    gint i, ibest = 0;

    for (i = 0; i < m; i++) {
        if (rss[i] < rss[ibest])
            ibest = i;
    }
    best = refine_grid_value(pm, kind, grid, rss, m, ibest, theta);
    if (kind == DRIFT_MODEL_OSCILLATION) {
        gint *minima = g_new(gint, m + 1), n_minima = 0, j;

        /* The lowest local minima besides the best, REFINED_MINIMA of them:
         * a long series has hundreds, each refined by some thirty fits,
         * and the grid is eight times finer than the series resolves, so
         * a true minimum lies beside one of the lowest. */
        for (i = 0; i < m; i++) {
            if (i == ibest || (i > 0 && rss[i-1] < rss[i])
                || (i+1 < m && rss[i+1] < rss[i]))
                continue;
            for (j = n_minima; j > 0 && rss[minima[j-1]] > rss[i]; j--)
                minima[j] = minima[j-1];
            minima[j] = i;
            n_minima = MIN(n_minima + 1, REFINED_MINIMA);
        }
        for (j = 0; j < n_minima; j++) {
            value = refine_grid_value(pm, kind, grid, rss, m, minima[j], &t);
            if (value < best) {
                best = value;
                *theta = t;
                ibest = minima[j];
            }
        }
        g_free(minima);
    }
    return ibest;
}

/* The first of m ascending values that is at least x (m if none). */
static gint
first_at_least(const gdouble *values, gint m, gdouble x)
{
    gint lo = 0, hi = m;

    while (lo < hi) {
        gint mid = lo + (hi - lo)/2;

        if (values[mid] < x)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo;
}

/* Whether the used measurements' times, spans and displacements are all
 * finite. */
static gboolean
used_values_finite(const Prepared *pm)
{
    gint i;

    for (i = 0; i < pm->n; i++) {
        if (pm->w[i] > 0.0
            && !(isfinite(pm->w[i]) && isfinite(pm->ta[i] - pm->tb[i]) && isfinite(pm->half[i])
                 && isfinite(pm->d[0][i]) && isfinite(pm->d[1][i])))
            return FALSE;
    }
    return TRUE;
}

/* The jump's residual sums of squares at an ascending grid, equal to the
 * last bit to solve_fixed() at each value, in a fraction of its time.  A
 * measurement's step basis is exactly zero unless the jump falls within
 * its span, so each measurement is added only into the sums of the grid
 * values within its span: a long series' grid has thousands of values and
 * each sees a few of its tens of thousands of measurements.  Every sum
 * takes its nonzero terms in solve_fixed()'s order, and the zeros it
 * leaves out change no sum (with doubles evaluated as doubles, as on
 * x86-64's SSE: FLT_EVAL_METHOD 0).  NULL when the grid is not ascending
 * or a value is not finite (solve_fixed() at each value then). */
static gdouble*
jump_grid_rss(const Prepared *pm, const gdouble *grid, gint m)
{
    gdouble fa[MAX_BASIS], fb[MAX_BASIS], ata[4], atb[2][MAX_BASIS], coef[2][MAX_BASIS];
    gdouble sums0[5] = { 0.0, 0.0, 0.0, 0.0, 0.0 }, *sums1, *rss, wi, r0, r1, lo, hi, margin;
    gint i, j, ax, *spanned;

    for (j = 0; j < m; j++) {
        if (!isfinite(grid[j]) || (j && !(grid[j-1] <= grid[j])))
            return NULL;
    }
    if (!used_values_finite(pm))
        return NULL;
    /* sums0: a00, b0 of each axis, d.d of each axis; sums1 per grid value:
     * a01, a10, a11, b1 of each axis. */
    sums1 = g_new0(gdouble, 5*m);
    spanned = g_new0(gint, m);
    for (i = 0; i < pm->n; i++) {
        if (pm->w[i] <= 0.0)
            continue;
        wi = pm->w[i];
        r0 = pm->ta[i] - pm->tb[i];
        sums0[0] += wi*r0*r0;
        sums0[1] += wi*r0*pm->d[0][i];
        sums0[2] += wi*r0*pm->d[1][i];
        sums0[3] += wi*pm->d[0][i]*pm->d[0][i];
        sums0[4] += wi*pm->d[1][i]*pm->d[1][i];
        /* Beyond the span by far more than rounding, both ends of the
         * basis are clamped alike and their difference is 0. */
        lo = MIN(pm->ta[i], pm->tb[i]) - fabs(pm->half[i]);
        hi = MAX(pm->ta[i], pm->tb[i]) + fabs(pm->half[i]);
        margin = 1e-9*(fabs(lo) + fabs(hi)) + G_MINDOUBLE;
        for (j = first_at_least(grid, m, lo - margin); j < m && grid[j] <= hi + margin; j++) {
            model_basis_mean(DRIFT_MODEL_JUMP, grid[j], pm->ta[i], pm->half[i], fa);
            model_basis_mean(DRIFT_MODEL_JUMP, grid[j], pm->tb[i], pm->half[i], fb);
            r1 = fa[1] - fb[1];
            spanned[j] += spans_jump(r1);
            sums1[5*j] += wi*r0*r1;
            sums1[5*j + 1] += wi*r1*r0;
            sums1[5*j + 2] += wi*r1*r1;
            sums1[5*j + 3] += wi*r1*pm->d[0][i];
            sums1[5*j + 4] += wi*r1*pm->d[1][i];
        }
    }
    rss = g_new(gdouble, m);
    for (j = 0; j < m; j++) {
        ata[0] = sums0[0];
        ata[1] = sums1[5*j];
        ata[2] = sums1[5*j + 1];
        ata[3] = sums1[5*j + 2];
        for (ax = 0; ax < 2; ax++) {
            atb[ax][0] = sums0[1 + ax];
            atb[ax][1] = sums1[5*j + 3 + ax];
        }
        rss[j] = jump_separable(spanned[j], pm->n_used)
                 ? solve_normal(ata, atb, sums0 + 3, 2, coef) : NAN;
        if (!isfinite(rss[j]))
            rss[j] = G_MAXDOUBLE;
    }
    g_free(sums1);
    g_free(spanned);
    return rss;
}

/* The residual sums of squares at every grid value (G_MAXDOUBLE where the
 * fit is not finite). */
static gdouble*
grid_rss(const Prepared *pm, FitKind kind, const gdouble *grid, gint m)
{
    gdouble coef[2][MAX_BASIS], *rss;
    gint i, k;

    if (kind == DRIFT_MODEL_JUMP && (rss = jump_grid_rss(pm, grid, m)))
        return rss;
    rss = g_new(gdouble, m);
    for (i = 0; i < m; i++) {
        rss[i] = solve_fixed(pm, kind, grid[i], coef, &k);
        if (!isfinite(rss[i]))
            rss[i] = G_MAXDOUBLE;
    }
    return rss;
}

/* Every coefficient and the nonlinear parameter finite. */
static gboolean
fit_is_finite(const DriftFit *fit, gdouble rss)
{
    gint ax, j;

    if (!isfinite(rss) || !isfinite(fit->nonlinear))
        return FALSE;
    for (ax = 0; ax < 2; ax++) {
        for (j = 0; j < fit->n_basis; j++) {
            if (!isfinite(fit->coef[ax][j]))
                return FALSE;
        }
    }
    return TRUE;
}

static gboolean
fit_prepared(const Prepared *pm, FitKind kind,
             const DriftFitOptions *options, DriftFit *fit)
{
    gdouble coef[2][MAX_BASIS], *grid = NULL, *rss_grid, theta = 0.0, rss;
    gint m, k, ibest, nn;

    memset(fit, 0, sizeof(DriftFit));
    if (kind >= DRIFT_MODEL_NTYPES) {
        fit->type = DRIFT_MODEL_NONE;
        fit->creep = kind - DRIFT_MODEL_NTYPES;
    }
    else
        fit->type = kind;
    fit->cv_rms_nm = NAN;
    fit->bic = fit->rms_nm = NAN;
    if (pm->n_used < 3)
        return FALSE;

    if (model_has_nonlinear(kind)) {
        if (!(m = parameter_grid(pm, kind, options, &grid, &rss_grid)))
            return FALSE;
        if (!rss_grid)
            rss_grid = grid_rss(pm, kind, grid, m);
        fit->range[0] = MIN(grid[0], grid[m-1]);
        fit->range[1] = MAX(grid[0], grid[m-1]);
        ibest = search_grid(pm, kind, grid, rss_grid, m, &theta);
        g_free(rss_grid);
        fit->at_limit = (grid[ibest] == fit->range[1]) ? 1
                        : (grid[ibest] == fit->range[0]) ? -1 : 0;
        g_free(grid);
    }
    rss = solve_fixed(pm, kind, theta, coef, &k);
    fit->n_basis = k;
    memcpy(fit->coef, coef, sizeof(coef));
    fit->nonlinear = theta;
    fit->n_params = 2*k + (model_has_nonlinear(kind) ? 1 : 0);
    nn = fit->n_used = 2*pm->n_used;
    /* A non-finite fit (times whose squares overflow, say) must not reach
     * the criterion: clamping its NaN residual would make it the best. */
    if (!fit_is_finite(fit, rss) || nn <= fit->n_params)
        return FALSE;
    fit->rms_nm = sqrt(rss/nn);
    fit->bic = nn*log(MAX(rss/nn, 1e-30)) + fit->n_params*log(nn);
    fit->ok = TRUE;
    return TRUE;
}

/* fit_prepared() on the measurements mask keeps (NULL: all). */
static gboolean
fit_masked(const DriftMeasurement *meas, gint n, const gboolean *mask,
           FitKind kind, const DriftFitOptions *options, DriftFit *fit)
{
    Prepared pm;
    gboolean ok;

    prepare(meas, n, mask, &pm);
    ok = fit_prepared(&pm, kind, options, fit);
    prepared_free(&pm);
    return ok;
}

gboolean
drift_fit_model(const DriftMeasurement *meas, gint n, DriftModelType type,
                const DriftFitOptions *options, DriftFit *fit)
{
    DriftFitOptions defaults;

    options = options_or_defaults(options, &defaults);
    return fit_masked(meas, n, NULL, type, options, fit);
}

gboolean
drift_fit_refit_at(const DriftMeasurement *meas, gint n, gdouble theta,
                   DriftFit *fit)
{
    FitKind kind = fit_kind(fit);
    gdouble coef[2][MAX_BASIS], rss;
    Prepared pm;
    gint k;

    if (!fit->ok || !model_has_nonlinear(kind) || !isfinite(theta))
        return FALSE;
    prepare(meas, n, NULL, &pm);
    rss = solve_fixed(&pm, kind, theta, coef, &k);
    prepared_free(&pm);
    if (!isfinite(rss) || k != fit->n_basis)
        return FALSE;
    memcpy(fit->coef, coef, sizeof(coef));
    fit->nonlinear = theta;
    fit->rms_nm = sqrt(rss/fit->n_used);
    fit->bic = fit->n_used*log(MAX(rss/fit->n_used, 1e-30))
               + fit->n_params*log(fit->n_used);
    return TRUE;
}

/* p at t averaged over [t - h, t + h], nm. */
static void
eval_mean(const DriftFit *fit, gdouble t, gdouble h, gdouble *p)
{
    gdouble f[MAX_BASIS];
    gint j, k, ax;

    k = model_basis_mean(fit_kind(fit), fit->nonlinear, t, h, f);
    for (ax = 0; ax < 2; ax++) {
        p[ax] = 0.0;
        for (j = 0; j < MIN(k, fit->n_basis); j++)
            p[ax] += fit->coef[ax][j]*f[j];
    }
}

void
drift_fit_eval(const DriftFit *fit, gdouble t, gdouble *px, gdouble *py)
{
    gdouble p[2];

    eval_mean(fit, t, 0.0, p);
    *px = 1e-9*p[0];
    *py = 1e-9*p[1];
}

void
drift_fit_predict(const DriftFit *fit, const DriftMeasurement *m,
                  gdouble *dx, gdouble *dy)
{
    gdouble a[2], b[2], h = (m->span > 0.0 && isfinite(m->span)) ? 0.5*m->span : 0.0;

    eval_mean(fit, m->t_a, h, a);
    eval_mean(fit, m->t_b, h, b);
    *dx = 1e-9*(a[0] - b[0]);
    *dy = 1e-9*(a[1] - b[1]);
}

static gboolean
held_out(const DriftMeasurement *m, gint folds, gint f)
{
    return (m->group % folds + folds) % folds == f;
}

/* The folds of cross_validate_masked(), fitted each on its own. */
typedef struct {
    const DriftMeasurement *meas;
    gint n;
    const gboolean *mask;
    FitKind kind;
    const DriftFitOptions *options;
    gint folds;
    gboolean have_periods;
    gdouble periods[2];
    DriftFit *fits;       /* one per fold */
    gboolean *fitted;     /* one per fold */
} FoldFits;

/* The model fitted without fold f (nothing when it holds nothing out). */
static void
fit_fold_task(gpointer data, gint f)
{
    FoldFits *ff = data;
    gboolean *train = g_new(gboolean, MAX(ff->n, 1)), any = FALSE;
    Prepared pm;
    gint i;

    for (i = 0; i < ff->n; i++) {
        gboolean held = held_out(ff->meas + i, ff->folds, f);

        train[i] = !held && (!ff->mask || ff->mask[i]);
        any |= held;
    }
    ff->fitted[f] = FALSE;
    if (any) {
        prepare(ff->meas, ff->n, train, &pm);
        pm.periods_given = TRUE;
        pm.period_range[0] = ff->have_periods ? ff->periods[0] : 1.0;
        pm.period_range[1] = ff->have_periods ? ff->periods[1] : 0.0;
        ff->fitted[f] = fit_prepared(&pm, ff->kind, ff->options, ff->fits + f);
        prepared_free(&pm);
    }
    g_free(train);
}

/* The folds are fitted on every core (each a whole search of the model's
 * nonlinear parameter), then their held-out measurements are summed in
 * fold order, as one fold after another would. */
static gdouble
cross_validate_masked(const DriftMeasurement *meas, gint n,
                      const gboolean *mask, FitKind kind,
                      const DriftFitOptions *options)
{
    gint folds = MAX(options->n_folds, 2), f, i, count = 0;
    gdouble sum = 0.0, wsum = 0.0;
    FoldFits ff = { meas, n, mask, kind, options, folds, FALSE, { 0.0, 0.0 },
                    g_new(DriftFit, folds), g_new(gboolean, folds) };
    Prepared pm;

    /* The periods searched are those the whole series can show.  A held-out
     * fold leaves gaps in the training times whose alias limit (twice the
     * longest gap) would shut out periods the series shows well, and the
     * held-out groups would then be predicted by a wrong period. */
    prepare(meas, n, mask, &pm);
    ff.have_periods = observable_periods(&pm, options, ff.periods, ff.periods + 1);
    prepared_free(&pm);
    parallel_run(0, folds, fit_fold_task, &ff);
    for (f = 0; f < folds; f++) {
        for (i = 0; i < n && ff.fitted[f]; i++) {
            gdouble dx, dy, rx, ry;

            if (!held_out(meas + i, folds, f) || (mask && !mask[i])
                || !(meas[i].weight > 0.0))
                continue;
            drift_fit_predict(ff.fits + f, meas + i, &dx, &dy);
            rx = 1e9*(meas[i].dx - dx);
            ry = 1e9*(meas[i].dy - dy);
            sum += meas[i].weight*(rx*rx + ry*ry);
            wsum += 2.0*meas[i].weight;
            count++;
        }
    }
    g_free(ff.fits);
    g_free(ff.fitted);
    return count ? sqrt(sum/wsum) : NAN;
}

gboolean
drift_fit_observable_periods(const DriftMeasurement *meas, gint n,
                             const DriftFitOptions *options,
                             gdouble *shortest, gdouble *longest)
{
    DriftFitOptions defaults;
    Prepared pm;
    gboolean ok;

    options = options_or_defaults(options, &defaults);
    prepare(meas, n, NULL, &pm);
    ok = observable_periods(&pm, options, shortest, longest);
    prepared_free(&pm);
    return ok;
}

gdouble
drift_fit_cross_validate(const DriftMeasurement *meas, gint n,
                         DriftModelType type, const DriftFitOptions *options)
{
    DriftFitOptions defaults;

    options = options_or_defaults(options, &defaults);
    return cross_validate_masked(meas, n, NULL, type, options);
}

gboolean
drift_fit_creep(const DriftMeasurement *meas, gint n, DriftFitCreep creep,
                const DriftFitOptions *options, DriftFit *fit)
{
    DriftFitOptions defaults;
    FitKind kind = DRIFT_MODEL_NTYPES + creep;

    g_return_val_if_fail(creep == DRIFT_FIT_CREEP_ACCELERATION
                         || creep == DRIFT_FIT_CREEP_LOGARITHMIC, FALSE);
    options = options_or_defaults(options, &defaults);
    if (fit_masked(meas, n, NULL, kind, options, fit))
        fit->cv_rms_nm = cross_validate_masked(meas, n, NULL, kind, options);
    return fit->ok;
}

static gint
lowest_bic(const DriftFit *fits, gint n_types)
{
    gint i, best = -1;

    for (i = 0; i < n_types; i++) {
        if (fits[i].ok && (best < 0 || fits[i].bic < fits[best].bic))
            best = i;
    }
    return best;
}

/* Outliers are cut in rounds, each taking those within this factor of the
 * round's worst residual: a failed registration pulls the fit towards
 * itself by a fraction of its own residual, so what it makes of good
 * measurements stays well below it and waits for the refit, while the
 * tail of alike residuals goes at once (refitting after each of them cost
 * half the time of a short series). */
#define OUTLIER_ROUND 0.5

static gint
compare_residuals(gconstpointer a, gconstpointer b, gpointer user_data)
{
    const gdouble *r = user_data;
    gdouble x = r[*(const gint*)a], y = r[*(const gint*)b];

    return (x < y) - (x > y);
}

/* The kept measurements that are gross outliers (failed registrations) by
 * a robust (median) scale of the kept residuals, beyond floor_nm (the
 * residual is the RMS of its two axes) and within OUTLIER_ROUND of the largest residual, at most `most` of them
 * (the largest), lose their place in mask; returns how many did.  Without
 * the floor, nearly exact measurements lose good ones: at a scale of 0.05
 * nm the rounds cut blocks 0.3 nm off after a jump until too few measured
 * times were left behind it to fit the jump at all (seed 104000114 of
 * test-hidden-effects, an 8-px jump read as none). */
static gint
cut_outliers(const DriftMeasurement *meas, gint n, const DriftFit *fit,
             gdouble sigmas, gdouble floor_nm, gint most, gboolean *mask)
{
    gdouble *r = g_new(gdouble, n), *sorted = g_new(gdouble, n), limit, cut;
    gint *beyond = g_new(gint, n), i, m = 0, worst = -1, count = 0;

    for (i = 0; i < n; i++) {
        gdouble dx, dy;

        r[i] = NAN;
        if (!mask[i] || !(meas[i].weight > 0.0))
            continue;
        drift_fit_predict(fit, meas + i, &dx, &dy);
        r[i] = 1e9*sqrt(0.5*((meas[i].dx - dx)*(meas[i].dx - dx)
                             + (meas[i].dy - dy)*(meas[i].dy - dy)));
        if (!isfinite(r[i]))
            continue;
        sorted[m++] = r[i];
        if (worst < 0 || r[i] > r[worst])
            worst = i;
    }
    if (m) {
        /* The median of a 2-D radial residual is about 1.18 sigma. */
        limit = MAX(sigmas*MAX(median_kth_in_place(sorted, m, m/2)/1.1774, 1e-6), floor_nm);
        cut = MAX(limit, OUTLIER_ROUND*r[worst]);
        for (i = 0; i < n && r[worst] > limit; i++) {
            if (r[i] > cut)
                beyond[count++] = i;
        }
        if (count > most) {
            g_qsort_with_data(beyond, count, sizeof(gint), compare_residuals, r);
            count = most;
        }
        for (i = 0; i < count; i++)
            mask[beyond[i]] = FALSE;
    }
    g_free(beyond);
    g_free(r);
    g_free(sorted);
    return count;
}

/* Drops gross outliers round by round, the worst first, refitting fit's
 * model after each round: a single failed registration pulls a
 * least-squares fit far enough that a whole group of good measurements
 * (those spanning a jump, say) would look like outliers if all were judged
 * at once. */
static void
drop_outliers(const DriftMeasurement *meas, gint n,
              const DriftFitOptions *options, DriftFit *fit, gboolean *mask)
{
    FitKind kind = fit_kind(fit);
    gint dropped, cut;

    for (dropped = 0; dropped < n/4; dropped += cut) {
        cut = cut_outliers(meas, n, fit, options->outlier_sigmas, options->outlier_floor_nm,
                           n/4 - dropped, mask);
        if (!cut)
            break;
        if (!fit_masked(meas, n, mask, kind, options, fit))
            break;
    }
}

/* RMS of what the effect explains beyond constant drift. */
static gdouble
explained_rms(const DriftFit *none, const DriftFit *effect)
{
    return sqrt(MAX(none->rms_nm*none->rms_nm
                    - effect->rms_nm*effect->rms_nm, 0.0));
}

gint
drift_fit_select(const DriftMeasurement *meas, gint n,
                 const DriftFitOptions *options, DriftFit *fits)
{
    return drift_fit_select_kept(meas, n, options, fits, NULL);
}

/* Whether a settling slower than half the series is more than curvature:
 * over such a span the exponential differs from a parabola by a fraction of
 * its bend, so it must beat the constant acceleration by the evidence any
 * effect needs against constant drift (held-out gain cv_gain, explaining
 * min_explained times its residual).  Registration errors of frames that
 * share their content are correlated, and a shape of a few hundredths of a
 * pixel is within them (test-hidden-effects seed 103000176: tau 183 s over
 * 256 s, 0.27 nm beyond the acceleration at 0.59 nm residual). */
static gboolean
settling_beyond_curvature(const DriftFit *fits, const DriftModelType *types,
                          gint n_types, const DriftFit *fit,
                          const DriftFitOptions *options)
{
    gint i;

    for (i = 0; i < n_types; i++) {
        if (types[i] != DRIFT_MODEL_ACCELERATION || !fits[i].ok)
            continue;
        if (explained_rms(fits + i, fit) < options->min_explained*fit->rms_nm)
            return FALSE;
        if (options->n_folds >= 2 && isfinite(fits[i].cv_rms_nm) && isfinite(fit->cv_rms_nm))
            return fit->cv_rms_nm < (1.0 - options->cv_gain)*fits[i].cv_rms_nm;
        return TRUE;
    }
    return TRUE;
}

/* The candidate models fitted by fit_every_model(), each on its own. */
typedef struct {
    const DriftMeasurement *meas;
    gint n;
    const gboolean *mask;     /* NULL: no cross-validation */
    const Prepared *pm;
    const DriftFitOptions *options;
    const DriftModelType *types;
    DriftFit *fits;
} ModelFits;

static void
fit_model_task(gpointer data, gint i)
{
    ModelFits *mf = data;
    DriftFit *fit = mf->fits + i;

    fit_prepared(mf->pm, mf->types[i], mf->options, fit);
    if (mf->mask && fit->ok && mf->options->n_folds >= 2)
        fit->cv_rms_nm = cross_validate_masked(mf->meas, mf->n, mf->mask, mf->types[i],
                                               mf->options);
}

/* Every candidate model fitted to pm and, with mask (the measurements pm
 * was prepared from), cross-validated.  The models are independent, so
 * they run on every core: the oscillation's and the jump's searches take
 * most of a long series' fit. */
static void
fit_every_model(const DriftMeasurement *meas, gint n, const gboolean *mask,
           const Prepared *pm, const DriftFitOptions *options, DriftFit *fits)
{
    ModelFits mf = { meas, n, mask, pm, options, NULL, fits };
    gint n_types;

    mf.types = drift_fit_candidates(&n_types);
    parallel_run(0, n_types, fit_model_task, &mf);
}

/* The outliers cut again, from every measurement, against fits[against]
 * (fitted without the earlier cut's outliers), and every model refitted.
 * Gross outliers can make a wrong model the first best (a settling's time
 * constant at the end of its range, a constant acceleration instead),
 * which then cuts the good measurements that only the right model
 * explains: the first seconds of a fast settling, 0.3-0.4 px off the
 * acceleration, went and the settling fitted to the rest read its travel
 * 12 % short (test-series-correction seed 370000064, case 11: 0.6 px
 * everywhere).  Or the first best bends to the outliers and keeps them
 * (an oscillation through three blocks of one frame's content read
 * 6 px off in every pair), while the model chosen is a simpler one
 * that calls them outliers: kept, they pulled the velocity 25 % short
 * (test-series-command.sh seed 440001096: 1.2 px). */
static void
recut_against(const DriftMeasurement *meas, gint n,
              const DriftFitOptions *options, Prepared *pm, DriftFit *fits,
              gint against, gboolean *mask)
{
    DriftFit model = fits[against];
    gint i;

    for (i = 0; i < n; i++)
        mask[i] = TRUE;
    drop_outliers(meas, n, options, &model, mask);
    prepared_free(pm);
    prepare(meas, n, mask, pm);
    fit_every_model(meas, n, mask, pm, options, fits);
}

/* Whether fit calls some of the measurements mask keeps gross outliers. */
static gboolean
outliers_beyond(const DriftMeasurement *meas, gint n, const DriftFit *fit,
                const DriftFitOptions *options, const gboolean *mask)
{
    gboolean *copy = g_new(gboolean, MAX(n, 1));
    gint cut;

    memcpy(copy, mask, n*sizeof(gboolean));
    cut = cut_outliers(meas, n, fit, options->outlier_sigmas,
                       options->outlier_floor_nm, n, copy);
    g_free(copy);
    return cut > 0;
}

/* The model chosen among fits: the best by BIC of those that beat
 * constant drift by every criterion and are observable. */
static gint
choose_model(const DriftFit *fits, const DriftModelType *types, gint n_types,
             gdouble span, const DriftFitOptions *options)
{
    gint i, chosen, inone = -1;

    for (i = 0; i < n_types; i++) {
        if (types[i] == DRIFT_MODEL_NONE)
            inone = i;
    }
    chosen = inone;
    for (i = 0; i < n_types; i++) {
        if (i == inone || !fits[i].ok)
            continue;
        /* An oscillation that wants the longest observable period wants a
         * longer one still: it bends the trajectory, it does not repeat. */
        if (types[i] == DRIFT_MODEL_OSCILLATION && fits[i].at_limit > 0)
            continue;
        /* A settling slower than the series is curvature, which a constant
         * acceleration says with fewer parameters; so, mostly, is one slower
         * than half the series. */
        if (types[i] == DRIFT_MODEL_SETTLING
            && (fits[i].nonlinear > span
                || (fits[i].nonlinear > 0.5*span
                    && !settling_beyond_curvature(fits, types, n_types, fits + i, options))))
            continue;
        if (inone >= 0 && fits[inone].ok
            && (fits[inone].bic - fits[i].bic < options->bic_margin
                || (options->n_folds >= 2
                    && !(fits[i].cv_rms_nm
                         < (1.0 - options->cv_gain)*fits[inone].cv_rms_nm))
                || (explained_rms(fits + inone, fits + i)
                    < options->min_explained*fits[i].rms_nm)))
            continue;
        if (chosen == inone || fits[i].bic < fits[chosen].bic)
            chosen = i;
    }
    if (chosen < 0 || !fits[chosen].ok)
        chosen = lowest_bic(fits, n_types);
    return chosen;
}

gint
drift_fit_select_kept(const DriftMeasurement *meas, gint n,
                      const DriftFitOptions *options, DriftFit *fits,
                      gboolean *kept)
{
    DriftFitOptions defaults;
    gint n_types, i, best, chosen, against;
    const DriftModelType *types = drift_fit_candidates(&n_types);
    gdouble span;
    gboolean *mask = g_new(gboolean, n);
    Prepared pm;

    options = options_or_defaults(options, &defaults);
    prepare(meas, n, NULL, &pm);
    span = pm.t_max - pm.t_min;
    fit_every_model(meas, n, NULL, &pm, options, fits);
    prepared_free(&pm);
    if ((best = lowest_bic(fits, n_types)) < 0) {
        if (kept)
            memset(kept, 0, n*sizeof(gboolean));
        g_free(mask);
        return -1;
    }
    for (i = 0; i < n; i++)
        mask[i] = TRUE;
    if (options->outlier_sigmas > 0.0)
        drop_outliers(meas, n, options, fits + best, mask);
    prepare(meas, n, mask, &pm);
    fit_every_model(meas, n, mask, &pm, options, fits);
    against = best;
    /* The best model once the outliers are gone, then the model chosen,
     * judge them again when they are other than the one they were cut
     * against (and the chosen one only when it disagrees with the cut). */
    best = lowest_bic(fits, n_types);
    if (options->outlier_sigmas > 0.0 && best >= 0 && best != against) {
        recut_against(meas, n, options, &pm, fits, best, mask);
        against = best;
    }
    chosen = choose_model(fits, types, n_types, span, options);
    if (options->outlier_sigmas > 0.0 && chosen >= 0 && chosen != against
        && outliers_beyond(meas, n, fits + chosen, options, mask)) {
        recut_against(meas, n, options, &pm, fits, chosen, mask);
        chosen = choose_model(fits, types, n_types, span, options);
    }
    if (kept)
        memcpy(kept, mask, n*sizeof(gboolean));
    prepared_free(&pm);
    g_free(mask);
    return chosen;
}

/* Amplitude and phase of A sin + B cos as R sin(. + phase). */
static void
oscillation_polar(const DriftFit *fit, gdouble *amp, gdouble *phase)
{
    gdouble r0 = hypot(fit->coef[0][1], fit->coef[0][2]);
    gdouble r1 = hypot(fit->coef[1][1], fit->coef[1][2]);
    gint big = (r1 > r0) ? 1 : 0, ax;

    *phase = atan2(fit->coef[big][2], fit->coef[big][1]);
    for (ax = 0; ax < 2; ax++)
        amp[ax] = (fit->coef[ax][1]*cos(*phase)
                   + fit->coef[ax][2]*sin(*phase));
}

/* The effect's coefficient (after the velocity) of both axes, scaled. */
static void
second_coefficients(const DriftFit *fit, gdouble scale, gdouble *v)
{
    v[0] = scale*fit->coef[0][1];
    v[1] = scale*fit->coef[1][1];
}

void
drift_fit_parameters(const DriftFit *fit, DriftFitParameters *params)
{
    gint ax;

    params->tau_s = params->period_s = params->phase_rad = NAN;
    params->t_s = NAN;
    for (ax = 0; ax < 2; ax++) {
        params->velocity_nm_per_s[ax] = fit->coef[ax][0];
        params->u_nm_per_s[ax] = params->amplitude_nm[ax] = NAN;
        params->step_nm[ax] = params->accel_nm_per_s2[ax] = NAN;
    }
    switch (fit_kind(fit)) {
        /* A logarithmic creep reports t0 and its initial excess velocity
         * in settling's places. */
        case DRIFT_MODEL_SETTLING:
        case KIND_LOG_CREEP:
        params->tau_s = fit->nonlinear;
        second_coefficients(fit, 1.0, params->u_nm_per_s);
        break;

        case DRIFT_MODEL_OSCILLATION:
        params->period_s = fit->nonlinear;
        oscillation_polar(fit, params->amplitude_nm, &params->phase_rad);
        break;

        case DRIFT_MODEL_JUMP:
        params->t_s = fit->nonlinear;
        second_coefficients(fit, 1.0, params->step_nm);
        break;

        case DRIFT_MODEL_ACCELERATION:
        case KIND_ACCELERATION:
        second_coefficients(fit, 2.0, params->accel_nm_per_s2);
        break;

        default:
        break;
    }
}

/* A pair in nm as metres. */
static void
pair_to_metres(const gdouble *nm, gdouble *m)
{
    m[0] = 1e-9*nm[0];
    m[1] = 1e-9*nm[1];
}

void
drift_fit_to_model(const DriftFit *fit, DriftModel *model)
{
    DriftFitParameters params;

    memset(model, 0, sizeof(DriftModel));
    model->type = fit->type;
    model->tau = model->period = model->walk_dt = 1.0;
    drift_fit_parameters(fit, &params);
    pair_to_metres(params.velocity_nm_per_s, model->v);
    switch (fit->type) {
        case DRIFT_MODEL_SETTLING:
        model->tau = params.tau_s;
        pair_to_metres(params.u_nm_per_s, model->u);
        break;

        case DRIFT_MODEL_OSCILLATION:
        model->period = params.period_s;
        model->phase = params.phase_rad;
        pair_to_metres(params.amplitude_nm, model->a);
        break;

        case DRIFT_MODEL_JUMP:
        model->t_jump = params.t_s;
        pair_to_metres(params.step_nm, model->step);
        break;

        case DRIFT_MODEL_ACCELERATION:
        pair_to_metres(params.accel_nm_per_s2, model->accel);
        break;

        default:
        break;
    }
}
