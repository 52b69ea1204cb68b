/*
 *  `simscan benchmark` and `simscan score`: the command lines of the public
 *  drift benchmark (docs/benchmark.md).
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <stdio.h>
#include <string.h>
#include <math.h>
#include <json-glib/json-glib.h>
#include "json-values.h"
#include "output-files.h"
#include "option-values.h"
#include "option-parse.h"
#include "simscan-i18n.h"
#include "benchmark-write.h"
#include "benchmark-score.h"
#include "benchmark-plot.h"
#include "benchmark-command.h"

#define DEFAULT_SEED 1

static GQuark
benchmark_error_quark(void)
{
    return g_quark_from_static_string("simscan-benchmark-error");
}

/* $LOCALSCAN_MEASURED_DIR, else ../shared/data/measured. */
static const gchar*
default_measured_dir(void)
{
    const gchar *dir = g_getenv("LOCALSCAN_MEASURED_DIR");

    return (dir && *dir) ? dir : "../shared/data/measured";
}

static gboolean
parse_size(const gchar *text, BenchmarkSize *size, GError **error)
{
    if (!text || strcmp(text, "small") == 0)
        *size = BENCHMARK_SIZE_SMALL;
    else if (strcmp(text, "full") == 0)
        *size = BENCHMARK_SIZE_FULL;
    else {
        gchar *what = g_strdup_printf(_("'%.40s' is not small or full"), text);
        gboolean ok = option_value_refuse("size", what, error);

        g_free(what);
        return ok;
    }
    return TRUE;
}

int
simscan_benchmark_main(int argc, char **argv)
{
    gchar *output = NULL, *seed_text = NULL, *size_text = NULL;
    gchar *measured = NULL;
    GOptionEntry entries[] = {
        { "output", 'o', 0, G_OPTION_ARG_FILENAME, &output,
          N_("Write the cases into DIR (new or empty)"), N_("DIR") },
        { "seed", 0, 0, G_OPTION_ARG_STRING, &seed_text,
          N_("Seed of the draws (default 1): the same seed, the same bytes"),
          N_("S") },
        { "size", 0, 0, G_OPTION_ARG_STRING, &size_text,
          N_("small (default) or full"), N_("SIZE") },
        { "measured", 0, 0, G_OPTION_ARG_FILENAME, &measured,
          N_("Folder of the measured samples (default $LOCALSCAN_MEASURED_DIR "
             "or ../shared/data/measured)"), N_("DIR") },
        { NULL, 0, 0, 0, NULL, NULL, NULL },
    };
    GOptionContext *context;
    GError *error = NULL;
    BenchmarkSize size = BENCHMARK_SIZE_SMALL;
    gint seed = DEFAULT_SEED, status = 1;

    context = g_option_context_new(_("- write the drift benchmark's cases"));
    g_option_context_set_translation_domain(context, GETTEXT_PACKAGE);
    g_option_context_add_main_entries(context, entries, GETTEXT_PACKAGE);
    if (!option_parse_naming(context, &argc, &argv, &error))
        goto end;
    if (argc > 1) {
        g_set_error(&error, benchmark_error_quark(), 0,
                    _("unexpected argument '%s'"), argv[1]);
        goto end;
    }
    if (!output) {
        g_set_error(&error, benchmark_error_quark(), 0,
                    _("no output folder (-o DIR)"));
        goto end;
    }
    if (seed_text && !option_value_parse_int(seed_text, 0, G_MAXINT, "seed",
                                             &seed, &error))
        goto end;
    if (!parse_size(size_text, &size, &error))
        goto end;
    if (benchmark_write(output, (guint32)seed, size,
                        measured ? measured : default_measured_dir(), &error))
        status = 0;

end:
    if (error)
        simscan_print_error("simscan benchmark", error);
    g_clear_error(&error);
    g_option_context_free(context);
    g_free(output);
    g_free(seed_text);
    g_free(size_text);
    g_free(measured);
    return status;
}

/* A case's folder name: letters, digits, '-', '_' and '.', not starting
 * with '.', so a manifest from elsewhere names nothing outside DIR. */
static gboolean
plain_case_name(const gchar *name)
{
    const gchar *p;

    if (!name || !*name || *name == '.' || strlen(name) > 200)
        return FALSE;
    for (p = name; *p; p++) {
        if (!g_ascii_isalnum(*p) && !strchr("-_.", *p))
            return FALSE;
    }
    return TRUE;
}

