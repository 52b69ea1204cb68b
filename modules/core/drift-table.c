/*
 *  The per-stripe drift table (docs/drift-table.md):
 *  reading, validation, physical-unit conversion and writing.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <errno.h>
#include <math.h>
#include <float.h>
#include <stdio.h>
#include <string.h>
#include <glib/gstdio.h>
#include "drift-table.h"
#include "quoted-input.h"
#include "stripe-geometry.h"
#include "localscan-intl.h"


/* Whole-pixel tolerance for px tables: values written by other tools may
 * carry a last-digit error, but a real fraction is a wrong table. */
#define WHOLE_PIXEL_TOLERANCE 1e-9
/* A unit's conversion is a product and a quotient: a few ulps off. */
#define HALF_PIXEL_ULPS 8

/* A table has a row per stripe and a stripe at least a row of the image:
 * 64 MiB hold a million rows of 64 bytes, more than any image has.  A
 * larger file is not read into memory. */
#define DRIFT_TABLE_MAX_BYTES (64 << 20)

#define DEFAULT_SOURCE_NAME N_("drift table")

static const struct {
    const gchar *name;
    DriftUnit unit;
    gdouble metres;
} units[] = {
    { "px", DRIFT_UNIT_PX, 0.0,  },
    { "m",  DRIFT_UNIT_M,  1.0,  },
    { "nm", DRIFT_UNIT_NM, 1e-9, },
    { "um", DRIFT_UNIT_UM, 1e-6, },
};

/* Lines of the text being parsed, and the table taking shape. */
typedef struct {
    const gchar *source_name;
    gchar **lines;
    gint n_lines;
    DriftTable *table;
    gint n_columns;
    GArray *rows;
    GPtrArray *extra_values;
} DriftTableParser;

GQuark
drift_table_error_quark(void)
{
    return g_quark_from_static_string("drift-table-error-quark");
}

const gchar*
drift_unit_name(DriftUnit unit)
{
    guint i;

    for (i = 0; i < G_N_ELEMENTS(units); i++) {
        if (units[i].unit == unit)
            return units[i].name;
    }
    g_return_val_if_reached(NULL);
}

/* Case-insensitive, and the micro sign is taken for u, because that is how
 * people and spreadsheets write micrometres. */
gboolean
drift_unit_from_name(const gchar *name, DriftUnit *unit)
{
    guint i;

    g_return_val_if_fail(name, FALSE);
    if (g_str_equal(name, "\xc2\xb5m") || g_str_equal(name, "\xce\xbcm")) {
        if (unit)
            *unit = DRIFT_UNIT_UM;
        return TRUE;
    }
    for (i = 0; i < G_N_ELEMENTS(units); i++) {
        if (g_ascii_strcasecmp(name, units[i].name) == 0) {
            if (unit)
                *unit = units[i].unit;
            return TRUE;
        }
    }
    return FALSE;
}

static gdouble
unit_metres(DriftUnit unit)
{
    guint i;

    for (i = 0; i < G_N_ELEMENTS(units); i++) {
        if (units[i].unit == unit)
            return units[i].metres;
    }
    g_return_val_if_reached(0.0);
}

static const gchar*
table_source_name(const DriftTable *table)
{
    return table->source_name ? table->source_name : _(DEFAULT_SOURCE_NAME);
}

static void G_GNUC_PRINTF(5, 6)
set_line_error(GError **error, gint code, const gchar *source_name, gint line,
               const gchar *format, ...)
{
    gchar *problem;
    va_list ap;

    va_start(ap, format);
    problem = g_strdup_vprintf(format, ap);
    va_end(ap);
    g_set_error(error, DRIFT_TABLE_ERROR, code, "%s:%d: %s",
                source_name, line, problem);
    g_free(problem);
}

/* The shortest of %.15g, %.16g, %.17g that reads back as the same double, so
 * written tables are both readable and exact. */
static gchar*
format_number(gchar *buf, gdouble value)
{
    static const gchar *formats[] = { "%.15g", "%.16g", "%.17g" };
    guint i;

    for (i = 0; i < G_N_ELEMENTS(formats); i++) {
        g_ascii_formatd(buf, G_ASCII_DTOSTR_BUF_SIZE, formats[i], value);
        if (g_ascii_strtod(buf, NULL) == value)
            break;
    }
    return buf;
}

/* Table construction and copying. */

