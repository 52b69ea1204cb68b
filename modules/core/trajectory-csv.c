/*
 *  The drift trajectory's CSV format: one writer and one strict reader, so
 *  that what the series correction and the benchmark write is exactly
 *  what the scorer reads.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <string.h>
#include <math.h>
#include "localscan-intl.h"
#include "trajectory-csv.h"

void
trajectory_csv_begin(GString *text, const gchar *what, gdouble xstep,
                     gdouble ystep)
{
    gchar x[G_ASCII_DTOSTR_BUF_SIZE], y[G_ASCII_DTOSTR_BUF_SIZE];

    g_string_append_printf(text, "# %s p(t) - p(0), t = 0 at the start of "
                           "the first frame, t_s the centre of the line's "
                           "trace\n", what);
    g_string_append_printf(text, "# pixels of the first frame: dx %s m, "
                           "dy %s m\n",
                           g_ascii_formatd(x, sizeof(x), "%.6g", xstep),
                           g_ascii_formatd(y, sizeof(y), "%.6g", ystep));
    g_string_append(text, TRAJECTORY_CSV_HEADER "\n");
}

void
trajectory_csv_line(GString *text, gint frame, gint row, gdouble t,
                    gdouble dx, gdouble dy, gint decimals)
{
    gchar a[G_ASCII_DTOSTR_BUF_SIZE], b[G_ASCII_DTOSTR_BUF_SIZE],
          c[G_ASCII_DTOSTR_BUF_SIZE], format[8];

    g_snprintf(format, sizeof(format), "%%.%df", CLAMP(decimals, 0, 12));
    g_string_append_printf(text, "%d,%d,%s,%s,%s\n", frame, row,
                           g_ascii_formatd(a, sizeof(a), "%.6f", t),
                           g_ascii_formatd(b, sizeof(b), format, dx),
                           g_ascii_formatd(c, sizeof(c), format, dy));
}

static gboolean
parse_int(const gchar *s, gint lo, gint hi, gint *value)
{
    gchar *end;
    gint64 v;

    while (*s == ' ')
        s++;
    v = g_ascii_strtoll(s, &end, 10);
    while (*end == ' ')
        end++;
    if (end == s || *end || v < lo || v > hi)
        return FALSE;
    *value = (gint)v;
    return TRUE;
}

static gboolean
parse_double(const gchar *s, gdouble *value)
{
    gchar *end;

    while (*s == ' ')
        s++;
    *value = g_ascii_strtod(s, &end);
    while (*end == ' ')
        end++;
    return end != s && !*end && isfinite(*value);
}

/* One data line into table; why not, else NULL. */
static gchar*
parse_line(const gchar *line, TrajectoryTable *table)
{
    gchar **f = g_strsplit(line, ",", -1), *failure = NULL;
    gint frame, row, i;
    gdouble t, dx, dy;

    if (g_strv_length(f) != 5)
        failure = g_strdup(_("not 5 fields"));
    else if (!parse_int(f[0], 0, table->n_frames - 1, &frame))
        failure = g_strdup_printf(_("frame '%.20s' is not 0 to %d"), f[0],
                                  table->n_frames - 1);
    else if (!parse_int(f[1], 0, table->yres - 1, &row))
        failure = g_strdup_printf(_("row '%.20s' is not 0 to %d"), f[1],
                                  table->yres - 1);
    else if (!parse_double(f[2], &t) || !parse_double(f[3], &dx)
             || !parse_double(f[4], &dy))
        failure = g_strdup(_("a value is not a finite number"));
    else if (table->have[i = frame*table->yres + row])
        failure = g_strdup_printf(_("frame %d row %d given twice"), frame,
                                  row);
    else {
        table->have[i] = TRUE;
        table->t[i] = t;
        table->dx[i] = dx;
        table->dy[i] = dy;
    }
    g_strfreev(f);
    return failure;
}

gchar*
trajectory_csv_parse(const gchar *text, gint n_frames, gint yres,
                     TrajectoryTable *table)
{
    gsize n = (gsize)MAX(n_frames, 0)*MAX(yres, 0);
    gchar **lines = g_strsplit(text, "\n", -1), *failure = NULL, *why;
    gboolean header = FALSE;
    gint i;

    table->n_frames = n_frames;
    table->yres = yres;
    table->t = g_new0(gdouble, 3*MAX(n, 1));
    table->dx = table->t + n;
    table->dy = table->dx + n;
    table->have = g_new0(gboolean, MAX(n, 1));
    for (i = 0; lines[i] && !failure; i++) {
        g_strchomp(lines[i]);
        if (!*lines[i] || lines[i][0] == '#')
            continue;
        if (!header) {
            if (strcmp(lines[i], TRAJECTORY_CSV_HEADER) != 0)
                failure = g_strdup_printf(_("line %d: the header is not '%s'"),
                                          i + 1, TRAJECTORY_CSV_HEADER);
            header = TRUE;
        }
        else if ((why = parse_line(lines[i], table))) {
            failure = g_strdup_printf(_("line %d: %s"), i + 1, why);
            g_free(why);
        }
    }
    if (!failure && !header)
        failure = g_strdup_printf(_("no header '%s'"), TRAJECTORY_CSV_HEADER);
    g_strfreev(lines);
    return failure;
}

void
trajectory_table_free(TrajectoryTable *table)
{
    g_free(table->t);
    g_free(table->have);
    table->t = table->dx = table->dy = NULL;
    table->have = NULL;
}
