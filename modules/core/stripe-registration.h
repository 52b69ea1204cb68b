/*
 *  Drift measured from the data: each stripe of an image registered against
 *  a reference frame of the same area (FFT cross-correlation, FFTW).
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_STRIPE_REGISTRATION_H
#define LOCALSCAN_STRIPE_REGISTRATION_H

#include <glib.h>
#include <libprocess/datafield.h>
#include <libprocess/gwyprocessenums.h>
#include "drift-table.h"
#include "frame-conditioning.h"

G_BEGIN_DECLS

#define STRIPE_REGISTRATION_ERROR stripe_registration_error_quark()

typedef enum {
    STRIPE_REGISTRATION_ERROR_SIZE,     /* image and reference differ, or too small */
    STRIPE_REGISTRATION_ERROR_STRIPES,  /* n outside 1..yres */
    STRIPE_REGISTRATION_ERROR_VALUE,    /* no valid pixel, or a bad prediction */
    STRIPE_REGISTRATION_ERROR_NO_MATCH, /* no stripe could be registered */
} StripeRegistrationError;

/* A min_score that rejects featureless and ambiguous (periodic) stripes but
 * keeps every well-textured one; what the tools use unless told otherwise. */
#define STRIPE_REGISTRATION_DEFAULT_MIN_SCORE 0.25
/* The largest shift searched by default, as a fraction of the frame in
 * each axis: beyond it too little of a stripe can still lie on the
 * reference for a match to mean anything. */
#define STRIPE_REGISTRATION_WHOLE_FRAME 0.45

typedef struct {
    gdouble search_x;      /* largest |dx| searched, px; <= 0: the whole frame
                              (STRIPE_REGISTRATION_WHOLE_FRAME of xres) */
    gdouble search_y;      /* the same for dy and yres */
    gdouble min_score;     /* stripes scoring less are left empty */
    gdouble pixel_aspect;  /* physical height over width of a pixel */
    /* For the field functions: the channels' masks (either may be NULL)
     * and what they mean to the registration.  GWY_MASK_EXCLUDE: masked
     * pixels are missing (Gwyddion's importers mask the pixels a file
     * lacks and fill them); GWY_MASK_INCLUDE: only masked pixels are
     * data; GWY_MASK_IGNORE (the default): masks do not matter. */
    GwyDataField *image_mask;
    GwyDataField *reference_mask;
    GwyMaskingType masking;
} StripeRegistrationOptions;

typedef struct {
    gdouble dx;        /* px: content of the reference at (r, c) appears in */
    gdouble dy;        /* the image at (r + dy, c + dx), the table convention;
                          at the stripe's centre row (the stripe's mean for a
                          drift changing linearly over its rows) */
    gdouble score;     /* confidence in [0, 1] */
    gdouble sigma;     /* px: standard uncertainty of dx and dy (the larger
                          of the two), from the match's residual; 0 when
                          not measured */
    gboolean accepted; /* score >= min_score and a sub-pixel match */
    gboolean in_reference; /* at the shift the coarse stage found, most of
                              the stripe lies on the reference (TRUE when
                              there was nothing to tell) */
    gdouble row;       /* the image row whose shift dx, dy are: the centre
                          row, except where the sub-pixel match fitted one
                          shift for all the stripe's rows, which is the
                          shift of the rows whose texture decided it (rows
                          by the frame's edge, which the filters reach,
                          decide nothing); a drift changing over the rows
                          is measured at that row */
    /* Diagnostics. */
    gdouble peak;      /* normalised cross-correlation at the chosen peak */
    gdouble rival;     /* the highest competing peak (in the window used) */
    gboolean resolved; /* the stripe's own best peak disagreed with its
                          neighbours and was replaced by the best one near
                          their prediction */
} StripeShift;

/* Whether the measured stripes can support a result. */
typedef struct {
    gint stripes;          /* n */
    gint in_reference;     /* stripes whose content lies in the reference */
    gint measured;         /* accepted stripes */
    gdouble median_score;  /* over the measured stripes */
    gboolean supported;    /* at least two stripes and at least half of those
                              in the reference measured */
} StripeRegistrationSupport;

GQuark       stripe_registration_error_quark(void);

void         stripe_registration_options_init(StripeRegistrationOptions *options);

/* Measures n stripes of image against reference (same xres, yres, raw
 * channels: both are conditioned first, see frame-conditioning.h).  NaN and
 * infinite pixels are missing and carry no weight.  The search runs coarse
 * to fine: the whole frame's shift at reduced resolution, then bands of
 * rows, then every stripe on its own at full resolution around its band's
 * shift, so that a jump between two stripes is measured, not smoothed.
 * options may be NULL (defaults). */
gboolean     stripe_registration_measure (const gdouble *image,
                                          const gdouble *reference,
                                          gint xres,
                                          gint yres,
                                          gint n,
                                          const StripeRegistrationOptions *options,
                                          StripeShift *shifts,
                                          GError **error);