static void
number_table_lines(DriftTable *table)
{
    gint i;

    table->header_line = (table->unit != DRIFT_UNIT_PX) ? 2 : 1;
    for (i = 0; i < table->n_stripes; i++)
        table->rows[i].line = table->header_line + 1 + i;
}

/* The rows get the line numbers they will have once written, so messages
 * about a table built in memory still point somewhere meaningful. */
DriftTable*
drift_table_new(gint n_stripes, DriftUnit unit)
{
    DriftTable *table;
    gint i;

    g_return_val_if_fail(n_stripes >= 0, NULL);
    g_return_val_if_fail(drift_unit_name(unit), NULL);

    table = g_new0(DriftTable, 1);
    table->unit = unit;
    table->n_stripes = n_stripes;
    table->rows = g_new0(DriftTableRow, MAX(n_stripes, 1));
    for (i = 0; i < n_stripes; i++)
        table->rows[i].stripe = i;
    table->extra_names = g_new0(gchar*, 1);
    table->extra_values = g_new0(gchar*, 1);
    number_table_lines(table);
    return table;
}

void
drift_table_free(DriftTable *table)
{
    gint i;

    if (!table)
        return;
    for (i = 0; i < table->n_extra; i++)
        g_free(table->extra_names[i]);
    for (i = 0; i < table->n_extra*table->n_stripes; i++)
        g_free(table->extra_values[i]);
    g_free(table->extra_names);
    g_free(table->extra_values);
    g_free(table->rows);
    g_free(table->source_name);
    g_free(table);
}

DriftTable*
drift_table_copy(const DriftTable *table)
{
    DriftTable *copy;
    gint i, n_values;

    g_return_val_if_fail(table, NULL);

    copy = g_new(DriftTable, 1);
    *copy = *table;
    copy->source_name = g_strdup(table->source_name);
    copy->rows = g_new0(DriftTableRow, MAX(table->n_stripes, 1));
    if (table->n_stripes)
        memcpy(copy->rows, table->rows,
               table->n_stripes*sizeof(DriftTableRow));
    copy->extra_names = g_new0(gchar*, table->n_extra + 1);
    for (i = 0; i < table->n_extra; i++)
        copy->extra_names[i] = g_strdup(table->extra_names[i]);
    n_values = table->n_extra*table->n_stripes;
    copy->extra_values = g_new0(gchar*, n_values + 1);
    for (i = 0; i < n_values; i++)
        copy->extra_values[i] = g_strdup(table->extra_values[i]);
    return copy;
}

/* Numbers. */

static gboolean
is_nan_or_infinity(const gchar *field)
{
    if (*field == '+' || *field == '-')
        field++;
    return (g_ascii_strcasecmp(field, "nan") == 0
            || g_ascii_strcasecmp(field, "inf") == 0
            || g_ascii_strcasecmp(field, "infinity") == 0);
}

/* g_ascii_strtod() alone also takes hex floats, "nan", "inf" and leading
 * blanks; the table format is plain decimal only, so characters are checked
 * first and the whole field must be consumed. */
static gboolean
parse_decimal(const gchar *field, gdouble *value)
{
    const gchar *p;
    gchar *end;
    gdouble v;

    errno = 0;
    if (!*field)
        return FALSE;
    for (p = field; *p; p++) {
        if (!g_ascii_isdigit(*p) && !strchr("+-.eE", *p))
            return FALSE;
    }
    v = g_ascii_strtod(field, &end);
    if (end == field || *end)
        return FALSE;
    if (!isfinite(v))
        return FALSE;
    *value = v;
    return TRUE;
}

/* A stripe index: optional sign, decimal digits only. */
static gboolean
parse_stripe(const gchar *field, gint *stripe)
{
    const gchar *p = field;
    gchar *end;
    gint64 v;

    if (*p == '+' || *p == '-')
        p++;
    if (!*p)
        return FALSE;
    for (; *p; p++) {
        if (!g_ascii_isdigit(*p))
            return FALSE;
    }
    errno = 0;
    v = g_ascii_strtoll(field, &end, 10);
    if (errno || *end || v < G_MININT || v > G_MAXINT)
        return FALSE;
    *stripe = (gint)v;
    return TRUE;
}

