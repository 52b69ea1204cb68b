/*
 *  simscan's command line.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <string.h>
#include <math.h>
#include <stdarg.h>
#include "channel-spec.h"
#include "simscan-presets.h"
#include "local-scan.h"
#include "simscan-sample-file.h"
#include "option-values.h"
#include "option-parse.h"
#include "output-files.h"
#include "simscan-options.h"
#include "simscan-i18n.h"

#define NM 1e-9
#define UM 1e-6

/* Limits beyond which a simulation would only exhaust memory or time; --help
 * states them. */
#define MAX_SIZE_UM    1000.0
#define MIN_RES        8
#define MAX_RES        16384
#define MAX_PIXELS     (4096*4096)
#define MAX_PARTICLES  1000000
/* A local scan's search moves its line by 1.5 R up to r_max + R each way:
 * so many lines at most per search keep a run within seconds. */
#define MAX_SEARCH_LINES 2000
/* Samples of all local scans together (stripes x lines x points). */
#define MAX_LOCAL_SAMPLES 2e7
/* The drift may carry the sample at most this many scan sizes away over
 * the simulated time; beyond, no particle is ever found again and the
 * numbers only exercise overflow. */
#define MAX_DRIFT_SCANS 100.0
/* Components of the two-number drift options, nm or nm/s. */
#define MAX_DRIFT_NM    1e9

/* The options as the user writes them (nm, um, s). */
typedef struct {
    gchar *preset, *sample, *size, *direction, *drift;
    gchar *velocity, *offset, *settle_velocity, *amplitude, *jump_step;
    gchar *acceleration;
    gdouble radius, radius_spread, density, spacing, roughness, correlation;
    gint count;
    gint xres, yres;
    gdouble line_time, noise, tip_radius;
    gdouble tau, period, phase, jump_time, walk_sigma, walk_dt;
    gint stripes, ls_points;
    gdouble ls_speed, ls_rmax, ls_overhead, ls_delay, ls_threshold;
    gboolean prefer_whole;
    gint64 seed;
    gchar *output, *table, *json;
    gboolean quiet;
    /* Options whose defaults a measured sample replaces: text, so that
     * whether the user gave them is known. */
    gchar *radius_text, *ls_rmax_text, *xres_text, *yres_text;
} RawOptions;

static void
raw_from_config(RawOptions *raw, const SimscanConfig *config)
{
    const SimParticleParams *pp = &config->particles;

    memset(raw, 0, sizeof(RawOptions));
    raw->radius = pp->radius/NM;
    raw->radius_spread = pp->radius_spread;
    raw->count = pp->count;
    raw->density = pp->density*UM*UM;
    raw->spacing = pp->min_spacing/NM;
    raw->roughness = pp->roughness_rms/NM;
    raw->correlation = pp->roughness_corr/NM;
    raw->xres = config->xres;
    raw->yres = config->yres;
    raw->line_time = config->line_time;
    raw->noise = config->noise_rms/NM;
    raw->tip_radius = config->tip_radius/NM;
    raw->tau = config->drift.tau;
    raw->period = config->drift.period;
    raw->phase = config->drift.phase;
    raw->jump_time = config->drift.t_jump;
    raw->walk_sigma = config->drift.walk_sigma/NM;
    raw->walk_dt = config->drift.walk_dt;
    raw->stripes = config->n_stripes;
    raw->ls_points = config->local.points;
    raw->ls_speed = config->local.tip_speed/UM;
    raw->ls_rmax = config->local.r_max/NM;
    raw->ls_overhead = config->local.line_overhead;
    raw->ls_delay = config->local_delay;
    raw->ls_threshold = config->local.threshold_fraction;
    raw->prefer_whole = (config->local.choice == PARTICLE_CHOICE_PREFER_WHOLE);
    raw->seed = config->seed;
}

