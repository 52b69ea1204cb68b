/*
 *  simscan's summary on stdout.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
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

static void
print_stripes(FILE *fh, const SimscanMeasurement *m)
{
    gint s;

    fprintf(fh, _("  stripe  true dx, dy (px)   measured exact (px)   "
                  "table  lines\n"));
    for (s = 0; s < m->n_stripes; s++) {
        const LocalScanParticle *r = m->scans + s;
        const DriftTableRow *row = m->table->rows + s;

        fprintf(fh, "  %6d  %7.3f %7.3f    ", s, m->true_dx[s], m->true_dy[s]);
        if (row->has_drift)
            fprintf(fh, "%7.3f %7.3f       %3.0f %3.0f  %5d\n",
                    r->dx, r->dy, row->dx, row->dy, r->lines);
        else
            fprintf(fh, "%-21s  %-7s  %5d\n",
                    r->lines ? _("not found") : _("no particle"), "", r->lines);
    }
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
    print_stripes(fh, m);
    if (!m->have_errors)
        return;
    fprintf(fh, _("particle centres against their true places (the sample as "
                  "at the local scans, drift %.2f, %.2f nm):\n"),
            1e9*m->ref_drift[0], 1e9*m->ref_drift[1]);
    simscan_report_centre_error(fh, _("before"), &m->before);
    simscan_report_centre_error(fh, _("after"), &m->after);
}