static gboolean
parse_drift_value(DriftTableParser *parser, gint line, const gchar *name,
                  const gchar *field, gdouble *value, GError **error)
{
    gchar *quoted;

    if (is_nan_or_infinity(field)) {
        set_line_error(error, DRIFT_TABLE_ERROR_VALUE, parser->source_name,
                       line, _("%s = %s: NaN or infinity is not a drift"),
                       name, field);
        return FALSE;
    }
    if (!parse_decimal(field, value)) {
        quoted = quoted_input_excerpt(field, -1);
        if (errno == ERANGE)
            set_line_error(error, DRIFT_TABLE_ERROR_VALUE,
                           parser->source_name, line,
                           _("%s = %s is out of range"), name, quoted);
        else
            set_line_error(error, DRIFT_TABLE_ERROR_SYNTAX,
                           parser->source_name, line,
                           _("bad number '%s' for %s"), quoted, name);
        g_free(quoted);
        return FALSE;
    }
    return TRUE;
}

/* Lines and fields. */

static gchar**
split_fields(const gchar *line, gint *n_fields)
{
    /* g_strsplit_set() walks the text once; g_strsplit() searches with
     * strstr() from each field, which sanitizers make quadratic. */
    gchar **fields = g_strsplit_set(line, ",", -1);
    gint i;

    for (i = 0; fields[i]; i++)
        g_strstrip(fields[i]);
    *n_fields = i;
    return fields;
}

/* Returns TRUE for a '# units: X' comment and puts the stripped X (owned by
 * the caller) to unit_text.  Other comments are not unit lines. */
static gboolean
is_units_comment(const gchar *line, gchar **unit_text)
{
    const gchar *p = line + 1;

    while (g_ascii_isspace(*p))
        p++;
    if (g_ascii_strncasecmp(p, "units", 5) != 0)
        return FALSE;
    p += 5;
    while (g_ascii_isspace(*p))
        p++;
    if (*p != ':')
        return FALSE;
    *unit_text = g_strstrip(g_strdup(p + 1));
    return TRUE;
}

static gboolean
parse_units_comment(DriftTableParser *parser, gint line, const gchar *text,
                    GError **error)
{
    DriftTable *table = parser->table;
    gchar *unit_text = NULL, *quoted;
    DriftUnit unit;

    if (!is_units_comment(text, &unit_text))
        return TRUE;
    if (table->header_line) {
        set_line_error(error, DRIFT_TABLE_ERROR_UNIT, parser->source_name,
                       line, _("the units line must come before the header"));
        g_free(unit_text);
        return FALSE;
    }
    if (!drift_unit_from_name(unit_text, &unit)) {
        quoted = quoted_input_excerpt(unit_text, -1);
        set_line_error(error, DRIFT_TABLE_ERROR_UNIT, parser->source_name,
                       line, _("unknown unit '%s' (known: px, m, nm, um)"),
                       quoted);
        g_free(quoted);
        g_free(unit_text);
        return FALSE;
    }
    g_free(unit_text);
    if (table->unit_given && unit != table->unit) {
        set_line_error(error, DRIFT_TABLE_ERROR_UNIT, parser->source_name,
                       line, _("a second units line contradicts the first"));
        return FALSE;
    }
    table->unit = unit;
    table->unit_given = TRUE;
    return TRUE;
}

static gboolean
parse_header(DriftTableParser *parser, gint line, const gchar *text,
             GError **error)
{
    DriftTable *table = parser->table;
    GHashTable *seen;
    gchar **fields, *quoted;
    gint n_fields, i;
    gboolean ok = TRUE;

    fields = split_fields(text, &n_fields);
    if (n_fields < 3
        || !g_str_equal(fields[0], "stripe")
        || !g_str_equal(fields[1], "dx")
        || !g_str_equal(fields[2], "dy")) {
        quoted = quoted_input_excerpt(text, -1);
        set_line_error(error, DRIFT_TABLE_ERROR_SYNTAX, parser->source_name,
                       line, _("missing header: expected a line starting "
                       "'stripe,dx,dy', got '%s'"), quoted);
        g_free(quoted);
        g_strfreev(fields);
        return FALSE;
    }
    /* A hash of the names seen keeps the check linear in the columns: a
     * header of a million columns is refused in moments. */
    seen = g_hash_table_new(g_str_hash, g_str_equal);
    for (i = 0; i < 3; i++)
        g_hash_table_add(seen, fields[i]);
    for (i = 3; ok && i < n_fields; i++) {
        if (!*fields[i]) {
            set_line_error(error, DRIFT_TABLE_ERROR_SYNTAX,
                           parser->source_name, line,
                           _("column %d of the header has no name"), i + 1);
            ok = FALSE;
        }
        else if (!g_hash_table_add(seen, fields[i])) {
            quoted = quoted_input_excerpt(fields[i], -1);
            set_line_error(error, DRIFT_TABLE_ERROR_SYNTAX,
                           parser->source_name, line,
                           _("column '%s' appears twice in the header"),
                           quoted);
            g_free(quoted);
            ok = FALSE;
        }
    }
    g_hash_table_destroy(seen);
    if (!ok) {
        g_strfreev(fields);
        return FALSE;
    }
    table->header_line = line;
    parser->n_columns = n_fields;
    table->n_extra = n_fields - 3;
    g_free(table->extra_names);
    table->extra_names = g_new0(gchar*, table->n_extra + 1);
    for (i = 0; i < table->n_extra; i++)
        table->extra_names[i] = g_strdup(fields[3 + i]);
    g_strfreev(fields);
    return TRUE;
}

