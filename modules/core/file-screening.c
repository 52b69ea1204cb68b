/*
 *  Input files screened before Gwyddion's loaders read them.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <errno.h>
#include <math.h>
#include <string.h>
#include <unistd.h>
#include <glib/gstdio.h>
#include <gio/gio.h>
#include "file-screening.h"
#include "localscan-intl.h"

/* Gwyddion's native format: "GWYP" and one serialised object; "GWYO" is
 * the format of Gwyddion 1, whose container is laid out differently, so
 * only its outer frame is checked. */
#define GWY_MAGIC_SIZE 4
#define GWY_MAGIC      "GWYP"
#define GWY_MAGIC_OLD  "GWYO"
#define GWY_EXTENSION  ".gwy"

GQuark
file_screening_error_quark(void)
{
    return g_quark_from_static_string("file-screening-error-quark");
}

/* A walk through a serialised object tree, every length checked against
 * the bytes that are really there before anything is read. */
typedef struct {
    const guchar *bytes;
    gsize pos;
    const gchar *problem;    /* the first problem found, untranslated */
    gsize problem_at;
} GwyWalk;

/* What a GwyDataField or GwyDataLine says of its own size, to compare with
 * the data it carries. */
typedef struct {
    gint64 xres, yres, res;
    gint64 n_data;           /* -1: no data array */
    gdouble xreal, yreal;    /* physical size; 1 when not stated */
} FieldShape;

static gboolean
walk_fail(GwyWalk *w, const gchar *problem)
{
    if (!w->problem) {
        w->problem = problem;
        w->problem_at = w->pos;
    }
    return FALSE;
}

static gboolean
walk_string(GwyWalk *w, gsize end, const gchar **s)
{
    const guchar *nul = memchr(w->bytes + w->pos, 0, end - w->pos);

    if (!nul)
        return walk_fail(w, N_("truncated: a name or string runs past the end of its object"));
    *s = (const gchar*)(w->bytes + w->pos);
    w->pos = nul - w->bytes + 1;
    return TRUE;
}

static gboolean
walk_u32(GwyWalk *w, gsize end, guint32 *value)
{
    guint32 v;

    if (end - w->pos < sizeof(v))
        return walk_fail(w, N_("truncated: a size runs past the end of its object"));
    memcpy(&v, w->bytes + w->pos, sizeof(v));
    *value = GUINT32_FROM_LE(v);
    w->pos += sizeof(v);
    return TRUE;
}

static gboolean
walk_skip(GwyWalk *w, gsize end, guint64 n)
{
    if (end - w->pos < n)
        return walk_fail(w, N_("truncated: a value runs past the end of its object"));
    w->pos += n;
    return TRUE;
}

static gboolean
walk_double(GwyWalk *w, gsize end, gdouble *value)
{
    guint64 v;

    if (end - w->pos < sizeof(v))
        return walk_fail(w, N_("truncated: a value runs past the end of its object"));
    memcpy(&v, w->bytes + w->pos, sizeof(v));
    v = GUINT64_FROM_LE(v);
    memcpy(value, &v, sizeof(v));
    w->pos += sizeof(v);
    return TRUE;
}

static gboolean
walk_i32(GwyWalk *w, gsize end, gint64 *value)
{
    guint32 v;

    if (!walk_u32(w, end, &v))
        return FALSE;
    *value = (gint32)v;
    return TRUE;
}

/* Type names are C identifiers; anything else is not a type any loader
 * knows and would only be looked up in vain. */
static gboolean
is_type_name(const gchar *name)
{
    const gchar *p;

    if (!g_ascii_isalpha(*name) && *name != '_')
        return FALSE;
    for (p = name; *p; p++) {
        if (!g_ascii_isalnum(*p) && *p != '_')
            return FALSE;
    }
    return p - name <= 256;
}

static gboolean walk_object(GwyWalk *w, gsize end, guint depth, const gchar **type);

