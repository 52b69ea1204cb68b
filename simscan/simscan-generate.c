/*
 *  The main simscan command.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <stdlib.h>
#include <stdio.h>
#include "simscan-options.h"
#include "simscan-run.h"
#include "simscan-output.h"
#include "simscan-report.h"
#include "simscan-sample-file.h"
#include "simscan-generate.h"
#include "option-values.h"
#include "simscan-i18n.h"

static int
fail(GError *error)
{
    simscan_print_error("simscan", error);
    g_error_free(error);
    return EXIT_FAILURE;
}

int
simscan_generate_main(int argc, char **argv)
{
    SimscanConfig config;
    SimscanScene *scene = NULL;
    SimscanMeasurement *m = NULL;
    GwyDataField *sample_field = NULL;
    GError *error = NULL;
    gboolean ok;

    simscan_config_init(&config);
    ok = simscan_options_parse(argc, argv,
                               _("- simulate a drifting scan and its local "
                                 "scans"), NULL, &config, &error);
    if (ok && config.sample_file)
        ok = !!(sample_field = simscan_load_channel(config.sample_file,
                                                    config.sample_channel,
                                                    &error));
    ok = ok && (scene = simscan_scene_new(&config, sample_field, &error));
    ok = ok && (m = simscan_measure(scene, config.n_stripes, &error));
    ok = ok && simscan_output_write_all(scene, m, &error);
    if (ok && !config.quiet)
        simscan_report_print(stdout, scene, m);
    simscan_measurement_free(m);
    simscan_scene_free(scene);
    g_clear_object(&sample_field);
    simscan_config_clear(&config);
    return ok ? EXIT_SUCCESS : fail(error);
}
