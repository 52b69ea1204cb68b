/*
 *  gwy-localscan: batch local-scan drift compensation from the command line
 *  (docs/cli.md).
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <errno.h>
#include <locale.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <glib/gstdio.h>
#include <libgwyddion/gwymacros.h>
#include <libprocess/datafield.h>
#include <app/gwyapp.h>
#include "drift-table.h"
#include "stripe-registration.h"
#include "continuous-compensate.h"
#include "channel-spec.h"
#include "localscan-channel.h"
#include "headless-run.h"
#include "localscan-settings.h"
#include "compensation-marker.h"
#include "run-description.h"
#include "library-log.h"
#include "quoted-input.h"
#include "safe-output.h"
#include "series-command.h"
#include "series-options.h"
#include "option-parse.h"
#include "scan-timing-meta.h"

#undef _
#define _(s) dgettext(GETTEXT_PACKAGE, s)

#define PROGRAM_NAME "gwy-localscan"

/* No -c given: the channel with the lowest id. */
#define CHANNEL_FIRST G_MININT

#define STRIPES_UNSET G_MININT

/* The largest --search (px): beyond any image Gwyddion handles. */
#define SEARCH_MAX 100000

enum {
    EXIT_OK    = 0,
    EXIT_ERROR = 1,   /* bad input, table, module or output */
    EXIT_USAGE = 2,   /* bad command line */
};

typedef struct {
    gchar *output;
    gchar *table_file;
    gchar *channel_arg;
    gint channel;                /* from channel_arg, unless it is a title */
    gchar *mode_name;
    gchar *write_drift;
    gchar *reference;
    gchar *stripes_arg;
    gint stripes;
    gchar *search_arg;
    gdouble search_x;            /* px, 0: the whole frame */
    gdouble search_y;
    gboolean accept_partial;
    gchar *masking_name;
    gint masking;                /* GwyMaskingType */
    gchar *line_time_arg;
    gchar *direction_name;
    gchar *frame_start_arg;
    gchar *interpolation_name;
    gint interpolation;          /* -1: the user's setting */
    gboolean force;
    gboolean all_channels;
    gboolean show_version;
    gboolean verbose;
    gchar **inputs;
} Options;

static Options options = {
    .channel = CHANNEL_FIRST,
    .stripes = STRIPES_UNSET,
    .interpolation = -1,
};

/* --reference FILE[:ID|:TITLE] taken apart. */
typedef struct {
    gchar *file;       /* NULL: the INPUT itself */
    gint channel;      /* CHANNEL_FIRST: the first channel of file */
    gchar *title;      /* the channel titled so instead; NULL: none */
} ReferenceSpec;

static ReferenceSpec reference_spec = { NULL, CHANNEL_FIRST, NULL };

/* Every option gwy-localscan knows; --help is generated from this table.
 * A new option is one entry here plus its handling in run_batch() (drift
 * sources: obtain_drift_table()). */
static GOptionEntry option_table[] = {
    { "output", 'o', 0, G_OPTION_ARG_FILENAME, &options.output,
      N_("Write the result to OUT.gwy (required)"), N_("OUT.gwy") },
    { "drift", 'd', 0, G_OPTION_ARG_FILENAME, &options.table_file,
      N_("Read the drift table from TABLE.csv instead of the one stored "
         "with the channel"), N_("TABLE.csv") },
    { "channel", 'c', 0, G_OPTION_ARG_FILENAME, &options.channel_arg,
      N_("Compensate channel ID, or the channel titled TITLE (default: the first channel)"),
      N_("ID|TITLE") },
    { "mode", 'm', 0, G_OPTION_ARG_STRING, &options.mode_name,
      N_("Compensation mode: paper (default) or continuous (line by line, "
         "timed by the file's metadata: line time or line rate, slow-scan "
         "direction, frame start; where it says nothing, by --line-time, "
         "--direction, --frame-start)"),
      N_("paper|continuous") },
    { "reference", 0, 0, G_OPTION_ARG_FILENAME, &options.reference,
      N_("Measure the drift by registering stripes of the image against "
         "a drift-free scan of the same area: channel ID of FILE, or the "
         "channel titled TITLE (default its first channel); FILE may be INPUT "
         "itself, and :ID or :TITLE alone means that channel of INPUT.  Not "
         "with -d"), N_("FILE[:ID|:TITLE]") },
    { "stripes", 0, 0, G_OPTION_ARG_STRING, &options.stripes_arg,
      NULL, N_("N") },   /* stripes_help() */
    { "search", 0, 0, G_OPTION_ARG_STRING, &options.search_arg,
      N_("With --reference: search shifts up to PX columns and PY rows (PY defaults to PX; "
         "default: 45 % of the frame in each axis)"), N_("PX[,PY]") },
    { "masking", 0, 0, G_OPTION_ARG_STRING, &options.masking_name,
      N_("With --reference: what the image's and the reference's masks mean: exclude (default: "
         "masked pixels are missing, as Gwyddion's importers mark the pixels a file lacks), "
         "include (only masked pixels are data) or ignore"), N_("MODE") },
    { "accept-partial", 0, 0, G_OPTION_ARG_NONE, &options.accept_partial,
      N_("With --reference: use the stripes measured even when they cannot support the result "
         "(fewer than two, none with --stripes 1, or fewer than half of those whose content lies in the reference); "
         "without it such a registration is refused"), NULL },
    { "line-time", 0, 0, G_OPTION_ARG_STRING, &options.line_time_arg,
      N_("Continuous mode: seconds per scan line, trace and retrace, where the "
         "file's metadata does not give it (the metadata wins; default 1)"), N_("S") },
    { "direction", 0, 0, G_OPTION_ARG_STRING, &options.direction_name,
      N_("Continuous mode: slow-scan direction where the file's metadata does "
         "not give it (the metadata wins; default down)"), N_("down|up") },
    { "frame-start", 0, 0, G_OPTION_ARG_STRING, &options.frame_start_arg,
      N_("Continuous mode: start of the frame, seconds in the clock of the "
         "table's t_image and t_local, where the file's metadata does not give "
         "it (the metadata wins; default 0)"), N_("S") },
    { "interpolation", 0, 0, G_OPTION_ARG_STRING, &options.interpolation_name,
      NULL, N_("NAME") },   /* interpolation_help() */
    { "force", 0, 0, G_OPTION_ARG_NONE, &options.force,
      N_("Compensate a channel that is already local-scan compensated (it carries the "
         "metadata item 'Local-scan compensation'); without it such a channel is refused"),
      NULL },
    { "all-channels", 0, 0, G_OPTION_ARG_NONE, &options.all_channels,
      N_("Apply the channel's correction also to every other channel of the same scan (same "
         "pixels and physical size, same scan time) and to their masks"), NULL },
    { "write-drift", 0, 0, G_OPTION_ARG_FILENAME, &options.write_drift,
      N_("Also write the drift table used to TABLE.csv"), N_("TABLE.csv") },
    { "verbose", 'v', 0, G_OPTION_ARG_NONE, &options.verbose,
      N_("Also show what Gwyddion and its libraries logged (kept from the output "
         "otherwise)"), NULL },
    { "version", 0, 0, G_OPTION_ARG_NONE, &options.show_version,
      N_("Print the version and exit"), NULL },
    { G_OPTION_REMAINING, 0, 0, G_OPTION_ARG_FILENAME_ARRAY, &options.inputs,
      NULL, N_("INPUT") },
    { NULL, 0, 0, 0, NULL, NULL, NULL },
};

