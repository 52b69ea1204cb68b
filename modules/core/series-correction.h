/*
 *  Correcting a whole frame series (docs/series.md): the displacements
 *  between its frames measured, one absolute drift trajectory p(t) fitted
 *  to them, frames that disagree with the rest flagged and left out of the
 *  fit, and every frame corrected line by line from the trajectory into the
 *  coordinate frame of the start of the first frame.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_SERIES_CORRECTION_H
#define LOCALSCAN_SERIES_CORRECTION_H

#include <glib.h>
#include <json-glib/json-glib.h>
#include <libprocess/datafield.h>
#include <libprocess/gwyprocessenums.h>
#include "frame-series.h"
#include "fit-report.h"
#include "drift-trajectory.h"
#include "smooth-trajectory.h"
#include "progress.h"

G_BEGIN_DECLS

/* The metadata item that marks a channel corrected by the series
 * correction (its value says how): such a channel is no frame of a
 * series to be corrected again. */
#define SERIES_CORRECTED_META_KEY "Drift correction"
/* How its value begins, by the tool that made the channel. */
#define SERIES_CORRECTED_BY_TOOL "gwy-localscan series"
#define SERIES_CORRECTED_BY_DIALOG "Local Scan Series Drift"

#define SERIES_CORRECTION_ERROR series_correction_error_quark()

typedef enum {
    SERIES_CORRECTION_ERROR_FIT,      /* too few frames registered */
    SERIES_CORRECTION_ERROR_COMPENSATE, /* the trajectory folds a frame */
    SERIES_CORRECTION_ERROR_CANCELLED,  /* progress stopped it */
} SeriesCorrectionError;

/* What the series says about one frame. */
typedef struct {
    gboolean flagged;
    gchar *reason;          /* why it is flagged (NULL when it is not) */
    gdouble residual_px;    /* how far its best-agreeing frame pair lies from
                               the trajectory: the median over that pair's
                               blocks of |measured - fitted|, px; NaN when
                               no pair of it was registered */
    gint n_pairs;           /* registered pairs it belongs to */
} SeriesFrameVerdict;

typedef struct {
    FitReport fit;          /* measurements and models (the final fit, the
                               flagged frames' measurements at weight 0) */
    gint n_frames;
    SeriesFrameVerdict *frames;
    gdouble typical_px;     /* the median pair residual of the series, px */
    GPtrArray *warnings;    /* strings */
    gdouble xstep, ystep;   /* pixel size of the frames, m */
    gdouble frame_nm;       /* the frames' smaller physical side, nm */
    gdouble span_s;         /* from t = 0 to the end of the last frame */
    SmoothTrajectory *smooth; /* the flexible trajectory fitted beside the
                                 models (NULL when it could not be) */
    gboolean use_smooth;    /* it predicts held-out blocks better than the
                               chosen model by the fit's cv_gain: the
                               trajectory is it */
    gint jump_tied_lines;   /* scan lines of frames not flagged that nothing
                               places on either side of the chosen jump
                               (docs/series.md, step 5); 0 when none */
    gdouble jump_window[2]; /* the times (s) between which the jump may lie
                               as far as those lines tell */
    /* private: the effect the last fit chose and refused as too large for
     * the frames (DriftModelType, -1: none), said once in the warnings */
    gint refused_type;
    gdouble refused_nm;
} SeriesCorrection;

/* Pairs of frames registered in a long series: each frame against this
 * many earlier ones.  Short series register every pair. */
#define SERIES_CORRECTION_PAIR_REACH 3
#define SERIES_CORRECTION_ALL_PAIRS_UP_TO 16
/* Up to this many frames, each is judged by the fit of the others (a fit
 * per frame); longer series by the fit of all. */
#define SERIES_CORRECTION_LEAVE_OUT_UP_TO 8

GQuark    series_correction_error_quark(void);

