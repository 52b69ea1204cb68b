/*
 *  Conditioning of raw instrument channels before registration: what
 *  correlation must see is the sample, not the scanner's artefacts.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_FRAME_CONDITIONING_H
#define LOCALSCAN_FRAME_CONDITIONING_H

#include <glib.h>

G_BEGIN_DECLS

/* A conditioned copy of a channel; the user's data is never touched. */
typedef struct {
    gint xres;
    gint yres;
    gdouble *data;           /* yres x xres, unit RMS, 0 where missing */
    gdouble *weight;         /* yres x xres, 1 where valid, 0 where missing;
                                after the band-pass, a missing pixel among
                                data holds the band-pass's estimate with
                                the narrow blur's coverage (0.5 to 1) for
                                weight */
    gdouble *levelled;       /* the same without the band-pass's wide cut
                                (line offsets, strokes and the column trend
                                removed, the narrow blur, line medians,
                                unit RMS), for the fine stages of
                                registration: the wide cut, which a search
                                over large shifts needs, paints texture
                                into featureless regions and moves content
                                near the frame's edges; NULL in a
                                downsampled frame */
    gdouble valid_fraction;  /* of the pixels, valid in the data given
                                (1: every weight is 1) */
    gdouble narrow_sigma;    /* px, the band-pass's narrow blur: within
                                about twice this of the frame's edge the
                                blur is one-sided and moves content */
} ConditionedFrame;

/* Conditions data (yres x xres, row-major): NaN and infinite pixels, and
 * pixels where exclude (may be NULL) is above 0.5, are missing and carry no
 * weight (those among data get the band-pass's estimate and a weight of
 * its coverage, see weight).  Then, on the valid pixels: per-scan-line offsets (medians of the
 * differences of adjacent lines), strokes one line tall, the plane along x
 * and the bow (a quadratic fitted to the column medians), and a band-pass
 * that keeps features between a pixel or more (more
 * where pixel noise outweighs them) and a twentieth of the frame (against
 * 1/f noise, planes and bows).  pixel_aspect is the physical height of
 * a pixel over its width, so that the band is the same physical size along
 * both axes.  Returns NULL when no pixel is valid. */
ConditionedFrame* frame_condition          (const gdouble *data,
                                            const gdouble *exclude,
                                            gint xres,
                                            gint yres,
                                            gdouble pixel_aspect);

/* The same in two steps, for two frames that must get one band-pass:
 * steps up to the band-pass, ... */
ConditionedFrame* frame_condition_level    (const gdouble *data,
                                            const gdouble *exclude,
                                            gint xres,
                                            gint yres);
/* ... the narrow blur (px) a levelled frame's pixel noise calls for, ... */
gdouble           conditioned_frame_noise_scale(const ConditionedFrame *frame,
                                                gdouble pixel_aspect);
/* The variance of a levelled frame's white pixel noise, robustly: from
 * the median difference of neighbouring pixels along the lines, which
 * sparse features raise for few pixels.  (The noise scale above weighs
 * noise against the features by mean squares, where a few small sharp
 * particles count as noise: on a simulated series' frame that read about
 * 200 times this, and featureless lines could not be told by it.) */
gdouble           conditioned_frame_pixel_noise(const ConditionedFrame *frame);
/* The variance of each line's valid pixels (NaN with fewer than 8), for
 * a levelled frame (its lines' offsets, plane and bow removed); an array
 * of yres for g_free(). */
gdouble*          conditioned_frame_line_variances(const ConditionedFrame *frame);
/* ... and the rest, with the larger of the two frames' narrow blurs. */
void              conditioned_frame_band_pass(ConditionedFrame *frame,
                                              gdouble pixel_aspect,
                                              gdouble narrow_sigma);

/* Block means over factor x factor pixels (valid pixels only); a block with
 * no valid pixel is missing. */
ConditionedFrame* conditioned_frame_downsample(const ConditionedFrame *frame,
                                               gint factor);

/* A copy of its own, for a frame levelled once and band-passed for each
 * partner. */
ConditionedFrame* conditioned_frame_copy   (const ConditionedFrame *frame);

void              conditioned_frame_free   (ConditionedFrame *frame);

G_END_DECLS

#endif