/* Continuous mode's timing where the metadata does not say, and which
 * parts the command line gave. */
typedef struct {
    gdouble line_time;
    ScanDirection direction;
    gdouble frame_start;
    LocalscanTimingFound given;
} TimingFallback;

static TimingFallback timing_fallback = {
    LOCALSCAN_LINE_TIME_DEFAULT, LOCALSCAN_DEFAULT_DIRECTION, LOCALSCAN_FRAME_START_DEFAULT, 0,
};

/* The modes of -m; whole_pixels is what the module's validation of the
 * table requires in that mode. */
typedef struct {
    const gchar *name;
    LocalscanMode value;
    gboolean whole_pixels;
} CompensationMode;

static const CompensationMode compensation_modes[] = {
    { "paper",      LOCALSCAN_MODE_PAPER,      TRUE,  },
    { "continuous", LOCALSCAN_MODE_CONTINUOUS, FALSE, },
};

/* Messages must stay one printable line, whatever a file or a library put
 * into them. */
static void
print_error(const gchar *message)
{
    gchar *line = quoted_input_message_line(message);

    fprintf(stderr, "%s: %s\n", PROGRAM_NAME, line);
    g_free(line);
}

/* Warnings wait until the run succeeds: printed as they arose, a failure
 * after them (too many missing pixels, an output that cannot be written)
 * gave two lines where one explains it (test-hostile-input, seed
 * 4018615478). */
static GPtrArray *pending_warnings = NULL;

/* Takes line, a whole line with its newline. */
static void
warn_later(gchar *line)
{
    if (!pending_warnings)
        pending_warnings = g_ptr_array_new_with_free_func(g_free);
    g_ptr_array_add(pending_warnings, line);
}

static void
finish_warnings(gboolean succeeded)
{
    guint i;

    for (i = 0; succeeded && pending_warnings && i < pending_warnings->len; i++)
        fputs(g_ptr_array_index(pending_warnings, i), stderr);
    if (pending_warnings)
        g_ptr_array_free(pending_warnings, TRUE);
    pending_warnings = NULL;
}

static void
free_options(void)
{
    g_free(options.output);
    g_free(options.table_file);
    g_free(options.mode_name);
    g_free(options.channel_arg);
    g_free(options.write_drift);
    g_free(options.reference);
    g_free(options.search_arg);
    g_free(options.stripes_arg);
    g_free(options.masking_name);
    g_free(options.line_time_arg);
    g_free(options.direction_name);
    g_free(options.frame_start_arg);
    g_free(options.interpolation_name);
    g_free(reference_spec.file);
    g_free(reference_spec.title);
    g_strfreev(options.inputs);
}

/* The module's default and limit, as they are. */
static gchar*
stripes_help(void)
{
    return g_strdup_printf(_("Register N stripes with --reference (default %d; at most %d and half the "
                             "image's rows)"),
                           LOCALSCAN_STRIPES_DEFAULT, LOCALSCAN_STRIPES_MAX);
}

static gchar*
interpolation_help(void)
{
    gchar *names = run_description_interpolation_names(), *help;

    help = g_strdup_printf(_("Continuous mode: interpolation kernel, one of %s (default: the "
                             "module's setting, initially %s, which keeps heights)"),
                           names, run_description_interpolation_name(LOCALSCAN_DEFAULT_INTERPOLATION));
    g_free(names);
    return help;
}

static GOptionEntry*
find_option(const gchar *long_name)
{
    GOptionEntry *entry;

    for (entry = option_table; entry->long_name; entry++) {
        if (gwy_strequal(entry->long_name, long_name))
            return entry;
    }
    g_return_val_if_reached(NULL);
}

static gboolean
parse_options(gint *argc, gchar ***argv, GError **error)
{
    GOptionContext *context;
    gchar *help = stripes_help(), *kernel_help = interpolation_help();
    gboolean ok;

    /* Entries with a description are translated by the context; these
     * already are. */
    find_option("stripes")->description = help;
    find_option("interpolation")->description = kernel_help;

    context = g_option_context_new(NULL);
    g_option_context_set_translation_domain(context, GETTEXT_PACKAGE);
    g_option_context_set_summary(context,
        _("Removes thermal drift from an AFM image by the local-scan method:\n"
          "every stripe of the image is moved back by its measured drift.\n"
          "INPUT is any file Gwyddion can read; INPUT is never modified."));
    g_option_context_set_description(context,
        _("Exit status: 0 on success, 1 on any error, 2 on a bad command "
          "line.\nOn error nothing is written."));
    g_option_context_add_main_entries(context, option_table, GETTEXT_PACKAGE);
    ok = option_parse_naming(context, argc, argv, error);
    g_option_context_free(context);
    g_free(help);
    g_free(kernel_help);
    return ok;
}