static gsize
scalar_size(gchar type)
{
    switch (g_ascii_tolower(type)) {
        case 'b': case 'c': return 1;
        case 'i': return 4;
        case 'q': case 'd': return 8;
        default: return 0;
    }
}

/* One component's value of type type; shape gets what matters of a field. */
static gboolean
walk_value(GwyWalk *w, gsize end, gchar type, const gchar *name, guint depth, FieldShape *shape)
{
    const gchar *s;
    guint32 count, i;
    gint64 v;

    if (type == 'i' && (g_str_equal(name, "xres") || g_str_equal(name, "yres")
                        || g_str_equal(name, "res"))) {
        if (!walk_i32(w, end, &v))
            return FALSE;
        *(name[0] == 'x' ? &shape->xres : name[0] == 'y' ? &shape->yres : &shape->res) = v;
        return TRUE;
    }
    if (type == 'd' && (g_str_equal(name, "xreal") || g_str_equal(name, "yreal")))
        return walk_double(w, end, name[0] == 'x' ? &shape->xreal : &shape->yreal);
    if (type == 's')
        return walk_string(w, end, &s);
    if (type == 'o')
        return walk_object(w, end, depth + 1, &s);
    if (g_ascii_islower(type) && scalar_size(type))
        return walk_skip(w, end, scalar_size(type));
    if (!strchr("CIQDSO", type) || !type)
        return walk_fail(w, N_("an unknown value type: not a Gwyddion file or a damaged one"));
    if (!walk_u32(w, end, &count))
        return FALSE;
    if (type == 'D' && g_str_equal(name, "data"))
        shape->n_data = count;
    if (scalar_size(type))
        return walk_skip(w, end, (guint64)count*scalar_size(type));
    /* Strings and objects take at least a byte each: a count beyond what
     * is left is refused before any loop. */
    if (count > end - w->pos)
        return walk_fail(w, N_("truncated: an array runs past the end of its object"));
    for (i = 0; i < count; i++) {
        if (!(type == 'S' ? walk_string(w, end, &s) : walk_object(w, end, depth + 1, &s)))
            return FALSE;
    }
    return TRUE;
}

/* Images and curves whose stated size disagrees with their data make
 * Gwyddion's deserialisers complain or worse. */
static gboolean
check_shape(GwyWalk *w, const gchar *type, const FieldShape *shape)
{
    if (g_str_equal(type, "GwyDataField")) {
        if (shape->xres < 1 || shape->yres < 1 || shape->n_data < 0
            || shape->xres*shape->yres != shape->n_data)
            return walk_fail(w, N_("an image whose size does not match its data"));
        /* Gwyddion takes a width of 0 or less for 1 m: a table in nm then
         * rounded to 0 px without a word. */
        if (!(shape->xreal > 0.0 && shape->yreal > 0.0)
            || !isfinite(shape->xreal) || !isfinite(shape->yreal))
            return walk_fail(w, N_("an image whose physical width or height is not a positive "
                                   "number"));
    }
    else if (g_str_equal(type, "GwyDataLine")) {
        if (shape->res < 1 || shape->n_data != shape->res)
            return walk_fail(w, N_("a curve whose size does not match its data"));
    }
    return TRUE;
}

/* A serialised object: type name, size, then components (name, type,
 * value) filling exactly that size. */
static gboolean
walk_object(GwyWalk *w, gsize end, guint depth, const gchar **type)
{
    FieldShape shape = { 0, 0, 0, -1, 1.0, 1.0 };
    const gchar *name;
    gsize object_end;
    guint32 size;
    gchar vtype;

    if (depth > FILE_SCREENING_MAX_DEPTH)
        return walk_fail(w, N_("objects nested too deeply"));
    if (!walk_string(w, end, type))
        return FALSE;
    if (!is_type_name(*type))
        return walk_fail(w, N_("an object without a valid type name"));
    if (!walk_u32(w, end, &size))
        return FALSE;
    if (size > end - w->pos)
        return walk_fail(w, N_("truncated: an object is larger than what is left of the file"));
    object_end = w->pos + size;
    while (w->pos < object_end) {
        if (!walk_string(w, object_end, &name))
            return FALSE;
        if (w->pos == object_end)
            return walk_fail(w, N_("truncated: a component has no value"));
        vtype = (gchar)w->bytes[w->pos++];
        if (!walk_value(w, object_end, vtype, name, depth, &shape))
            return FALSE;
    }
    return check_shape(w, *type, &shape);
}