static void
raw_clear(RawOptions *raw)
{
    gchar **strings[] = {
        &raw->preset, &raw->sample, &raw->size, &raw->direction, &raw->drift,
        &raw->velocity, &raw->offset, &raw->settle_velocity, &raw->amplitude,
        &raw->jump_step, &raw->acceleration, &raw->output, &raw->table,
        &raw->json,
        &raw->radius_text, &raw->ls_rmax_text, &raw->xres_text,
        &raw->yres_text,
    };
    guint i;

    for (i = 0; i < G_N_ELEMENTS(strings); i++) {
        g_free(*strings[i]);
        *strings[i] = NULL;
    }
}

static GOptionEntry*
make_entries(RawOptions *raw)
{
    GOptionEntry entries[] = {
        { "preset", 0, 0, G_OPTION_ARG_STRING, &raw->preset,
          N_("paper (Section IV) or figure6 (the paper's Figure 6); "
             "later options override it"), "NAME" },
        { "sample", 0, 0, G_OPTION_ARG_FILENAME, &raw->sample,
          N_("measured image used as the sample (channel ID, default the "
             "first), scanned over its own size and by default at its own "
             "resolution, with the paper's drift scaled to its pixel size"),
          "FILE[:ID]" },
        { "radius", 0, 0, G_OPTION_ARG_STRING, &raw->radius_text,
          N_("particle radius, nm (25; with --sample: the typical radius of "
             "the particles found on it)"), "NM" },
        { "radius-spread", 0, 0, G_OPTION_ARG_DOUBLE, &raw->radius_spread,
          N_("relative RMS spread of the radii (0)"), "F" },
        { "count", 0, 0, G_OPTION_ARG_INT, &raw->count,
          N_("number of particles (0: use --density; at most 1000000)"),
          "N" },
        { "density", 0, 0, G_OPTION_ARG_DOUBLE, &raw->density,
          N_("particles per um^2 when --count is 0 (4; density times the "
             "area at most 1000000 particles)"), "D" },
        { "spacing", 0, 0, G_OPTION_ARG_DOUBLE, &raw->spacing,
          N_("least distance between particle centres, nm (100)"), "NM" },
        { "roughness", 0, 0, G_OPTION_ARG_DOUBLE, &raw->roughness,
          N_("substrate RMS roughness, nm (0.3)"), "NM" },
        { "correlation", 0, 0, G_OPTION_ARG_DOUBLE, &raw->correlation,
          N_("substrate correlation length, nm (50)"), "NM" },
        { "xres", 0, 0, G_OPTION_ARG_STRING, &raw->xres_text,
          N_("pixels per line (256; 8 to 16384, xres times yres at most "
             "16777216)"), "N" },
        { "yres", 0, 0, G_OPTION_ARG_STRING, &raw->yres_text,
          N_("lines per image (256; 8 to 16384)"), "N" },
        { "size", 0, 0, G_OPTION_ARG_STRING, &raw->size,
          N_("scan size, um, square or width,height (5; at most 1000, more "
             "than the particle diameter; not with --sample)"), "UM[,UM]" },
        { "line-time", 0, 0, G_OPTION_ARG_DOUBLE, &raw->line_time,
          N_("seconds per line, trace and retrace (300/256)"), "S" },
        { "direction", 0, 0, G_OPTION_ARG_STRING, &raw->direction,
          N_("slow-scan direction, down or up (down)"), "DIR" },
        { "noise", 0, 0, G_OPTION_ARG_DOUBLE, &raw->noise,
          N_("RMS measurement noise, nm (0)"), "NM" },
        { "tip-radius", 0, 0, G_OPTION_ARG_DOUBLE, &raw->tip_radius,
          N_("spherical tip radius, nm (0: sharp)"), "NM" },
        { "drift", 0, 0, G_OPTION_ARG_STRING, &raw->drift,
          N_("none (constant velocity), settling, oscillation, jump, "
             "random-walk, acceleration, or figure6 (per-stripe shifts)"),
          "MODEL" },
        { "velocity", 0, 0, G_OPTION_ARG_STRING, &raw->velocity,
          N_("constant drift velocity, nm/s (0.08,0.02; with --sample "
             "scaled by its pixel size against the paper's)"), "VX,VY" },
        { "offset", 0, 0, G_OPTION_ARG_STRING, &raw->offset,
          N_("drift at t = 0, nm (0,0)"), "X,Y" },
        { "settle-velocity", 0, 0, G_OPTION_ARG_STRING, &raw->settle_velocity,
          N_("settling: initial excess velocity, nm/s (0,0)"), "UX,UY" },
        { "tau", 0, 0, G_OPTION_ARG_DOUBLE, &raw->tau,
          N_("settling: time constant, s (1)"), "S" },
        { "amplitude", 0, 0, G_OPTION_ARG_STRING, &raw->amplitude,
          N_("oscillation: amplitude, nm (0,0)"), "AX,AY" },
        { "period", 0, 0, G_OPTION_ARG_DOUBLE, &raw->period,
          N_("oscillation: period, s (1)"), "S" },
        { "phase", 0, 0, G_OPTION_ARG_DOUBLE, &raw->phase,
          N_("oscillation: phase, rad (0)"), "RAD" },
        { "jump-time", 0, 0, G_OPTION_ARG_DOUBLE, &raw->jump_time,
          N_("jump: when, s (0)"), "S" },
        { "jump-step", 0, 0, G_OPTION_ARG_STRING, &raw->jump_step,
          N_("jump: step, nm (0,0)"), "DX,DY" },
        { "acceleration", 0, 0, G_OPTION_ARG_STRING, &raw->acceleration,
          N_("acceleration: constant acceleration, nm/s^2 (0,0)"), "AX,AY" },
        { "walk-sigma", 0, 0, G_OPTION_ARG_DOUBLE, &raw->walk_sigma,
          N_("random walk: velocity diffusion, nm/s per sqrt(s) (0)"), "NM" },
        { "walk-dt", 0, 0, G_OPTION_ARG_DOUBLE, &raw->walk_dt,
          N_("random walk: time step, s (1)"), "S" },
        { "stripes", 0, 0, G_OPTION_ARG_INT, &raw->stripes,
          N_("number of stripes N, one local scan each (16)"), "N" },
        { "ls-points", 0, 0, G_OPTION_ARG_INT, &raw->ls_points,
          N_("samples per local-scan line (64)"), "N" },
        { "ls-speed", 0, 0, G_OPTION_ARG_DOUBLE, &raw->ls_speed,
          N_("tip speed along a local-scan line, um/s (4)"), "UM_S" },
        { "ls-rmax", 0, 0, G_OPTION_ARG_STRING, &raw->ls_rmax_text,
          N_("largest drift expected, nm; lines are 2(R + rmax) long (100; "
             "with --sample scaled like the velocity)"), "NM" },
        { "ls-overhead", 0, 0, G_OPTION_ARG_DOUBLE, &raw->ls_overhead,
          N_("extra time per local-scan line, s (0)"), "S" },
        { "ls-delay", 0, 0, G_OPTION_ARG_DOUBLE, &raw->ls_delay,
          N_("time from the end of the image to the first local scan, s (0)"),
          "S" },
        { "ls-threshold", 0, 0, G_OPTION_ARG_DOUBLE, &raw->ls_threshold,
          N_("chord threshold, fraction of the particle height (0.75)"), "F" },
        { "prefer-whole-particles", 0, 0, G_OPTION_ARG_NONE,
          &raw->prefer_whole,
          N_("deviate from the paper's rule (the particle closest to the "
             "stripe's centre): prefer particles clear of the stripe's first "
             "and last rows, since one cut by a stripe boundary may be "
             "sheared by the two stripes' different drifts and measured a "
             "pixel off"), NULL },
        { "seed", 0, 0, G_OPTION_ARG_INT64, &raw->seed,
          N_("random seed, 0 to 4294967295 (1)"), "N" },
        { "output", 'o', 0, G_OPTION_ARG_FILENAME, &raw->output,
          N_("write the .gwy file (contaminated image with its drift table, "
             "truth)"), "OUT.gwy" },
        { "table", 0, 0, G_OPTION_ARG_FILENAME, &raw->table,
          N_("write the measured drift table as CSV"), "OUT.csv" },
        { "json", 0, 0, G_OPTION_ARG_FILENAME, &raw->json,
          N_("write a JSON summary (true and measured drift per stripe)"),
          "OUT.json" },
        { "quiet", 'q', 0, G_OPTION_ARG_NONE, &raw->quiet,
          N_("print nothing on success"), NULL },
        { NULL, 0, 0, 0, NULL, NULL, NULL },
    };

    return g_memdup2(entries, sizeof(entries));
}

