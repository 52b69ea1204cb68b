/*
 *  Sub-pixel shift of a stripe: Gauss-Newton matching of the stripe
 *  against the reference interpolated at fractional shifts.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_STRIPE_SUBPIXEL_H
#define LOCALSCAN_STRIPE_SUBPIXEL_H

#include <glib.h>

G_BEGIN_DECLS

typedef struct _StripeSubpixel StripeSubpixel;

/* image and reference are yres x xres, row-major; weight and ref_weight
 * (either may be NULL: all valid) are the image's and the reference's
 * pixel weights, 0 on their missing pixels (a weight between 0 and 1
 * lowers a pixel's share, times its gradient taps'); window holds xres
 * column weights.  All must outlive the object.  Stripes up to max_height rows can
 * be refined.  Image pixels within edge_margin of the frame's edge take no
 * part (filtered frames are biased there), nor do those whose reference
 * sample reaches a missing pixel. */
StripeSubpixel* stripe_subpixel_new   (const gdouble *image,
                                       const gdouble *reference,
                                       const gdouble *weight,
                                       const gdouble *ref_weight,
                                       gint xres,
                                       gint yres,
                                       const gdouble *window,
                                       gint max_height,
                                       gint edge_margin);
void            stripe_subpixel_free  (StripeSubpixel *sp);

/* Refines the shift (dy, dx) (table convention: reference content at (r, c)
 * appears in the image at (r + dy, c + dx)) of image rows first .. end-1,
 * starting from the given values, which must lie within reach px (per
 * axis) of the whole-pixel shift (anchor_dy, anchor_dx).  Returns FALSE,
 * leaving dy and dx unchanged, when the match does not converge within that
 * square, too little of the stripe stays on the reference, or less than
 * half of it meets reference pixels present (the rest in a hole).  sigma
 * (may be NULL) gets the standard uncertainty of the shift, px; row (may
 * be NULL) the image row whose shift it is (see refine_rows). */
gboolean        stripe_subpixel_refine(StripeSubpixel *sp,
                                       gint first,
                                       gint end,
                                       gint anchor_dy,
                                       gint anchor_dx,
                                       gint reach,
                                       gdouble *dy,
                                       gdouble *dx,
                                       gdouble *sigma,
                                       gdouble *row);

G_END_DECLS

#endif
