/*
 *  simscan's summary on stdout: timing, per-stripe true and measured drift,
 *  particle-centre errors before and after compensation.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef SIMSCAN_REPORT_H
#define SIMSCAN_REPORT_H

#include <stdio.h>
#include "simscan-run.h"

G_BEGIN_DECLS

void  simscan_report_print        (FILE *fh,
                                   const SimscanScene *scene,
                                   const SimscanMeasurement *m);
/* One line: "before: RMS a px (b nm), max c px (d nm), e of f particles". */
void  simscan_report_centre_error (FILE *fh,
                                   const gchar *label,
                                   const CentreError *error);

G_END_DECLS

#endif
