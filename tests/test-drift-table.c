/*
 *  Tests of the drift table CSV reader and writer (docs/drift-table.md).
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <sys/stat.h>
#include <check.h>
#include <glib.h>
#include <glib/gstdio.h>
#include "drift-table.h"
#include "test-common.h"

static DriftTable*
parse_ok(const gchar *text)
{
    GError *error = NULL;
    DriftTable *table = drift_table_parse(text, -1, "t.csv", &error);

    ck_assert_msg(table, "refused: %s\ntext:\n%s",
                  error ? error->message : "(no error)", text);
    ck_assert(!error);
    return table;
}

static void
assert_parse_error(const gchar *text, gint code, const gchar *message)
{
    GError *error = NULL;
    DriftTable *table = drift_table_parse(text, -1, "t.csv", &error);

    ck_assert_msg(!table, "accepted:\n%s", text);
    ck_assert(error);
    ck_assert_str_eq(error->message, message);
    ck_assert_msg(g_error_matches(error, DRIFT_TABLE_ERROR, code),
                  "error code %d, expected %d for %s",
                  error->code, code, message);
    g_clear_error(&error);
}

static void
assert_pixels_error(const gchar *text, gint yres, gboolean whole_pixels,
                    gint code, const gchar *message)
{
    GError *error = NULL;
    DriftTable *table = parse_ok(text);
    gdouble dx[64], dy[64];

    ck_assert(!drift_table_to_pixels(table, yres, 1e-9, 1e-9, whole_pixels,
                                     dx, dy, &error));
    ck_assert(error);
    ck_assert_str_eq(error->message, message);
    ck_assert_int_eq(error->code, code);
    g_clear_error(&error);
    drift_table_free(table);
}

/* Bitwise on numbers, so that -0 and 0 count as different. */
static void
assert_same_table(const DriftTable *a, const DriftTable *b)
{
    gint i, j;

    ck_assert_int_eq(a->unit, b->unit);
    ck_assert_int_eq(a->unit_given, b->unit_given);
    ck_assert_int_eq(a->n_stripes, b->n_stripes);
    ck_assert_int_eq(a->n_extra, b->n_extra);
    for (i = 0; i < a->n_stripes; i++) {
        ck_assert_int_eq(a->rows[i].stripe, b->rows[i].stripe);
        ck_assert_int_eq(a->rows[i].has_drift, b->rows[i].has_drift);
        ck_assert(memcmp(&a->rows[i].dx, &b->rows[i].dx, sizeof(gdouble)) == 0);
        ck_assert(memcmp(&a->rows[i].dy, &b->rows[i].dy, sizeof(gdouble)) == 0);
    }
    for (j = 0; j < a->n_extra; j++)
        ck_assert_str_eq(a->extra_names[j], b->extra_names[j]);
    for (i = 0; i < a->n_stripes*a->n_extra; i++)
        ck_assert_str_eq(a->extra_values[i], b->extra_values[i]);
}

/* Round trips. */

START_TEST(test_round_trip_text)
{
    static const gchar *texts[] = {
        "stripe,dx,dy\n0,-1,0\n1,-2,0\n2,,\n3,-4,-1\n",
        "# units: nm\nstripe,dx,dy,t_image,t_local,label\n"
        "0,1.5,-2.25,0.125,,a\n1,,,1.5,2,\n2,0.1,1e-09,,,x y\n",
        "# units: px\nstripe,dx,dy\n0,-0,0\n",
        "# units: um\nstripe,dx,dy,score\n0,0.30000000000000004,1e+300,0.5\n",
    };
    DriftTable *table, *again;
    gchar *text, *text2;
    guint k;

    for (k = 0; k < G_N_ELEMENTS(texts); k++) {
        table = parse_ok(texts[k]);
        text = drift_table_to_string(table);
        ck_assert_str_eq(text, texts[k]);
        again = parse_ok(text);
        assert_same_table(table, again);
        for (gint i = 0; i < table->n_stripes; i++)
            ck_assert_int_eq(table->rows[i].line, again->rows[i].line);
        text2 = drift_table_to_string(again);
        ck_assert_str_eq(text2, text);
        g_free(text);
        g_free(text2);
        drift_table_free(table);
        drift_table_free(again);
    }
}
END_TEST