/* Index of the first data line after line index from whose stripe field is
 * stripe, or -1; tells 'missing' from 'not ascending'. */
static gint
find_later_stripe(DriftTableParser *parser, gint from, gint stripe)
{
    gchar **fields, *text;
    gint i, n_fields, found;
    gboolean hit;

    for (i = from; i < parser->n_lines; i++) {
        text = g_strstrip(g_strdup(parser->lines[i]));
        hit = FALSE;
        if (*text && *text != '#') {
            fields = split_fields(text, &n_fields);
            hit = (parse_stripe(fields[0], &found) && found == stripe);
            g_strfreev(fields);
        }
        g_free(text);
        if (hit)
            return i;
    }
    return -1;
}

static gboolean
check_stripe_order(DriftTableParser *parser, gint index, gint stripe,
                   GError **error)
{
    const DriftTableRow *rows = (const DriftTableRow*)parser->rows->data;
    gint expected = parser->rows->len, later, line = index + 1;

    if (stripe == expected)
        return TRUE;
    if (stripe >= 0 && stripe < expected) {
        set_line_error(error, DRIFT_TABLE_ERROR_STRIPES, parser->source_name,
                       line, _("repeated stripe %d (first on line %d)"),
                       stripe, rows[stripe].line);
        return FALSE;
    }
    later = (stripe > expected
             ? find_later_stripe(parser, index + 1, expected) : -1);
    if (later >= 0) {
        set_line_error(error, DRIFT_TABLE_ERROR_STRIPES, parser->source_name,
                       line, _("stripes not ascending: stripe %d comes before "
                       "stripe %d (line %d)"), stripe, expected, later + 1);
        return FALSE;
    }
    set_line_error(error, DRIFT_TABLE_ERROR_STRIPES, parser->source_name,
                   line, _("missing stripe: expected stripe %d, got %d"),
                   expected, stripe);
    return FALSE;
}

static gboolean
parse_row(DriftTableParser *parser, gint index, const gchar *text,
          GError **error)
{
    DriftTableRow row;
    gchar **fields, *quoted;
    gint n_fields, i, line = index + 1;
    gboolean ok = FALSE;

    memset(&row, 0, sizeof(row));
    row.line = line;
    fields = split_fields(text, &n_fields);
    if (n_fields != parser->n_columns) {
        set_line_error(error, DRIFT_TABLE_ERROR_SYNTAX, parser->source_name,
                       line, _("expected %d fields, got %d"),
                       parser->n_columns, n_fields);
        goto end;
    }
    if (!parse_stripe(fields[0], &row.stripe)) {
        quoted = quoted_input_excerpt(fields[0], -1);
        set_line_error(error, DRIFT_TABLE_ERROR_SYNTAX, parser->source_name,
                       line, _("stripe '%s' is not an integer"), quoted);
        g_free(quoted);
        goto end;
    }
    if (!check_stripe_order(parser, index, row.stripe, error))
        goto end;
    if (!*fields[1] != !*fields[2]) {
        set_line_error(error, DRIFT_TABLE_ERROR_SYNTAX, parser->source_name,
                       line, _("%s is blank but %s is not; give both or neither"),
                       *fields[1] ? "dy" : "dx", *fields[1] ? "dx" : "dy");
        goto end;
    }
    if (*fields[1]) {
        if (!parse_drift_value(parser, line, "dx", fields[1], &row.dx, error)
            || !parse_drift_value(parser, line, "dy", fields[2], &row.dy,
                                  error))
            goto end;
        row.has_drift = TRUE;
    }
    g_array_append_val(parser->rows, row);
    for (i = 3; i < n_fields; i++)
        g_ptr_array_add(parser->extra_values, g_strdup(fields[i]));
    ok = TRUE;

end:
    g_strfreev(fields);
    return ok;
}