static gboolean
bad_value(GError **error, const gchar *option, const gchar *what)
{
    return option_value_refuse(option, what, error);
}

/* bad_value() with the reason formatted. */
static gboolean G_GNUC_PRINTF(3, 4)
bad_value_printf(GError **error, const gchar *option, const gchar *format,
                 ...)
{
    va_list ap;
    gchar *what;

    va_start(ap, format);
    what = g_strdup_vprintf(format, ap);
    va_end(ap);
    bad_value(error, option, what);
    g_free(what);
    return FALSE;
}

/* "A" or "A,B" (single: both the same when allow_single); each number
 * from -MAX_DRIFT_NM to MAX_DRIFT_NM before scale. */
static gboolean
parse_pair(const gchar *text, const gchar *option, gboolean allow_single,
           gdouble scale, gdouble *v, GError **error)
{
    gchar **parts = g_strsplit(text, ",", -1);
    guint n = g_strv_length(parts), i;
    gboolean ok = (n == 2 || (n == 1 && allow_single)), in_range = TRUE;
    gchar *msg;

    for (i = 0; ok && i < n; i++) {
        gchar *end;

        g_strstrip(parts[i]);
        v[i] = g_ascii_strtod(parts[i], &end);
        ok = (*parts[i] && !*end && isfinite(v[i]));
        in_range = in_range && fabs(v[i]) <= MAX_DRIFT_NM;
        v[i] *= scale;
    }
    if (ok && n == 1)
        v[1] = v[0];
    g_strfreev(parts);
    if (!ok)
        return bad_value(error, option,
                         allow_single ? _("expected a number or two numbers "
                                          "separated by a comma")
                                      : _("expected two numbers separated "
                                          "by a comma"));
    if (!in_range) {
        msg = g_strdup_printf(_("each number must be from %g to %g"), -MAX_DRIFT_NM, MAX_DRIFT_NM);
        bad_value(error, option, msg);
        g_free(msg);
        return FALSE;
    }
    return TRUE;
}