START_TEST(test_round_trip_built)
{
    static const gchar expected[] =
        "# units: nm\n"
        "stripe,dx,dy,t_image,dx_exact\n"
        "0,0.1,-0.30000000000000004,12.5,0.123456789012345\n"
        "1,,,,\n"
        "2,1e-300,-7,,\n";
    DriftTable *table = drift_table_new(3, DRIFT_UNIT_NM), *back, *copy;
    gchar *text, *text2;
    gdouble v;

    drift_table_set_drift(table, 0, 0.1, -(0.1 + 0.2));
    drift_table_set_drift(table, 1, 4.0, NAN);
    drift_table_set_drift(table, 2, 1e-300, -7.0);
    ck_assert(!table->rows[1].has_drift && table->rows[1].dx == 0.0);
    drift_table_set_extra(table, 0, "t_image", 12.5);
    drift_table_set_extra(table, 0, "dx_exact", 0.123456789012345);
    drift_table_set_extra(table, 2, "t_image", NAN);
    text = drift_table_to_string(table);
    ck_assert_str_eq(text, expected);

    back = parse_ok(text);
    ck_assert(back->unit_given);
    back->unit_given = FALSE;
    assert_same_table(table, back);
    back->unit_given = TRUE;
    text2 = drift_table_to_string(back);
    ck_assert_str_eq(text2, expected);

    ck_assert(drift_table_get_extra(back, 0, "t_image", &v) && v == 12.5);
    ck_assert(!drift_table_get_extra(back, 1, "t_image", &v));
    ck_assert(!drift_table_get_extra(back, 2, "t_image", &v));
    ck_assert(!drift_table_get_extra(back, 0, "no_such", &v));
    ck_assert_int_eq(drift_table_find_column(back, "dx_exact"), 1);
    ck_assert_int_eq(drift_table_find_column(back, "dx"), -1);

    copy = drift_table_copy(back);
    assert_same_table(copy, back);
    drift_table_set_extra(copy, 1, "t_image", -3.0);
    ck_assert(drift_table_get_extra(copy, 1, "t_image", &v) && v == -3.0);
    ck_assert(!drift_table_get_extra(back, 1, "t_image", &v));

    g_free(text);
    g_free(text2);
    drift_table_free(table);
    drift_table_free(back);
    drift_table_free(copy);
}
END_TEST

/* An in-memory px table writes no units line; one read with a units line
 * keeps it. */
START_TEST(test_units_line_written)
{
    DriftTable *table = drift_table_new(1, DRIFT_UNIT_PX);
    gchar *text;

    table->rows[0].has_drift = TRUE;
    table->rows[0].dx = 3;
    text = drift_table_to_string(table);
    ck_assert_str_eq(text, "stripe,dx,dy\n0,3,0\n");
    g_free(text);
    table->unit_given = TRUE;
    text = drift_table_to_string(table);
    ck_assert_str_eq(text, "# units: px\nstripe,dx,dy\n0,3,0\n");
    g_free(text);
    drift_table_free(table);
}
END_TEST

START_TEST(test_extra_text_kept)
{
    static const gchar text[] = "stripe,dx,dy,note,x\n0,1,2,hello,3.50\n";
    DriftTable *table = parse_ok(text);
    gchar *out;
    gdouble v = 0.0;

    ck_assert_int_eq(table->n_extra, 2);
    ck_assert_str_eq(table->extra_names[0], "note");
    ck_assert_str_eq(table->extra_values[0], "hello");
    ck_assert(!drift_table_get_extra(table, 0, "note", &v));
    ck_assert(drift_table_get_extra(table, 0, "x", &v) && v == 3.5);
    out = drift_table_to_string(table);
    /* Extra columns are text: 3.50 stays 3.50. */
    ck_assert_str_eq(out, text);
    g_free(out);
    drift_table_free(table);
}
END_TEST

/* Tolerated input. */