/* Measures the series (doptions, NULL for defaults; a long series gets
 * SERIES_CORRECTION_PAIR_REACH unless doptions says otherwise), fits the
 * drift models (foptions, NULL for defaults), flags frames that disagree
 * and fits again without them.  FALSE with error set when no model could
 * be fitted (too few registered blocks), or when fewer than two frames
 * are left unflagged: nothing supports a trajectory.  The correction is
 * cleared with series_correction_clear() either way. */
gboolean  series_correction_compute   (const FrameSeries *series,
                                       const DisplacementOptions *doptions,
                                       const DriftFitOptions *foptions,
                                       SeriesCorrection *correction,
                                       GError **error);
/* The same, telling progress (NULL: none) how far it has come; FALSE with
 * SERIES_CORRECTION_ERROR_CANCELLED when progress stopped it. */
gboolean  series_correction_compute_progress(const FrameSeries *series,
                                             const DisplacementOptions *doptions,
                                             const DriftFitOptions *foptions,
                                             const Progress *progress,
                                             SeriesCorrection *correction,
                                             GError **error);
void      series_correction_clear     (SeriesCorrection *correction);

/* p(t) - p(0) of the chosen fit in pixels of the frames. */
void      series_correction_eval      (const SeriesCorrection *correction,
                                       gdouble t,
                                       gdouble *dx_px,
                                       gdouble *dy_px);

/* A fitted drift over one frame as the trajectory the continuous
 * compensation follows: D(t) = p(t) - p(0) in pixels of xstep by ystep
 * (m), sampled at every line (docs/series.md).  For studies that correct
 * frames with a fit of their own choosing. */
DriftTrajectory* series_fit_trajectory(const DriftFit *fit,
                                       gdouble xstep,
                                       gdouble ystep,
                                       const ScanTiming *timing,
                                       GError **error);

/* A field scanned with timing (a frame, or another channel of the same
 * scan) corrected line by line (continuous-compensate.h) into the
 * coordinate frame of t = 0: result and mask (1 where no data exists) are
 * resized and filled, result with the field's units and real sizes.
 * Pixels with no source get the field's mean. */
gboolean  series_correction_correct_field(const SeriesCorrection *correction,
                                          GwyDataField *field,
                                          const ScanTiming *timing,
                                          GwyInterpolationType interpolation,
                                          GwyDataField *result,
                                          GwyDataField *mask,
                                          GError **error);
/* The same for frame k of the series. */
gboolean  series_correction_correct_frame(const SeriesCorrection *correction,
                                          const FrameSeries *series,
                                          gint k,
                                          GwyInterpolationType interpolation,
                                          GwyDataField *result,
                                          GwyDataField *mask,
                                          GError **error);

/* The trajectory as CSV text (docs/series.md): comment lines, then
 * frame,row,t_s,dx_px,dy_px for every scan line of every frame, rows in
 * the order they were scanned. */
gchar*    series_correction_trajectory_csv(const SeriesCorrection *correction,
                                           const FrameSeries *series);

/* The JSON of `gwy-localscan series --json` (docs/series.md). */
gchar*    series_correction_to_json   (const SeriesCorrection *correction,
                                       const FrameSeries *series);

/* The largest rectangle (col, row, width, height) inside every mask
 * (1 = no data) of n same-sized masks; FALSE when no pixel is covered by
 * every frame. */
gboolean  series_correction_common_area(GwyDataField **masks,
                                        gint n,
                                        gint *col,
                                        gint *row,
                                        gint *width,
                                        gint *height);
/* The same over the masks of the frames not flagged (every frame's when
 * all are): a flagged frame's missing pixels do not shrink the area the
 * trusted ones share.  area gets col, row, width, height. */
gboolean  series_correction_trusted_area(const SeriesCorrection *correction,
                                         GwyDataField **masks,
                                         gint n,
                                         gint *area);
/* The part of field inside area (col, row, width, height), placed where it
 * lies (its offsets moved by the area's corner). */
GwyDataField* series_correction_crop_to_area(GwyDataField *field,
                                             const gint *area);

G_END_DECLS

#endif
