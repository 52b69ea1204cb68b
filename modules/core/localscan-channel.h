/*
 *  Local-scan compensation of one channel (a GwyDataField in a container):
 *  the GTK-free part of the Gwyddion module, usable by the tools too.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef LOCALSCAN_CHANNEL_H
#define LOCALSCAN_CHANNEL_H

#include <glib.h>
#include <libgwyddion/gwycontainer.h>
#include <libprocess/datafield.h>
#include "drift-table.h"
#include "scan-timing.h"

G_BEGIN_DECLS

/* The new channel's title is the source title followed by this suffix.  It
 * is part of the command-line interface (scripts find the channel by it), so
 * it is never translated. */
#define LOCALSCAN_TITLE_SUFFIX " (local-scan compensated)"

/* Metadata items of ours that describe the content of the channel they
 * are attached to, not its scan (the simulator's particle positions, in
 * the drift-contaminated image): a compensated copy must not carry them. */
#define LOCALSCAN_META_SIMULATED_PARTICLES "Simulated particles (px)"

/* Line time assumed when the channel's metadata does not give one. */
#define LOCALSCAN_DEFAULT_LINE_TIME 1.0

#define LOCALSCAN_CHANNEL_ERROR localscan_channel_error_quark()

typedef enum {
    LOCALSCAN_CHANNEL_ERROR_NO_TABLE,     /* no table stored with the channel */
    LOCALSCAN_CHANNEL_ERROR_UNITS,        /* physical table, non-metre image */
    LOCALSCAN_CHANNEL_ERROR_REFERENCE,    /* no usable reference image */
    LOCALSCAN_CHANNEL_ERROR_STRIPES,      /* more stripes than image rows */
    LOCALSCAN_CHANNEL_ERROR_COMPENSATED,  /* the channel is a result already */
} LocalscanChannelError;

/* The values are stored in the settings: never renumber them. */
typedef enum {
    LOCALSCAN_SOURCE_STORED    = 0,   /* DRIFT_TABLE_META_KEY of the channel */
    LOCALSCAN_SOURCE_FILE      = 1,   /* a CSV file */
    LOCALSCAN_SOURCE_REFERENCE = 2,   /* registration against a reference image */
} LocalscanSource;

typedef enum {
    LOCALSCAN_MODE_PAPER      = 0,
    LOCALSCAN_MODE_CONTINUOUS = 1,
} LocalscanMode;

typedef enum {
    LOCALSCAN_FILL_MEAN    = 0,      /* the paper's d */
    LOCALSCAN_FILL_ZERO    = 1,
    LOCALSCAN_FILL_MINIMUM = 2,
    LOCALSCAN_FILL_MAXIMUM = 3,
} LocalscanFill;

typedef struct {
    LocalscanMode mode;
    LocalscanFill fill;
    GwyInterpolationType interpolation;   /* continuous mode only */
    gdouble line_time;                    /* s, continuous mode only */
    ScanDirection direction;              /* continuous mode only */
    gdouble frame_start;                  /* s, continuous mode only, in the
                                             clock of the table's t_image,
                                             t_local */
} LocalscanOptions;

/* The parts of a channel's scan timing its metadata gave. */
typedef enum {
    LOCALSCAN_TIMING_LINE_TIME   = 1 << 0,
    LOCALSCAN_TIMING_DIRECTION   = 1 << 1,
    LOCALSCAN_TIMING_FRAME_START = 1 << 2,
} LocalscanTimingFound;

/* What one compensation applied: the drift of every stripe in pixels after
 * unit conversion and the nearest-stripe rule. */
typedef struct {
    gint n_stripes;
    gdouble *dx_px;
    gdouble *dy_px;
    gint n_filled;
} LocalscanApplied;

GQuark       localscan_channel_error_quark   (void);

gchar*       localscan_channel_result_title  (const gchar *source_title);

/* How messages name the table stored with channel id: "FILE, channel ID
 * drift table" ("channel ID drift table" without filename), followed by
 * ":LINE: problem". */
gchar*       localscan_channel_table_label   (const gchar *filename,
                                              gint id);
/* The text stored with channel id (item DRIFT_TABLE_META_KEY of its
 * metadata "/<id>/meta"), or NULL. */
const gchar* localscan_channel_stored_table_text(GwyContainer *data,
                                                 gint id);
/* The table stored with channel id, parsed; the label without file name is
 * the source name in messages. */
DriftTable*  localscan_channel_stored_table  (GwyContainer *data,
                                              gint id,
                                              GError **error);