START_TEST(test_tolerant_input)
{
    DriftTable *table;
    gchar *text;

    table = parse_ok("\xef\xbb\xbf# comment\r\n\r\n  #   UNITS :  NM  \r\n"
                     " stripe , dx , dy \r\n  0 , -0 , +1 \r\n"
                     "\r\n# between\r\n1,1e-9,  \t2.5e+1\r\n2 ,, ");
    ck_assert_int_eq(table->unit, DRIFT_UNIT_NM);
    ck_assert(table->unit_given);
    ck_assert_int_eq(table->n_stripes, 3);
    ck_assert_int_eq(table->header_line, 4);
    ck_assert_int_eq(table->rows[0].line, 5);
    ck_assert_int_eq(table->rows[1].line, 8);
    ck_assert_int_eq(table->rows[2].line, 9);
    ck_assert(table->rows[0].dx == 0.0 && signbit(table->rows[0].dx));
    ck_assert(table->rows[0].dy == 1.0);
    ck_assert(table->rows[1].dx == 1e-9 && table->rows[1].dy == 25.0);
    ck_assert(!table->rows[2].has_drift);
    text = drift_table_to_string(table);
    ck_assert_str_eq(text, "# units: nm\nstripe,dx,dy\n0,-0,1\n1,1e-09,25\n2,,\n");
    g_free(text);
    drift_table_free(table);

    table = parse_ok("#units:um\nstripe,dx,dy\n0,1,1");
    ck_assert_int_eq(table->unit, DRIFT_UNIT_UM);
    drift_table_free(table);
    table = parse_ok("# units: \xc2\xb5m\nstripe,dx,dy\n0,1,1\n");
    ck_assert_int_eq(table->unit, DRIFT_UNIT_UM);
    drift_table_free(table);
    table = parse_ok("# units are pixels, this is a plain comment\n"
                     "stripe,dx,dy\n0,1,1\n");
    ck_assert_int_eq(table->unit, DRIFT_UNIT_PX);
    ck_assert(!table->unit_given);
    drift_table_free(table);
}
END_TEST

START_TEST(test_unit_names)
{
    DriftUnit unit;

    ck_assert_str_eq(drift_unit_name(DRIFT_UNIT_PX), "px");
    ck_assert_str_eq(drift_unit_name(DRIFT_UNIT_M), "m");
    ck_assert_str_eq(drift_unit_name(DRIFT_UNIT_NM), "nm");
    ck_assert_str_eq(drift_unit_name(DRIFT_UNIT_UM), "um");
    ck_assert(drift_unit_from_name("Nm", &unit) && unit == DRIFT_UNIT_NM);
    ck_assert(drift_unit_from_name("M", &unit) && unit == DRIFT_UNIT_M);
    ck_assert(!drift_unit_from_name("mm", &unit));
    ck_assert(!drift_unit_from_name("", &unit));
}
END_TEST

/* Refusals, each with its exact message. */

/* A NUL byte ends the text a C string holds: the rows after it were
 * dropped unread (four stripes read as one, exit status 0).  Named by the
 * line it lies on, wherever it lies. */
START_TEST(test_refuse_nul_byte)
{
    static const gchar text[] = "stripe,dx,dy\n0,1,0\0\n1,0,0\n2,5,5\n3,nan,0\n";
    static const gchar first[] = "\0stripe,dx,dy\n0,1,0\n";
    GError *error = NULL;

    ck_assert(!drift_table_parse(text, sizeof(text) - 1, "t.csv", &error));
    ck_assert_str_eq(error->message, "t.csv:2: a NUL byte: this is not a text table");
    ck_assert(g_error_matches(error, DRIFT_TABLE_ERROR, DRIFT_TABLE_ERROR_SYNTAX));
    g_clear_error(&error);
    ck_assert(!drift_table_parse(first, sizeof(first) - 1, "t.csv", &error));
    ck_assert_str_eq(error->message, "t.csv:1: a NUL byte: this is not a text table");
    g_clear_error(&error);
}
END_TEST