static gboolean
parse_line(DriftTableParser *parser, gint index, GError **error)
{
    gchar *text = parser->lines[index];

    g_strstrip(text);
    if (!*text)
        return TRUE;
    if (*text == '#')
        return parse_units_comment(parser, index + 1, text, error);
    if (!parser->table->header_line)
        return parse_header(parser, index + 1, text, error);
    return parse_row(parser, index, text, error);
}

static gboolean
finish_table(DriftTableParser *parser, GError **error)
{
    DriftTable *table = parser->table;
    gint i, n_values;

    if (!table->header_line || !parser->rows->len) {
        set_line_error(error, DRIFT_TABLE_ERROR_EMPTY, parser->source_name,
                       table->header_line ? table->header_line
                       : MAX(parser->n_lines, 1),
                       table->header_line ? _("empty table: no stripe rows")
                       : _("empty table: no header and no stripe rows"));
        return FALSE;
    }
    table->n_stripes = parser->rows->len;
    g_free(table->rows);
    table->rows = (DriftTableRow*)g_array_free(parser->rows, FALSE);
    parser->rows = NULL;
    n_values = table->n_extra*table->n_stripes;
    g_free(table->extra_values);
    table->extra_values = g_new0(gchar*, n_values + 1);
    for (i = 0; i < n_values; i++)
        table->extra_values[i] = g_ptr_array_index(parser->extra_values, i);
    /* The strings now belong to the table. */
    g_ptr_array_set_free_func(parser->extra_values, NULL);
    return TRUE;
}

/* A trailing newline does not start another line; a UTF-8 byte order mark
 * (spreadsheets write one) is not part of the first line. */
static gchar**
split_lines(const gchar *text, gssize length, gint *n_lines)
{
    gchar *copy, **lines;
    gint n;

    if (length < 0)
        length = strlen(text);
    if (length >= 3 && memcmp(text, "\xef\xbb\xbf", 3) == 0) {
        text += 3;
        length -= 3;
    }
    copy = g_strndup(text, length);
    lines = g_strsplit_set(copy, "\n", -1);
    g_free(copy);
    n = g_strv_length(lines);
    if (n && !*lines[n-1]) {
        g_free(lines[n-1]);
        lines[n-1] = NULL;
        n--;
    }
    *n_lines = n;
    return lines;
}

DriftTable*
drift_table_parse(const gchar *text, gssize length, const gchar *source_name,
                  GError **error)
{
    DriftTableParser parser;
    DriftTable *table;
    gboolean ok = TRUE;
    gint i;

    g_return_val_if_fail(text || !length, NULL);
    g_return_val_if_fail(!error || !*error, NULL);

    /* A NUL byte ends a C string: the rows after it were dropped unread
     * (a table of four stripes read as one, with exit status 0). */
    if (text && length > 0 && memchr(text, '\0', length)) {
        const gchar *nul = memchr(text, '\0', length), *p;
        gint line = 1;

        for (p = text; p < nul; p++)
            line += (*p == '\n');
        set_line_error(error, DRIFT_TABLE_ERROR_SYNTAX,
                       source_name ? source_name : _(DEFAULT_SOURCE_NAME), line,
                       _("a NUL byte: this is not a text table"));
        return NULL;
    }
    table = drift_table_new(0, DRIFT_UNIT_PX);
    table->source_name = g_strdup(source_name ? source_name
                                  : _(DEFAULT_SOURCE_NAME));
    table->header_line = 0;
    memset(&parser, 0, sizeof(parser));
    parser.source_name = table->source_name;
    parser.table = table;
    parser.lines = split_lines(text ? text : "", text ? length : 0,
                               &parser.n_lines);
    parser.rows = g_array_new(FALSE, TRUE, sizeof(DriftTableRow));
    parser.extra_values = g_ptr_array_new_with_free_func(g_free);

    for (i = 0; ok && i < parser.n_lines; i++)
        ok = parse_line(&parser, i, error);
    if (ok)
        ok = finish_table(&parser, error);

    if (parser.rows)
        g_array_free(parser.rows, TRUE);
    g_ptr_array_free(parser.extra_values, TRUE);
    g_strfreev(parser.lines);
    if (!ok) {
        drift_table_free(table);
        return NULL;
    }
    return table;
}

