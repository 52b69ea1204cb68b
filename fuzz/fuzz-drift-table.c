/*
 *  libFuzzer harness: the drift-table parser on arbitrary bytes.  A table
 *  that parses must write out and parse back to the same rows, and every
 *  refusal must be one printable line (quoted-input.h).
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <stdlib.h>
#include <string.h>
#include "drift-table.h"
#include "quoted-input.h"

static void
check_message(const gchar *message)
{
    gchar *line = quoted_input_message_line(message);

    /* A message quoting the input stays short: the excerpt is bounded. */
    if (strchr(line, '\n') || strlen(message) > 4096 + 2*QUOTED_INPUT_EXCERPT_CHARS*4)
        abort();
    g_free(line);
}

int LLVMFuzzerTestOneInput(const guint8 *data, size_t size);

int
LLVMFuzzerTestOneInput(const guint8 *data, size_t size)
{
    GError *error = NULL;
    DriftTable *table, *again;
    gchar *text;
    gint i;

    table = drift_table_parse((const gchar*)data, size, "fuzz.csv", &error);
    if (!table) {
        if (!error)
            abort();
        check_message(error->message);
        g_error_free(error);
        return 0;
    }
    text = drift_table_to_string(table);
    again = drift_table_parse(text, -1, "again.csv", &error);
    if (!again || again->n_stripes != table->n_stripes)
        abort();
    for (i = 0; i < table->n_stripes; i++) {
        if (again->rows[i].has_drift != table->rows[i].has_drift
            || (table->rows[i].has_drift
                && (again->rows[i].dx != table->rows[i].dx
                    || again->rows[i].dy != table->rows[i].dy)))
            abort();
    }
    drift_table_free(again);
    drift_table_free(table);
    g_free(text);
    return 0;
}