START_TEST(test_refuse_syntax)
{
    assert_parse_error("0,1,2\n", DRIFT_TABLE_ERROR_SYNTAX,
                       "t.csv:1: missing header: expected a line starting "
                       "'stripe,dx,dy', got '0,1,2'");
    assert_parse_error("# c\n\nstripe,dy,dx\n0,1,2\n", DRIFT_TABLE_ERROR_SYNTAX,
                       "t.csv:3: missing header: expected a line starting "
                       "'stripe,dx,dy', got 'stripe,dy,dx'");
    assert_parse_error("stripe,dx,dy,\n0,1,2,\n", DRIFT_TABLE_ERROR_SYNTAX,
                       "t.csv:1: column 4 of the header has no name");
    assert_parse_error("stripe,dx,dy,t,t\n", DRIFT_TABLE_ERROR_SYNTAX,
                       "t.csv:1: column 't' appears twice in the header");
    assert_parse_error("# c\nstripe,dx,dy\n0,1\n", DRIFT_TABLE_ERROR_SYNTAX,
                       "t.csv:3: expected 3 fields, got 2");
    assert_parse_error("stripe,dx,dy,t\r\n0,1,2,3\r\n1,1,2\r\n",
                       DRIFT_TABLE_ERROR_SYNTAX,
                       "t.csv:3: expected 4 fields, got 3");
    assert_parse_error("stripe,dx,dy\n0,1,2,3\n", DRIFT_TABLE_ERROR_SYNTAX,
                       "t.csv:2: expected 3 fields, got 4");
    assert_parse_error("stripe,dx,dy\n0,1x,2\n", DRIFT_TABLE_ERROR_SYNTAX,
                       "t.csv:2: bad number '1x' for dx");
    assert_parse_error("stripe,dx,dy\n0,1,0x10\n", DRIFT_TABLE_ERROR_SYNTAX,
                       "t.csv:2: bad number '0x10' for dy");
    assert_parse_error("stripe,dx,dy\n0,0x1p3,1\n", DRIFT_TABLE_ERROR_SYNTAX,
                       "t.csv:2: bad number '0x1p3' for dx");
    assert_parse_error("stripe,dx,dy\n0,1 2,1\n", DRIFT_TABLE_ERROR_SYNTAX,
                       "t.csv:2: bad number '1 2' for dx");
    assert_parse_error("stripe,dx,dy\n0,1e,1\n", DRIFT_TABLE_ERROR_SYNTAX,
                       "t.csv:2: bad number '1e' for dx");
    assert_parse_error("stripe,dx,dy\n0,1,2,\n", DRIFT_TABLE_ERROR_SYNTAX,
                       "t.csv:2: expected 3 fields, got 4");
    assert_parse_error("stripe,dx,dy\n0,,1\n", DRIFT_TABLE_ERROR_SYNTAX,
                       "t.csv:2: dx is blank but dy is not; give both or neither");
    assert_parse_error("stripe,dx,dy\n0,1,2\n1,3, \n", DRIFT_TABLE_ERROR_SYNTAX,
                       "t.csv:3: dy is blank but dx is not; give both or neither");
    assert_parse_error("stripe,dx,dy\n0.5,1,2\n", DRIFT_TABLE_ERROR_SYNTAX,
                       "t.csv:2: stripe '0.5' is not an integer");
    assert_parse_error("stripe,dx,dy\n,1,2\n", DRIFT_TABLE_ERROR_SYNTAX,
                       "t.csv:2: stripe '' is not an integer");
    assert_parse_error("stripe,dx,dy\n1e0,1,2\n", DRIFT_TABLE_ERROR_SYNTAX,
                       "t.csv:2: stripe '1e0' is not an integer");
}
END_TEST

START_TEST(test_refuse_values)
{
    assert_parse_error("stripe,dx,dy\n0,1,nan\n", DRIFT_TABLE_ERROR_VALUE,
                       "t.csv:2: dy = nan: NaN or infinity is not a drift");
    assert_parse_error("stripe,dx,dy\n0,-inf,1\n", DRIFT_TABLE_ERROR_VALUE,
                       "t.csv:2: dx = -inf: NaN or infinity is not a drift");
    assert_parse_error("stripe,dx,dy\n0,1,1\n1,Infinity,1\n",
                       DRIFT_TABLE_ERROR_VALUE,
                       "t.csv:3: dx = Infinity: NaN or infinity is not a drift");
    assert_parse_error("stripe,dx,dy\n0,NAN,1\n", DRIFT_TABLE_ERROR_VALUE,
                       "t.csv:2: dx = NAN: NaN or infinity is not a drift");
    assert_parse_error("stripe,dx,dy\n0,1e999,1\n", DRIFT_TABLE_ERROR_VALUE,
                       "t.csv:2: dx = 1e999 is out of range");
}
END_TEST

START_TEST(test_refuse_stripes)
{
    assert_parse_error("stripe,dx,dy\n1,1,1\n", DRIFT_TABLE_ERROR_STRIPES,
                       "t.csv:2: missing stripe: expected stripe 0, got 1");
    assert_parse_error("stripe,dx,dy\n0,1,1\n# gap\n2,1,1\n",
                       DRIFT_TABLE_ERROR_STRIPES,
                       "t.csv:4: missing stripe: expected stripe 1, got 2");
    assert_parse_error("stripe,dx,dy\n-1,1,1\n", DRIFT_TABLE_ERROR_STRIPES,
                       "t.csv:2: missing stripe: expected stripe 0, got -1");
    assert_parse_error("stripe,dx,dy\n0,1,1\n1,1,1\n1,2,2\n",
                       DRIFT_TABLE_ERROR_STRIPES,
                       "t.csv:4: repeated stripe 1 (first on line 3)");
    assert_parse_error("stripe,dx,dy\n0,1,1\n1,,\n\n0,2,2\n",
                       DRIFT_TABLE_ERROR_STRIPES,
                       "t.csv:5: repeated stripe 0 (first on line 2)");
    assert_parse_error("stripe,dx,dy\n0,1,1\n2,1,1\n1,1,1\n",
                       DRIFT_TABLE_ERROR_STRIPES,
                       "t.csv:3: stripes not ascending: stripe 2 comes before "
                       "stripe 1 (line 4)");
}
END_TEST