static gboolean
check_range(gdouble value, gdouble min, gdouble max, gboolean min_open,
            const gchar *option, GError **error)
{
    return option_value_check_range(value, min, max, min_open, option, error);
}

/* Each number within its range, checked in this order. */
static gboolean
check_numbers(const RawOptions *raw, GError **error)
{
    const struct {
        gdouble value, min, max;
        gboolean min_open;
        const gchar *option;
    } ranges[] = {
        { raw->radius, 0, 1e6, TRUE, "radius" },
        { raw->radius_spread, 0, 1, FALSE, "radius-spread" },
        { raw->count, 0, MAX_PARTICLES, FALSE, "count" },
        { raw->density, 0, 1e6, TRUE, "density" },
        { raw->spacing, 0, 1e9, FALSE, "spacing" },
        { raw->roughness, 0, 1e6, FALSE, "roughness" },
        { raw->correlation, 0, 1e9, TRUE, "correlation" },
        { raw->xres, MIN_RES, MAX_RES, FALSE, "xres" },
        { raw->yres, MIN_RES, MAX_RES, FALSE, "yres" },
        { raw->line_time, 0, 1e6, TRUE, "line-time" },
        { raw->noise, 0, 1e6, FALSE, "noise" },
        { raw->tip_radius, 0, 1e6, FALSE, "tip-radius" },
        { raw->tau, 0, 1e9, TRUE, "tau" },
        { raw->period, 0, 1e9, TRUE, "period" },
        { raw->phase, -1e6, 1e6, FALSE, "phase" },
        { raw->jump_time, -1e9, 1e9, FALSE, "jump-time" },
        { raw->walk_sigma, 0, 1e6, FALSE, "walk-sigma" },
        { raw->walk_dt, 1e-6, 1e6, FALSE, "walk-dt" },
        { raw->stripes, 1, raw->yres, FALSE, "stripes" },
        { raw->ls_points, 3, 1000000, FALSE, "ls-points" },
        { raw->ls_speed, 0, 1e6, TRUE, "ls-speed" },
        { raw->ls_rmax, 0, 1e9, FALSE, "ls-rmax" },
        { raw->ls_overhead, 0, 1e6, FALSE, "ls-overhead" },
        { raw->ls_delay, 0, 1e9, FALSE, "ls-delay" },
        { raw->ls_threshold, 0, 1, TRUE, "ls-threshold" },
        { raw->seed, 0, G_MAXUINT32, FALSE, "seed" },
    };
    guint i;

    for (i = 0; i < G_N_ELEMENTS(ranges); i++) {
        if (!check_range(ranges[i].value, ranges[i].min, ranges[i].max,
                         ranges[i].min_open, ranges[i].option, error))
            return FALSE;
    }
    return TRUE;
}

