/*
 *  How the row loops of continuous compensation are vectorised: chunks of
 *  constant length, and per-processor clones picked when the library loads.
 *  Internal to the core.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_VECTOR_LOOPS_H
#define LOCALSCAN_VECTOR_LOOPS_H

#include <glib.h>

G_BEGIN_DECLS

/* Columns per inner loop.  A constant count lets GCC vectorise at -O2,
 * whose cost model refuses loops that would need a scalar epilogue; 16
 * doubles are whole vectors for SSE2 and AVX2 alike. */
enum { ROW_CHUNK = 16 };

/* The only place that knows about processor dispatch.  A function marked
 * VECTOR_CLONES is compiled twice where GCC can pick the version when the
 * library is loaded: for the x86-64 baseline (SSE2, two doubles per
 * vector) and for x86-64-v3 (AVX2 and FMA, four), which halves the
 * instruction count of the hot row loops.  Results of the two differ by
 * rounding only (FMA).  Elsewhere (other compilers, older GCC, other
 * processors or systems without ifunc) it is empty and the plain code is
 * built once. */
#if defined(__GNUC__) && !defined(__clang__) && __GNUC__ >= 11 \
    && defined(__x86_64__) && defined(__linux__)
#define VECTOR_CLONES \
    __attribute__((target_clones("arch=x86-64-v3", "default")))
#else
#define VECTOR_CLONES /* */
#endif

G_END_DECLS

#endif
