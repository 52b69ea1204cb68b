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
#include "benchmark-command.h"
#include "simscan-i18n.h"
#include "output-files.h"
#include "library-log.h"

/* --verbose, anywhere before "--", shows what libraries logged
 * (library-log.h); it is taken out before a subcommand parses the rest. */
static gboolean
take_verbose(int *argc, char **argv)
{
    gboolean verbose = FALSE;
    int i, j;

    for (i = j = 1; i < *argc; i++) {
        if (g_str_equal(argv[i], "--"))
            break;
        if (g_str_equal(argv[i], "--verbose"))
            verbose = TRUE;
        else
            argv[j++] = argv[i];
    }
    for (; i < *argc; i++)
        argv[j++] = argv[i];
    argv[j] = NULL;
    *argc = j;
    return verbose;
}

int
main(int argc, char **argv)
{
    g_set_prgname("simscan");
    library_log_capture("simscan", take_verbose(&argc, argv));
    setlocale(LC_ALL, "");
    bindtextdomain(GETTEXT_PACKAGE, LOCALEDIR);
    bind_textdomain_codeset(GETTEXT_PACKAGE, "UTF-8");

    /* A subcommand is the first argument; without one, simulate. */
    if (argc > 1 && strcmp(argv[1], "sweep") == 0)
        return output_files_finish_stdout("simscan sweep", simscan_sweep_main(argc - 1, argv + 1));
    if (argc > 1 && strcmp(argv[1], "compare") == 0)
        return output_files_finish_stdout("simscan compare", simscan_compare_main(argc - 1, argv + 1));
    if (argc > 1 && strcmp(argv[1], "fit") == 0)
        return output_files_finish_stdout("simscan fit", simscan_fit_main(argc - 1, argv + 1));
    if (argc > 1 && strcmp(argv[1], "benchmark") == 0)
        return output_files_finish_stdout("simscan benchmark", simscan_benchmark_main(argc - 1, argv + 1));
    if (argc > 1 && strcmp(argv[1], "score") == 0)
        return output_files_finish_stdout("simscan score", simscan_score_main(argc - 1, argv + 1));
    return output_files_finish_stdout("simscan", simscan_generate_main(argc, argv));
}