static const CompensationMode*
find_mode(const gchar *name, GError **error)
{
    guint i;

    if (!name)
        return compensation_modes;
    for (i = 0; i < G_N_ELEMENTS(compensation_modes); i++) {
        if (gwy_strequal(name, compensation_modes[i].name))
            return compensation_modes + i;
    }
    g_set_error(error, G_OPTION_ERROR, G_OPTION_ERROR_BAD_VALUE,
                _("unknown mode '%s' (known: paper, continuous)"), name);
    return NULL;
}

/* --search PX[,PY]: at least 1 and at most SEARCH_MAX px each. */
static gboolean
parse_search(const gchar *arg, GError **error)
{
    gchar **parts = g_strsplit(arg, ",", 0);
    gdouble values[2];
    gint n = g_strv_length(parts), i;
    gboolean ok = (n == 1 || n == 2);

    for (i = 0; ok && i < n; i++)
        ok = option_parse_number(parts[i], values + i) && values[i] >= 1.0 && values[i] <= SEARCH_MAX;
    g_strfreev(parts);
    if (!ok) {
        gchar *quoted = quoted_input_excerpt(arg, -1);

        g_set_error(error, G_OPTION_ERROR, G_OPTION_ERROR_BAD_VALUE,
                    _("--search takes PX or PX,PY, each from 1 to %d px, not '%s'"), SEARCH_MAX, quoted);
        g_free(quoted);
        return FALSE;
    }
    options.search_x = values[0];
    options.search_y = (n == 2) ? values[1] : values[0];
    return TRUE;
}

/* --stripes N: a whole number, space around it allowed (GLib's own
 * integer option refused "8 " in its own words); its range is checked
 * with the rest of the command line. */
static gboolean
parse_stripes(const gchar *arg, GError **error)
{
    gdouble v;

    if (!option_parse_number(arg, &v) || v != floor(v) || fabs(v) > G_MAXINT/2) {
        gchar *quoted = quoted_input_excerpt(arg, -1);

        g_set_error(error, G_OPTION_ERROR, G_OPTION_ERROR_BAD_VALUE,
                    _("--stripes must be a whole number from %d to %d, not '%s'"),
                    LOCALSCAN_STRIPES_MIN, LOCALSCAN_STRIPES_MAX, quoted);
        g_free(quoted);
        return FALSE;
    }
    options.stripes = (gint)v;
    return TRUE;
}

/* -c ID|TITLE: text that reads as an integer is an id (a negative one is
 * reported as a channel the file lacks); anything else is a title, looked
 * up once the file is read. */
static gboolean
parse_channel(const gchar *arg, GError **error)
{
    GError *err = NULL;
    gint64 id;

    if (!*arg) {
        g_set_error(error, G_OPTION_ERROR, G_OPTION_ERROR_BAD_VALUE,
                    _("-c is empty: give a channel's id or title"));
        return FALSE;
    }
    if (g_ascii_string_to_signed(arg, 10, G_MININT + 1, G_MAXINT, &id, &err))
        options.channel = (gint)id;
    else if (g_error_matches(err, G_NUMBER_PARSER_ERROR, G_NUMBER_PARSER_ERROR_OUT_OF_BOUNDS)) {
        gchar *quoted = quoted_input_excerpt(arg, -1);

        g_set_error(error, G_OPTION_ERROR, G_OPTION_ERROR_BAD_VALUE,
                    _("-c %s: no channel id lies that far from 0"), quoted);
        g_free(quoted);
        g_error_free(err);
        return FALSE;
    }
    g_clear_error(&err);
    return TRUE;
}

/* FILE:TITLE where the whole text names no file but FILE (or the INPUT,
 * for :TITLE) does: file names may hold colons, so the whole text is
 * tried as a file first. */
static void
split_reference_title(gchar **file, ReferenceSpec *spec)
{
    gchar *colon = strrchr(*file, ':');

    if (!colon || !colon[1] || g_file_test(*file, G_FILE_TEST_EXISTS))
        return;
    spec->title = g_strdup(colon + 1);
    *colon = '\0';
}

/* FILE[:ID|:TITLE] (channel-spec.h); an empty FILE is the INPUT. */
static gboolean
parse_reference(const gchar *arg, ReferenceSpec *spec, GError **error)
{
    GError *err = NULL;
    gchar *file;
    gint id;

    /* An empty name is a slip, not the INPUT (":ID" names a channel of
     * the INPUT). */
    if (!*arg) {
        g_set_error(error, G_OPTION_ERROR, G_OPTION_ERROR_BAD_VALUE,
                    _("--reference: the file name is empty"));
        return FALSE;
    }
    if (!channel_spec_parse(arg, &file, &id, &err)) {
        g_set_error(error, G_OPTION_ERROR, G_OPTION_ERROR_BAD_VALUE,
                    "--reference %s", err->message);
        g_error_free(err);
        return FALSE;
    }
    if (id == CHANNEL_SPEC_NO_ID)
        split_reference_title(&file, spec);
    spec->channel = (id == CHANNEL_SPEC_NO_ID ? CHANNEL_FIRST : id);
    spec->file = (*file ? file : NULL);
    if (!*file)
        g_free(file);
    return TRUE;
}

/* An output may be none of the files read, nor the other output: each is
 * written by renaming a finished temporary over it, so an input would be
 * replaced (and the tool promises never to modify one). */
