/*
 *  Random drift effects hidden in simulated frame series, and their blind
 *  fit (see hidden-effect-cases.c for the ranges and tolerances).
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef TESTS_HIDDEN_EFFECT_CASES_H
#define TESTS_HIDDEN_EFFECT_CASES_H

#include <glib.h>
#include <json-glib/json-glib.h>
#include "drift-model.h"

G_BEGIN_DECLS

#define HIDDEN_CASE_FRAMES 4
#define HIDDEN_CASE_EFFECTS 5

/* The effect of case i: none, settling, oscillation, jump, acceleration
 * in turn. */
DriftModelType hidden_case_effect       (gint i);
/* The index (0 .. HIDDEN_CASE_EFFECTS - 1) of an effect among them, or
 * HIDDEN_CASE_EFFECTS for a type that is none of them. */
gint           hidden_case_effect_index (DriftModelType type);

/* Case i of a run: effect hidden_case_effect(i). */
void         hidden_case_draw        (guint32 base_seed, gint i,
                                      DriftModel *model);
/* Scans the frames into .gwy files in dir (no timing stored). */
gchar**      hidden_case_make_frames (guint32 base_seed, gint i,
                                      const DriftModel *model,
                                      const gchar *dir);
/* Runs `simscan fit` on the files alone (timing as options); NULL when it
 * fails.  The object belongs to parser. */
JsonObject*  hidden_case_fit         (gchar **files, const gchar *dir,
                                      JsonParser *parser);
gdouble      hidden_case_pair        (JsonObject *obj, const gchar *name,
                                      gint i);
/* NULL when the fitted parameters are within tolerance, else why not. */
gchar*       hidden_case_check       (gint i, const DriftModel *model,
                                      JsonObject *result);

G_END_DECLS

#endif