static gboolean
screening_error(GError **error, gint code, const gchar *name, const gchar *problem)
{
    g_set_error(error, FILE_SCREENING_ERROR, code, "%s: %s", name, problem);
    return FALSE;
}

static gboolean
check_native(const gchar *name, const guchar *bytes, gsize length, GError **error)
{
    GwyWalk w = { bytes, GWY_MAGIC_SIZE, NULL, 0 };
    const gchar *type;
    guint32 size;
    gchar *msg;
    gboolean ok;

    if (length <= GWY_MAGIC_SIZE)
        return screening_error(error, FILE_SCREENING_ERROR_CORRUPT, name,
                               _("truncated: a Gwyddion file with nothing after its magic bytes"));
    if (memcmp(bytes, GWY_MAGIC, GWY_MAGIC_SIZE) == 0) {
        ok = walk_object(&w, length, 0, &type);
        if (ok && !g_str_equal(type, "GwyContainer"))
            ok = walk_fail(&w, N_("its data is not a Gwyddion container"));
    }
    else {
        ok = (walk_string(&w, length, &type) && is_type_name(type) && walk_u32(&w, length, &size)
              && (size <= length - w.pos
                  || walk_fail(&w, N_("truncated: an object is larger than what is left of "
                                      "the file"))));
        if (!ok && !w.problem)
            walk_fail(&w, N_("an object without a valid type name"));
    }
    if (ok)
        return TRUE;
    msg = g_strdup_printf(_("damaged Gwyddion file: %s (at byte %" G_GSIZE_FORMAT ")"),
                          _(w.problem), w.problem_at);
    screening_error(error, FILE_SCREENING_ERROR_CORRUPT, name, msg);
    g_free(msg);
    return FALSE;
}

static gboolean
has_magic(const guchar *bytes, gsize length, const gchar *magic)
{
    return length >= GWY_MAGIC_SIZE && memcmp(bytes, magic, GWY_MAGIC_SIZE) == 0;
}

/* A gzip stream (Anasys .axz, any .gz a loader unpacks) must decompress
 * to its end: a loader reads what it can of a cut one and hands on part
 * of the file's channels (a .axz cut at 1 MB of 3.5 MB was read, and
 * corrected, as if whole).  Every member is inflated (a file may hold
 * several, as bgzip and pigz write them) and the data dropped, at most
 * FILE_SCREENING_MAX_BYTES of them; after the last member only zero
 * padding may follow. */
/* The message below names the limit. */
G_STATIC_ASSERT(FILE_SCREENING_MAX_BYTES == ((gint64)4 << 30));

static gboolean
check_gzip(const gchar *name, const guchar *bytes, gsize length, GError **error)
{
    GConverter *inflater = G_CONVERTER(g_zlib_decompressor_new(G_ZLIB_COMPRESSOR_FORMAT_GZIP));
    GConverterResult result;
    guchar *out = g_malloc(1 << 16);
    gsize pos = 0, nread, nwritten;
    guint64 total = 0;
    const gchar *problem = NULL;
    gint code = FILE_SCREENING_ERROR_CORRUPT;

    while (!problem) {
        result = g_converter_convert(inflater, bytes + pos, length - pos, out, 1 << 16,
                                     G_CONVERTER_INPUT_AT_END, &nread, &nwritten, NULL);
        pos += nread;
        total += nwritten;
        if (total > (guint64)FILE_SCREENING_MAX_BYTES) {
            problem = N_("larger than 4 GiB once decompressed: refused");
            code = FILE_SCREENING_ERROR_SIZE;
        }
        else if (result == G_CONVERTER_ERROR || (result == G_CONVERTER_CONVERTED && !nread && !nwritten))
            problem = N_("truncated or corrupt: its compressed data do not decompress to their end");
        else if (result == G_CONVERTER_FINISHED) {
            while (pos < length && !bytes[pos])
                pos++;
            if (pos == length)
                break;
            if (length - pos < 2 || bytes[pos] != 0x1f || bytes[pos+1] != 0x8b)
                problem = N_("corrupt: something else than compressed data follows them");
            g_converter_reset(inflater);
        }
    }
    g_free(out);
    g_object_unref(inflater);
    return !problem || screening_error(error, code, name, _(problem));
}