static gboolean
json_string_member(JsonObject *o, const gchar *name)
{
    JsonNode *node = json_object_get_member(o, name);

    return node && json_node_get_value_type(node) == G_TYPE_STRING;
}

/* The case names benchmark.json lists, each a plain name; NULL when the
 * manifest is not one. */
static gchar**
manifest_case_names(JsonObject *o)
{
    JsonNode *node = json_object_get_member(o, "cases");
    JsonArray *a;
    gchar **names;
    guint i;

    if (!node || !JSON_NODE_HOLDS_ARRAY(node)
        || !json_string_member(o, "benchmark_version")
        || !json_string_member(o, "size")
        || !json_object_has_member(o, "seed")
        || json_node_get_value_type(json_object_get_member(o, "seed")) != G_TYPE_INT64)
        return NULL;
    a = json_node_get_array(node);
    names = g_new0(gchar*, json_array_get_length(a) + 1);
    for (i = 0; i < json_array_get_length(a); i++) {
        JsonNode *e = json_array_get_element(a, i);

        if (json_node_get_value_type(e) != G_TYPE_STRING
            || !plain_case_name(json_node_get_string(e))) {
            g_strfreev(names);
            return NULL;
        }
        names[i] = g_strdup(json_node_get_string(e));
    }
    return names;
}

/* The case names benchmark.json lists, and its header figures. */
static gchar**
read_manifest(const gchar *truth, gchar **summary, GError **error)
{
    gchar *path = g_build_filename(truth, "benchmark.json", NULL);
    JsonParser *parser = json_parser_new();
    JsonObject *o = NULL;
    JsonNode *root;
    gchar **names = NULL;

    if (json_parser_load_from_file(parser, path, error)) {
        root = json_parser_get_root(parser);
        if (root && JSON_NODE_HOLDS_OBJECT(root))
            o = json_node_get_object(root);
        if (o && (names = manifest_case_names(o)))
            *summary = g_strdup_printf("benchmark version %s, seed %" G_GINT64_FORMAT
                                       ", size %s",
                                       json_object_get_string_member(o, "benchmark_version"),
                                       json_object_get_int_member(o, "seed"),
                                       json_object_get_string_member(o, "size"));
        else
            g_set_error(error, benchmark_error_quark(), 0,
                        _("%s: not a benchmark manifest"), path);
    }
    g_object_unref(parser);
    g_free(path);
    return names;
}

/* Trajectory / frame residual; stripes that did not register against the
 * truth are named, so that wrecked frames cannot pass for good ones. */
static void
print_cell(const BenchmarkScore *s)
{
    gchar frame[48];

    if (s->failure) {
        printf(" failed |");
        return;
    }
    if (!s->stripes_judged)
        g_snprintf(frame, sizeof(frame), "—");
    else if (s->stripes_lost == s->stripes_judged)
        g_snprintf(frame, sizeof(frame), "none registered");
    else if (s->stripes_lost)
        g_snprintf(frame, sizeof(frame), "%.3f (%d/%d lost)", s->frame_rms_px,
                   s->stripes_lost, s->stripes_judged);
    else
        g_snprintf(frame, sizeof(frame), "%.3f", s->frame_rms_px);
    printf(" %.3f / %s |", s->trajectory_rms_px, frame);
}

static void
print_table(gchar **cases, gchar **methods, BenchmarkScore *scores)
{
    gint nm = g_strv_length(methods), i, j;

    printf("\nTrajectory RMS / corrected-frame residual, px (— where the method "
           "gives no corrected frames; stripes that do not register against "
           "the truth are counted as lost):\n\n| case |");
    for (j = 0; j < nm; j++)
        printf(" %s |", methods[j]);
    printf("\n|---|");
    for (j = 0; j < nm; j++)
        printf("---|");
    printf("\n");
    for (i = 0; cases[i]; i++) {
        printf("| %s |", cases[i]);
        for (j = 0; j < nm; j++)
            print_cell(scores + i*nm + j);
        printf("\n");
    }
}