static gboolean
check_outputs_distinct(GError **error)
{
    const gchar *outputs[2] = { options.output, options.write_drift };
    const gchar *output_options[2] = { "-o", "--write-drift" };
    const gchar *inputs[3] = { options.inputs[0], options.table_file, reference_spec.file };
    /* Whole sentences, so that translations can order them. */
    const gchar *refusals[3] = {
        N_("refusing to overwrite the input file %s (named by %s)"),
        N_("refusing to overwrite the drift table %s given with -d (named by %s)"),
        N_("refusing to overwrite the reference file %s (named by %s)"),
    };
    gboolean ok = TRUE;
    guint i, j;

    for (i = 0; ok && i < G_N_ELEMENTS(outputs); i++) {
        for (j = 0; ok && outputs[i] && j < G_N_ELEMENTS(inputs); j++) {
            if (inputs[j] && output_files_same(outputs[i], inputs[j])) {
                g_set_error(error, G_OPTION_ERROR, G_OPTION_ERROR_FAILED,
                            _(refusals[j]), inputs[j], output_options[i]);
                ok = FALSE;
            }
        }
    }
    if (ok && options.write_drift && output_files_same(options.output, options.write_drift)) {
        g_set_error(error, G_OPTION_ERROR, G_OPTION_ERROR_FAILED,
                    _("-o and --write-drift name the same file %s"), options.write_drift);
        ok = FALSE;
    }
    return ok;
}

static gboolean
parse_timing_options(GError **error)
{
    TimingFallback *tf = &timing_fallback;

    if (options.line_time_arg) {
        if (!series_options_parse_seconds("--line-time", options.line_time_arg,
                           LOCALSCAN_LINE_TIME_MIN, LOCALSCAN_LINE_TIME_MAX, &tf->line_time, error))
            return FALSE;
        tf->given |= LOCALSCAN_TIMING_LINE_TIME;
    }
    if (options.frame_start_arg) {
        if (!series_options_parse_seconds("--frame-start", options.frame_start_arg,
                           LOCALSCAN_FRAME_START_MIN, LOCALSCAN_FRAME_START_MAX,
                           &tf->frame_start, error))
            return FALSE;
        tf->given |= LOCALSCAN_TIMING_FRAME_START;
    }
    if (options.direction_name) {
        gint direction;

        if (!series_options_parse_direction(options.direction_name, &direction, error))
            return FALSE;
        tf->direction = direction;
        tf->given |= LOCALSCAN_TIMING_DIRECTION;
    }
    return TRUE;
}

static const CompensationMode*
check_command_line(GError **error)
{
    guint ninputs = options.inputs ? g_strv_length(options.inputs) : 0;

    if (!options.output) {
        g_set_error(error, G_OPTION_ERROR, G_OPTION_ERROR_FAILED,
                    _("no output file: give -o OUT.gwy"));
        return NULL;
    }
    if (ninputs != 1) {
        g_set_error(error, G_OPTION_ERROR, G_OPTION_ERROR_FAILED,
                    ninputs
                    ? _("exactly one INPUT file is needed, %u were given")
                    : _("no INPUT file given"), ninputs);
        return NULL;
    }
    if (!output_files_check_names_given((const gchar *const[]){ "-o", "-d", "--write-drift", "INPUT" },
                                        (const gchar *const[]){ options.output, options.table_file,
                                                                options.write_drift, options.inputs[0] },
                                        4, error))
        return NULL;
    if (options.reference && options.table_file) {
        g_set_error(error, G_OPTION_ERROR, G_OPTION_ERROR_FAILED,
                    _("-d and --reference both give the drift: use one of "
                      "them"));
        return NULL;
    }
    if (options.stripes_arg && !parse_stripes(options.stripes_arg, error))
        return NULL;
    if (options.stripes != STRIPES_UNSET && !options.reference) {
        g_set_error(error, G_OPTION_ERROR, G_OPTION_ERROR_FAILED,
                    _("--stripes needs --reference"));
        return NULL;
    }
    if (options.stripes != STRIPES_UNSET
        && (options.stripes < LOCALSCAN_STRIPES_MIN || options.stripes > LOCALSCAN_STRIPES_MAX)) {
        g_set_error(error, G_OPTION_ERROR, G_OPTION_ERROR_BAD_VALUE,
                    _("--stripes must be from %d to %d, not %d"),
                    LOCALSCAN_STRIPES_MIN, LOCALSCAN_STRIPES_MAX, options.stripes);
        return NULL;
    }
    if (options.channel_arg
        && (!option_value_to_utf8(&options.channel_arg, "-c", error) || !parse_channel(options.channel_arg, error)))
        return NULL;
    if (options.reference && !parse_reference(options.reference, &reference_spec, error))
        return NULL;
    if ((options.search_arg || options.accept_partial || options.masking_name) && !options.reference) {
        g_set_error(error, G_OPTION_ERROR, G_OPTION_ERROR_FAILED,
                    _("%s needs --reference"),
                    options.search_arg ? "--search" : options.accept_partial ? "--accept-partial" : "--masking");
        return NULL;
    }
    options.masking = LOCALSCAN_DEFAULT_MASKING;
    if (options.masking_name
        && (options.masking = run_description_masking_from_name(options.masking_name)) < 0) {
        g_set_error(error, G_OPTION_ERROR, G_OPTION_ERROR_BAD_VALUE,
                    _("--masking takes exclude, include or ignore, not \"%s\""), options.masking_name);
        return NULL;
    }
    if (options.search_arg && !parse_search(options.search_arg, error))
        return NULL;
    if (!parse_timing_options(error))
        return NULL;
    if (options.interpolation_name
        && (options.interpolation
            = run_description_interpolation_from_name(options.interpolation_name)) < 0) {
        gchar *names = run_description_interpolation_names();

        g_set_error(error, G_OPTION_ERROR, G_OPTION_ERROR_BAD_VALUE,
                    _("unknown interpolation '%s' (known: %s)"), options.interpolation_name, names);
        g_free(names);
        return NULL;
    }
    if (!check_outputs_distinct(error)
        || !output_files_check_kind(options.output, error)
        || !output_files_check_kind(options.write_drift, error))
        return NULL;
    return find_mode(options.mode_name, error);
}

/* A one-file movie may hold hundreds of channels: the list names this
 * many and counts the rest, so that the message stays one line. */
#define TITLED_CHANNELS_LISTED 20

