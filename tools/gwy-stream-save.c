/*
 *  Writing a .gwy file without building it in memory first.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <errno.h>
#include <stdio.h>
#include <string.h>
#include <glib/gstdio.h>
#include <libgwyddion/gwymacros.h>
#include <libgwyddion/gwyserializable.h>
#include <libprocess/datafield.h>
#include "gwy-stream-save.h"

#undef _
#define _(s) dgettext(GETTEXT_PACKAGE, s)

/*
 * Gwyddion's own writer serialises the whole container into one buffer and
 * then writes it: for a 4096 x 4096 channel, its result and mask, 384 MiB
 * more in memory.  Here the container is serialised by Gwyddion with every
 * large data field replaced by a 1 x 1 stand-in of the same geometry and
 * units (a few kilobytes), and that byte stream is copied to the file,
 * generically parsed (the GWY format: an object is its type name, a 32-bit
 * size and its components; a component is a name, a type letter and a
 * value), except that each stand-in's "xres", "yres" and "data" components
 * are written with the real field's values, the data straight from the
 * field.  Only the format's framing is assumed, never a component list.
 */

/* Fields with fewer values are serialised by Gwyddion as they are. */
#define STREAMED_MIN_VALUES 4096
#define GWY_MAGIC "GWYP"

typedef struct {
    FILE *file;
    GHashTable *stand_ins;     /* key quark -> the real GwyDataField */
    const guchar *p;           /* reading the stand-in container's bytes */
    const guchar *end;
    gboolean ok;
} Writer;

static void
put(Writer *w, const void *bytes, gsize n)
{
    if (w->ok && n && fwrite(bytes, 1, n, w->file) != n)
        w->ok = FALSE;
}

static void
put_u32(Writer *w, guint32 v)
{
    guchar b[4] = { v & 0xff, (v >> 8) & 0xff, (v >> 16) & 0xff, v >> 24 };

    put(w, b, 4);
}

static guint32
get_u32(const guchar *p)
{
    return p[0] | (p[1] << 8) | (p[2] << 16) | ((guint32)p[3] << 24);
}

/* Length of a NUL-terminated string at p, terminator included; 0 when it
 * runs past end. */
static gsize
string_size(const guchar *p, const guchar *end)
{
    const guchar *nul = memchr(p, '\0', end - p);

    return nul ? (gsize)(nul - p) + 1 : 0;
}

/* Size of one value of type t at p (an array's count included); 0 on a
 * malformed stream. */
static gsize
value_size(guchar t, const guchar *p, const guchar *end)
{
    static const struct { guchar type; gsize size; } fixed[] = {
        { 'b', 1 }, { 'c', 1 }, { 'i', 4 }, { 'q', 8 }, { 'd', 8 },
    };
    gsize size = 0, n, i, one;
    guint k;

    for (k = 0; k < G_N_ELEMENTS(fixed); k++) {
        if (t == fixed[k].type)
            return (gsize)(end - p) >= fixed[k].size ? fixed[k].size : 0;
        if (t == g_ascii_toupper(fixed[k].type) && t != 'B') {
            if (end - p < 4)
                return 0;
            size = 4 + get_u32(p)*(gsize)fixed[k].size;
            return size <= (gsize)(end - p) ? size : 0;
        }
    }
    if (t == 's')
        return string_size(p, end);
    if (t == 'o') {
        if (!(size = string_size(p, end)) || (gsize)(end - p) < size + 4)
            return 0;
        size += 4 + get_u32(p + size);
        return size <= (gsize)(end - p) ? size : 0;
    }
    if (t == 'S' || t == 'O') {
        if (end - p < 4)
            return 0;
        n = get_u32(p);
        size = 4;
        for (i = 0; i < n; i++) {
            if (!(one = value_size(g_ascii_tolower(t), p + size, end)))
                return 0;
            size += one;
        }
        return size;
    }
    return 0;
}

/* A stand-in data field written as the real one: the object's size grows
 * by the data it now holds. */
static void
put_field(Writer *w, GwyDataField *field, const guchar *p, const guchar *end)
{
    gsize n = (gsize)gwy_data_field_get_xres(field)*gwy_data_field_get_yres(field);
    gsize name_size = string_size(p, end), size, cn, vs;
    const guchar *q, *object_end;
    gint32 res;

    if (!name_size || (gsize)(end - p) < name_size + 4) {
        w->ok = FALSE;
        return;
    }
    size = get_u32(p + name_size);
    object_end = p + name_size + 4 + size;
    put(w, p, name_size);
    put_u32(w, size + 8*(n - 1));
    for (q = p + name_size + 4; w->ok && q < object_end; q += cn + 1 + vs) {
        if (!(cn = string_size(q, object_end)) || q + cn >= object_end
            || !(vs = value_size(q[cn], q + cn + 1, object_end))) {
            w->ok = FALSE;
            return;
        }
        put(w, q, cn + 1);
        if (q[cn] == 'i' && (gwy_strequal((const gchar*)q, "xres")
                             || gwy_strequal((const gchar*)q, "yres"))) {
            res = (gwy_strequal((const gchar*)q, "xres")
                   ? gwy_data_field_get_xres(field) : gwy_data_field_get_yres(field));
            put_u32(w, (guint32)res);
        }
        else if (q[cn] == 'D' && gwy_strequal((const gchar*)q, "data")) {
            put_u32(w, (guint32)n);
            put(w, gwy_data_field_get_data_const(field), n*sizeof(gdouble));
        }
        else
            put(w, q + cn + 1, vs);
    }
}