/* Read by hand rather than with g_file_get_contents() so the message carries
 * the plain system reason, in the table's own "FILE: problem" form. */
DriftTable*
drift_table_load(const gchar *filename, GError **error)
{
    GString *contents;
    DriftTable *table;
    GStatBuf st;
    gchar buf[65536];
    gsize n;
    FILE *fh;
    gint saved_errno = 0;

    g_return_val_if_fail(filename, NULL);
    g_return_val_if_fail(!error || !*error, NULL);

    /* A FIFO or a device would block or never end. */
    if (g_stat(filename, &st) == 0 && !S_ISREG(st.st_mode)) {
        g_set_error(error, DRIFT_TABLE_ERROR, DRIFT_TABLE_ERROR_IO, _("%s: cannot read: %s"),
                    filename, S_ISDIR(st.st_mode) ? g_strerror(EISDIR) : _("not a regular file"));
        return NULL;
    }
    if (!(fh = g_fopen(filename, "rb"))) {
        saved_errno = errno;
        g_set_error(error, DRIFT_TABLE_ERROR, DRIFT_TABLE_ERROR_IO,
                    _("%s: cannot read: %s"), filename, g_strerror(saved_errno));
        return NULL;
    }
    contents = g_string_new(NULL);
    while ((n = fread(buf, 1, sizeof(buf), fh)) > 0
           && contents->len <= DRIFT_TABLE_MAX_BYTES)
        g_string_append_len(contents, buf, n);
    if (contents->len > DRIFT_TABLE_MAX_BYTES) {
        fclose(fh);
        g_set_error(error, DRIFT_TABLE_ERROR, DRIFT_TABLE_ERROR_IO,
                    _("%s: larger than %d MiB: not a drift table"),
                    filename, DRIFT_TABLE_MAX_BYTES >> 20);
        g_string_free(contents, TRUE);
        return NULL;
    }
    if (ferror(fh))
        saved_errno = errno ? errno : EIO;
    fclose(fh);
    if (saved_errno) {
        g_set_error(error, DRIFT_TABLE_ERROR, DRIFT_TABLE_ERROR_IO,
                    _("%s: cannot read: %s"), filename, g_strerror(saved_errno));
        g_string_free(contents, TRUE);
        return NULL;
    }
    table = drift_table_parse(contents->str, contents->len, filename, error);
    g_string_free(contents, TRUE);
    return table;
}

/* Writing. */

gchar*
drift_table_to_string(const DriftTable *table)
{
    gchar bufx[G_ASCII_DTOSTR_BUF_SIZE], bufy[G_ASCII_DTOSTR_BUF_SIZE];
    const DriftTableRow *row;
    GString *str;
    gint i, j;

    g_return_val_if_fail(table, NULL);

    str = g_string_new(NULL);
    if (table->unit != DRIFT_UNIT_PX || table->unit_given)
        g_string_append_printf(str, "# units: %s\n",
                               drift_unit_name(table->unit));
    g_string_append(str, "stripe,dx,dy");
    for (j = 0; j < table->n_extra; j++)
        g_string_append_printf(str, ",%s", table->extra_names[j]);
    g_string_append_c(str, '\n');
    for (i = 0; i < table->n_stripes; i++) {
        row = table->rows + i;
        if (row->has_drift)
            g_string_append_printf(str, "%d,%s,%s", row->stripe,
                                   format_number(bufx, row->dx),
                                   format_number(bufy, row->dy));
        else
            g_string_append_printf(str, "%d,,", row->stripe);
        for (j = 0; j < table->n_extra; j++)
            g_string_append_printf(str, ",%s",
                                   table->extra_values[i*table->n_extra + j]);
        g_string_append_c(str, '\n');
    }
    return g_string_free(str, FALSE);
}

/* g_file_set_contents() writes a temporary file beside the target and
 * renames it over, removing the temporary on failure: no half-written table
 * is ever visible. */
