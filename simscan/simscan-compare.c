/*
 *  `simscan compare`: errors of a compensated simulator file.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <stdlib.h>
#include <stdio.h>
#include <string.h>
#include <math.h>
#include <libgwymodule/gwymodule-file.h>
#include <app/gwyapp.h>
#include "localscan-channel.h"
#include "localscan-params.h"
#include "compensation-marker.h"
#include "run-description.h"
#include "particle-detect.h"
#include "centre-error.h"
#include "simscan-output.h"
#include "simscan-sample-file.h"
#include "output-files.h"
#include "simscan-report.h"
#include "channel-png.h"
#include "simscan-compare.h"
#include "isolated-load.h"
#include "library-log.h"
#include "option-values.h"
#include "option-parse.h"
#include "simscan-i18n.h"

/* Particles this close to the border are left out, px. */
#define BORDER_MARGIN 4.0
/* Pictures are enlarged by whole pixels to at least this size. */
#define PICTURE_SIZE 512

typedef struct {
    gchar *before_png, *after_png, *truth_png;
    gchar **inputs;
} CompareOptions;

/* The lowest id whose title says it is compensated, or -1. */
static gint
find_compensated(GwyContainer *data)
{
    gint *ids = localscan_channel_ids(data);
    const gchar *title;
    gint i, found = -1;

    for (i = 0; ids[i] >= 0 && found < 0; i++) {
        if ((title = localscan_channel_title(data, ids[i]))
            && g_str_has_suffix(title, LOCALSCAN_TITLE_SUFFIX))
            found = ids[i];
    }
    g_free(ids);
    return found;
}

/* The mode the channel was compensated in: its compensation marker says,
 * else its log ("proc::" entries list the function's parameters, older
 * files by number); -1 when neither says. */
static gint
compensation_mode(GwyContainer *data, gint id)
{
    static const gchar call[] = "::" LOCALSCAN_FUNCTION_NAME "(";
    GwyStringList *log = NULL;
    const gchar *entry, *marker;
    gchar name[40];
    gint i, mode = -1;

    if ((marker = compensation_marker_get(data, id)))
        return run_description_parse_mode(marker);
    g_snprintf(name, sizeof(name), "/%d/data/log", id);
    if (!gwy_container_gis_object_by_name(data, name, &log)
        || !GWY_IS_STRING_LIST(log))
        return -1;
    /* The last compensation made the channel. */
    for (i = gwy_string_list_get_length(log) - 1; i >= 0 && mode < 0; i--) {
        entry = gwy_string_list_get(log, i);
        if (entry && strstr(entry, call))
            mode = run_description_parse_mode(strstr(entry, call) + strlen(call));
    }
    return mode;
}

/* The after picture's title: what the file says was done. */
static const gchar*
after_title(gint mode)
{
    if (mode == LOCALSCAN_MODE_PAPER)
        return _("After: compensated by local scans (paper mode)");
    if (mode == LOCALSCAN_MODE_CONTINUOUS)
        return _("After: compensated by local scans (continuous mode)");
    return _("After: compensated by local scans");
}

static const gchar*
mode_name(gint mode)
{
    if (mode == LOCALSCAN_MODE_PAPER)
        return _("paper mode");
    if (mode == LOCALSCAN_MODE_CONTINUOUS)
        return _("continuous mode");
    return _("mode not recorded");
}

/* The simulator's particle list: true and shown positions, px. */
static gint
read_particles(GwyContainer *data, gdouble **truth, gdouble **shown)
{
    const gchar *text = simscan_output_particles(data);
    gchar **lines;
    gint n = 0, i;

    if (!text)
        return 0;
    lines = g_strsplit(text, "\n", -1);
    *truth = g_new(gdouble, 2*g_strv_length(lines));
    *shown = g_new(gdouble, 2*g_strv_length(lines));
    for (i = 1; lines[i]; i++) {
        gchar **f = g_strsplit(lines[i], ",", -1);

        if (g_strv_length(f) == 4) {
            (*truth)[2*n] = g_ascii_strtod(f[0], NULL);
            (*truth)[2*n + 1] = g_ascii_strtod(f[1], NULL);
            (*shown)[2*n] = g_ascii_strtod(f[2], NULL);
            (*shown)[2*n + 1] = g_ascii_strtod(f[3], NULL);
            n++;
        }
        g_strfreev(f);
    }
    g_strfreev(lines);
    return n;
}

