/*
 *  Output rows as weighted sums of a few rows, written past the caches.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <string.h>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#include "row-combine.h"
#include "vector-loops.h"

/* Writes ROW_CHUNK values to dest, past the caches where the processor can
 * (x86: non-temporal stores, dest 16-byte aligned).  Output rows are
 * written once and not read here; an ordinary store first reads every line
 * it writes, and for an image beyond the caches that read doubles the
 * traffic of writing it.  The combining loops compute a chunk into a small
 * buffer first: GCC vectorises that, and the stores then take whole
 * vectors from it. */
static inline void
stream_chunk(gdouble *dest, const gdouble *block)
{
#if defined(__SSE2__)
    gint j;

    if (((guintptr)dest & 15) == 0) {
        for (j = 0; j < ROW_CHUNK; j += 2)
            _mm_stream_pd(dest + j, _mm_loadu_pd(block + j));
        return;
    }
#endif
    memcpy(dest, block, ROW_CHUNK*sizeof(gdouble));
}

/* Non-temporal stores are weakly ordered: the fence makes them visible
 * before anything done after the call. */
void
row_stream_finish(void)
{
#if defined(__SSE2__)
    _mm_sfence();
#endif
}

void
row_copy_streamed(const gdouble *restrict src, gint n, gdouble *restrict dest)
{
    gint c = 0;

    for (; c + ROW_CHUNK <= n; c += ROW_CHUNK)
        stream_chunk(dest + c, src + c);
    for (; c < n; c++)
        dest[c] = src[c];
}

/* dest = w1 r1 + w2 r2, streamed. */
static void VECTOR_CLONES
combine_two_rows(const gdouble *restrict r1, const gdouble *restrict r2,
                 gdouble w1, gdouble w2, gint n, gdouble *restrict dest)
{
    gdouble block[ROW_CHUNK];
    gint c = 0, j;

    for (; c + ROW_CHUNK <= n; c += ROW_CHUNK) {
        for (j = 0; j < ROW_CHUNK; j++)
            block[j] = w1*r1[c + j] + w2*r2[c + j];
        stream_chunk(dest + c, block);
    }
    for (; c < n; c++)
        dest[c] = w1*r1[c] + w2*r2[c];
}

void VECTOR_CLONES
row_combine_streamed(const gdouble **rows, const gdouble *w, gint n,
                     gdouble *restrict dest)
{
    const gdouble *restrict r0 = rows[0], *restrict r1 = rows[1];
    const gdouble *restrict r2 = rows[2], *restrict r3 = rows[3];
    gdouble w0 = w[0], w1 = w[1], w2 = w[2], w3 = w[3], block[ROW_CHUNK];
    gint c = 0, j;

    if (w0 == 0.0 && w3 == 0.0) {
        combine_two_rows(r1, r2, w1, w2, n, dest);
        return;
    }
    for (; c + ROW_CHUNK <= n; c += ROW_CHUNK) {
        for (j = 0; j < ROW_CHUNK; j++) {
            block[j] = (w0*r0[c + j] + w1*r1[c + j]
                        + w2*r2[c + j] + w3*r3[c + j]);
        }
        stream_chunk(dest + c, block);
    }
    for (; c < n; c++)
        dest[c] = w0*r0[c] + w1*r1[c] + w2*r2[c] + w3*r3[c];
}
