/*
 *  libFuzzer harness: input-file screening on arbitrary bytes, named .gwy
 *  and otherwise.  Whatever the bytes, it answers in bounded time without
 *  reading outside them, and a refusal names the file in one line.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <stdlib.h>
#include <string.h>
#include "file-screening.h"

int LLVMFuzzerTestOneInput(const guint8 *data, size_t size);

static void
screen(const gchar *name, const guint8 *data, size_t size)
{
    GError *error = NULL;
    /* A private copy of exactly size bytes: ASan sees any read past it. */
    guint8 *copy = size ? g_memdup2(data, size) : NULL;

    if (!file_screening_check_bytes(name, copy, size, &error)) {
        if (!error || !g_str_has_prefix(error->message, name) || strchr(error->message, '\n'))
            abort();
        g_error_free(error);
    }
    g_free(copy);
}

int
LLVMFuzzerTestOneInput(const guint8 *data, size_t size)
{
    screen("fuzz.gwy", data, size);
    screen("fuzz.sxm", data, size);
    return 0;
}