/* "0 'ZSensor', 1 'Phase'": the channels a title may name. */
static gchar*
format_titled_channel_list(GwyContainer *data, const gint *ids)
{
    GString *str = g_string_new(NULL);
    const gchar *title;
    gchar *quoted;
    guint i, n;

    for (n = 0; ids[n] != -1; n++)
        ;
    for (i = 0; i < MIN(n, TITLED_CHANNELS_LISTED); i++) {
        title = localscan_channel_title(data, ids[i]);
        quoted = quoted_input_excerpt(title ? title : "", -1);
        g_string_append_printf(str, i ? ", %d '%s'" : "%d '%s'", ids[i], quoted);
        g_free(quoted);
    }
    if (n > TITLED_CHANNELS_LISTED)
        g_string_append_printf(str, _(" and %u more"), n - TITLED_CHANNELS_LISTED);
    return g_string_free(str, FALSE);
}

/* The one channel titled title exactly; -1 with error set when none or
 * several are (ids: the file's channels, for the message). */
static gint
pick_titled_channel(GwyContainer *data, const gchar *filename, const gint *ids,
                    const gchar *title, GError **error)
{
    gint *titled = localscan_channel_ids_titled(data, title), n, id = titled[0];
    gchar *list, *quoted = quoted_input_excerpt(title, -1);

    for (n = 0; titled[n] != -1; n++)
        ;
    if (!n) {
        list = format_titled_channel_list(data, ids);
        g_set_error(error, HEADLESS_RUN_ERROR, HEADLESS_RUN_ERROR_CHANNEL,
                    _("%s has no channel titled '%s' (its channels: %s)"),
                    filename, quoted, list);
        g_free(list);
    }
    else if (n > 1) {
        list = localscan_channel_id_list(titled);
        g_set_error(error, HEADLESS_RUN_ERROR, HEADLESS_RUN_ERROR_CHANNEL,
                    _("%s has %d channels titled '%s' (%s): give its id instead"),
                    filename, n, quoted, list);
        g_free(list);
        id = -1;
    }
    g_free(titled);
    g_free(quoted);
    return id;
}

/* The channel -c names (wanted, or title where it is not an id). */
static gint
pick_channel(GwyContainer *data, const gchar *filename, gint wanted,
             const gchar *title, GError **error)
{
    gint *ids = localscan_channel_ids(data);
    gchar *list;
    gint id = -1;

    if (ids[0] == -1) {
        g_set_error(error, HEADLESS_RUN_ERROR, HEADLESS_RUN_ERROR_CHANNEL,
                    _("%s contains no image channel"), filename);
    }
    else if (title)
        id = pick_titled_channel(data, filename, ids, title, error);
    else if (wanted == CHANNEL_FIRST)
        id = ids[0];
    else if (headless_run_has_channel(data, wanted))
        id = wanted;
    else {
        list = localscan_channel_id_list(ids);
        g_set_error(error, HEADLESS_RUN_ERROR, HEADLESS_RUN_ERROR_CHANNEL,
                    _("%s has no channel %d (its channels: %s)"),
                    filename, wanted, list);
        g_free(list);
    }
    g_free(ids);
    return id;
}

/* Messages read "in.gwy, channel 0 drift table:LINE: ...". */
static DriftTable*
load_stored_table(GwyContainer *data, const gchar *filename, gint id, GError **error)
{
    GError *err = NULL;
    DriftTable *table;

    if ((table = localscan_channel_stored_table_of_file(data, id, filename, &err)))
        return table;
    if (g_error_matches(err, LOCALSCAN_CHANNEL_ERROR, LOCALSCAN_CHANNEL_ERROR_NO_TABLE))
        g_set_error(error, err->domain, err->code,
                    _("%s; give one with -d TABLE.csv"), err->message);
    else
        g_propagate_error(error, g_error_copy(err));
    g_error_free(err);
    return NULL;
}

static gchar*
describe_channel(const gchar *filename, gint id)
{
    return g_strdup_printf(_("%s channel %d"), filename, id);
}

/* A registration the measured stripes cannot support is refused, unless
 * the user accepts it knowingly; then it is said on stderr. */
static gboolean
check_support(const StripeRegistrationSupport *support, const gchar *image_name, GError **error)
{
    gchar *why = stripe_registration_support_message(support);

    if (!why)
        return TRUE;
    if (!options.accept_partial) {
        g_set_error(error, STRIPE_REGISTRATION_ERROR, STRIPE_REGISTRATION_ERROR_NO_MATCH,
                    _("the registration of %s does not support a result: %s "
                      "(--accept-partial uses them anyway)"), image_name, why);
        g_free(why);
        return FALSE;
    }
    warn_later(g_strdup_printf(_("gwy-localscan: warning: the registration of %s does not support a "
                                 "result: %s\n"), image_name, why));
    g_free(why);
    return TRUE;
}

/* Registration's own messages name neither image nor reference; the one
 * a user meets most often gets both names. */
static DriftTable*
register_stripes(GwyDataField *image, GwyDataField *image_mask, const gchar *image_name,
                 GwyDataField *reference, GwyDataField *reference_mask, const gchar *reference_name,
                 gint n, const CompensationMode *mode, GError **error)
{
    StripeRegistrationOptions regopts;
    StripeRegistrationSupport support;
    GError *err = NULL;
    DriftTable *table;

    stripe_registration_options_init(&regopts);
    regopts.search_x = options.search_x;
    regopts.search_y = options.search_y;
    regopts.image_mask = image_mask;
    regopts.reference_mask = reference_mask;
    regopts.masking = options.masking;
    table = stripe_registration_table_for_fields(image, reference, n, &regopts,
                                                 mode->whole_pixels, &support, &err);
    if (table && !check_support(&support, image_name, error)) {
        drift_table_free(table);
        return NULL;
    }
    if (table)
        return table;
    if (g_error_matches(err, STRIPE_REGISTRATION_ERROR,
                        STRIPE_REGISTRATION_ERROR_NO_MATCH)) {
        g_set_error(error, STRIPE_REGISTRATION_ERROR,
                    STRIPE_REGISTRATION_ERROR_NO_MATCH,
                    _("no stripe of %s matched the reference %s"),
                    image_name, reference_name);
        g_error_free(err);
    }
    else
        g_propagate_error(error, err);
    return NULL;
}