static gboolean
parse_sample(const gchar *text, SimscanConfig *config, GError **error)
{
    GError *err = NULL;
    gint id;

    if (!channel_spec_parse(text, &config->sample_file, &id, &err)) {
        bad_value(error, "sample", err->message);
        g_error_free(err);
        return FALSE;
    }
    config->sample_channel = (id == CHANNEL_SPEC_NO_ID) ? -1 : id;
    if (!*config->sample_file)
        return bad_value(error, "sample", _("empty file name"));
    return TRUE;
}

static gboolean
parse_drift(const RawOptions *raw, SimscanConfig *config, GError **error)
{
    DriftModel *m = &config->drift;
    DriftModelType type = m->type;
    const struct {
        const gchar *text, *option;
        gdouble *value;
    } pairs[] = {
        { raw->velocity, "velocity", m->v },
        { raw->offset, "offset", m->p0 },
        { raw->settle_velocity, "settle-velocity", m->u },
        { raw->amplitude, "amplitude", m->a },
        { raw->jump_step, "jump-step", m->step },
        { raw->acceleration, "acceleration", m->accel },
    };
    guint i;

    if (raw->drift) {
        config->figure6 = g_str_equal(raw->drift, "figure6");
        if (!config->figure6
            && !drift_model_type_from_name(raw->drift, &type))
            return bad_value(error, "drift",
                             _("unknown model (none, settling, oscillation, "
                               "jump, random-walk, acceleration, figure6)"));
        m->type = type;
    }
    for (i = 0; i < G_N_ELEMENTS(pairs); i++) {
        if (pairs[i].text
            && !parse_pair(pairs[i].text, pairs[i].option, FALSE, NM,
                           pairs[i].value, error))
            return FALSE;
    }
    m->tau = raw->tau;
    m->period = raw->period;
    m->phase = raw->phase;
    m->t_jump = raw->jump_time;
    m->walk_sigma = raw->walk_sigma*NM;
    m->walk_dt = raw->walk_dt;
    m->walk_seed = config->seed;
    return TRUE;
}

