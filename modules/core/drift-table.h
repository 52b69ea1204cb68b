/*
 *  The per-stripe drift table (docs/drift-table.md):
 *  reading, validation, physical-unit conversion and writing.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_DRIFT_TABLE_H
#define LOCALSCAN_DRIFT_TABLE_H

#include <glib.h>

G_BEGIN_DECLS

/* Where a drift table is stored with a channel in a GwyContainer: the CSV
 * text as the string item of this name in the channel's metadata container
 * "/<id>/meta".  Gwyddion's file validator knows only its own keys, and the
 * metadata is where it keeps a channel's extra information for users to see
 * (the metadata browser). */
#define DRIFT_TABLE_META_KEY "Local-scan drift table"

/* A drift beyond this many pixels is nonsense for any image; refusing it lets
 * callers cast pixel drift to gint safely. */
#define DRIFT_TABLE_MAX_PIXELS 1e9

#define DRIFT_TABLE_ERROR drift_table_error_quark()

typedef enum {
    DRIFT_TABLE_ERROR_IO,          /* unreadable file */
    DRIFT_TABLE_ERROR_SYNTAX,      /* missing header, wrong column count, bad number */
    DRIFT_TABLE_ERROR_VALUE,       /* NaN/inf, fraction where whole pixels needed */
    DRIFT_TABLE_ERROR_STRIPES,     /* missing, repeated or unordered stripe */
    DRIFT_TABLE_ERROR_UNIT,        /* unknown unit */
    DRIFT_TABLE_ERROR_IMAGE,       /* does not fit the image (too many stripes) */
    DRIFT_TABLE_ERROR_EMPTY,       /* no stripe has a drift at all */
} DriftTableError;

typedef enum {
    DRIFT_UNIT_PX = 0,
    DRIFT_UNIT_M,
    DRIFT_UNIT_NM,
    DRIFT_UNIT_UM,
} DriftUnit;

/* One stripe's row.  Extra columns are kept as their original text so that a
 * table read and written again is the same table. */
typedef struct {
    gint stripe;
    gboolean has_drift;    /* FALSE for a blank dx,dy: no particle */
    gdouble dx;            /* in the table's unit; 0 when !has_drift */
    gdouble dy;
    gint line;             /* line number in the source text, 1-based */
} DriftTableRow;

typedef struct {
    gchar *source_name;    /* file name or other label used in messages */
    DriftUnit unit;
    gboolean unit_given;   /* the text had a '# units:' line */
    gint n_stripes;
    DriftTableRow *rows;   /* n_stripes */
    gint n_extra;          /* extra columns after stripe,dx,dy */
    gchar **extra_names;   /* n_extra */
    gchar **extra_values;  /* n_stripes*n_extra, row-major; "" where blank */
    gint header_line;
} DriftTable;

GQuark       drift_table_error_quark    (void);

DriftTable*  drift_table_new            (gint n_stripes, DriftUnit unit);
void         drift_table_free           (DriftTable *table);
DriftTable*  drift_table_copy           (const DriftTable *table);

/* Parsing.  source_name is used in every message ("FILE:LINE: problem"). */
DriftTable*  drift_table_parse          (const gchar *text,
                                         gssize length,
                                         const gchar *source_name,
                                         GError **error);
DriftTable*  drift_table_load           (const gchar *filename,
                                         GError **error);

/* Writing exactly the interface format.  save writes to a temporary file and
 * renames it, so no half-written table is ever left behind. */
gchar*       drift_table_to_string      (const DriftTable *table);
gboolean     drift_table_save           (const DriftTable *table,
                                         const gchar *filename,
                                         GError **error);

/* Sets stripe's drift in the table's unit; NaN in either clears it (a blank
 * dx,dy: no particle). */
void         drift_table_set_drift      (DriftTable *table,
                                         gint stripe,
                                         gdouble dx,
                                         gdouble dy);

/* Extra columns. */
gint         drift_table_find_column    (const DriftTable *table,
                                         const gchar *name);
/* Value of an extra column as a number; FALSE when blank or absent. */
gboolean     drift_table_get_extra      (const DriftTable *table,
                                         gint stripe,
                                         const gchar *name,
                                         gdouble *value);
/* Sets (adding the column if needed) an extra value; NaN writes a blank. */
void         drift_table_set_extra      (DriftTable *table,
                                         gint stripe,
                                         const gchar *name,
                                         gdouble value);

/* The whole pixel nearest to v, halves away from zero (-0.5 -> -1, 0.5 ->
 * 1, -1.5 -> -2): the one rounding of drift to whole pixels, so a drift
 * and its negative round to opposite shifts.  Never a negative zero. */
gdouble      drift_px_round             (gdouble v);

const gchar* drift_unit_name            (DriftUnit unit);
gboolean     drift_unit_from_name       (const gchar *name, DriftUnit *unit);

/* Checks the table against an image of yres rows: at most yres stripes and at
 * least one stripe with drift.  The message names the source and line. */
gboolean     drift_table_check_image    (const DriftTable *table,
                                         gint yres,
                                         GError **error);

/* Converts to pixels with the image's pixel sizes (metres per pixel; x and y
 * may differ; ignored for px tables) and applies the nearest-stripe rule.
 * dx_px, dy_px get n_stripes values.  With whole_pixels, a px table with a
 * fraction (more than 1e-9 from an integer) is refused (paper mode), and
 * physical values are rounded to the nearest pixel (halves away from zero);
 * the results are then exact integers that fit a gint.  A drift of more than
 * 1e9 pixels is refused in either case.  Calls drift_table_check_image()
 * first.  Tables built with drift_table_new() are named "drift table" in
 * messages, with the line numbers they would have when written. */
gboolean     drift_table_to_pixels      (const DriftTable *table,
                                         gint yres,
                                         gdouble x_pixel_size,
                                         gdouble y_pixel_size,
                                         gboolean whole_pixels,
                                         gdouble *dx_px,
                                         gdouble *dy_px,
                                         GError **error);

G_END_DECLS

#endif