/* Each stripe searched only within radius_px (in both axes) of its
 * predicted shift (px, table convention), with no coarse stage: for shifts
 * known roughly beforehand, such as those of a frame series registered
 * against an older frame.  The peaks that compete for a stripe's score are
 * those within its window. */
gboolean     stripe_registration_measure_around(const gdouble *image,
                                                const gdouble *reference,
                                                gint xres,
                                                gint yres,
                                                gint n,
                                                const gdouble *predicted_dx,
                                                const gdouble *predicted_dy,
                                                gdouble radius_px,
                                                gdouble min_score,
                                                StripeShift *shifts,
                                                GError **error);

/* A frame conditioned once for registration against several others (a
 * series registers each frame against its neighbours): the steps up to
 * the band-pass are its own; the band-pass, which two frames share (the
 * noisier frame's), is made with the frame's own band beforehand and for
 * a pair that asks for another one when registered.  Not changed after:
 * several threads may register it at once.  NULL when the frame is
 * smaller than 4 x 4 px or has no valid pixel. */
typedef struct _StripeRegistrationFrame StripeRegistrationFrame;

StripeRegistrationFrame* stripe_registration_frame_new(const gdouble *data,
                                                       gint xres,
                                                       gint yres,
                                                       gdouble pixel_aspect);

void         stripe_registration_frame_free(StripeRegistrationFrame *frame);

/* stripe_registration_measure_around() for two such frames, conditioned
 * as it would condition them, with a narrow blur of at least min_narrow
 * px (0: the frames' own noise scale).  Without uncertainty, the shifts'
 * sigma is not computed (0; it costs more than the sub-pixel match
 * itself), and a stripe is not rejected for a sigma as wide as its
 * search window. */
gboolean     stripe_registration_measure_around_frames(const StripeRegistrationFrame *image,
                                                       const StripeRegistrationFrame *reference,
                                                       gint n,
                                                       const gdouble *predicted_dx,
                                                       const gdouble *predicted_dy,
                                                       gdouble radius_px,
                                                       gdouble min_narrow,
                                                       gdouble min_score,
                                                       gboolean uncertainty,
                                                       StripeShift *shifts,
                                                       GError **error);

/* The whole frame's shift (px, table convention) within radius_x_px
 * columns and radius_y_px rows of the predicted one (each at most half the
 * frame's side), to the correlation map's resolution (its peak refined by
 * a quadratic), without the sub-pixel match, which would cost as much as
 * all the stripes' together: where to search the stripes (at half
 * resolution on frames of 128 px and more).  shift->peak is the
 * correlation at the peak.  min_narrow as above. */
gboolean     stripe_registration_frame_shift(const StripeRegistrationFrame *image,
                                             const StripeRegistrationFrame *reference,
                                             gdouble predicted_dx,
                                             gdouble predicted_dy,
                                             gdouble radius_x_px,
                                             gdouble radius_y_px,
                                             gdouble min_narrow,
                                             StripeShift *shift);

/* The same for two channels; refuses (with a message giving both sizes)
 * fields or masks of different pixel dimensions.  The pixel aspect comes
 * from the image's pixel sizes (options' is ignored); pixels the masks
 * make missing carry no weight; options may be NULL. */
gboolean     stripe_registration_measure_fields(GwyDataField *image,
                                                GwyDataField *reference,
                                                gint n,
                                                const StripeRegistrationOptions *options,
                                                StripeShift *shifts,
                                                GError **error);

/* A px table of the shifts: rejected stripes are blank (nearest-stripe rule),
 * with dx_exact, dy_exact, score and sigma_px columns. */
DriftTable*  stripe_registration_to_table(const StripeShift *shifts, gint n,
                                          gboolean whole_pixels);

/* What the tool and the module call: measures and returns the table (see
 * above), or NULL with an error when the sizes differ, n is out of range,
 * or no stripe is accepted.  support (may be NULL) says whether the
 * measured stripes support the result; a table is returned either way. */
DriftTable*  stripe_registration_table_for_fields(GwyDataField *image,
                                                  GwyDataField *reference,
                                                  gint n,
                                                  const StripeRegistrationOptions *options,
                                                  gboolean whole_pixels,
                                                  StripeRegistrationSupport *support,
                                                  GError **error);

/* How many stripes were accepted. */
gint         stripe_registration_count_accepted(const StripeShift *shifts,
                                                gint n);

void         stripe_registration_support(const StripeShift *shifts,
                                         gint n,
                                         StripeRegistrationSupport *support);

/* One line for a result that is not supported, e.g. "only 3 of the 12
 * stripes whose content lies in the reference were measured"; NULL when
 * it is supported. */
gchar*       stripe_registration_support_message(const StripeRegistrationSupport *support);

G_END_DECLS

#endif