/* What goes wrong beyond the figures: failures and flags. */
static void
print_notes(gchar **cases, gchar **methods, BenchmarkScore *scores)
{
    gint nm = g_strv_length(methods), i, j;
    const BenchmarkScore *s;

    printf("\n");
    for (i = 0; cases[i]; i++) {
        for (j = 0; j < nm; j++) {
            s = scores + i*nm + j;
            if (s->failure)
                printf("%s, %s: failed: %s\n", cases[i], methods[j],
                       s->failure);
            else if (s->flags_missed > 0 || s->flags_false > 0
                     || (s->disturbed && s->flags_missed == 0))
                printf("%s, %s: %d of %d disturbed frame(s) flagged, %d "
                       "trusted frame(s) flagged\n", cases[i], methods[j],
                       s->disturbed - s->flags_missed, s->disturbed,
                       s->flags_false);
            else if (s->disturbed && s->flags_missed < 0)
                printf("%s, %s: flags no frames (none given)\n", cases[i],
                       methods[j]);
        }
    }
}

static void
add_score(JsonBuilder *b, const gchar *name, const BenchmarkScore *s)
{
    json_builder_begin_object(b);
    json_builder_set_member_name(b, "case");
    json_builder_add_string_value(b, name);
    json_builder_set_member_name(b, "failure");
    if (s->failure)
        json_builder_add_string_value(b, s->failure);
    else
        json_builder_add_null_value(b);
    json_values_set_number(b, "trajectory_rms_px", s->trajectory_rms_px);
    json_values_set_number(b, "trajectory_worst_px", s->trajectory_worst_px);
    json_values_set_number(b, "frame_rms_px", s->frame_rms_px);
    json_values_set_number(b, "frame_worst_px", s->frame_worst_px);
    json_builder_set_member_name(b, "stripes_lost");
    json_builder_add_int_value(b, s->stripes_lost);
    json_builder_set_member_name(b, "stripes_judged");
    json_builder_add_int_value(b, s->stripes_judged);
    json_values_set_number(b, "flags_missed",
                           s->flags_missed >= 0 ? s->flags_missed : NAN);
    json_values_set_number(b, "flags_false",
                           s->flags_false >= 0 ? s->flags_false : NAN);
    json_builder_end_object(b);
}

static gchar*
scores_json(const gchar *summary, gchar **cases, gchar **methods,
            BenchmarkScore *scores)
{
    JsonBuilder *b = json_builder_new();
    gint nm = g_strv_length(methods), i, j;

    json_builder_begin_object(b);
    json_builder_set_member_name(b, "truth");
    json_builder_add_string_value(b, summary);
    json_builder_set_member_name(b, "methods");
    json_builder_begin_array(b);
    for (j = 0; j < nm; j++) {
        json_builder_begin_object(b);
        json_builder_set_member_name(b, "name");
        json_builder_add_string_value(b, methods[j]);
        json_builder_set_member_name(b, "cases");
        json_builder_begin_array(b);
        for (i = 0; cases[i]; i++)
            add_score(b, cases[i], scores + i*nm + j);
        json_builder_end_array(b);
        json_builder_end_object(b);
    }
    json_builder_end_array(b);
    json_builder_end_object(b);
    return json_values_finish(b);
}

static gboolean
score_all(const gchar *truth, gchar **results, gchar **cases,
          BenchmarkScore *scores, GError **error)
{
    gint nm = g_strv_length(results), i, j;
    gchar **rdirs = g_new0(gchar*, nm + 1), *tdir;
    gboolean ok = TRUE;

    for (i = 0; cases[i] && ok; i++) {
        tdir = g_build_filename(truth, cases[i], NULL);
        for (j = 0; j < nm; j++) {
            g_free(rdirs[j]);
            rdirs[j] = g_build_filename(results[j], cases[i], NULL);
        }
        ok = benchmark_score_case(tdir, rdirs, nm, scores + i*nm, error);
        g_free(tdir);
    }
    g_strfreev(rdirs);
    return ok;
}

/* The methods' names, their folders' names: each RESULT must be a folder,
 * and no two may share a name (their columns could not be told apart). */
static gchar**
method_names(gchar **results, GError **error)
{
    gint n = g_strv_length(results), j, i;
    gchar **names = g_new0(gchar*, n + 1);

    for (j = 0; j < n; j++) {
        names[j] = g_path_get_basename(results[j]);
        if (!g_file_test(results[j], G_FILE_TEST_IS_DIR)) {
            g_set_error(error, benchmark_error_quark(), 0,
                        _("%s: not a folder of results"), results[j]);
            break;
        }
        for (i = 0; i < j && strcmp(names[i], names[j]) != 0; i++)
            ;
        if (i < j) {
            g_set_error(error, benchmark_error_quark(), 0,
                        _("%s and %s: two methods named %s"), results[i],
                        results[j], names[j]);
            break;
        }
    }
    if (j < n) {
        g_strfreev(names);
        return NULL;
    }
    return names;
}

