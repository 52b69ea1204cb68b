/*
 *  Displacement measurements of a frame series: blocks of rows of each
 *  frame registered against the earlier frames, each tied to the scan times
 *  of the rows involved (drift-fit.h's DriftMeasurement).
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_DISPLACEMENT_MEASURE_H
#define LOCALSCAN_DISPLACEMENT_MEASURE_H

#include <glib.h>
#include "frame-series.h"
#include "drift-fit.h"
#include "progress.h"

G_BEGIN_DECLS

#define DISPLACEMENT_HELD_BYTES ((gsize)768 << 20)

typedef struct {
    gint n_blocks;          /* blocks of rows per frame (default 16) */
    gdouble max_shift;      /* fraction of the frame searched for the frame's
                               overall shift (default 0.25) */
    gdouble block_range;    /* fraction searched around it per block
                               (default 0.08, at least 4 px) */
    gdouble min_score;      /* accepted blocks correlating worse are
                               dropped too (0.3) */
    gint pair_reach;        /* frames are registered against the earlier
                               frames up to this many apart; 0 (default):
                               every earlier frame */
    gsize held_bytes;       /* frames prepared for registration held at
                               once within about this (default 768 MB; 0:
                               the default); frames not held are prepared
                               again per pair, with the same result */
} DisplacementOptions;

void               displacement_options_init (DisplacementOptions *options);

/* Registers one image against a reference of the same size with the core's
 * stripe registration (stripe_registration_measure_around_frames): n blocks of
 * rows, each giving (dx, dy) px in the drift-table convention (content of the
 * reference at (r, c) appears in the image at (r + dy, c + dx)) and a score
 * (the normalised correlation at the peak of a block the registration
 * accepted, else 0).  The raw frames go to the registration's own
 * conditioning (raw-channel artefacts, missing pixels); pixel_aspect is the
 * physical dy/dx of a pixel.  The frame's overall shift
 * (the whole frame as one stripe) is searched around guess (px, may be NULL:
 * around 0, within max_shift) and stored in global (dx, dy, correlation; may
 * be NULL), to the correlation map's resolution only; the blocks are
 * searched within block_range of it. */
void               displacement_register_blocks(const gdouble *image,
                                                const gdouble *reference,
                                                gint xres,
                                                gint yres,
                                                gint n,
                                                const DisplacementOptions *options,
                                                gdouble pixel_aspect,
                                                const gdouble *guess,
                                                gdouble *dx,
                                                gdouble *dy,
                                                gdouble *score,
                                                gdouble *global);

/* All measurements of the series (metres, seconds); *n gets their count.
 * Block b of frame k against frame j becomes one measurement of group b;
 * with a pair reach (a long series), an older pair whose frames hardly
 * change within themselves comes in displacement_tall_blocks() taller
 * blocks (displacement-measure.c, older_pair_blocks), each of the group of
 * the block at its centre. */
/* How many blocks an older pair of nearly rigid frames of a long series
 * is registered in, for n_blocks blocks a pair: a quarter, each four times
 * taller, where that leaves four or more; else n_blocks. */
gint               displacement_tall_blocks (gint n_blocks);

DriftMeasurement*  displacement_measure_series(const FrameSeries *series,
                                               const DisplacementOptions *options,
                                               gint *n);
/* The same, telling progress after each chunk of frames; NULL when
 * progress stopped it. */
DriftMeasurement*  displacement_measure_series_progress(const FrameSeries *series,
                                                        const DisplacementOptions *options,
                                                        const Progress *progress,
                                                        gint *n);

/* How many frames displacement_measure_series() prepares per chunk
 * (*chunk) and how many older prepared frames it holds for the next
 * chunks' pairs (*keep): within options->held_bytes, down to 2 and 1. */
void               displacement_held_frames (const FrameSeries *series,
                                             const DisplacementOptions *options,
                                             gint *chunk,
                                             gint *keep);

G_END_DECLS

#endif
