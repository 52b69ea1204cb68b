/*
 *  Registration of large frames at half resolution, where their texture
 *  holds nothing finer than the full-resolution match would use.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_REGISTRATION_BINNING_H
#define LOCALSCAN_REGISTRATION_BINNING_H

#include <glib.h>

G_BEGIN_DECLS

/* The factor (1 or 2) by which both frames (yres x xres, NaN missing) may
 * be binned before n stripes are registered: 2 only for frames of
 * REGISTRATION_BINNING_MIN_SIDE px and more on either side, stripes
 * keeping several binned rows, and textures of both frames whose
 * registered content (what the band-pass keeps) lies almost all below
 * the binned frame's Nyquist frequency along both axes. */
#define REGISTRATION_BINNING_MIN_SIDE 1024

gint     registration_binning_factor     (const gdouble *image,
                                          const gdouble *reference,
                                          gint xres,
                                          gint yres,
                                          gint n);

/* What binning by two would lose or garble of a frame's registered texture
 * along one axis, as a share (0 to 1) of it: the power spectrum of sampled
 * lines above its white-noise floor, weighted as the narrow blur and the
 * match's gradients weigh it, from a fifth to a quarter of a cycle per
 * pixel (too near the binned frame's Nyquist frequency), and above a
 * quarter as what comes back aliased at 0.5 - f.  1 when no sampled line
 * is whole or nothing stands above the noise. */
gdouble  registration_fine_texture_share (const gdouble *data,
                                          gint xres,
                                          gint yres,
                                          gboolean along_x);

/* The means of factor x factor blocks ((xres/factor) x (yres/factor);
 * the last columns and rows that make no whole block are left out); a
 * block with a missing pixel is missing (NaN): half-missing blocks would
 * move the hole's edge by a fraction of a block. */
gdouble* registration_bin_frame          (const gdouble *data,
                                          gint xres,
                                          gint yres,
                                          gint factor);

G_END_DECLS

#endif