/* The drift measured by registering the image's stripes against the
 * reference channel, which may live in the input file itself. */
static DriftTable*
measure_reference_table(GwyContainer *data, const gchar *filename, gint id,
                        const CompensationMode *mode, GError **error)
{
    const ReferenceSpec spec = reference_spec;
    GwyContainer *refdata;
    GwyDataField *image, *reference, *image_mask = NULL, *reference_mask = NULL;
    gchar *image_name, *reference_name = NULL;
    const gchar *reffile;
    DriftTable *table = NULL;
    gboolean same_file;
    gint refid;

    same_file = (!spec.file || output_files_same(spec.file, filename));
    reffile = spec.file ? spec.file : filename;
    refdata = (same_file ? g_object_ref(data)
               : headless_run_load(reffile, error));
    image_name = describe_channel(filename, id);
    if (!refdata)
        goto end;
    if ((refid = pick_channel(refdata, reffile, spec.channel, spec.title, error)) < 0)
        goto end;
    reference_name = describe_channel(reffile, refid);
    if (same_file && refid == id) {
        g_set_error(error, HEADLESS_RUN_ERROR, HEADLESS_RUN_ERROR_CHANNEL,
                    _("the reference %s is the image itself: name another "
                      "channel with --reference FILE:ID"), reference_name);
        goto end;
    }
    image = gwy_container_get_object(data, gwy_app_get_data_key_for_id(id));
    reference = gwy_container_get_object(refdata,
                                         gwy_app_get_data_key_for_id(refid));
    image_mask = localscan_channel_mask(data, id);
    reference_mask = localscan_channel_mask(refdata, refid);
    if (localscan_reference_check(image, image_name, reference, reference_name,
                                  options.stripes, error)) {
        table = register_stripes(image, image_mask, image_name, reference, reference_mask,
                                 reference_name, options.stripes, mode, error);
    }

end:
    if (refdata)
        g_object_unref(refdata);
    g_free(reference_name);
    g_free(image_name);
    return table;
}

/* Where the drift comes from: -d, --reference, else the table stored with
 * the channel. */
static DriftTable*
obtain_drift_table(GwyContainer *data, const gchar *filename, gint id,
                   const CompensationMode *mode, GError **error)
{
    if (options.table_file)
        return drift_table_load(options.table_file, error);
    if (options.reference)
        return measure_reference_table(data, filename, id, mode, error);
    return load_stored_table(data, filename, id, error);
}

/* The interpolation continuous mode will use: the user's, as in a pygwy
 * script. */
static GwyInterpolationType
settings_interpolation(void)
{
    gint32 interpolation = LOCALSCAN_DEFAULT_INTERPOLATION;

    if (options.interpolation >= 0)
        return options.interpolation;
    gwy_container_gis_int32_by_name(gwy_app_settings_get(), LOCALSCAN_SETTINGS_KEY(INTERPOLATION),
                                    &interpolation);
    return interpolation;
}

/* The options continuous compensation of channel id runs with: its
 * metadata's timing, the command line's where the metadata says nothing. */
static void
continuous_options(GwyContainer *data, gint id, LocalscanOptions *lo)
{
    const TimingFallback *tf = &timing_fallback;
    ScanTiming timing;

    localscan_channel_scan_timing_fallback(data, id, tf->line_time, tf->direction,
                                           tf->frame_start, &timing);
    lo->mode = LOCALSCAN_MODE_CONTINUOUS;
    lo->fill = LOCALSCAN_FILL_MEAN;
    lo->interpolation = settings_interpolation();
    lo->line_time = timing.line_time;
    lo->direction = timing.direction;
    lo->frame_start = timing.frame_start;
}

/* Continuous compensation checked here as the module will do it (planned,
 * not computed: the module computes it once), so that its refusals name
 * the table as the user named it (not the absolute path the module is
 * given); the few that do not name it get its name. */
static gboolean
check_continuous(GwyContainer *data, gint id, const DriftTable *table, GwyDataField *field,
                 GError **error)
{
    LocalscanOptions lo;
    GError *err = NULL;
    gboolean ok;

    continuous_options(data, id, &lo);
    ok = localscan_compensate_check(field, table, &lo, &err);
    if (ok)
        return TRUE;
    if (g_error_matches(err, CONTINUOUS_COMPENSATE_ERROR, CONTINUOUS_COMPENSATE_ERROR_TOO_FAST))
        g_set_error(error, err->domain, err->code, "%s: %s", table->source_name, err->message);
    else
        g_propagate_error(error, g_error_copy(err));
    g_error_free(err);
    return FALSE;
}

/* The same checks the module makes, so that every problem is reported here
 * with file and line instead of as a silent no-op of the module or its
 * message about a file name it was given. */
static gboolean
check_table_fits(GwyContainer *data, gint id, const DriftTable *table, GwyDataField *field,
                 const CompensationMode *mode, GError **error)
{
    gdouble *dx = g_new(gdouble, table->n_stripes);
    gdouble *dy = g_new(gdouble, table->n_stripes);
    gboolean ok;

    ok = localscan_table_to_field_pixels(table, field, mode->whole_pixels, dx, dy, error);
    g_free(dx);
    g_free(dy);
    if (ok && mode->value == LOCALSCAN_MODE_CONTINUOUS)
        ok = check_continuous(data, id, table, field, error);
    return ok;
}

/* A compensated channel without a mask is correct when no pixel was
 * filled, so only the channel itself is required.  table_file NULL: the
 * table stored with the channel. */