static gboolean
raw_to_config(const RawOptions *raw, SimscanConfig *config, GError **error)
{
    SimParticleParams *pp = &config->particles;
    gdouble size[2];

    if (!check_numbers(raw, error))
        return FALSE;
    config->seed = (guint32)raw->seed;
    pp->radius = raw->radius*NM;
    pp->radius_spread = raw->radius_spread;
    pp->count = raw->count;
    pp->density = raw->density/(UM*UM);
    pp->min_spacing = raw->spacing*NM;
    pp->roughness_rms = raw->roughness*NM;
    pp->roughness_corr = raw->correlation*NM;
    config->xres = raw->xres;
    config->yres = raw->yres;
    if (raw->size) {
        if (!parse_pair(raw->size, "size", TRUE, 1.0, size, error))
            return FALSE;
        if (!check_range(size[0], 0, MAX_SIZE_UM, TRUE, "size", error)
            || !check_range(size[1], 0, MAX_SIZE_UM, TRUE, "size", error))
            return FALSE;
        config->xreal = pp->xreal = size[0]*UM;
        config->yreal = pp->yreal = size[1]*UM;
    }
    config->line_time = raw->line_time;
    if (raw->direction) {
        if (g_str_equal(raw->direction, "down"))
            config->direction = SCAN_DIRECTION_DOWN;
        else if (g_str_equal(raw->direction, "up"))
            config->direction = SCAN_DIRECTION_UP;
        else
            return bad_value(error, "direction", _("expected down or up"));
    }
    config->noise_rms = raw->noise*NM;
    config->tip_radius = raw->tip_radius*NM;
    if (!parse_drift(raw, config, error))
        return FALSE;
    config->n_stripes = raw->stripes;
    config->local.radius = pp->radius;
    config->local.points = raw->ls_points;
    config->local.tip_speed = raw->ls_speed*UM;
    config->local.r_max = raw->ls_rmax*NM;
    config->local.line_overhead = raw->ls_overhead;
    config->local.threshold_fraction = raw->ls_threshold;
    config->local.choice = raw->prefer_whole ? PARTICLE_CHOICE_PREFER_WHOLE
                                             : PARTICLE_CHOICE_CLOSEST;
    config->local_delay = raw->ls_delay;
    if (raw->sample && !parse_sample(raw->sample, config, error))
        return FALSE;
    config->output = g_strdup(raw->output);
    config->table = g_strdup(raw->table);
    config->json = g_strdup(raw->json);
    config->quiet = raw->quiet;
    return TRUE;
}

/* Parses the options whose defaults a measured sample replaces; given gets
 * the SimscanGiven flags of those the user gave. */
static gboolean
parse_given(RawOptions *raw, guint *given, GError **error)
{
    const struct {
        const gchar *text, *option;
        gdouble min, max;
        gboolean min_open;
        gdouble *real;              /* a number ... */
        gint *integer;              /* ... or a whole number */
        guint flag;
    } options[] = {
        { raw->radius_text, "radius", 0, 1e6, TRUE, &raw->radius, NULL,
          SIMSCAN_GIVEN_RADIUS },
        { raw->ls_rmax_text, "ls-rmax", 0, 1e9, FALSE, &raw->ls_rmax, NULL,
          SIMSCAN_GIVEN_RMAX },
        { raw->xres_text, "xres", MIN_RES, MAX_RES, FALSE, NULL, &raw->xres,
          SIMSCAN_GIVEN_RESOLUTION },
        { raw->yres_text, "yres", MIN_RES, MAX_RES, FALSE, NULL, &raw->yres,
          SIMSCAN_GIVEN_RESOLUTION },
    };
    guint i;

    *given = 0;
    for (i = 0; i < G_N_ELEMENTS(options); i++) {
        if (!options[i].text)
            continue;
        if (options[i].real
            ? !option_value_parse_double(options[i].text, options[i].min,
                                         options[i].max, options[i].min_open,
                                         options[i].option, options[i].real,
                                         error)
            : !option_value_parse_int(options[i].text, (gint)options[i].min,
                                      (gint)options[i].max, options[i].option,
                                      options[i].integer, error))
            return FALSE;
        *given |= options[i].flag;
    }
    if (raw->velocity)
        *given |= SIMSCAN_GIVEN_VELOCITY;
    return TRUE;
}