gboolean
drift_table_save(const DriftTable *table, const gchar *filename,
                 GError **error)
{
    GError *err = NULL;
    gchar *text;
    gboolean ok;

    g_return_val_if_fail(table && filename, FALSE);
    g_return_val_if_fail(!error || !*error, FALSE);

    text = drift_table_to_string(table);
    ok = g_file_set_contents(filename, text, -1, &err);
    g_free(text);
    if (!ok) {
        g_set_error(error, DRIFT_TABLE_ERROR, DRIFT_TABLE_ERROR_IO,
                    _("%s: cannot write: %s"), filename, err->message);
        g_clear_error(&err);
    }
    return ok;
}

void
drift_table_set_drift(DriftTable *table, gint stripe, gdouble dx, gdouble dy)
{
    DriftTableRow *row;

    g_return_if_fail(table);
    g_return_if_fail(stripe >= 0 && stripe < table->n_stripes);
    g_return_if_fail(!isinf(dx) && !isinf(dy));

    row = table->rows + stripe;
    row->has_drift = !isnan(dx) && !isnan(dy);
    row->dx = row->has_drift ? dx : 0.0;
    row->dy = row->has_drift ? dy : 0.0;
}

/* Extra columns. */

gint
drift_table_find_column(const DriftTable *table, const gchar *name)
{
    gint j;

    g_return_val_if_fail(table && name, -1);
    for (j = 0; j < table->n_extra; j++) {
        if (g_str_equal(table->extra_names[j], name))
            return j;
    }
    return -1;
}

gboolean
drift_table_get_extra(const DriftTable *table, gint stripe, const gchar *name,
                      gdouble *value)
{
    const gchar *text;
    gdouble v;
    gint j;

    g_return_val_if_fail(table && name, FALSE);
    g_return_val_if_fail(stripe >= 0 && stripe < table->n_stripes, FALSE);

    if ((j = drift_table_find_column(table, name)) < 0)
        return FALSE;
    text = table->extra_values[stripe*table->n_extra + j];
    if (!parse_decimal(text, &v))
        return FALSE;
    if (value)
        *value = v;
    return TRUE;
}

static gint
add_extra_column(DriftTable *table, const gchar *name)
{
    gint n_old = table->n_extra, n_new = n_old + 1, i, j;
    gchar **values;

    values = g_new0(gchar*, n_new*table->n_stripes + 1);
    for (i = 0; i < table->n_stripes; i++) {
        for (j = 0; j < n_old; j++)
            values[i*n_new + j] = table->extra_values[i*n_old + j];
        values[i*n_new + n_old] = g_strdup("");
    }
    g_free(table->extra_values);
    table->extra_values = values;
    table->extra_names = g_renew(gchar*, table->extra_names, n_new + 1);
    table->extra_names[n_old] = g_strdup(name);
    table->extra_names[n_new] = NULL;
    table->n_extra = n_new;
    return n_old;
}

void
drift_table_set_extra(DriftTable *table, gint stripe, const gchar *name,
                      gdouble value)
{
    gchar buf[G_ASCII_DTOSTR_BUF_SIZE];
    gchar **slot;
    gint j;

    g_return_if_fail(table && name && *name);
    g_return_if_fail(!strpbrk(name, ",\r\n") && name[0] != '#');
    g_return_if_fail(stripe >= 0 && stripe < table->n_stripes);
    g_return_if_fail(!isinf(value));

    if ((j = drift_table_find_column(table, name)) < 0) {
        g_return_if_fail(!g_str_equal(name, "stripe")
                         && !g_str_equal(name, "dx")
                         && !g_str_equal(name, "dy"));
        j = add_extra_column(table, name);
    }
    slot = table->extra_values + stripe*table->n_extra + j;
    g_free(*slot);
    *slot = g_strdup(isnan(value) ? "" : format_number(buf, value));
}

/* Checks against the image and conversion to pixels. */

gboolean
drift_table_check_image(const DriftTable *table, gint yres, GError **error)
{
    const gchar *source_name;
    gint i;

    g_return_val_if_fail(table, FALSE);
    g_return_val_if_fail(!error || !*error, FALSE);

    source_name = table_source_name(table);
    if (!table->n_stripes) {
        set_line_error(error, DRIFT_TABLE_ERROR_EMPTY, source_name,
                       table->header_line, _("empty table: no stripe rows"));
        return FALSE;
    }
    if (table->n_stripes > yres) {
        set_line_error(error, DRIFT_TABLE_ERROR_IMAGE, source_name,
                       table->rows[table->n_stripes-1].line,
                       _("the table has %d stripes but the image has only "
                       "%d rows"), table->n_stripes, yres);
        return FALSE;
    }
    for (i = 0; i < table->n_stripes; i++) {
        if (table->rows[i].has_drift)
            return TRUE;
    }
    set_line_error(error, DRIFT_TABLE_ERROR_EMPTY, source_name,
                   table->header_line,
                   _("no stripe has a drift (every dx,dy is blank)"));
    return FALSE;
}