START_TEST(test_refuse_units)
{
    assert_parse_error("# units: furlong\nstripe,dx,dy\n0,1,1\n",
                       DRIFT_TABLE_ERROR_UNIT,
                       "t.csv:1: unknown unit 'furlong' (known: px, m, nm, um)");
    assert_parse_error("\n#  Units:\nstripe,dx,dy\n0,1,1\n",
                       DRIFT_TABLE_ERROR_UNIT,
                       "t.csv:2: unknown unit '' (known: px, m, nm, um)");
    assert_parse_error("stripe,dx,dy\n# units: nm\n0,1,1\n",
                       DRIFT_TABLE_ERROR_UNIT,
                       "t.csv:2: the units line must come before the header");
    assert_parse_error("# units: nm\n# units: px\nstripe,dx,dy\n0,1,1\n",
                       DRIFT_TABLE_ERROR_UNIT,
                       "t.csv:2: a second units line contradicts the first");
}
END_TEST

START_TEST(test_refuse_empty)
{
    assert_parse_error("", DRIFT_TABLE_ERROR_EMPTY,
                       "t.csv:1: empty table: no header and no stripe rows");
    assert_parse_error("# nothing\n\n# here\n", DRIFT_TABLE_ERROR_EMPTY,
                       "t.csv:3: empty table: no header and no stripe rows");
    assert_parse_error("# units: nm\nstripe,dx,dy\n\n", DRIFT_TABLE_ERROR_EMPTY,
                       "t.csv:2: empty table: no stripe rows");
}
END_TEST

START_TEST(test_refuse_image)
{
    GError *error = NULL;
    DriftTable *table;

    table = parse_ok("stripe,dx,dy\n0,1,1\n1,1,1\n# end\n2,1,1\n\n");
    ck_assert(drift_table_check_image(table, 3, &error));
    ck_assert(!error);
    ck_assert(!drift_table_check_image(table, 2, &error));
    ck_assert_str_eq(error->message,
                     "t.csv:5: the table has 3 stripes but the image has "
                     "only 2 rows");
    ck_assert_int_eq(error->code, DRIFT_TABLE_ERROR_IMAGE);
    g_clear_error(&error);
    drift_table_free(table);

    assert_pixels_error("stripe,dx,dy\n0,1,1\n1,2,2\n", 1, FALSE,
                        DRIFT_TABLE_ERROR_IMAGE,
                        "t.csv:3: the table has 2 stripes but the image has "
                        "only 1 rows");
    assert_pixels_error("# none\nstripe,dx,dy\n0,,\n1,,\n", 10, FALSE,
                        DRIFT_TABLE_ERROR_EMPTY,
                        "t.csv:2: no stripe has a drift (every dx,dy is blank)");
}
END_TEST

START_TEST(test_refuse_fraction)
{
    GError *error = NULL;
    DriftTable *table;
    gdouble dx[3], dy[3];

    assert_pixels_error("stripe,dx,dy\n0,1,0\n1,1.5,0\n", 10, TRUE,
                        DRIFT_TABLE_ERROR_VALUE,
                        "t.csv:3: dx = 1.5 px is not a whole number of "
                        "pixels; paper mode needs whole pixels");
    assert_pixels_error("stripe,dx,dy\n0,2,-0.25\n", 10, TRUE,
                        DRIFT_TABLE_ERROR_VALUE,
                        "t.csv:2: dy = -0.25 px is not a whole number of "
                        "pixels; paper mode needs whole pixels");
    assert_pixels_error("stripe,dx,dy\n0,2,1e10\n", 10, FALSE,
                        DRIFT_TABLE_ERROR_VALUE,
                        "t.csv:2: dy = 10000000000 px is more than "
                        "1e+09 pixels");

    /* Without whole_pixels the fraction is kept; within 1e-9 of an integer
     * it counts as whole. */
    table = parse_ok("stripe,dx,dy\n0,1.5,-0.25\n1,2.0000000001,-3\n"
                     "2,-0,0\n");
    ck_assert(drift_table_to_pixels(table, 10, 1.0, 1.0, FALSE, dx, dy,
                                    &error));
    ck_assert(dx[0] == 1.5 && dy[0] == -0.25);
    ck_assert(dx[1] == 2.0000000001 && dy[1] == -3.0);
    ck_assert(dx[2] == 0.0 && !signbit(dx[2]));
    ck_assert(!drift_table_to_pixels(table, 10, 1.0, 1.0, TRUE, dx, dy,
                                     &error));
    g_clear_error(&error);
    drift_table_free(table);

    table = parse_ok("stripe,dx,dy\n0,1.0000000001,-2.9999999999\n");
    ck_assert(drift_table_to_pixels(table, 1, 1.0, 1.0, TRUE, dx, dy,
                                    &error));
    ck_assert(dx[0] == 1.0 && dy[0] == -3.0);
    drift_table_free(table);
}
END_TEST