/* The same named for messages as localscan_channel_table_label(filename,
 * id) names it; a missing table is "FILE: channel ID has no stored drift
 * table (...)" (code LOCALSCAN_CHANNEL_ERROR_NO_TABLE). */
DriftTable*  localscan_channel_stored_table_of_file(GwyContainer *data,
                                                    gint id,
                                                    const gchar *filename,
                                                    GError **error);
/* Store the table (its text) with channel id, in its metadata, which is
 * created if absent; other metadata items are kept. */
void         localscan_channel_store_table   (GwyContainer *data,
                                              gint id,
                                              const DriftTable *table);
void         localscan_channel_store_table_text(GwyContainer *data,
                                                gint id,
                                                const gchar *text);

/* The scan timing of channel id (its field's xres, yres) from its metadata
 * "/<id>/meta" as scan_timing_meta_read() finds it; where it says nothing:
 * line time LOCALSCAN_DEFAULT_LINE_TIME, fallback_direction, frame start 0.
 * A frame start that is a date (Nanoscope "Date", Anasys "TimeStamp") is
 * not used: a table's t_image, t_local columns are in the frame start's
 * clock, and no table is written in dates.  Returns the parts found in the
 * metadata. */
LocalscanTimingFound localscan_channel_scan_timing(GwyContainer *data,
                                                   gint id,
                                                   ScanDirection fallback_direction,
                                                   ScanTiming *timing);
/* The same with every fallback given: the module's settings (line time,
 * slow-scan direction, frame start) stand in for what the metadata does
 * not say; the metadata always wins. */
LocalscanTimingFound localscan_channel_scan_timing_fallback(GwyContainer *data,
                                                            gint id,
                                                            gdouble fallback_line_time,
                                                            ScanDirection fallback_direction,
                                                            gdouble fallback_frame_start,
                                                            ScanTiming *timing);

/* Removes from channel id's metadata the items that describe the source's
 * content (LOCALSCAN_META_SIMULATED_PARTICLES); for a new channel made from
 * a copy of its source's metadata. */
void         localscan_channel_drop_source_meta(GwyContainer *data,
                                                gint id);

gdouble      localscan_fill_value            (GwyDataField *field,
                                              LocalscanFill fill);

/* Converts the table to pixels of field (its own x and y pixel sizes);
 * physical tables need a field whose lateral unit is the metre. */
gboolean     localscan_table_to_field_pixels (const DriftTable *table,
                                              GwyDataField *field,
                                              gboolean whole_pixels,
                                              gdouble *dx_px,
                                              gdouble *dy_px,
                                              GError **error);

/* Compensates field into result (resized and given field's geometry and
 * units); mask (may be NULL) gets 1.0 at filled pixels, dimensionless.
 * applied (may be NULL) is filled; free it with localscan_applied_clear().
 * field is never changed.  On failure result and mask are unspecified. */
gboolean     localscan_compensate_field      (GwyDataField *field,
                                              const DriftTable *table,
                                              const LocalscanOptions *options,
                                              GwyDataField *result,
                                              GwyDataField *mask,
                                              LocalscanApplied *applied,
                                              GError **error);
void         localscan_applied_clear         (LocalscanApplied *applied);

/* Whether localscan_compensate_field() would accept table and options for
 * field, with the same errors, without compensating it (continuous mode
 * plans its resampling; work of the order of the rows, not the pixels). */
gboolean     localscan_compensate_check      (GwyDataField *field,
                                              const DriftTable *table,
                                              const LocalscanOptions *options,
                                              GError **error);
/* The stripes whose local scans continuous compensation of field with
 * table and options leaves out of its trajectory as gross errors (the
 * robust smoothing gives them a weight below DRIFT_TRAJECTORY_DOWNWEIGHTED:
 * a local scan that found another particle, a value mistyped) and lie more
 * than LOCALSCAN_LEFT_OUT_MIN_PX from it (local scans scatter by tenths of
 * a pixel, and a tenth may be an outlier among exact ones), in table
 * order, into stripes and their distance from it (px) into off_px (may be
 * NULL; room for table->n_stripes each); returns how many, -1 with error
 * where the trajectory cannot be built.  Paper mode leaves none out (0). */
#define LOCALSCAN_LEFT_OUT_MIN_PX 1.0
gint         localscan_continuous_left_out   (GwyDataField *field,
                                              const DriftTable *table,
                                              const LocalscanOptions *options,
                                              gint *stripes,
                                              gdouble *off_px,
                                              GError **error);

/* A copy of a px table with dx, dy rounded to whole pixels by
 * drift_px_round(), as stripe_registration_to_table() rounds them, extra
 * columns kept: the paper-mode form of a measured table, made without
 * measuring again. */