/* What the options allow one by one may still be too much together. */
static gboolean
check_scene_limits(const SimscanConfig *config, GError **error)
{
    const SimParticleParams *pp = &config->particles;
    gdouble pixels = (gdouble)config->xres*config->yres, particles;

    if (pixels > MAX_PIXELS)
        return bad_value_printf(error, "xres",
                                _("%d x %d is more than %d pixels"),
                                config->xres, config->yres, MAX_PIXELS);
    if (config->sample_file)
        return TRUE;
    if (2.0*pp->radius >= MIN(pp->xreal, pp->yreal))
        return bad_value_printf(error, "radius",
                                _("particles %g nm across do not fit a scan "
                                  "of %g x %g um"), 2e9*pp->radius,
                                1e6*pp->xreal, 1e6*pp->yreal);
    particles = pp->density*pp->xreal*pp->yreal;
    if (!pp->count && particles > MAX_PARTICLES)
        return bad_value_printf(error, "density",
                                _("%g particles per um^2 over %g x %g um are "
                                  "%.3g particles, more than %d"),
                                pp->density*UM*UM, 1e6*pp->xreal,
                                1e6*pp->yreal, particles, MAX_PARTICLES);
    return TRUE;
}

/* Lines of one search (local-scan.c): from the centre out by 1.5 R to
 * r_max + R on both sides, and the lines through the chord. */
static gdouble
search_lines(const LocalScanParams *lp)
{
    return 4.0 + 2.0*ceil((lp->r_max + lp->radius)/(1.5*lp->radius));
}

/* How far the drift can carry the sample over time t at most: every term
 * of every model at its largest, the random walk at five sigma. */
static gdouble
drift_reach(const DriftModel *m, gdouble t)
{
    gdouble reach = hypot(m->p0[0], m->p0[1]) + hypot(m->v[0], m->v[1])*t;

    reach += hypot(m->u[0], m->u[1])*m->tau + hypot(m->a[0], m->a[1])
             + hypot(m->step[0], m->step[1])
             + 0.5*hypot(m->accel[0], m->accel[1])*t*t;
    if (m->type == DRIFT_MODEL_RANDOM_WALK)
        reach += 5.0*m->walk_sigma*t*sqrt(t);
    return reach;
}

/* Options that are each within range may still ask for endless work
 * together: a search over a radius of metres, millions of samples per
 * line, a drift that leaves the sample behind.  Checked once the sample
 * (measured or not) has set the scale. */
static gboolean
check_work_limits(const SimscanConfig *config, GError **error)
{
    const LocalScanParams *lp = &config->local;
    gdouble lines = search_lines(lp), size = MAX(config->xreal, config->yreal);
    gdouble rmax_limit = (1.5*(MAX_SEARCH_LINES - 4)/2.0 - 1.0)*lp->radius, samples, t, reach;
    gchar *msg;

    if (lines > MAX_SEARCH_LINES || lp->r_max > size) {
        msg = g_strdup_printf(_("%g nm is out of range (from 0 to %g nm: at most the scan size "
                                "and %d search lines of particles of radius %g nm)"),
                              lp->r_max/NM, MIN(rmax_limit, size)/NM, MAX_SEARCH_LINES,
                              lp->radius/NM);
        bad_value(error, "ls-rmax", msg);
        g_free(msg);
        return FALSE;
    }
    samples = (gdouble)config->n_stripes*lines*lp->points;
    if (samples > MAX_LOCAL_SAMPLES) {
        msg = g_strdup_printf(_("%d points per line are too many: %d stripes of up to %g lines "
                                "allow from 3 to %d"), lp->points, config->n_stripes, lines,
                              (gint)MAX(3, floor(MAX_LOCAL_SAMPLES/(config->n_stripes*lines))));
        bad_value(error, "ls-points", msg);
        g_free(msg);
        return FALSE;
    }
    t = config->local_delay + config->yres*config->line_time
        + config->n_stripes*lines*local_scan_line_time(lp);
    reach = drift_reach(&config->drift, t);
    if (!(reach <= MAX_DRIFT_SCANS*size)) {
        msg = g_strdup_printf(_("the drift would carry the sample %g um over the %g s simulated, "
                                "more than %g times the scan size of %g um: lower --velocity, "
                                "--offset, --settle-velocity, --amplitude, --jump-step, "
                                "--acceleration or "
                                "--walk-sigma, or the times"),
                              reach/UM, t, MAX_DRIFT_SCANS, size/UM);
        bad_value(error, "drift", msg);
        g_free(msg);
        return FALSE;
    }
    return TRUE;
}