/* Units and conversion. */

START_TEST(test_physical_units)
{
    GError *error = NULL;
    DriftTable *table;
    gdouble dx[4], dy[4];

    /* x pixels of 2 nm, y pixels of 5 nm. */
    table = parse_ok("# units: nm\nstripe,dx,dy\n0,10,10\n1,3.2,3.2\n"
                     "2,-5.2,-12.4\n3,0.9,-1\n");
    ck_assert(drift_table_to_pixels(table, 8, 2e-9, 5e-9, FALSE, dx, dy,
                                    &error));
    ck_assert_msg(fabs(dx[0] - 5.0) < 1e-12 && fabs(dy[0] - 2.0) < 1e-12,
                  "got %g %g", dx[0], dy[0]);
    ck_assert(fabs(dx[1] - 1.6) < 1e-12 && fabs(dy[1] - 0.64) < 1e-12);
    ck_assert(fabs(dx[2] + 2.6) < 1e-12 && fabs(dy[2] + 2.48) < 1e-12);
    ck_assert(fabs(dx[3] - 0.45) < 1e-12 && fabs(dy[3] + 0.2) < 1e-12);
    /* Whole pixels: the nearest. */
    ck_assert(drift_table_to_pixels(table, 8, 2e-9, 5e-9, TRUE, dx, dy,
                                    &error));
    ck_assert(dx[0] == 5.0 && dy[0] == 2.0);
    ck_assert(dx[1] == 2.0 && dy[1] == 1.0);
    ck_assert(dx[2] == -3.0 && dy[2] == -2.0);
    ck_assert(dx[3] == 0.0 && !signbit(dx[3]));
    ck_assert(dy[3] == 0.0 && !signbit(dy[3]));
    drift_table_free(table);

    table = parse_ok("# units: um\nstripe,dx,dy\n0,0.01,-0.004\n");
    ck_assert(drift_table_to_pixels(table, 1, 1e-9, 2e-9, TRUE, dx, dy,
                                    &error));
    ck_assert(dx[0] == 10.0 && dy[0] == -2.0);
    drift_table_free(table);

    table = parse_ok("# units: m\nstripe,dx,dy\n0,3e-8,6e-8\n");
    ck_assert(drift_table_to_pixels(table, 1, 1e-8, 3e-8, TRUE, dx, dy,
                                    &error));
    ck_assert(dx[0] == 3.0 && dy[0] == 2.0);
    drift_table_free(table);

    /* Half pixels round away from zero whatever the unit they are given
     * in: in um the conversion gave 2.4999999999999996 and 2. */
    {
        static const gchar *const tables[] = {
            "# units: um\nstripe,dx,dy\n0,0.09765625,-0.09765625\n",
            "# units: nm\nstripe,dx,dy\n0,97.65625,-97.65625\n",
            "# units: m\nstripe,dx,dy\n0,9.765625e-8,-9.765625e-8\n",
        };
        guint k;

        for (k = 0; k < G_N_ELEMENTS(tables); k++) {
            table = parse_ok(tables[k]);
            ck_assert(drift_table_to_pixels(table, 1, 5e-6/128, 5e-6/128, TRUE, dx, dy, &error));
            ck_assert_msg(dx[0] == 3.0 && dy[0] == -3.0, "%s: %g, %g", tables[k], dx[0], dy[0]);
            drift_table_free(table);
        }
    }
    ck_assert(!error);
}
END_TEST