/* Half the closest distance between two particles: beyond it a match could
 * be the neighbour. */
static gdouble
match_radius(const gdouble *truth, gint n)
{
    gdouble best = G_MAXDOUBLE;
    gint i, k;

    for (i = 0; i < n; i++)
        for (k = i+1; k < n; k++)
            best = fmin(best, hypot(truth[2*i] - truth[2*k],
                                    truth[2*i+1] - truth[2*k+1]));
    return (best < G_MAXDOUBLE) ? 0.5*best : 4.0;
}

static void
measure(GwyDataField *field, const gdouble *search, const gdouble *truth,
        gint n, gdouble radius, CentreError *error)
{
    ParticleDetectParams params;
    GArray *found;

    particle_detect_params_init(&params);
    found = particle_detect(field, &params, NULL, NULL);
    centre_error_measure(found, search, truth, n,
                         gwy_data_field_get_xres(field),
                         gwy_data_field_get_yres(field),
                         BORDER_MARGIN, radius,
                         gwy_data_field_get_dx(field),
                         gwy_data_field_get_dy(field), error);
    g_array_free(found, TRUE);
}

/* One picture; the caption is its title line, then what all share. */
static gboolean
add_picture(OutputFiles *files, GwyDataField *field, ChannelPngStyle *style,
            const gchar *title, const gchar *what, const gchar *filename,
            GError **error)
{
    gchar *caption = g_strdup_printf("%s\n%s\n%s", title, what,
                                     style->caption);
    const gchar *shared = style->caption;
    GByteArray *png;
    gboolean ok;

    style->caption = caption;
    png = channel_png_render(field, style);
    style->caption = shared;
    g_free(caption);
    ok = output_files_add(files, filename, png->data, png->len, error);
    g_byte_array_unref(png);
    return ok;
}

/* Before, after and truth on one grey scale (the truth's, substrate to
 * highest particle), enlarged to PICTURE_SIZE, with rings where the
 * particles belong, so the drift and its removal can be seen.  All three
 * pictures are written or none. */
static gboolean
write_pngs(GwyContainer *data, gint comp_id, const CompareOptions *options,
           const gdouble *truth, gint n, GError **error)
{
    GwyDataField *before = localscan_channel_item(data, 0, "data");
    GwyDataField *after = localscan_channel_item(data, comp_id, "data");
    GwyDataField *drift_free = localscan_channel_item(data, 1, "data");
    gint res = MAX(gwy_data_field_get_xres(before),
                   gwy_data_field_get_yres(before));
    OutputFiles *files = output_files_new();
    ChannelPngStyle style;
    gchar *shared;
    gboolean ok;

    channel_png_style_init(&style, drift_free ? drift_free : before);
    style.scale = MAX(1, (PICTURE_SIZE + res - 1)/res);
    shared = g_strdup_printf(_("black %.1f nm to white %.1f nm in all three "
                               "pictures"),
                             1e9*style.low, 1e9*style.high);
    style.caption = shared;
    style.rings = truth;
    style.n_rings = n;
    ok = (!options->before_png
          || add_picture(files, before, &style,
                         _("Before: the drift-contaminated scan"),
                         _("red rings: where the particles truly are"),
                         options->before_png, error));
    style.mask = localscan_channel_item(data, comp_id, "mask");
    ok = ok && (!options->after_png
                || add_picture(files, after, &style,
                               after_title(compensation_mode(data, comp_id)),
                               _("red rings: true places; blue: filled "
                                 "pixels (no data)"),
                               options->after_png, error));
    style.mask = NULL;
    style.n_rings = 0;
    ok = ok && (!options->truth_png || !drift_free
                || add_picture(files, drift_free, &style,
                               _("Truth: the sample scanned without drift"),
                               _("(the local scans saw it shifted by the "
                                 "drift at their time)"),
                               options->truth_png, error));
    ok = ok && output_files_commit(files, error);
    output_files_free(files);
    if (options->before_png || options->after_png || options->truth_png)
        channel_png_release_fonts();
    g_free(shared);
    return ok;
}

