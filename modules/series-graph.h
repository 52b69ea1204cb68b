/*
 *  The graph of a series' drift trajectory (docs/series.md): dx(t) and
 *  dy(t) fitted on every scan line, and the block measurements as points
 *  (each measured displacement added to the fit at the earlier moment), in
 *  metres against seconds.  Gwyddion's graph model lives in its widget
 *  library, outside the GTK-free core.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_SERIES_GRAPH_H
#define LOCALSCAN_SERIES_GRAPH_H

#include <libgwydgets/gwygraphmodel.h>
#include "series-correction.h"

G_BEGIN_DECLS

GwyGraphModel*  series_graph_new  (const SeriesCorrection *correction,
                                   const FrameSeries *series);
/* Puts the graph's legend in the corner of the plot its curves' points
 * crowd least (the legend covered the measurements where they
 * cluster). */
void            series_graph_place_legend(GwyGraphModel *graph);

G_END_DECLS

#endif