START_TEST(test_blank_rows_filled)
{
    GError *error = NULL;
    DriftTable *table;
    gdouble dx[6], dy[6];
    static const gdouble want_dx[6] = { 5, 5, 5, 10, 10, 10 };
    static const gdouble want_dy[6] = { 2, 2, 2, -4, -4, -4 };
    gint s;

    /* Stripe 2 is a tie between 1 and 3: the lower index wins. */
    table = parse_ok("# units: nm\nstripe,dx,dy\n0,,\n1,10,10\n2,,\n"
                     "3,20,-20\n4,,\n5,,\n");
    ck_assert(drift_table_to_pixels(table, 6, 2e-9, 5e-9, TRUE, dx, dy,
                                    &error));
    for (s = 0; s < 6; s++) {
        ck_assert_msg(dx[s] == want_dx[s] && dy[s] == want_dy[s],
                      "stripe %d: %g,%g", s, dx[s], dy[s]);
    }
    /* The table itself is not changed. */
    ck_assert(!table->rows[0].has_drift && !table->rows[2].has_drift);
    drift_table_free(table);
}
END_TEST

START_TEST(test_built_table_messages)
{
    GError *error = NULL;
    DriftTable *table = drift_table_new(2, DRIFT_UNIT_PX);
    gdouble dx[2], dy[2];

    ck_assert(!drift_table_check_image(table, 5, &error));
    ck_assert_str_eq(error->message, "drift table:1: no stripe has a drift "
                     "(every dx,dy is blank)");
    g_clear_error(&error);
    table->rows[1].has_drift = TRUE;
    table->rows[1].dx = 0.5;
    ck_assert(!drift_table_to_pixels(table, 5, 1.0, 1.0, TRUE, dx, dy,
                                     &error));
    ck_assert_str_eq(error->message, "drift table:3: dx = 0.5 px is not a "
                     "whole number of pixels; paper mode needs whole pixels");
    g_clear_error(&error);
    drift_table_free(table);
}
END_TEST

/* Files. */

static gchar*
make_scratch_dir(void)
{
    GError *error = NULL;
    gchar *dir = g_dir_make_tmp("test-drift-table-XXXXXX", &error);

    ck_assert_msg(dir, "cannot make a scratch folder: %s",
                  error ? error->message : "");
    return dir;
}

static gint
count_entries(const gchar *dirname)
{
    GDir *dir = g_dir_open(dirname, 0, NULL);
    gint n = 0;

    ck_assert(dir);
    while (g_dir_read_name(dir))
        n++;
    g_dir_close(dir);
    return n;
}

START_TEST(test_save_load)
{
    static const gchar text[] = "# units: nm\nstripe,dx,dy,t_local\n"
                                "0,1.25,-3,0.5\n1,,,\n";
    GError *error = NULL;
    DriftTable *table = parse_ok(text), *loaded;
    gchar *dir = make_scratch_dir(), *path, *contents;

    path = g_build_filename(dir, "table.csv", NULL);
    ck_assert(g_file_set_contents(path, "old contents\n", -1, NULL));
    ck_assert(drift_table_save(table, path, &error));
    ck_assert(!error);
    ck_assert(g_file_get_contents(path, &contents, NULL, NULL));
    ck_assert_str_eq(contents, text);
    g_free(contents);
    ck_assert_int_eq(count_entries(dir), 1);

    loaded = drift_table_load(path, &error);
    ck_assert(loaded);
    ck_assert_str_eq(loaded->source_name, path);
    assert_same_table(table, loaded);
    drift_table_free(loaded);

    ck_assert(g_file_set_contents(path, "stripe,dx,dy\n0,1,1\n1,q,1\n",
                                  -1, NULL));
    ck_assert(!drift_table_load(path, &error));
    contents = g_strdup_printf("%s:3: bad number 'q' for dx", path);
    ck_assert_str_eq(error->message, contents);
    g_free(contents);
    g_clear_error(&error);

    g_unlink(path);
    g_rmdir(dir);
    g_free(path);
    g_free(dir);
    drift_table_free(table);
}
END_TEST

START_TEST(test_load_missing)
{
    GError *error = NULL;
    gchar *dir = make_scratch_dir(), *path, *expected;

    path = g_build_filename(dir, "absent.csv", NULL);
    ck_assert(!drift_table_load(path, &error));
    expected = g_strdup_printf("%s: cannot read: No such file or directory",
                               path);
    ck_assert_str_eq(error->message, expected);
    ck_assert(g_error_matches(error, DRIFT_TABLE_ERROR, DRIFT_TABLE_ERROR_IO));
    g_clear_error(&error);
    g_free(expected);

    /* A folder is not a table. */
    ck_assert(!drift_table_load(dir, &error));
    expected = g_strdup_printf("%s: cannot read: Is a directory", dir);
    ck_assert_str_eq(error->message, expected);
    g_clear_error(&error);
    g_free(expected);

    g_rmdir(dir);
    g_free(path);
    g_free(dir);
}
END_TEST

