/*
 *  The dialog's preview of a large image: a reduced copy, made once, that
 *  every change of a setting compensates instead of the whole image, so
 *  that the dialog answers at once on 4096 x 4096.  An image no larger than
 *  the preview is previewed as it is, exactly.  GTK-free.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_PREVIEW_FIELD_H
#define LOCALSCAN_PREVIEW_FIELD_H

#include <glib.h>
#include <libprocess/datafield.h>
#include "drift-table.h"
#include "localscan-channel.h"

G_BEGIN_DECLS

/* The longest side of a reduced copy, px: about the dialog's preview. */
#define PREVIEW_FIELD_SIZE 512

typedef struct _PreviewField PreviewField;

/* A preview of field; reduced (its pixels averaged) when a side exceeds
 * max_size.  field must outlive it and not change. */
PreviewField* preview_field_new        (GwyDataField *field,
                                        gint max_size);
/* An exact preview of field whose result and mask are the given fields
 * (referenced), e.g. where the final result will be made anyway. */
PreviewField* preview_field_new_with_result(GwyDataField *field,
                                            GwyDataField *result,
                                            GwyDataField *mask);
void          preview_field_free       (PreviewField *preview);
gboolean      preview_field_is_reduced (const PreviewField *preview);
gint          preview_field_xres       (const PreviewField *preview);
gint          preview_field_yres       (const PreviewField *preview);
/* The field previewed: the reduced copy, or the image itself. */
GwyDataField* preview_field_source     (PreviewField *preview);
/* A mask of the image (its size) in the reduced copy's pixels: a preview
 * pixel is masked when any pixel it covers is, or one its value was
 * interpolated from (a new field; the mask itself, referenced, when the
 * copy is not reduced; NULL for NULL). */
GwyDataField* preview_field_reduce_mask(const PreviewField *preview,
                                        GwyDataField *mask);
/* The compensated preview and its filled-pixel mask (preview size). */
GwyDataField* preview_field_result     (PreviewField *preview);
GwyDataField* preview_field_mask       (PreviewField *preview);

/* A table of the image's pixels in the reduced copy's pixels: dx, dy and
 * dx_exact, dy_exact scaled, rounded to whole pixels when whole_pixels;
 * physical tables are copied as they are.  A new table. */
DriftTable*   preview_field_table      (const PreviewField *preview,
                                        const DriftTable *table,
                                        gboolean whole_pixels);

/* The other way: a table of the reduced copy's pixels (registered on it)
 * in the image's pixels, not rounded.  A new table. */
DriftTable*   preview_field_table_to_image(const PreviewField *preview,
                                           const DriftTable *table);

/* Compensates the preview with a table of the image (its pixels or
 * physical), or of the preview's pixels when table_in_preview_px, and the
 * image's options: the line time is scaled so that every reduced row
 * keeps the time of the image rows it stands for.  applied (may be NULL)
 * is in the preview's pixels. */
gboolean      preview_field_compensate (PreviewField *preview,
                                        const DriftTable *table,
                                        gboolean table_in_preview_px,
                                        const LocalscanOptions *options,
                                        LocalscanApplied *applied,
                                        GError **error);

G_END_DECLS

#endif