static gboolean
compensate_channel(GwyContainer *data, gint id, const gchar *table_file,
                   const CompensationMode *mode, GError **error)
{
    LocalscanBatchParams params;

    params.source = (table_file
                     ? LOCALSCAN_SOURCE_FILE : LOCALSCAN_SOURCE_STORED);
    params.table_file = table_file;
    params.mode = mode->value;
    params.line_time = timing_fallback.line_time;
    params.direction = timing_fallback.direction;
    params.frame_start = timing_fallback.frame_start;
    params.interpolation = options.interpolation;
    params.force = options.force;
    params.all_channels = options.all_channels;
    localscan_settings_apply(&params);
    return headless_run_process(data, id, LOCALSCAN_FUNCTION_NAME, error) >= 0;
}

/* A measured table reaches the module as a CSV file (the same path as -d),
 * so the new channel stores exactly the table used.  The file lives in a
 * private folder that is always removed. */
static gboolean
compensate_with_measured(GwyContainer *data, gint id, const DriftTable *table,
                         const CompensationMode *mode, GError **error)
{
    gchar *dir, *csv;
    gboolean ok;

    /* Both registered, so that a signal removes them too (safe-output.h). */
    if (!(dir = safe_output_temp_dir_new(PROGRAM_NAME))) {
        g_set_error(error, HEADLESS_RUN_ERROR, HEADLESS_RUN_ERROR_SAVE,
                    _("cannot make a temporary folder: %s"), g_strerror(errno));
        return FALSE;
    }
    csv = g_build_filename(dir, "measured-drift.csv", NULL);
    safe_output_register(csv);
    ok = (drift_table_save(table, csv, error)
          && compensate_channel(data, id, csv, mode, error));
    safe_output_discard(csv);
    g_rmdir(dir);
    safe_output_forget(dir);
    g_free(csv);
    g_free(dir);
    return ok;
}

/* OUT and the --write-drift table appear together or not at all, and an
 * older file at either name survives any failure. */
static gboolean
save_results(GwyContainer *data, const DriftTable *table, GError **error)
{
    OutputFiles *files = output_files_new();
    gchar *text;
    gboolean ok;
    gint *dropped, i;

    /* What INPUT stored as a channel's mask but is none goes no further
     * than it: OUT is a file Gwyddion opens. */
    dropped = localscan_channels_drop_misfit_masks(data);
    for (i = 0; dropped[i] >= 0; i++)
        warn_later(g_strdup_printf(_("gwy-localscan: warning: the mask of channel %d does not fit the "
                                     "channel and is left out of %s\n"), dropped[i], options.output));
    g_free(dropped);
    /* The channels copied from INPUT too hold no NaN (docs/missing-data.md). */
    localscan_channels_fill_missing(data);
    ok = headless_run_add_gwy(files, data, options.output, error);
    if (ok && options.write_drift) {
        text = drift_table_to_string(table);
        ok = headless_run_add_text(files, text, options.write_drift, error);
        g_free(text);
    }
    ok = ok && output_files_commit(files, error);
    output_files_free(files);
    return ok;
}

/* The result of an earlier run carries its drift table, so only the
 * marker stops the drift from being applied twice. */
static gboolean
check_not_compensated(GwyContainer *data, const gchar *filename, gint id, GError **error)
{
    gchar *name = describe_channel(filename, id);
    gboolean ok = compensation_marker_check(data, id, name, options.force,
                                            _("give --force to compensate it again"), error);

    g_free(name);
    return ok;
}

/* What the channel's metadata holds for the parts of its timing not
 * known, where it holds something unusable ("'Line time (s)' is 'nan'"),
 * joined; NULL when it holds nothing for them: such a value was reported
 * as absent. */
static gchar*
unusable_timing(GwyContainer *data, gint id, LocalscanTimingFound known)
{
    GwyContainer *meta = localscan_channel_meta(data, id, FALSE);
    gchar *line = (known & LOCALSCAN_TIMING_LINE_TIME) ? NULL
                  : scan_timing_meta_unusable(meta, SCAN_META_LINE_TIME);
    gchar *start = (known & LOCALSCAN_TIMING_FRAME_START) ? NULL
                   : scan_timing_meta_unusable(meta, SCAN_META_FRAME_START);
    gchar *joined;

    if (line && start)
        joined = g_strconcat(line, ", ", start, NULL);
    else
        joined = g_strdup(line ? line : start);
    g_free(line);
    g_free(start);
    return joined;
}

/* Local scans the line-by-line trajectory leaves out as gross errors are
 * named, with how far they lie from it: the result no longer follows
 * them, and the user should know which line of the table (or which
 * stripe of the registration) said what the others contradict. */
static void
warn_left_out(GwyContainer *data, gint id, const DriftTable *table, GwyDataField *field,
              const CompensationMode *mode)
{
    gint *stripes, n, i;
    LocalscanOptions lo;
    gdouble *off;

    if (mode->value != LOCALSCAN_MODE_CONTINUOUS)
        return;
    continuous_options(data, id, &lo);
    stripes = g_new(gint, MAX(table->n_stripes, 1));
    off = g_new(gdouble, MAX(table->n_stripes, 1));
    n = localscan_continuous_left_out(field, table, &lo, stripes, off, NULL);
    for (i = 0; i < n; i++) {
        if (table->source_name)
            warn_later(g_strdup_printf(_("%s: warning: %s:%d: stripe %d's drift lies %.1f px "
                                         "from what the other stripes give; continuous "
                                         "compensation leaves it out\n"),
                                       PROGRAM_NAME, table->source_name,
                                       table->rows[stripes[i]].line, stripes[i], off[i]));
        else
            warn_later(g_strdup_printf(_("%s: warning: the registration's stripe %d lies %.1f px "
                                         "from what the other stripes give; continuous "
                                         "compensation leaves it out\n"),
                                       PROGRAM_NAME, stripes[i], off[i]));
    }
    g_free(stripes);
    g_free(off);
}

/* Times in the table are compared with the scan's own: a timing neither the
 * file nor the command line gave is a guess the user should know of. */