gboolean
file_screening_check_bytes(const gchar *name, const guchar *bytes, gsize length, GError **error)
{
    gchar *lower;
    gboolean gwy_extension;

    g_return_val_if_fail(name && (bytes || !length), FALSE);
    if (!length)
        return screening_error(error, FILE_SCREENING_ERROR_SIZE, name, _("the file is empty"));
    if (has_magic(bytes, length, GWY_MAGIC) || has_magic(bytes, length, GWY_MAGIC_OLD))
        return check_native(name, bytes, length, error);
    lower = g_ascii_strdown(name, -1);
    gwy_extension = g_str_has_suffix(lower, GWY_EXTENSION);
    g_free(lower);
    if (gwy_extension)
        return screening_error(error, FILE_SCREENING_ERROR_TYPE, name,
                               _("not a Gwyddion file although named .gwy (it does not start "
                                 "with GWYP)"));
    if (length >= 2 && bytes[0] == 0x1f && bytes[1] == 0x8b)
        return check_gzip(name, bytes, length, error);
    /* Other formats are left to Gwyddion's detection; a loader's complaint
     * is kept from the user by library-log.h. */
    return TRUE;
}

static gboolean
check_file_kind(const gchar *filename, GStatBuf *st, GError **error)
{
    gchar *msg;

    if (g_stat(filename, st) != 0) {
        return screening_error(error, FILE_SCREENING_ERROR_ACCESS, filename,
                               errno == ENOENT ? _("no such file") : g_strerror(errno));
    }
    if (S_ISDIR(st->st_mode))
        return screening_error(error, FILE_SCREENING_ERROR_ACCESS, filename, _("it is a directory"));
    /* A FIFO or a device could block or never end. */
    if (!S_ISREG(st->st_mode))
        return screening_error(error, FILE_SCREENING_ERROR_ACCESS, filename,
                               _("not a regular file"));
    if (st->st_size == 0)
        return screening_error(error, FILE_SCREENING_ERROR_SIZE, filename, _("the file is empty"));
    if ((gint64)st->st_size > FILE_SCREENING_MAX_BYTES) {
        msg = g_strdup_printf(_("larger than %d GiB: refused"),
                              (gint)(FILE_SCREENING_MAX_BYTES >> 30));
        screening_error(error, FILE_SCREENING_ERROR_SIZE, filename, msg);
        g_free(msg);
        return FALSE;
    }
    return TRUE;
}

gboolean
file_screening_check(const gchar *filename, GError **error)
{
    GMappedFile *mapped;
    GError *err = NULL;
    GStatBuf st;
    gboolean ok;

    g_return_val_if_fail(filename, FALSE);
    if (!check_file_kind(filename, &st, error))
        return FALSE;
    if (access(filename, R_OK) != 0)
        return screening_error(error, FILE_SCREENING_ERROR_ACCESS, filename, g_strerror(errno));
    /* Mapped, not read: a large file costs no copy, and only the pages the
     * walk touches are read. */
    if (!(mapped = g_mapped_file_new(filename, FALSE, &err))) {
        screening_error(error, FILE_SCREENING_ERROR_ACCESS, filename, err->message);
        g_error_free(err);
        return FALSE;
    }
    ok = file_screening_check_bytes(filename, (const guchar*)g_mapped_file_get_contents(mapped),
                                    g_mapped_file_get_length(mapped), error);
    g_mapped_file_unref(mapped);
    return ok;
}
