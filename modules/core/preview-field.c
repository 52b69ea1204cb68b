/*
 *  The dialog's preview of a large image.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <math.h>
#include <libgwyddion/gwymacros.h>
#include "preview-field.h"

struct _PreviewField {
    GwyDataField *source;     /* the reduced copy, or the image (a ref) */
    GwyDataField *result;
    GwyDataField *mask;
    gdouble xscale;           /* preview px per image px */
    gdouble yscale;
    gboolean reduced;
};

PreviewField*
preview_field_new(GwyDataField *field, gint max_size)
{
    PreviewField *preview = g_new0(PreviewField, 1);
    gint xres = gwy_data_field_get_xres(field), yres = gwy_data_field_get_yres(field);
    gint longest = MAX(xres, yres), pxres, pyres;

    g_return_val_if_fail(max_size >= 1, NULL);
    preview->reduced = (longest > max_size);
    if (preview->reduced) {
        pxres = MAX(1, GWY_ROUND((gdouble)xres*max_size/longest));
        pyres = MAX(1, GWY_ROUND((gdouble)yres*max_size/longest));
        /* Sampled at the preview pixels' centres by linear interpolation:
         * this does not average the pixels a preview pixel covers (period-2
         * columns of 0 and 1 come out 0.55-0.98), so fine noise aliases into
         * the preview; the final run measures and compensates the image
         * itself. */
        preview->source = gwy_data_field_new_resampled(field, pxres, pyres,
                                                       GWY_INTERPOLATION_LINEAR);
    }
    else
        preview->source = g_object_ref(field);
    preview->xscale = (gdouble)gwy_data_field_get_xres(preview->source)/xres;
    preview->yscale = (gdouble)gwy_data_field_get_yres(preview->source)/yres;
    preview->result = gwy_data_field_new_alike(preview->source, TRUE);
    preview->mask = gwy_data_field_new_alike(preview->source, TRUE);
    return preview;
}

PreviewField*
preview_field_new_with_result(GwyDataField *field, GwyDataField *result, GwyDataField *mask)
{
    PreviewField *preview = g_new0(PreviewField, 1);

    preview->source = g_object_ref(field);
    preview->result = g_object_ref(result);
    preview->mask = g_object_ref(mask);
    preview->xscale = preview->yscale = 1.0;
    return preview;
}

void
preview_field_free(PreviewField *preview)
{
    if (!preview)
        return;
    g_object_unref(preview->source);
    g_object_unref(preview->result);
    g_object_unref(preview->mask);
    g_free(preview);
}

/* The preview pixels [*lo, *hi] along one axis that cover source pixel c
 * (scale: preview pixels per source pixel) or whose sample (the reduced
 * copy is sampled at the preview pixels' centres) is within a pixel of it. */
static void
preview_span(gint c, gdouble scale, gint n, gint *lo, gint *hi)
{
    gint cover = (gint)floor(c*scale);

    *lo = MAX(MIN(cover, (gint)ceil((c - 0.5)*scale - 0.5)), 0);
    *hi = MIN(MAX(cover, (gint)floor((c + 1.5)*scale - 0.5)), n - 1);
}

GwyDataField*
preview_field_reduce_mask(const PreviewField *preview, GwyDataField *mask)
{
    GwyDataField *reduced;
    const gdouble *m;
    gdouble *d;
    gint xres, yres, pxres, pyres, r, c, i, j, ilo, ihi, jlo, jhi;

    if (!mask)
        return NULL;
    if (!preview->reduced)
        return g_object_ref(mask);
    xres = gwy_data_field_get_xres(mask);
    yres = gwy_data_field_get_yres(mask);
    reduced = gwy_data_field_new_alike(preview->source, TRUE);
    pxres = gwy_data_field_get_xres(reduced);
    pyres = gwy_data_field_get_yres(reduced);
    m = gwy_data_field_get_data_const(mask);
    d = gwy_data_field_get_data(reduced);
    for (r = 0; r < yres; r++) {
        for (c = 0; c < xres; c++) {
            if (!(m[(gsize)r*xres + c] > 0.5))
                continue;
            preview_span(r, (gdouble)pyres/yres, pyres, &ilo, &ihi);
            preview_span(c, (gdouble)pxres/xres, pxres, &jlo, &jhi);
            for (i = ilo; i <= ihi; i++) {
                for (j = jlo; j <= jhi; j++)
                    d[(gsize)i*pxres + j] = 1.0;
            }
        }
    }
    gwy_data_field_invalidate(reduced);
    return reduced;
}

gboolean
preview_field_is_reduced(const PreviewField *preview)
{
    return preview->reduced;
}

gint
preview_field_xres(const PreviewField *preview)
{
    return gwy_data_field_get_xres(preview->source);
}

gint
preview_field_yres(const PreviewField *preview)
{
    return gwy_data_field_get_yres(preview->source);
}

GwyDataField*
preview_field_source(PreviewField *preview)
{
    return preview->source;
}

GwyDataField*
preview_field_result(PreviewField *preview)
{
    return preview->result;
}

GwyDataField*
preview_field_mask(PreviewField *preview)
{
    return preview->mask;
}

static void
scale_value(gdouble *v, gdouble scale, gboolean whole_pixels)
{
    *v *= scale;
    if (whole_pixels)
        *v = drift_px_round(*v);
}

static DriftTable*
scaled_table(const DriftTable *table, gdouble xscale, gdouble yscale, gboolean whole_pixels)
{
    DriftTable *scaled = drift_table_copy(table);
    gdouble v;
    gint s;

    if (table->unit != DRIFT_UNIT_PX)
        return scaled;
    for (s = 0; s < scaled->n_stripes; s++) {
        DriftTableRow *row = scaled->rows + s;

        if (row->has_drift) {
            scale_value(&row->dx, xscale, whole_pixels);
            scale_value(&row->dy, yscale, whole_pixels);
        }
        if (drift_table_get_extra(scaled, s, "dx_exact", &v))
            drift_table_set_extra(scaled, s, "dx_exact", v*xscale);
        if (drift_table_get_extra(scaled, s, "dy_exact", &v))
            drift_table_set_extra(scaled, s, "dy_exact", v*yscale);
    }
    return scaled;
}

DriftTable*
preview_field_table(const PreviewField *preview, const DriftTable *table, gboolean whole_pixels)
{
    if (!preview->reduced)
        return drift_table_copy(table);
    return scaled_table(table, preview->xscale, preview->yscale, whole_pixels);
}

DriftTable*
preview_field_table_to_image(const PreviewField *preview, const DriftTable *table)
{
    if (!preview->reduced)
        return drift_table_copy(table);
    return scaled_table(table, 1.0/preview->xscale, 1.0/preview->yscale, FALSE);
}

gboolean
preview_field_compensate(PreviewField *preview, const DriftTable *table,
                         gboolean table_in_preview_px, const LocalscanOptions *options,
                         LocalscanApplied *applied, GError **error)
{
    LocalscanOptions scaled_options = *options;
    DriftTable *scaled;
    gboolean ok;

    if (!preview->reduced) {
        return localscan_compensate_field(preview->source, table, options,
                                          preview->result, preview->mask, applied, error);
    }
    if (table_in_preview_px)
        scaled = drift_table_copy(table);
    else
        scaled = preview_field_table(preview, table, options->mode == LOCALSCAN_MODE_PAPER);
    scaled_options.line_time = options->line_time/preview->yscale;
    ok = localscan_compensate_field(preview->source, scaled, &scaled_options,
                                    preview->result, preview->mask, applied, error);
    drift_table_free(scaled);
    return ok;
}
