/*
 *  `simscan fit`: drift models fitted to a time series of frames, the
 *  command line over the core's fit (modules/core/fit-report.h).
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <string.h>
#include <stdlib.h>
#include <math.h>
#include <libgwyddion/gwyddion.h>
#include <libgwymodule/gwymodule.h>
#include <app/gwyapp.h>
#include "option-values.h"
#include "output-files.h"
#include "frame-series-load.h"
#include "series-options.h"
#include "fit-command.h"
#include "quoted-input.h"
#include "option-parse.h"

#define FIT_MAX_FRAMES 16

#undef _
#define _(s) dgettext(GETTEXT_PACKAGE, s)

/* Lines a registered block needs at least. */
#define MIN_BLOCK_LINES 4

/* Options of the command line beyond the series' (series-options.h).
 * Numbers stay text until checked, so that an option given with any value
 * counts as given. */
typedef struct {
    gchar *json;
    SeriesArgs series;
    gchar *blocks;
    gchar *bic_margin;
} FitArgs;

/* The numbers of the options, checked. */
typedef struct {
    gint blocks;               /* 0: not given */
    gdouble bic_margin;        /* < 0: not given */
} FitNumbers;

static gboolean
parse_fit_numbers(const FitArgs *args, FitNumbers *numbers, GError **error)
{
    numbers->blocks = 0;
    numbers->bic_margin = -1.0;
    if (args->bic_margin
        && !option_value_parse_double(args->bic_margin, 0.0, 1e6, FALSE,
                                      "bic-margin", &numbers->bic_margin,
                                      error))
        return FALSE;
    if (args->blocks
        && !option_value_parse_int(args->blocks, 1, G_MAXINT/MIN_BLOCK_LINES,
                                   "blocks", &numbers->blocks, error))
        return FALSE;
    return TRUE;
}

/* Every block needs MIN_BLOCK_LINES lines of the frames. */
static gboolean
choose_blocks(const FrameSeries *series, gint wanted, gint *n_blocks,
              GError **error)
{
    gint yres = series->frames[0].timing.yres;
    gint most = yres/MIN_BLOCK_LINES;
    gchar *msg;

    if (most < 1) {
        g_set_error(error, FRAME_SERIES_ERROR, FRAME_SERIES_ERROR_MISMATCH,
                    _("%s: frames of %d lines are too short to register "
                      "(at least %d lines)"),
                    series->frames[0].label, yres, MIN_BLOCK_LINES);
        return FALSE;
    }
    if (wanted > most) {
        msg = g_strdup_printf(_("%d blocks of at least %d lines do not fit "
                                "frames of %d lines (at most %d)"),
                              wanted, MIN_BLOCK_LINES, yres, most);
        option_value_refuse("blocks", msg, error);
        g_free(msg);
        return FALSE;
    }
    *n_blocks = wanted ? wanted : MIN(*n_blocks, most);
    return TRUE;
}

static gboolean
args_to_options(FitArgs *args, FrameSeriesOptions *options,
                FitNumbers *numbers, GError **error)
{
    return (series_args_to_options(&args->series, options, error)
            && parse_fit_numbers(args, numbers, error));
}

static gboolean
write_output(const gchar *filename, const gchar *text, GError **error)
{
    if (!filename || output_files_is_stdout(filename)) {
        fputs(text, stdout);
        fputc('\n', stdout);
        return TRUE;
    }
    return output_files_write_one(filename, (const guchar*)text,
                                  strlen(text), error);
}

/* Every pair of frames is registered, and the oscillation search refits
 * the model over all those measurements at every trial period and again
 * around every local minimum; the trial periods grow with the series'
 * span.  Measured on 128 x 128 frames 200 s apart: 10 frames 3 s, 16
 * frames 6 s, 18 frames 9 s, 19 frames 19 s, 20 frames 61 s.  The count is
 * bounded where a run still takes seconds (checked before any frame is
 * read, and again for the channels of one file). */
static gboolean
check_frame_count(gint n, GError **error)
{
    if (n <= FIT_MAX_FRAMES)
        return TRUE;
    g_set_error(error, FRAME_SERIES_ERROR, FRAME_SERIES_ERROR_CHANNEL,
                _("%d frames are too many to fit: from 1 to %d (fit a part of the series, or "
                  "every n-th frame)"), n, FIT_MAX_FRAMES);
    return FALSE;
}

/* A fit resting on fewer than half the measurements is said, as the
 * series command says it: three frames of white noise gave a jump of
 * 825 nm from 4 of 48 blocks matched by chance, with nothing on standard
 * error and no note.  Returns the note (added to the series' notes, for
 * the JSON), or NULL. */
static const gchar*
note_few_measurements(const FitReport *report, FrameSeries *series)
{
    gint i, used = 0;
    gchar *note;

    for (i = 0; i < report->n_meas; i++)
        used += (report->meas[i].weight > 0.0);
    if (2*used >= report->n_meas)
        return NULL;
    note = g_strdup_printf(_("only %d of %d measurements could be used: the fit rests on few "
                             "measurements"), used, report->n_meas);
    g_ptr_array_add(series->notes, note);
    return note;
}