static void
warn_assumed_timing(GwyContainer *data, const gchar *filename, gint id, const DriftTable *table,
                    const CompensationMode *mode)
{
    const TimingFallback *tf = &timing_fallback;
    LocalscanTimingFound known;
    GString *parts;
    ScanTiming timing;
    gchar *unusable;

    if (mode->value != LOCALSCAN_MODE_CONTINUOUS
        || (drift_table_find_column(table, "t_image") < 0
            && drift_table_find_column(table, "t_local") < 0))
        return;
    known = tf->given | localscan_channel_scan_timing_fallback(data, id, tf->line_time,
                                                               tf->direction, tf->frame_start,
                                                               &timing);
    if ((known & LOCALSCAN_TIMING_LINE_TIME) && (known & LOCALSCAN_TIMING_DIRECTION)
        && (known & LOCALSCAN_TIMING_FRAME_START))
        return;
    parts = g_string_new(NULL);
    if (!(known & LOCALSCAN_TIMING_LINE_TIME))
        g_string_append_printf(parts, _("line time %g s (--line-time)"), timing.line_time);
    if (!(known & LOCALSCAN_TIMING_DIRECTION)) {
        g_string_append(parts, parts->len ? ", " : "");
        g_string_append(parts, timing.direction == SCAN_DIRECTION_UP
                               ? _("slow scan up (--direction)")
                               : _("slow scan down (--direction)"));
    }
    if (!(known & LOCALSCAN_TIMING_FRAME_START)) {
        g_string_append(parts, parts->len ? ", " : "");
        g_string_append_printf(parts, _("frame start %g s (--frame-start)"), timing.frame_start);
    }
    unusable = unusable_timing(data, id, known);
    if (unusable)
        warn_later(g_strdup_printf(_("%s: warning: the table's t_image/t_local times are matched "
                                     "with an assumed %s: %s channel %d gives no usable value "
                                     "(%s)\n"),
                                   PROGRAM_NAME, parts->str, filename, id, unusable));
    else
        warn_later(g_strdup_printf(_("%s: warning: the table's t_image/t_local times are matched "
                                     "with an assumed %s: %s channel %d does not say\n"),
                                   PROGRAM_NAME, parts->str, filename, id));
    g_free(unusable);
    g_string_free(parts, TRUE);
}

static gboolean
run_batch(const CompensationMode *mode, GError **error)
{
    const gchar *input = options.inputs[0];
    GwyContainer *data;
    DriftTable *table = NULL;
    GwyDataField *field;
    gboolean ok = FALSE;
    gint id;

    if (!(data = headless_run_load(input, error)))
        return FALSE;
    if ((id = pick_channel(data, input, options.channel,
                           (options.channel_arg && options.channel == CHANNEL_FIRST)
                           ? options.channel_arg : NULL, error)) < 0)
        goto end;
    if (!check_not_compensated(data, input, id, error))
        goto end;
    if (!(table = obtain_drift_table(data, input, id, mode, error)))
        goto end;
    field = gwy_container_get_object(data, gwy_app_get_data_key_for_id(id));
    if (!check_table_fits(data, id, table, field, mode, error))
        goto end;
    warn_assumed_timing(data, input, id, table, mode);
    warn_left_out(data, id, table, field, mode);

    if (options.reference)
        ok = compensate_with_measured(data, id, table, mode, error);
    else
        ok = compensate_channel(data, id, options.table_file, mode, error);
    ok = ok && save_results(data, table, error);

end:
    if (table)
        drift_table_free(table);
    g_object_unref(data);
    return ok;
}

static gboolean
load_module(GError **error)
{
    const gchar *module_file = g_getenv("LOCALSCAN_MODULE");

    if (module_file && !*module_file)
        module_file = NULL;
    return (headless_run_init(module_file, error)
            && headless_run_require_function(LOCALSCAN_FUNCTION_NAME,
                                             GWY_LOCALSCAN_MODULE_DIR,
                                             error));
}

static void
bind_catalogue(void)
{
    const gchar *localedir = g_getenv("LOCALSCAN_LOCALEDIR");

    bindtextdomain(GETTEXT_PACKAGE,
                   localedir && *localedir ? localedir : LOCALEDIR);
    bind_textdomain_codeset(GETTEXT_PACKAGE, "UTF-8");
}

static void
init_i18n(void)
{
    setlocale(LC_ALL, "");
    bind_catalogue();
}

int
main(int argc, char *argv[])
{
    const CompensationMode *mode;
    GError *error = NULL;
    gint status = EXIT_OK;

    init_i18n();
    library_log_capture(PROGRAM_NAME, FALSE);
    if (argc > 1 && strcmp(argv[1], "series") == 0) {
        status = series_command_main(argc - 1, argv + 1);
        gwy_app_settings_free();
        return output_files_finish_stdout(PROGRAM_NAME " series", status);
    }
    if (!parse_options(&argc, &argv, &error)) {
        status = EXIT_USAGE;
        goto end;
    }
    library_log_capture(PROGRAM_NAME, options.verbose);
    if (options.show_version) {
        printf("%s %s\n", PROGRAM_NAME, PACKAGE_VERSION);
        goto end;
    }
    if (!(mode = check_command_line(&error))) {
        status = EXIT_USAGE;
        goto end;
    }
    if (options.stripes == STRIPES_UNSET)
        options.stripes = LOCALSCAN_STRIPES_DEFAULT;
    /* The module binds our domain to its installed catalogue when it
     * registers; LOCALSCAN_LOCALEDIR must stay in force after it. */
    if (load_module(&error))
        bind_catalogue();
    if (error || !run_batch(mode, &error))
        status = EXIT_ERROR;
    finish_warnings(status == EXIT_OK);
    /* A failure never goes unexplained, even when a library only logged
     * why (library-log.h). */
    if (status == EXIT_ERROR && !error)
        error = g_error_new(HEADLESS_RUN_ERROR, HEADLESS_RUN_ERROR_RUN, _("failed: %s"),
                            library_log_last() ? library_log_last()
                            : _("no reason given (try --verbose)"));
    gwy_app_settings_free();

end:
    if (error) {
        print_error(error->message);
        g_error_free(error);
    }
    free_options();
    return output_files_finish_stdout(PROGRAM_NAME, status);
}