/* The JSON and the plot, both or neither. */
static gboolean
write_outputs(const gchar *json, const gchar *svg, const gchar *summary,
              gchar **cases, gchar **methods, BenchmarkScore *scores,
              GError **error)
{
    OutputFiles *files = output_files_new();
    gchar *text;
    gboolean ok = TRUE;

    if (json) {
        text = scores_json(summary, cases, methods, scores);
        ok = output_files_add(files, json, (const guchar*)text, strlen(text),
                              error);
        g_free(text);
    }
    if (ok && svg) {
        text = benchmark_plot_svg(cases, methods, scores);
        ok = output_files_add(files, svg, (const guchar*)text, strlen(text),
                              error);
        g_free(text);
    }
    ok = ok && output_files_commit(files, error);
    output_files_free(files);
    return ok;
}

/* The scores are never written into the folders read: --json
 * truth/benchmark.json replaced the manifest, the next score failed. */
static gboolean
check_outputs_outside(const gchar *json, const gchar *svg, const gchar *truth, gchar **results,
                      GError **error)
{
    const gchar *outputs[2] = { json, svg }, *roles[2] = { "--json", "--svg" };
    gint i, r;

    for (i = 0; i < 2; i++) {
        if (!output_files_check_outside(roles[i], outputs[i], truth, _("the truth folder"), error))
            return FALSE;
        for (r = 0; results && results[r]; r++) {
            if (!output_files_check_outside(roles[i], outputs[i], results[r], _("the result folder"),
                                            error))
                return FALSE;
        }
    }
    return TRUE;
}

int
simscan_score_main(int argc, char **argv)
{
    gchar *truth = NULL, *json = NULL, *svg = NULL, **results = NULL;
    gchar **cases = NULL;
    gchar **methods = NULL, *summary = NULL;
    GOptionEntry entries[] = {
        { "truth", 0, 0, G_OPTION_ARG_FILENAME, &truth,
          N_("The cases as `simscan benchmark` wrote them"), N_("DIR") },
        { "json", 0, 0, G_OPTION_ARG_FILENAME, &json,
          N_("Write the scores as JSON to FILE"), N_("FILE") },
        { "svg", 0, 0, G_OPTION_ARG_FILENAME, &svg,
          N_("Plot the trajectory RMS per case and method into FILE (SVG)"),
          N_("FILE") },
        { G_OPTION_REMAINING, 0, 0, G_OPTION_ARG_FILENAME_ARRAY, &results,
          NULL, N_("RESULT...") },
        { NULL, 0, 0, 0, NULL, NULL, NULL },
    };
    BenchmarkScore *scores = NULL;
    GOptionContext *context;
    GError *error = NULL;
    gint status = 1, n = 0, i;

    context = g_option_context_new(_("- score methods' results against the "
                                     "benchmark's truth"));
    g_option_context_set_translation_domain(context, GETTEXT_PACKAGE);
    g_option_context_add_main_entries(context, entries, GETTEXT_PACKAGE);
    if (!option_parse_naming(context, &argc, &argv, &error))
        goto end;
    if (!truth || !results || !results[0]) {
        g_set_error(&error, benchmark_error_quark(), 0,
                    _("give --truth DIR and at least one RESULT folder"));
        goto end;
    }
    if (!check_outputs_outside(json, svg, truth, results, &error))
        goto end;
    if (!(cases = read_manifest(truth, &summary, &error)))
        goto end;
    if (!(methods = method_names(results, &error)))
        goto end;
    n = g_strv_length(cases)*g_strv_length(results);
    scores = g_new0(BenchmarkScore, MAX(n, 1));
    if (!score_all(truth, results, cases, scores, &error)
        || !write_outputs(json, svg, summary, cases, methods, scores, &error))
        goto end;
    printf("%s: %u cases, %u methods\n", summary, g_strv_length(cases),
           g_strv_length(results));
    print_table(cases, methods, scores);
    print_notes(cases, methods, scores);
    status = 0;

end:
    if (error)
        simscan_print_error("simscan score", error);
    g_clear_error(&error);
    for (i = 0; i < n; i++)
        benchmark_score_clear(scores + i);
    g_free(scores);
    g_option_context_free(context);
    g_free(truth);
    g_free(json);
    g_free(svg);
    g_free(summary);
    g_strfreev(results);
    g_strfreev(cases);
    g_strfreev(methods);
    return status;
}