gdouble
drift_px_round(gdouble v)
{
    return round(v) + 0.0;
}

/* Physical values are rounded to the nearest pixel for whole_pixels: a
 * measured length is never an exact multiple of the pixel size, so insisting
 * on whole numbers would refuse every real table.  A px table, however, says
 * pixels outright, and a fraction there means the table is not what paper
 * mode needs. */
static gboolean
convert_value(const DriftTable *table, const DriftTableRow *row,
              const gchar *name, gdouble value, gdouble pixel_size,
              gboolean whole_pixels, gdouble *px, GError **error)
{
    gchar buf[G_ASCII_DTOSTR_BUF_SIZE];
    const gchar *unit = drift_unit_name(table->unit);
    gdouble v = value;

    if (table->unit != DRIFT_UNIT_PX) {
        gdouble half;

        v = value*unit_metres(table->unit)/pixel_size;
        /* A half pixel given in a unit comes out of the conversion an ulp
         * or two off (2.5 px as 0.09765625 um on pixels of 0.0390625 um:
         * 2.4999999999999996), and rounding half away from zero then
         * went either way by the unit: it is the half it stands for. */
        half = round(2.0*v)/2.0;
        if (fabs(v - half) <= HALF_PIXEL_ULPS*DBL_EPSILON*MAX(1.0, fabs(v)))
            v = half;
    }
    if (!(fabs(v) <= DRIFT_TABLE_MAX_PIXELS)) {
        set_line_error(error, DRIFT_TABLE_ERROR_VALUE,
                       table_source_name(table), row->line,
                       _("%s = %s %s is more than %g pixels"), name,
                       format_number(buf, value), unit, DRIFT_TABLE_MAX_PIXELS);
        return FALSE;
    }
    if (whole_pixels) {
        if (table->unit == DRIFT_UNIT_PX
            && fabs(v - round(v)) > WHOLE_PIXEL_TOLERANCE) {
            set_line_error(error, DRIFT_TABLE_ERROR_VALUE,
                           table_source_name(table), row->line,
                           _("%s = %s px is not a whole number of pixels; "
                           "paper mode needs whole pixels"),
                           name, format_number(buf, value));
            return FALSE;
        }
        v = drift_px_round(v);
    }
    /* Adding +0.0 turns a -0 into 0, so callers never see a negative zero. */
    *px = v + 0.0;
    return TRUE;
}

gboolean
drift_table_to_pixels(const DriftTable *table, gint yres,
                      gdouble x_pixel_size, gdouble y_pixel_size,
                      gboolean whole_pixels, gdouble *dx_px, gdouble *dy_px,
                      GError **error)
{
    const DriftTableRow *row;
    gboolean *has_drift;
    gboolean ok = TRUE;
    gint i;

    g_return_val_if_fail(table && dx_px && dy_px, FALSE);
    g_return_val_if_fail(!error || !*error, FALSE);
    g_return_val_if_fail(table->unit == DRIFT_UNIT_PX
                         || (x_pixel_size > 0.0 && isfinite(x_pixel_size)
                             && y_pixel_size > 0.0
                             && isfinite(y_pixel_size)), FALSE);

    if (!drift_table_check_image(table, yres, error))
        return FALSE;

    has_drift = g_new(gboolean, table->n_stripes);
    for (i = 0; ok && i < table->n_stripes; i++) {
        row = table->rows + i;
        has_drift[i] = row->has_drift;
        dx_px[i] = dy_px[i] = 0.0;
        if (!row->has_drift)
            continue;
        ok = (convert_value(table, row, "dx", row->dx, x_pixel_size,
                            whole_pixels, dx_px + i, error)
              && convert_value(table, row, "dy", row->dy, y_pixel_size,
                               whole_pixels, dy_px + i, error));
    }
    if (ok)
        stripe_drift_fill_missing(table->n_stripes, has_drift, dx_px, dy_px);
    g_free(has_drift);
    return ok;
}