static gboolean
run_fit(FitArgs *args, gchar **files, gint n_files, GError **error)
{
    FrameSeriesOptions soptions;
    DisplacementOptions doptions;
    DriftFitOptions foptions;
    FrameSeries *series = NULL;
    FitNumbers numbers;
    FitReport report;
    gboolean ok = FALSE;
    const gchar *warning;
    gchar *text;

    memset(&report, 0, sizeof(report));
    if (!args_to_options(args, &soptions, &numbers, error))
        goto end;
    if (!(series = frame_series_load(files, n_files, &soptions, error))
        || !check_frame_count(series->n_frames, error))
        goto end;
    displacement_options_init(&doptions);
    if (!choose_blocks(series, numbers.blocks, &doptions.n_blocks, error))
        goto end;
    drift_fit_options_init(&foptions);
    foptions.min_period = drift_fit_min_period(series->frames[0].timing.line_time,
                                               series->frames[0].timing.yres,
                                               doptions.n_blocks);
    if (numbers.bic_margin >= 0.0)
        foptions.bic_margin = numbers.bic_margin;
    if (!fit_report_compute(series, &doptions, &foptions, &report)) {
        g_set_error(error, FRAME_SERIES_ERROR, FRAME_SERIES_ERROR_CHANNEL,
                    _("too few frames could be registered to fit a drift "
                      "model"));
        goto end;
    }
    warning = note_few_measurements(&report, series);
    text = fit_report_to_json(&report, series);
    ok = write_output(args->json, text, error);
    g_free(text);
    /* Only after the report is written: a failure is its one line. */
    if (ok && warning)
        g_printerr(_("simscan fit: warning: %s\n"), warning);

end:
    fit_report_clear(&report);
    frame_series_free(series);
    series_args_clear(NULL, &soptions);
    return ok;
}

/* The JSON may not replace a frame. */
static gboolean
check_files(const gchar *json, gchar **files, GError **error)
{
    guint n = g_strv_length(files), i;
    OutputFilesRole *roles = g_new(OutputFilesRole, n + 1);
    gboolean ok;

    for (i = 0; i < n; i++) {
        roles[i].role = _("frame");
        roles[i].filename = files[i];
        roles[i].is_input = TRUE;
    }
    roles[n].role = "--json";
    roles[n].filename = output_files_is_stdout(json) ? NULL : json;
    roles[n].is_input = FALSE;
    ok = output_files_check_roles(roles, n + 1, error);
    g_free(roles);
    return ok;
}

static void
ensure_gwyddion(void)
{
    static gboolean initialised = FALSE;

    /* The file loaders live in Gwyddion's modules. */
    if (!initialised && !gwy_module_lookup("gwyfile"))
        gwy_app_init_nongui("enable-threads", FALSE, NULL);
    initialised = TRUE;
}

int
simscan_fit_main(int argc, char **argv)
{
    FitArgs args;
    gchar **files = NULL;
    GOptionEntry entries[] = {
        { "json", 0, 0, G_OPTION_ARG_FILENAME, &args.json,
          N_("Write the JSON to FILE (default: standard output)"), N_("FILE") },
        { "blocks", 0, 0, G_OPTION_ARG_STRING, &args.blocks,
          N_("Blocks of lines registered per frame, each at least 4 lines "
             "(default 16, fewer in frames under 64 lines)"), N_("N") },
        { "bic-margin", 0, 0, G_OPTION_ARG_STRING, &args.bic_margin,
          N_("BIC gain an effect needs over constant drift, 0 or more "
             "(default 20)"),
          N_("X") },
        { G_OPTION_REMAINING, 0, 0, G_OPTION_ARG_FILENAME_ARRAY, &files,
          NULL, N_("FRAME...") },
        { NULL, 0, 0, 0, NULL, NULL, NULL },
    };
    GOptionContext *context;
    GError *error = NULL;
    gint status = 1;

    memset(&args, 0, sizeof(args));

    /* The FRAME... entry names the arguments itself. */
    context = g_option_context_new(_("- fit drift models to a time series of "
                                     "frames"));
    g_option_context_set_translation_domain(context, GETTEXT_PACKAGE);
    g_option_context_add_main_entries(context, entries, GETTEXT_PACKAGE);
    series_args_add_entries(context, &args.series);
    if (!option_parse_naming(context, &argc, &argv, &error))
        goto end;
    if (!files || !files[0]) {
        g_set_error(&error, FRAME_SERIES_ERROR, FRAME_SERIES_ERROR_CHANNEL,
                    _("no frames given (several files, or one file with a "
                      "channel per frame)"));
        goto end;
    }
    if (!check_frame_count(g_strv_length(files), &error) || !check_files(args.json, files, &error))
        goto end;
    ensure_gwyddion();
    if (run_fit(&args, files, g_strv_length(files), &error))
        status = 0;

end:
    if (error)
        simscan_print_error("simscan fit", error);
    g_clear_error(&error);
    g_option_context_free(context);
    g_strfreev(files);
    g_free(args.json);
    series_args_clear(&args.series, NULL);
    g_free(args.blocks);
    g_free(args.bic_margin);
    return status;
}