/* The user id root takes for the read-only folder case: nobody's. */
#define UNPRIVILEGED_UID 65534

static void
assert_save_fails(const DriftTable *table, const gchar *path)
{
    GError *error = NULL;
    gchar *prefix = g_strdup_printf("%s: cannot write: ", path);

    ck_assert(!drift_table_save(table, path, &error));
    ck_assert(error);
    ck_assert_msg(g_str_has_prefix(error->message, prefix),
                  "message '%s'", error->message);
    ck_assert(g_error_matches(error, DRIFT_TABLE_ERROR, DRIFT_TABLE_ERROR_IO));
    g_clear_error(&error);
    g_free(prefix);
}

START_TEST(test_save_fails_cleanly)
{
    DriftTable *table = parse_ok("stripe,dx,dy\n0,1,1\n");
    gchar *dir = make_scratch_dir(), *path, *sub;

    /* Missing folder. */
    path = g_build_filename(dir, "missing", "t.csv", NULL);
    assert_save_fails(table, path);
    ck_assert(!g_file_test(path, G_FILE_TEST_EXISTS));
    ck_assert_int_eq(count_entries(dir), 0);
    g_free(path);

    /* The target is a folder: the temporary file is written, the rename
     * fails, and nothing may be left behind. */
    sub = g_build_filename(dir, "sub", NULL);
    ck_assert(g_mkdir(sub, 0700) == 0);
    assert_save_fails(table, sub);
    ck_assert(g_file_test(sub, G_FILE_TEST_IS_DIR));
    ck_assert_int_eq(count_entries(dir), 1);

    /* A read-only folder.  Root writes anywhere, so root tries it with
     * the rights of an ordinary user (the effective user id only, so that
     * root's own come back). */
    path = g_build_filename(sub, "t.csv", NULL);
    if (geteuid() != 0) {
        ck_assert(g_chmod(sub, 0500) == 0);
        assert_save_fails(table, path);
    }
    else {
        ck_assert(g_chmod(dir, 0755) == 0);
        ck_assert(g_chmod(sub, 0555) == 0);
        ck_assert(seteuid(UNPRIVILEGED_UID) == 0);
        assert_save_fails(table, path);
        ck_assert(seteuid(0) == 0);
    }
    ck_assert_int_eq(count_entries(sub), 0);
    g_chmod(sub, 0700);
    g_free(path);
    /* A folder nobody can create files in, root included. */
    if (g_file_test("/proc/self", G_FILE_TEST_IS_DIR)) {
        assert_save_fails(table, "/proc/localscan-test.csv");
        ck_assert(!g_file_test("/proc/localscan-test.csv", G_FILE_TEST_EXISTS));
    }

    g_rmdir(sub);
    g_rmdir(dir);
    g_free(sub);
    g_free(dir);
    drift_table_free(table);
}
END_TEST

int
main(void)
{
    TCase *tc;
    Suite *suite = test_suite_new("drift-table", "core", &tc);

    tcase_add_test(tc, test_round_trip_text);
    tcase_add_test(tc, test_round_trip_built);
    tcase_add_test(tc, test_units_line_written);
    tcase_add_test(tc, test_extra_text_kept);
    tcase_add_test(tc, test_tolerant_input);
    tcase_add_test(tc, test_unit_names);
    tcase_add_test(tc, test_refuse_syntax);
    tcase_add_test(tc, test_refuse_nul_byte);
    tcase_add_test(tc, test_refuse_values);
    tcase_add_test(tc, test_refuse_stripes);
    tcase_add_test(tc, test_refuse_units);
    tcase_add_test(tc, test_refuse_empty);
    tcase_add_test(tc, test_refuse_image);
    tcase_add_test(tc, test_refuse_fraction);
    tcase_add_test(tc, test_physical_units);
    tcase_add_test(tc, test_blank_rows_filled);
    tcase_add_test(tc, test_built_table_messages);
    tcase_add_test(tc, test_save_load);
    tcase_add_test(tc, test_load_missing);
    tcase_add_test(tc, test_save_fails_cleanly);
    return test_run_suite(suite);
}