DriftTable*  localscan_table_round_px        (const DriftTable *table);

/* The drift the table states for each stripe that has one, in px of field:
 * dx_exact, dy_exact preferred, blank stripes left out (no nearest-stripe
 * filling).  stripes[], dx_px[], dy_px[] need room for table->n_stripes.
 * Returns how many stripes were written, or -1 with error set. */
gint         localscan_table_stated_px       (const DriftTable *table,
                                              GwyDataField *field,
                                              gint *stripes,
                                              gdouble *dx_px,
                                              gdouble *dy_px,
                                              GError **error);

/* Registration compares the image with another scan of the same area:
 * TRUE when reference has the image's pixels, physical size, lateral
 * unit and value unit (the same quantity). */
gboolean     localscan_reference_fits        (GwyDataField *image,
                                              GwyDataField *reference);
/* The same with a message naming both, and n_stripes (< 1: not checked)
 * at most half the image's rows (a stripe of one row cannot be
 * registered). */
gboolean     localscan_reference_check       (GwyDataField *image,
                                              const gchar *image_name,
                                              GwyDataField *reference,
                                              const gchar *reference_name,
                                              gint n_stripes,
                                              GError **error);

/* The centre of stripe (of n_stripes) in y, physical, with the field's y
 * offset: where a stripe's drift is plotted. */
gdouble      localscan_stripe_centre_y       (GwyDataField *field,
                                              gint stripe,
                                              gint n_stripes);

/* Stripe drift as curves in physical units: ypos[s] the stripe's centre
 * (lateral unit, with the field's y offset), dx[s], dy[s] the drift. */
void         localscan_applied_to_physical   (const LocalscanApplied *applied,
                                              GwyDataField *field,
                                              gdouble *ypos,
                                              gdouble *dx,
                                              gdouble *dy);

/* The ids of data's channels (items "/ID/data" holding a data field) in
 * ascending order, terminated by -1; free with g_free().  What Gwyddion's
 * data browser lists, without its GUI library. */
gint*        localscan_channel_ids           (GwyContainer *data);

/* The ids of data's channels titled exactly title, as
 * localscan_channel_ids() gives them (possibly none: ids[0] == -1). */
gint*        localscan_channel_ids_titled    (GwyContainer *data,
                                              const gchar *title);
/* "0, 3": ids (terminated by -1) as messages list them; g_free(). */
gchar*       localscan_channel_id_list       (const gint *ids);

/* The object at "/ID/ITEM" of data (item "data": the channel's field,
 * "mask", "meta"), or NULL when there is none; no reference is added. */
gpointer     localscan_channel_item          (GwyContainer *data,
                                              gint id,
                                              const gchar *item);
/* The channel's metadata container ("/ID/meta"), created when absent if
 * create, else NULL when absent; no reference is added. */
GwyContainer* localscan_channel_meta         (GwyContainer *data,
                                              gint id,
                                              gboolean create);
/* The string item key of the channel's metadata, or NULL when the channel
 * has no metadata or no such string; owned by the container. */
const gchar* localscan_channel_meta_string   (GwyContainer *data,
                                              gint id,
                                              const gchar *key);
/* The channel's title ("/ID/data/title"), or NULL. */
const gchar* localscan_channel_title         (GwyContainer *data,
                                              gint id);
/* The channel's mask when it is one: a data field of the channel's pixels
 * holding no NaN; NULL when there is none or when something else is
 * stored there (a field of another size, a container: a damaged or
 * hand-made file), which no step may treat as a mask. */
GwyDataField* localscan_channel_mask         (GwyContainer *data,
                                              gint id);
/* Removes from data every mask that is not one of its channel (see
 * localscan_channel_mask), for a file the tools write and Gwyddion
 * opens; returns the ids of the channels that lost one, -1 terminated
 * (g_free() it). */
gint*        localscan_channels_drop_misfit_masks(GwyContainer *data);
/* Missing pixels (NaN, infinite; docs/missing-data.md) of every image
 * channel of data are replaced by the mean of the channel's present pixels
 * and marked in its mask (made, or added to), as Gwyddion's importers do:
 * a file the tools write holds no NaN.  Returns how many were filled. */
gsize        localscan_channels_fill_missing (GwyContainer *data);

/* Why a run without a GUI failed, handed from the process function to its
 * caller (gwy-localscan) through the data container it ran on: object data,
 * never saved with the file.  set keeps a copy of error; take returns it
 * (NULL when the run left none) and removes it. */
void         localscan_run_error_set         (GwyContainer *data,
                                              const GError *error);
GError*      localscan_run_error_take        (GwyContainer *data);

G_END_DECLS

#endif