static void
add_growth(G_GNUC_UNUSED gpointer key, gpointer value, gpointer user_data)
{
    GwyDataField *field = (GwyDataField*)value;
    gsize *growth = (gsize*)user_data;

    *growth += 8*((gsize)gwy_data_field_get_xres(field)*gwy_data_field_get_yres(field) - 1);
}

/* The stand-in container's stream with the stand-ins written as the real
 * fields. */
static void
put_container(Writer *w)
{
    const guchar *p = w->p, *end = w->end, *object_end, *q;
    gsize name_size = string_size(p, end), size, growth = 0, cn, vs;
    GwyDataField *field;

    if (!name_size || (gsize)(end - p) < name_size + 4) {
        w->ok = FALSE;
        return;
    }
    size = get_u32(p + name_size);
    object_end = p + name_size + 4 + size;
    if (object_end > end) {
        w->ok = FALSE;
        return;
    }
    g_hash_table_foreach(w->stand_ins, add_growth, &growth);
    if (size + growth > G_MAXUINT32) {
        w->ok = FALSE;
        return;
    }
    put(w, p, name_size);
    put_u32(w, size + growth);
    for (q = p + name_size + 4; w->ok && q < object_end; q += cn + 1 + vs) {
        if (!(cn = string_size(q, object_end)) || q + cn >= object_end
            || !(vs = value_size(q[cn], q + cn + 1, object_end))) {
            w->ok = FALSE;
            return;
        }
        field = (q[cn] == 'o'
                 ? g_hash_table_lookup(w->stand_ins,
                                       GUINT_TO_POINTER(g_quark_try_string((const gchar*)q)))
                 : NULL);
        put(w, q, cn + 1);
        if (field)
            put_field(w, field, q + cn + 1, q + cn + 1 + vs);
        else
            put(w, q + cn + 1, vs);
    }
}

/* Every item of data in proxy, a large data field as a 1 x 1 stand-in. */
static void
add_item(gpointer hkey, gpointer hvalue, gpointer user_data)
{
    GQuark key = GPOINTER_TO_UINT(hkey);
    GValue *value = (GValue*)hvalue;
    GwyContainer *proxy = (GwyContainer*)user_data;
    GHashTable *stand_ins = g_object_get_data(G_OBJECT(proxy), "stand-ins");
    GwyDataField *field, *stand_in;
    GObject *object;

    if (G_VALUE_HOLDS_OBJECT(value) && (object = g_value_get_object(value))
        && GWY_IS_DATA_FIELD(object)) {
        field = GWY_DATA_FIELD(object);
        if ((gsize)gwy_data_field_get_xres(field)*gwy_data_field_get_yres(field)
            >= STREAMED_MIN_VALUES) {
            stand_in = gwy_data_field_new(1, 1, gwy_data_field_get_xreal(field),
                                          gwy_data_field_get_yreal(field), TRUE);
            gwy_data_field_set_xoffset(stand_in, gwy_data_field_get_xoffset(field));
            gwy_data_field_set_yoffset(stand_in, gwy_data_field_get_yoffset(field));
            gwy_si_unit_assign(gwy_data_field_get_si_unit_xy(stand_in),
                               gwy_data_field_get_si_unit_xy(field));
            gwy_si_unit_assign(gwy_data_field_get_si_unit_z(stand_in),
                               gwy_data_field_get_si_unit_z(field));
            gwy_container_set_object(proxy, key, stand_in);
            g_object_unref(stand_in);
            g_hash_table_insert(stand_ins, GUINT_TO_POINTER(key), field);
            return;
        }
    }
    gwy_container_set_value(proxy, key, value, NULL);
}

gboolean
gwy_stream_save(GwyContainer *data, const gchar *filename, GError **error)
{
    return gwy_stream_save_as(data, filename, filename, error);
}

gboolean
gwy_stream_save_as(GwyContainer *data, const gchar *filename,
                   const gchar *shown_name, GError **error)
{
    GwyContainer *proxy = gwy_container_new();
    GHashTable *stand_ins = g_hash_table_new(NULL, NULL);
    GByteArray *bytes;
    Writer w;
    gint saved_errno = 0;

    g_return_val_if_fail(G_BYTE_ORDER == G_LITTLE_ENDIAN, FALSE);
    g_object_set_data(G_OBJECT(proxy), "stand-ins", stand_ins);
    gwy_container_foreach(data, NULL, add_item, proxy);
    bytes = gwy_serializable_serialize(G_OBJECT(proxy), NULL);

    w.stand_ins = stand_ins;
    w.p = bytes->data;
    w.end = bytes->data + bytes->len;
    w.ok = TRUE;
    if (!(w.file = g_fopen(filename, "wb"))) {
        saved_errno = errno;
        w.ok = FALSE;
    }
    else {
        put(&w, GWY_MAGIC, 4);
        put_container(&w);
        if (!w.ok)
            saved_errno = errno;
        if (fclose(w.file) != 0 && w.ok) {
            saved_errno = errno;
            w.ok = FALSE;
        }
    }
    if (!w.ok) {
        g_set_error(error, G_FILE_ERROR, g_file_error_from_errno(saved_errno),
                    _("cannot write %s: %s"), shown_name,
                    saved_errno ? g_strerror(saved_errno) : _("malformed serialised data"));
    }
    g_byte_array_free(bytes, TRUE);
    g_hash_table_destroy(stand_ins);
    g_object_unref(proxy);
    return w.ok;
}
