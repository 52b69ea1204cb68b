/*
 *  Tests of the trajectory CSV format (modules/core/trajectory-csv.c): a
 *  seeded random trajectory written and read back, and every refusal of
 *  the strict reader with its message.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <string.h>
#include <math.h>
#include <check.h>
#include <glib.h>
#include "trajectory-csv.h"
#include "test-common.h"

#define FRAMES 4
#define ROWS 32

static guint32 test_seed;

/* A trajectory with random values, every line in random order. */
static gchar*
random_trajectory(GRand *rng, gdouble *dx, gdouble *dy, gdouble *t)
{
    GString *text = g_string_new(NULL);
    gint order[FRAMES*ROWS], i, j, tmp;

    for (i = 0; i < FRAMES*ROWS; i++) {
        order[i] = i;
        dx[i] = g_rand_double_range(rng, -50.0, 50.0);
        dy[i] = g_rand_double_range(rng, -50.0, 50.0);
        t[i] = g_rand_double_range(rng, 0.0, 1000.0);
    }
    for (i = FRAMES*ROWS - 1; i > 0; i--) {
        j = g_rand_int_range(rng, 0, i + 1);
        tmp = order[i];
        order[i] = order[j];
        order[j] = tmp;
    }
    trajectory_csv_begin(text, "test trajectory", 1e-9, 2e-9);
    for (i = 0; i < FRAMES*ROWS; i++) {
        j = order[i];
        trajectory_csv_line(text, j/ROWS, j % ROWS, t[j], dx[j], dy[j], 6);
    }
    return g_string_free(text, FALSE);
}

START_TEST(test_round_trip)
{
    GRand *rng = g_rand_new_with_seed(test_seed);
    gdouble dx[FRAMES*ROWS], dy[FRAMES*ROWS], t[FRAMES*ROWS];
    gchar *text = random_trajectory(rng, dx, dy, t), *failure;
    TrajectoryTable table;
    gint i;

    ck_assert(g_str_has_prefix(text, "# test trajectory p(t) - p(0)"));
    ck_assert(strstr(text, "\n" TRAJECTORY_CSV_HEADER "\n") != NULL);
    failure = trajectory_csv_parse(text, FRAMES, ROWS, &table);
    ck_assert_msg(failure == NULL, "refused: %s", failure);
    for (i = 0; i < FRAMES*ROWS; i++) {
        ck_assert(table.have[i]);
        ck_assert_msg(fabs(table.dx[i] - dx[i]) <= 5e-7
                      && fabs(table.dy[i] - dy[i]) <= 5e-7
                      && fabs(table.t[i] - t[i]) <= 5e-7,
                      "line %d: (%g, %g) at %g read as (%g, %g) at %g", i,
                      dx[i], dy[i], t[i], table.dx[i], table.dy[i], table.t[i]);
    }
    trajectory_table_free(&table);
    g_free(text);
    g_rand_free(rng);
}
END_TEST

/* Each malformed text is refused with its own message. */
static const struct {
    const gchar *text;
    const gchar *message;
} refusals[] = {
    { "# only comments\n", "no header" },
    { "frame,row,t,dx,dy\n0,0,0,0,0\n", "line 1: the header is not" },
    { "frame,row,t_s,dx_px,dy_px\n0,0,0,0\n", "line 2: not 5 fields" },
    { "frame,row,t_s,dx_px,dy_px\n4,0,0,0,0\n", "line 2: frame '4' is not 0 to 3" },
    { "frame,row,t_s,dx_px,dy_px\n0,-1,0,0,0\n", "line 2: row '-1' is not 0 to 31" },
    { "frame,row,t_s,dx_px,dy_px\n0,0,0,nan,0\n", "line 2: a value is not a finite number" },
    { "frame,row,t_s,dx_px,dy_px\n0,0,0,1e999,0\n", "line 2: a value is not a finite number" },
    { "frame,row,t_s,dx_px,dy_px\n0,0,0,1.5x,0\n", "line 2: a value is not a finite number" },
    { "#c\nframe,row,t_s,dx_px,dy_px\n0,3,0,0,0\n\n0,3,1,0,0\n", "line 5: frame 0 row 3 given twice" },
};

START_TEST(test_refusals)
{
    TrajectoryTable table;
    gchar *failure;

    failure = trajectory_csv_parse(refusals[_i].text, FRAMES, ROWS, &table);
    ck_assert_msg(failure && strstr(failure, refusals[_i].message),
                  "case %d: '%s', expected '%s'", _i,
                  failure ? failure : "accepted", refusals[_i].message);
    g_free(failure);
    trajectory_table_free(&table);
}
END_TEST

/* Comments, blank lines, CRLF line ends and spaces around values are
 * accepted; lines not given stay absent. */
START_TEST(test_lenient_layout)
{
    const gchar *text = "# a\r\n\r\nframe,row,t_s,dx_px,dy_px\r\n"
                        " 1 , 2 , 3.5 , -0.25 , 0.75 \r\n";
    TrajectoryTable table;
    gchar *failure;

    failure = trajectory_csv_parse(text, FRAMES, ROWS, &table);
    ck_assert_msg(failure == NULL, "refused: %s", failure);
    ck_assert(table.have[ROWS + 2] && !table.have[0]);
    ck_assert(table.dx[ROWS + 2] == -0.25 && table.dy[ROWS + 2] == 0.75
              && table.t[ROWS + 2] == 3.5);
    trajectory_table_free(&table);
}
END_TEST

static Suite*
trajectory_csv_suite(void)
{
    TCase *tc;
    Suite *s = test_suite_new("trajectory-csv", "core", &tc);

    tcase_add_test(tc, test_round_trip);
    tcase_add_loop_test(tc, test_refusals, 0, G_N_ELEMENTS(refusals));
    tcase_add_test(tc, test_lenient_layout);
    return s;
}

int
main(void)
{
    test_seed = test_seed_from_env("test-trajectory-csv");
    return test_run_suite(trajectory_csv_suite());
}