static gboolean
compare_file(const gchar *filename, const CompareOptions *options,
             GError **error)
{
    GwyContainer *data;
    gdouble *truth = NULL, *shown = NULL, radius;
    CentreError before, after;
    gint n, comp_id;
    gboolean ok = FALSE;

    gwy_app_init_nongui("enable-threads", FALSE, NULL);
    library_log_capture(g_get_prgname(), library_log_verbose());
    /* Screened, then loaded in a child process (isolated-load.h). */
    if (!(data = isolated_load(filename, error)))
        return FALSE;
    comp_id = find_compensated(data);
    n = read_particles(data, &truth, &shown);
    if (comp_id < 0 || !localscan_channel_item(data, 0, "data"))
        g_set_error(error, G_FILE_ERROR, G_FILE_ERROR_INVAL,
                    _("%s has no channel titled ...%s"), filename,
                    LOCALSCAN_TITLE_SUFFIX);
    else if (!n)
        g_set_error(error, G_FILE_ERROR, G_FILE_ERROR_INVAL,
                    _("%s holds no simulated particle list (%s)"), filename,
                    SIMSCAN_META_PARTICLES);
    else
        ok = write_pngs(data, comp_id, options, truth, n, error);
    if (ok) {
        radius = match_radius(truth, n);
        measure(localscan_channel_item(data, 0, "data"), shown, truth, n,
                radius, &before);
        measure(localscan_channel_item(data, comp_id, "data"), truth, truth,
                n, radius, &after);
        printf(_("%s: particle centres against their true places (channel "
                 "%d, %s)\n"),
               filename, comp_id, mode_name(compensation_mode(data, comp_id)));
        simscan_report_centre_error(stdout, _("before"), &before);
        simscan_report_centre_error(stdout, _("after"), &after);
    }
    g_free(truth);
    g_free(shown);
    g_object_unref(data);
    return ok;
}

/* No picture may replace the input or another picture. */
static gboolean
check_files(const CompareOptions *options, GError **error)
{
    OutputFilesRole roles[] = {
        { _("input"), options->inputs[0], TRUE },
        { "--before-png", options->before_png, FALSE },
        { "--after-png", options->after_png, FALSE },
        { "--truth-png", options->truth_png, FALSE },
    };

    return output_files_check_roles(roles, G_N_ELEMENTS(roles), error);
}

int
simscan_compare_main(int argc, char **argv)
{
    CompareOptions options = { NULL, NULL, NULL, NULL };
    GOptionEntry entries[] = {
        { "before-png", 0, 0, G_OPTION_ARG_FILENAME, &options.before_png,
          N_("draw the contaminated channel"), "OUT.png" },
        { "after-png", 0, 0, G_OPTION_ARG_FILENAME, &options.after_png,
          N_("draw the compensated channel"), "OUT.png" },
        { "truth-png", 0, 0, G_OPTION_ARG_FILENAME, &options.truth_png,
          N_("draw the drift-free truth"), "OUT.png" },
        { G_OPTION_REMAINING, 0, 0, G_OPTION_ARG_FILENAME_ARRAY,
          &options.inputs, NULL, "FILE.gwy" },
        { NULL, 0, 0, 0, NULL, NULL, NULL },
    };
    GOptionContext *context;
    GError *error = NULL;
    gboolean ok;

    context = g_option_context_new(_("FILE.gwy - errors of a compensated "
                                     "simscan file"));
    g_option_context_set_translation_domain(context, GETTEXT_PACKAGE);
    g_option_context_add_main_entries(context, entries, GETTEXT_PACKAGE);
    ok = option_parse_naming(context, &argc, &argv, &error);
    if (ok && (!options.inputs || g_strv_length(options.inputs) != 1)) {
        g_set_error(&error, G_OPTION_ERROR, G_OPTION_ERROR_FAILED,
                    _("expected one input file"));
        ok = FALSE;
    }
    ok = ok && check_files(&options, &error);
    ok = ok && compare_file(options.inputs[0], &options, &error);
    if (!ok) {
        simscan_print_error("simscan compare", error);
        g_error_free(error);
    }
    g_option_context_free(context);
    g_strfreev(options.inputs);
    g_free(options.before_png);
    g_free(options.after_png);
    g_free(options.truth_png);
    return ok ? EXIT_SUCCESS : EXIT_FAILURE;
}