/* No output may replace the sample or another output. */
static gboolean
check_files(const SimscanConfig *config, GError **error)
{
    OutputFilesRole roles[] = {
        { "--sample", config->sample_file, TRUE },
        { "--output", config->output, FALSE },
        { "--table", config->table, FALSE },
        { "--json", config->json, FALSE },
    };

    return output_files_check_roles(roles, G_N_ELEMENTS(roles), error);
}

/* A measured sample sets the defaults of what the user did not give. */
static gboolean
adopt_sample(SimscanConfig *config, const RawOptions *raw, guint given,
             GError **error)
{
    GwyDataField *field;
    gboolean ok;

    if (raw->size)
        return bad_value(error, "size", _("a measured sample is scanned "
                                          "over its own size"));
    field = simscan_load_channel(config->sample_file, config->sample_channel,
                                 error);
    if (!field)
        return FALSE;
    ok = simscan_config_adopt_sample(config, field, given, error);
    g_object_unref(field);
    return ok;
}

/* The preset is applied before the other options are parsed, so it must be
 * found first. */
static gboolean
find_preset(gint argc, gchar **argv, SimscanPreset *preset, GError **error)
{
    const gchar *name = NULL;
    gint i;

    for (i = 1; i < argc; i++) {
        if (g_str_equal(argv[i], "--"))
            break;
        if (g_str_equal(argv[i], "--preset") && i+1 < argc)
            name = argv[++i];
        else if (g_str_has_prefix(argv[i], "--preset="))
            name = argv[i] + strlen("--preset=");
    }
    *preset = SIMSCAN_PRESET_NONE;
    if (name && !simscan_preset_from_name(name, preset))
        return bad_value(error, "preset", _("unknown preset (paper, figure6)"));
    return TRUE;
}

gboolean
simscan_options_parse(gint argc, gchar **argv, const gchar *usage,
                      const GOptionEntry *extra, SimscanConfig *config,
                      GError **error)
{
    GOptionContext *context;
    GOptionEntry *entries;
    SimscanPreset preset;
    RawOptions raw;
    gchar **args;
    gboolean ok;
    guint given = 0;
    gint i;

    if (!find_preset(argc, argv, &preset, error))
        return FALSE;
    simscan_preset_apply(config, preset);
    raw_from_config(&raw, config);
    entries = make_entries(&raw);
    context = g_option_context_new(usage);
    g_option_context_set_translation_domain(context, GETTEXT_PACKAGE);
    g_option_context_add_main_entries(context, entries, GETTEXT_PACKAGE);
    if (extra)
        g_option_context_add_main_entries(context, extra, GETTEXT_PACKAGE);
    /* parse_strv consumes what it parses; argv stays the caller's. */
    args = g_new0(gchar*, argc + 1);
    for (i = 0; i < argc; i++)
        args[i] = g_strdup(argv[i]);
    ok = option_parse_naming_strv(context, &args, error);
    if (ok && g_strv_length(args) > 1) {
        g_set_error(error, G_OPTION_ERROR, G_OPTION_ERROR_FAILED,
                    _("unexpected argument %s"), args[1]);
        ok = FALSE;
    }
    ok = ok && parse_given(&raw, &given, error);
    ok = ok && raw_to_config(&raw, config, error);
    ok = ok && check_files(config, error);
    ok = ok && (!config->sample_file || adopt_sample(config, &raw, given, error));
    ok = ok && check_scene_limits(config, error);
    ok = ok && check_work_limits(config, error);
    g_strfreev(args);
    raw_clear(&raw);
    g_free(entries);
    g_option_context_free(context);
    return ok;
}
