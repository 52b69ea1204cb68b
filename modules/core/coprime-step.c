/*
 *  Steps through a regular layout that visit every position alike.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include "coprime-step.h"

static gsize
greatest_common_divisor(gsize a, gsize b)
{
    while (b) {
        gsize t = a % b;

        a = b;
        b = t;
    }
    return a;
}

gsize
coprime_step(gsize least, gsize period)
{
    gsize step = MAX(least, 1);

    if (period < 2)
        return step;
    while (greatest_common_divisor(step, period) != 1)
        step++;
    return step;
}
