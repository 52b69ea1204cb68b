/*
 *  simscan, the local-scan simulator: dispatches to its subcommands.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <string.h>
#include <locale.h>
#include "simscan-generate.h"
#include "n-sweep.h"
#include "simscan-compare.h"
#include "fit-command.h"
#include "simscan-i18n.h"

int
main(int argc, char **argv)
{
    setlocale(LC_ALL, "");
    bindtextdomain(GETTEXT_PACKAGE, LOCALEDIR);
    bind_textdomain_codeset(GETTEXT_PACKAGE, "UTF-8");

    /* A subcommand is the first argument; without one, simulate. */
    if (argc > 1 && strcmp(argv[1], "sweep") == 0)
        return simscan_sweep_main(argc - 1, argv + 1);
    if (argc > 1 && strcmp(argv[1], "compare") == 0)
        return simscan_compare_main(argc - 1, argv + 1);
    if (argc > 1 && strcmp(argv[1], "fit") == 0)
        return simscan_fit_main(argc - 1, argv + 1);
    return simscan_generate_main(argc, argv);
}
