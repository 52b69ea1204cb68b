/*
 *  simscan's summary on stdout.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include "simscan-presets.h"
#include "simscan-report.h"
#include "simscan-i18n.h"

void
simscan_report_centre_error(FILE *fh, const gchar *label,
                            const CentreError *e)
{
    fprintf(fh, _("  %-7s RMS %.3f px (%.2f nm), max %.3f px (%.2f nm), "
                  "%d of %d particles matched\n"),
            label, e->rms_px, e->rms_nm, e->max_px, e->max_nm,
            e->n_matched, e->n_expected);
}

/* Which stripes were measured on a grain that reaches the stripe's first
 * or last row (the particle choice made again, as local_scan_run did). */
static gboolean*
stripes_on_cut_grains(const SimscanScene *scene, gint n)
{
    gint xres = gwy_data_field_get_xres(scene->image);
    gint yres = gwy_data_field_get_yres(scene->image);
    gint *chosen = g_new(gint, n), s;
    gboolean *cut = g_new0(gboolean, n);

    particle_choose_for_stripes_by(scene->particles, n, xres, yres,
                                   scene->config->local.choice, chosen);
    for (s = 0; s < n; s++) {
        if (chosen[s] >= 0)
            cut[s] = particle_touches_stripe_boundary(
                         &g_array_index(scene->particles, DetectedParticle,
                                        chosen[s]), s, n, yres);
    }
    g_free(chosen);
    return cut;
}

static void
print_stripes(FILE *fh, const SimscanScene *scene, const SimscanMeasurement *m)
{
    gboolean *cut = stripes_on_cut_grains(scene, m->n_stripes);
    gint s, n_cut = 0;

    fprintf(fh, _("  stripe  true dx, dy (px)   measured exact (px)   "
                  "table  lines\n"));
    for (s = 0; s < m->n_stripes; s++) {
        const LocalScanParticle *r = m->scans + s;
        const DriftTableRow *row = m->table->rows + s;

        fprintf(fh, "  %6d  %7.3f %7.3f    ", s, m->true_dx[s], m->true_dy[s]);
        if (row->has_drift)
            fprintf(fh, "%7.3f %7.3f       %3.0f %3.0f  %5d%s\n",
                    r->dx, r->dy, row->dx, row->dy, r->lines,
                    cut[s] ? "  *" : "");
        else
            fprintf(fh, "%-21s  %-7s  %5d\n",
                    r->lines ? _("not found") : _("no particle"), "", r->lines);
        n_cut += (row->has_drift && cut[s]);
    }
    if (n_cut)
        fprintf(fh, _("  * measured on a grain that reaches the stripe's first "
                      "or last row: if a stripe boundary cut the particle,\n"
                      "    the stripes' different drifts sheared it and its "
                      "centre may be a pixel off (--prefer-whole-particles\n"
                      "    avoids such grains; the paper does not)\n"));
    g_free(cut);
}

static const gchar*
particle_choice_text(ParticleChoice choice)
{
    if (choice == PARTICLE_CHOICE_PREFER_WHOLE)
        return _("particles clear of the stripe boundaries first "
                 "(--prefer-whole-particles; the paper takes the closest)");
    return _("the particle closest to the stripe's centre (the paper's rule)");
}

void
simscan_report_print(FILE *fh, const SimscanScene *scene,
                     const SimscanMeasurement *m)
{
    const SimscanConfig *config = scene->config;
    gdouble pxs = 1e9*scene->scan.xreal/scene->scan.xres;

    fprintf(fh, _("simscan: preset %s, drift %s, %d x %d px over %.3g x %.3g um "
                  "(%.2f nm/px), seed %u\n"),
            simscan_preset_name(config->preset),
            scene->shift_dx ? "figure6"
                            : drift_model_type_name(scene->drift.type),
            scene->scan.xres, scene->scan.yres,
            1e6*scene->scan.xreal, 1e6*scene->scan.yreal, pxs, config->seed);
    fprintf(fh, _("image scanned in %.1f s; %u particles detected; local scans "
                  "%.3f to %.3f s (%.3f s, %d lines)\n"),
            scan_timing_frame_end(&scene->timing), scene->particles->len,
            m->t_start, m->t_end, m->t_end - m->t_start, m->lines);
    fprintf(fh, _("local scans: particle radius %.1f nm, lines %.0f nm long, "
                  "per stripe on %s\n"),
            1e9*config->local.radius,
            1e9*local_scan_line_length(&config->local),
            particle_choice_text(config->local.choice));
    print_stripes(fh, scene, m);
    if (!m->have_errors)
        return;
    fprintf(fh, _("particle centres against their true places (the sample as "
                  "at the local scans, drift %.2f, %.2f nm):\n"),
            1e9*m->ref_drift[0], 1e9*m->ref_drift[1]);
    simscan_report_centre_error(fh, _("before"), &m->before);
    simscan_report_centre_error(fh, _("after"), &m->after);
}
