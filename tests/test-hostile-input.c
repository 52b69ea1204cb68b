/*
 *  Hostile input against gwy-localscan and simscan: a seeded, generated set
 *  of bad days (damaged and disguised files, NaN pixels, binary and huge
 *  drift tables, absurd option values, outputs over inputs, killed runs).
 *  Every case must end within its time limit with either a correct result
 *  (finite outputs) or a non-zero exit and exactly one printable line;
 *  inputs unchanged; nothing left behind but the requested outputs.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <math.h>
#include <signal.h>
#include <sys/resource.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <glib/gstdio.h>
#include <libgwyddion/gwyddion.h>
#include <libprocess/gwyprocess.h>
#include "safe-output.h"
#include "test-common.h"

#define TOOL_PATH    TEST_BUILDDIR "/tools/gwy-localscan"
#define SIMSCAN_PATH TEST_BUILDDIR "/simscan/simscan"
#define DEFAULT_MODULE TEST_BUILDDIR "/modules/.libs/localscan.so"
/* Generated cases per run, and the time each may take (the 60 s;
 * the sanitizer build is slower but far within it). */
#define N_CASES 40
#define CASE_SECONDS 60
#define MESSAGE_MAX_CHARS 600

static guint32 seed;

typedef enum {
    EXPECT_FAILURE,      /* non-zero exit, one line, no output */
    EXPECT_SUCCESS,      /* exit 0, finite outputs */
    EXPECT_EITHER,       /* a loader may read it: either, each done right */
} Expectation;

/* One generated case: its folder, command and the files it may write. */
typedef struct {
    gchar *name;
    gchar *dir;
    GPtrArray *argv;
    GPtrArray *inputs;       /* files whose bytes must not change */
    GPtrArray *outputs;      /* files a success writes (.gwy checked finite) */
    GPtrArray *kept;         /* other files that must still be there */
    Expectation expect;
    const gchar *prefix;     /* the program's message prefix */
    const gchar *must_say;   /* a failure's message contains this, or NULL */
    gboolean needs_mask;     /* a success masks missing pixels of the result */
    gboolean sound_input;    /* a large sound file: its loader gets the tools'
                                own time, not the hostile cases' short one */
} HostileCase;

typedef struct {
    gint status;             /* exit status, or -signal */
    gchar *err;
} CaseRun;

/* Files. */

static gchar*
case_file(HostileCase *hc, const gchar *name)
{
    return g_build_filename(hc->dir, name, NULL);
}

static void
write_bytes(const gchar *path, const void *bytes, gsize length)
{
    GError *error = NULL;

    ck_assert_msg(g_file_set_contents(path, bytes, length, &error), "cannot write %s: %s", path,
                  error ? error->message : "?");
}

static gchar*
checksum_of(const gchar *path)
{
    gchar *contents = NULL, *sum;
    gsize length = 0;

    if (!g_file_get_contents(path, &contents, &length, NULL))
        return g_strdup("(unreadable)");
    sum = g_compute_checksum_for_data(G_CHECKSUM_SHA256, (const guchar*)contents, length);
    g_free(contents);
    return sum;
}

/* An image as Gwyddion serialises it: a container with one channel, of
 * the given physical size (any value: the struct is written directly) and
 * with one metadata item when meta_key is not NULL. */
static GByteArray*
serialised_image_full(gint xres, gint yres, const gdouble *data, gdouble xreal, gdouble yreal,
                      const gchar *meta_key, const gchar *meta_value)
{
    GwyContainer *container = gwy_container_new(), *meta;
    GwyDataField *field = gwy_data_field_new(xres, yres, 1.0, 1.0, FALSE);
    GByteArray *bytes = g_byte_array_new();

    field->xreal = xreal;
    field->yreal = yreal;
    if (meta_key) {
        meta = gwy_container_new();
        gwy_container_set_const_string_by_name(meta, meta_key, (const guchar*)meta_value);
        gwy_container_set_object_by_name(container, "/0/meta", meta);
        g_object_unref(meta);
    }
    memcpy(gwy_data_field_get_data(field), data, (gsize)xres*yres*sizeof(gdouble));
    gwy_si_unit_set_from_string(gwy_data_field_get_si_unit_xy(field), "m");
    gwy_si_unit_set_from_string(gwy_data_field_get_si_unit_z(field), "m");
    gwy_container_set_object_by_name(container, "/0/data", field);
    gwy_container_set_const_string_by_name(container, "/0/data/title", (const guchar*)"Height");
    g_byte_array_append(bytes, (const guint8*)"GWYP", 4);
    gwy_serializable_serialize(G_OBJECT(container), bytes);
    g_object_unref(field);
    g_object_unref(container);
    return bytes;
}

static GByteArray*
serialised_image(gint xres, gint yres, const gdouble *data)
{
    return serialised_image_full(xres, yres, data, xres*1e-8, yres*1e-8, NULL, NULL);
}

/* A rough surface with bumps, some pixels missing when missing > 0. */
static gdouble*
surface(GRand *rng, gint xres, gint yres, gdouble missing)
{
    static const gdouble specials[3] = { NAN, INFINITY, -INFINITY };
    gdouble *data = g_new(gdouble, (gsize)xres*yres);
    gint i, j;

    for (i = 0; i < yres; i++) {
        for (j = 0; j < xres; j++)
            data[i*xres + j] = 1e-9*(sin(0.3*j) + cos(0.21*i) + 0.1*g_rand_double(rng));
    }
    for (i = 0; i < xres*yres; i++) {
        if (g_rand_double(rng) < missing)
            data[i] = specials[g_rand_int_range(rng, 0, 3)];
    }
    return data;
}

/* Bumps of 20 nm on the surface: particles simscan finds on a sample. */
static void
add_particles(GRand *rng, gdouble *data, gint xres, gint yres, gint count)
{
    gint k, i, j;
    gdouble x0, y0, r2;

    for (k = 0; k < count; k++) {
        x0 = g_rand_double_range(rng, 6, xres - 6);
        y0 = g_rand_double_range(rng, 6, yres - 6);
        for (i = 0; i < yres; i++) {
            for (j = 0; j < xres; j++) {
                r2 = (j - x0)*(j - x0) + (i - y0)*(i - y0);
                if (r2 < 16.0 && isfinite(data[i*xres + j]))
                    data[i*xres + j] += 2e-8*sqrt(1.0 - r2/16.0);
            }
        }
    }
}

static gchar*
write_image_with(HostileCase *hc, GRand *rng, const gchar *name, gint xres, gint yres,
                 gdouble missing, gint particles)
{
    gchar *path = case_file(hc, name);
    gdouble *data = surface(rng, xres, yres, missing);

    add_particles(rng, data, xres, yres, particles);
    GByteArray *bytes = serialised_image(xres, yres, data);

    write_bytes(path, bytes->data, bytes->len);
    g_byte_array_free(bytes, TRUE);
    g_free(data);
    g_ptr_array_add(hc->inputs, g_strdup(path));
    return path;
}

static gchar*
write_image(HostileCase *hc, GRand *rng, const gchar *name, gint xres, gint yres, gdouble missing)
{
    return write_image_with(hc, rng, name, xres, yres, missing, 0);
}

/* Whole-pixel drift per stripe; dy 0 when steady, since continuous mode
 * rightly refuses y drift that changes by a stripe's height from one
 * stripe to the next. */
static gchar*
write_table_of(HostileCase *hc, GRand *rng, const gchar *name, gint n, gboolean steady)
{
    GString *text = g_string_new("stripe,dx,dy\n");
    gchar *path = case_file(hc, name);
    gint s;

    for (s = 0; s < n; s++)
        g_string_append_printf(text, "%d,%d,%d\n", s, g_rand_int_range(rng, -3, 4),
                               steady ? 0 : g_rand_int_range(rng, -3, 4));
    write_bytes(path, text->str, text->len);
    g_string_free(text, TRUE);
    g_ptr_array_add(hc->inputs, g_strdup(path));
    return path;
}

static gchar*
write_table(HostileCase *hc, GRand *rng, const gchar *name, gint n)
{
    return write_table_of(hc, rng, name, n, FALSE);
}

static gchar*
write_random_bytes(HostileCase *hc, GRand *rng, const gchar *name, const gchar *head, gsize length)
{
    gchar *path = case_file(hc, name);
    guint8 *bytes = g_new(guint8, MAX(length, 1));
    gsize i, n = head ? MIN(strlen(head), length) : 0;

    for (i = 0; i < length; i++)
        bytes[i] = (guint8)g_rand_int_range(rng, 0, 256);
    if (n)
        memcpy(bytes, head, n);
    write_bytes(path, bytes, length);
    g_free(bytes);
    g_ptr_array_add(hc->inputs, g_strdup(path));
    return path;
}

/* Cases. */

static HostileCase*
case_new(const gchar *scratch, gint index, const gchar *name, const gchar *program)
{
    HostileCase *hc = g_new0(HostileCase, 1);
    gchar *dirname = g_strdup_printf("case%02d", index);

    hc->name = g_strdup(name);
    hc->dir = g_build_filename(scratch, dirname, NULL);
    g_free(dirname);
    g_mkdir(hc->dir, 0700);
    hc->argv = g_ptr_array_new_with_free_func(g_free);
    hc->inputs = g_ptr_array_new_with_free_func(g_free);
    hc->outputs = g_ptr_array_new_with_free_func(g_free);
    hc->kept = g_ptr_array_new_with_free_func(g_free);
    hc->prefix = gwy_strequal(program, SIMSCAN_PATH) ? "simscan" : "gwy-localscan: ";
    g_ptr_array_add(hc->argv, g_strdup(program));
    return hc;
}

static void
case_free(HostileCase *hc)
{
    g_free(hc->name);
    g_free(hc->dir);
    g_ptr_array_free(hc->argv, TRUE);
    g_ptr_array_free(hc->inputs, TRUE);
    g_ptr_array_free(hc->outputs, TRUE);
    g_ptr_array_free(hc->kept, TRUE);
    g_free(hc);
}

static void
add_args(HostileCase *hc, ...)
{
    const gchar *arg;
    va_list ap;

    va_start(ap, hc);
    while ((arg = va_arg(ap, const gchar*)))
        g_ptr_array_add(hc->argv, g_strdup(arg));
    va_end(ap);
}

static void
add_output(HostileCase *hc, const gchar *option, const gchar *name)
{
    gchar *path = case_file(hc, name);

    add_args(hc, option, path, NULL);
    g_ptr_array_add(hc->outputs, path);
}

static gdouble
log_uniform(GRand *rng, gdouble lo, gdouble hi)
{
    return exp(g_rand_double_range(rng, log(lo), log(hi)));
}

static gchar*
number(gdouble v)
{
    gchar buf[G_ASCII_DTOSTR_BUF_SIZE];

    return g_strdup(g_ascii_dtostr(buf, sizeof(buf), v));
}

/* gwy-localscan on a damaged or disguised file. */
static void
make_damaged_file(HostileCase *hc, GRand *rng)
{
    static const gchar *const extensions[] = { ".gwy", ".sxm", ".001", ".txt", ".ibw", "" };
    gint kind = g_rand_int_range(rng, 0, 6);
    gchar *input = NULL, *name;
    GByteArray *bytes;
    gdouble *data;
    guint32 word, length, i;

    if (kind == 0) {
        input = write_random_bytes(hc, rng, "magic.gwy", g_rand_boolean(rng) ? "GWYP" : "GWYO", 4);
        hc->must_say = "magic.gwy";
    }
    else if (kind == 1) {
        data = surface(rng, 32, 32, 0.0);
        bytes = serialised_image(32, 32, data);
        input = case_file(hc, "truncated.gwy");
        write_bytes(input, bytes->data, g_rand_int_range(rng, 1, bytes->len));
        g_ptr_array_add(hc->inputs, g_strdup(input));
        g_byte_array_free(bytes, TRUE);
        g_free(data);
        hc->must_say = "truncated.gwy";
    }
    else if (kind == 2) {
        input = write_random_bytes(hc, rng, "noise.gwy", NULL, g_rand_int_range(rng, 1, 5000));
        hc->must_say = "noise.gwy";
    }
    else if (kind == 5) {
        /* Gwyddion 1's format: only its frame can be checked, and its
         * deserialiser loops for ever on some bodies (the loader runs in a
         * child process with a time limit). */
        length = g_rand_int_range(rng, 1, 64);
        bytes = g_byte_array_new();
        g_byte_array_append(bytes, (const guint8*)"GWYOGwyContainer", 17);
        word = GUINT32_TO_LE(length);
        g_byte_array_append(bytes, (const guint8*)&word, 4);
        for (i = 0; i < length; i++) {
            guint8 b = (guint8)g_rand_int_range(rng, 0, 256);

            g_byte_array_append(bytes, &b, 1);
        }
        input = case_file(hc, "old.gwy");
        write_bytes(input, bytes->data, bytes->len);
        g_ptr_array_add(hc->inputs, g_strdup(input));
        g_byte_array_free(bytes, TRUE);
        hc->expect = EXPECT_FAILURE;
        hc->must_say = "old.gwy";
    }
    else if (kind == 3) {
        input = case_file(hc, "empty.gwy");
        write_bytes(input, "", 0);
        g_ptr_array_add(hc->inputs, g_strdup(input));
        hc->must_say = "empty";
    }
    else {
        name = g_strconcat("disguised", extensions[g_rand_int_range(rng, 0, 6)], NULL);
        input = write_random_bytes(hc, rng, name, g_rand_boolean(rng) ? "GWYP" : NULL,
                                   g_rand_int_range(rng, 1, 20000));
        g_free(name);
        hc->expect = EXPECT_EITHER;
    }
    add_output(hc, "-o", "out.gwy");
    add_args(hc, input, NULL);
    g_free(input);
}

/* NaN and infinite pixels: compensated with them filled and masked, or
 * refused when more than half are missing. */
static void
make_missing_pixels(HostileCase *hc, GRand *rng)
{
    gint xres = g_rand_int_range(rng, 16, 97), yres = g_rand_int_range(rng, 16, 97);
    gint n = g_rand_int_range(rng, 1, MIN(yres, 17));
    gdouble fraction = g_rand_boolean(rng) ? g_rand_double_range(rng, 0.0, 0.45)
                                           : g_rand_double_range(rng, 0.6, 1.0);
    gboolean paper = g_rand_boolean(rng);
    gchar *input = write_image(hc, rng, "nan.gwy", xres, yres, fraction);
    gchar *table = write_table_of(hc, rng, "drift.csv", n, !paper);

    hc->expect = fraction < 0.5 ? EXPECT_SUCCESS : EXPECT_FAILURE;
    hc->must_say = "missing";
    hc->needs_mask = (fraction > 0.05);
    add_output(hc, "-o", "out.gwy");
    add_args(hc, "-d", table, "-m", paper ? "paper" : "continuous", input, NULL);
    g_free(input);
    g_free(table);
}

/* Drift tables a user's bad day makes: binary garbage, a 10 MB line,
 * absurd numbers, too many stripes, a header of many columns. */
static void
make_bad_table(HostileCase *hc, GRand *rng)
{
    gchar *input = write_image(hc, rng, "image.gwy", 32, 32, 0.0), *table = case_file(hc, "t.csv");
    gint kind = g_rand_int_range(rng, 0, 6), i;
    GString *text = g_string_new("stripe,dx,dy\n0,1,0\n");
    gsize length;

    if (kind == 0) {
        length = g_rand_int_range(rng, 1, 4000);
        for (i = 0; i < (gint)length; i++)
            g_string_append_c(text, (gchar)g_rand_int_range(rng, 1, 256));
    }
    else if (kind == 1) {
        g_string_append(text, "1,");
        length = g_rand_int_range(rng, 1 << 20, 10 << 20);
        for (i = 0; i < (gint)length; i++)
            g_string_append_c(text, (gchar)('0' + i % 10));
        g_string_append(text, "x,0\n");
    }
    else if (kind == 2)
        g_string_append_printf(text, "1,%g,0\n", log_uniform(rng, 1e9, 1e300));
    else if (kind == 3) {
        for (i = 1; i < 100000; i++)
            g_string_append_printf(text, "%d,0,0\n", i);
    }
    else if (kind == 5) {
        /* A FIFO nobody writes to: reading it would wait for ever. */
        ck_assert_int_eq(mkfifo(table, 0600), 0);
        g_ptr_array_add(hc->kept, g_strdup(table));
        hc->must_say = "t.csv";
        add_output(hc, "-o", "out.gwy");
        add_args(hc, "-d", table, input, NULL);
        g_string_free(text, TRUE);
        g_free(input);
        g_free(table);
        return;
    }
    else {
        g_string_assign(text, "stripe,dx,dy");
        for (i = 0; i < 200000; i++)
            g_string_append_printf(text, ",c%d", i % 150000);
        g_string_append(text, "\n");
    }
    write_bytes(table, text->str, text->len);
    g_ptr_array_add(hc->inputs, g_strdup(table));
    g_string_free(text, TRUE);
    hc->must_say = "t.csv";
    add_output(hc, "-o", "out.gwy");
    add_args(hc, "-d", table, input, NULL);
    g_free(input);
    g_free(table);
}

/* Damaged geometry or timing in an otherwise valid file or table: a NaN
 * or infinite physical size (refused when the file is screened), a line
 * time no instrument has, table times of 1e308 s. */
static void
make_bad_geometry(HostileCase *hc, GRand *rng)
{
    static const gdouble sizes[] = { NAN, INFINITY, -INFINITY };
    static const gchar *const timings[][2] = {
        { "Line time (s)", "1e300" }, { "Scan rate", "1e-300 Hz" }, { "Line time", "1e-30 s" },
        { "Frame time (s)", "nan" },
    };
    gint kind = g_rand_int_range(rng, 0, 3), t;
    gdouble *data = surface(rng, 32, 32, 0.0), size = sizes[g_rand_int_range(rng, 0, 3)];
    gchar *input = case_file(hc, "image.gwy"), *table = case_file(hc, "t.csv"), *text;
    GByteArray *bytes;

    t = g_rand_int_range(rng, 0, G_N_ELEMENTS(timings));
    if (kind == 0)
        bytes = serialised_image_full(32, 32, data, g_rand_boolean(rng) ? size : 3e-7, size, NULL, NULL);
    else
        bytes = serialised_image_full(32, 32, data, 3e-7, 3e-7, timings[t][0], timings[t][1]);
    write_bytes(input, bytes->data, bytes->len);
    g_ptr_array_add(hc->inputs, g_strdup(input));
    if (kind == 2)
        text = g_strdup_printf("stripe,dx,dy,t_image,t_local\n0,1,0,%g,5\n1,1,0,9,%g\n",
                               log_uniform(rng, 1e11, 1e308), -log_uniform(rng, 1e11, 1e308));
    else
        text = g_strdup("# units: nm\nstripe,dx,dy,t_image,t_local\n0,10,0,1,40\n1,12,0,20,41\n");
    write_bytes(table, text, strlen(text));
    g_ptr_array_add(hc->inputs, g_strdup(table));
    hc->expect = (kind == 1) ? EXPECT_SUCCESS : EXPECT_FAILURE;
    hc->must_say = (kind == 0) ? "physical width or height" : "t.csv";
    add_output(hc, "-o", "out.gwy");
    add_args(hc, "-d", table, "-m", "continuous", input, NULL);
    g_byte_array_free(bytes, TRUE);
    g_free(text);
    g_free(data);
    g_free(input);
    g_free(table);
}

/* Outputs that are inputs, in missing folders, or replace an older file
 * that must survive the failure. */
static void
make_bad_output(HostileCase *hc, GRand *rng)
{
    gchar *input = write_image(hc, rng, "image.gwy", 24, 24, 0.0);
    gchar *table = write_table(hc, rng, "drift.csv", 40), *old, *target;
    gint kind = g_rand_int_range(rng, 0, 3);

    if (kind == 0)
        add_args(hc, "-o", input, "-d", table, input, NULL);
    else if (kind == 1) {
        target = case_file(hc, "no/such/folder/out.gwy");
        add_args(hc, "-o", target, "-d", table, input, NULL);
        g_free(target);
    }
    else {
        /* The table has more stripes than the image has rows: refused,
         * and the older output stays as it was. */
        old = case_file(hc, "out.gwy");
        write_bytes(old, "an older output", 15);
        g_ptr_array_add(hc->inputs, g_strdup(old));
        add_args(hc, "-o", old, "-d", table, input, NULL);
        g_free(old);
    }
    g_free(input);
    g_free(table);
}

/* Option values out of their range. */
static void
make_bad_option(HostileCase *hc, GRand *rng)
{
    static const gchar *const stripes[] = { "0", "-7", "100000", "1e9", "x", "" };
    static const gchar *const seconds[] = { "nan", "inf", "-1", "1e300", "1e-30", "1,5" };
    gchar *input = write_image(hc, rng, "image.gwy", 24, 24, 0.0);
    gint kind = g_rand_int_range(rng, 0, 3);

    add_output(hc, "-o", "out.gwy");
    if (kind == 0)
        add_args(hc, "--reference", ":0", "--stripes", stripes[g_rand_int_range(rng, 0, 6)], NULL);
    else if (kind == 1)
        add_args(hc, "-m", "continuous", "--line-time", seconds[g_rand_int_range(rng, 0, 6)], NULL);
    else
        add_args(hc, "-c", g_rand_boolean(rng) ? "2147483647" : "-2147483648", NULL);
    add_args(hc, input, NULL);
    g_free(input);
}

/* simscan asked for endless work or given damaged samples. */
static void
make_simscan_case(HostileCase *hc, GRand *rng)
{
    gint kind = g_rand_int_range(rng, 0, 6);
    gchar *value = NULL, *sample, *pair;

    if (kind == 0)
        add_args(hc, "--ls-rmax", (value = number(log_uniform(rng, 1e5, 1e12))), NULL);
    else if (kind == 1) {
        pair = g_strdup_printf("%g,%g", log_uniform(rng, 1e6, 1e12), -log_uniform(rng, 1e6, 1e12));
        add_args(hc, g_rand_boolean(rng) ? "--velocity" : "--offset", pair, NULL);
        g_free(pair);
    }
    else if (kind == 2)
        add_args(hc, "--ls-points", (value = number(floor(log_uniform(rng, 2e5, 1e6)))), NULL);
    else if (kind == 3) {
        add_args(hc, "--drift", "random-walk", "--walk-sigma",
                 (value = number(log_uniform(rng, 1e3, 1e6))), NULL);
    }
    else if (kind == 4) {
        /* A measured sample with some missing pixels simulates fine. */
        sample = write_image_with(hc, rng, "sample.gwy", 96, 96, g_rand_double_range(rng, 0.0, 0.3),
                                  12);
        add_args(hc, "--sample", sample, "--radius", "40", "--ls-rmax", "100", NULL);
        hc->expect = EXPECT_SUCCESS;
        g_free(sample);
    }
    else {
        sample = write_random_bytes(hc, rng, "sample.gwy", "GWYP", g_rand_int_range(rng, 4, 64));
        add_args(hc, "--sample", sample, NULL);
        hc->must_say = "sample.gwy";
        g_free(sample);
    }
    add_output(hc, "-o", "sim.gwy");
    add_args(hc, "-q", NULL);
    g_free(value);
}

/* simscan fit given damaged frames or more frames than it can fit in
 * bounded time (refused before any is read). */
static void
make_fit_case(HostileCase *hc, GRand *rng)
{
    gint i, n = g_rand_int_range(rng, 17, 3000);
    gchar *frame;

    add_args(hc, "fit", NULL);
    add_output(hc, "--json", "fit.json");
    if (g_rand_boolean(rng)) {
        hc->must_say = "too many";
        for (i = 0; i < n; i++)
            g_ptr_array_add(hc->argv, g_strdup_printf("frame%d.gwy", i));
        return;
    }
    for (i = 0; i < 3; i++) {
        frame = g_strdup_printf("frame%d.gwy", i);
        g_free(write_random_bytes(hc, rng, frame, i ? "GWYP" : "GWYO", g_rand_int_range(rng, 4, 300)));
        g_ptr_array_add(hc->argv, frame);
    }
    hc->must_say = "frame0.gwy";
}

/* gwy-localscan series given frames that cannot form a series, timing
 * that cannot be, a frame with missing or no data, thousands of frames. */
static void
make_series_case(HostileCase *hc, GRand *rng)
{
    gint kind = g_rand_int_range(rng, 0, 7), k, n;
    gint xres = g_rand_int_range(rng, 48, 97), yres = g_rand_int_range(rng, 48, 97);
    gchar *frame;

    hc->prefix = "gwy-localscan series: ";
    add_args(hc, "series", NULL);
    add_output(hc, "-o", "series.gwy");
    add_output(hc, "--json", "series.json");
    add_output(hc, "--trajectory", "series.csv");
    if (kind == 0) {
        /* Thousands of frames, none there: refused at the first. */
        n = g_rand_int_range(rng, 1000, 5000);
        add_args(hc, "--line-time", "0.1", NULL);
        for (k = 0; k < n; k++)
            g_ptr_array_add(hc->argv, case_file(hc, "absent.gwy"));
        hc->must_say = "absent.gwy";
        return;
    }
    for (k = 0; k < 3; k++) {
        gint w = (kind == 1 && k == 2) ? xres + 1 : xres;
        gdouble missing = (kind == 5 && k == 1) ? 1.0 : (kind == 6 ? 0.1 : 0.0);

        frame = g_strdup_printf("frame%d.gwy", k);
        g_ptr_array_add(hc->argv, write_image_with(hc, rng, frame, w, yres,
                                                   missing, 12));
        g_free(frame);
        if (kind == 2)
            break;
    }
    switch (kind) {
        case 1:
        add_args(hc, "--line-time", "0.1", "--frame-times", "0,20,40", NULL);
        hc->must_say = "differs";
        break;

        case 2:
        add_args(hc, "--line-time", "0.1", "--frame-times", "0", NULL);
        hc->must_say = "at least two";
        break;

        case 3:
        add_args(hc, "--line-time", "0.1", "--frame-times", "0,40,20", NULL);
        hc->must_say = "time order";
        break;

        case 4:
        /* No timing in the files, none given: the first frame named. */
        hc->must_say = "frame0.gwy";
        break;

        default:
        /* A frame with no data, or every frame with missing pixels: either
         * refused in one line or corrected with finite outputs. */
        add_args(hc, "--line-time", "0.1", "--frame-times",
                 g_rand_boolean(rng) ? "0,20,40" : "0,12,24", NULL);
        hc->expect = EXPECT_EITHER;
        break;
    }
}

typedef void (*CaseMaker)(HostileCase *hc, GRand *rng);

static const struct {
    const gchar *name;
    const gchar *program;
    CaseMaker make;
} case_kinds[] = {
    { "damaged or disguised file", TOOL_PATH,    make_damaged_file,   },
    { "missing pixels",            TOOL_PATH,    make_missing_pixels, },
    { "bad drift table",           TOOL_PATH,    make_bad_table,      },
    { "bad output",                TOOL_PATH,    make_bad_output,     },
    { "bad geometry or timing",    TOOL_PATH,    make_bad_geometry,   },
    { "option out of range",       TOOL_PATH,    make_bad_option,     },
    { "simscan",                   SIMSCAN_PATH, make_simscan_case,   },
    { "simscan fit",               SIMSCAN_PATH, make_fit_case,       },
    { "gwy-localscan series",      TOOL_PATH,    make_series_case,    },
};

/* Running and judging. */

static gchar**
child_environment_for(const gchar *home, gboolean sound_input)
{
    const gchar *module = g_getenv("LOCALSCAN_MODULE");
    gchar **envp = g_get_environ();

    envp = g_environ_setenv(envp, "HOME", home, TRUE);
    envp = g_environ_setenv(envp, "LC_ALL", "C", TRUE);
    envp = g_environ_unsetenv(envp, "LANGUAGE");
    envp = g_environ_setenv(envp, "LOCALSCAN_MODULE", module && *module ? module : DEFAULT_MODULE,
                            TRUE);
    /* A loader that hangs is given up after this, not the tools' 30 s;
     * a sound 2048 x 2048 file took longer to load on a loaded machine
     * (seed 998000008 of a soak beside two builds). */
    if (sound_input)
        envp = g_environ_unsetenv(envp, "LOCALSCAN_LOAD_SECONDS");
    else
        envp = g_environ_setenv(envp, "LOCALSCAN_LOAD_SECONDS", "3", TRUE);
    return envp;
}

/* Runs argv under coreutils' timeout, which ends with 124 past the limit. */
static void
run_case(HostileCase *hc, const gchar *home, CaseRun *run)
{
    GPtrArray *argv = g_ptr_array_new();
    gchar **envp = child_environment_for(home, hc->sound_input);
    gchar *limit = g_strdup_printf("%d", CASE_SECONDS);
    GError *error = NULL;
    gint wait_status;
    guint i;

    g_ptr_array_add(argv, "timeout");
    g_ptr_array_add(argv, limit);
    for (i = 0; i < hc->argv->len; i++)
        g_ptr_array_add(argv, g_ptr_array_index(hc->argv, i));
    g_ptr_array_add(argv, NULL);
    ck_assert_msg(g_spawn_sync(hc->dir, (gchar**)argv->pdata, envp, G_SPAWN_SEARCH_PATH
                               | G_SPAWN_STDOUT_TO_DEV_NULL, NULL, NULL, NULL, &run->err,
                               &wait_status, &error),
                  "cannot run %s: %s", hc->name, error ? error->message : "?");
    run->status = WIFEXITED(wait_status) ? WEXITSTATUS(wait_status) : -WTERMSIG(wait_status);
    g_ptr_array_free(argv, TRUE);
    g_strfreev(envp);
    g_free(limit);
}

static gchar*
describe(HostileCase *hc)
{
    gchar *args = g_strjoinv(" ", (gchar**)hc->argv->pdata);
    gchar *text = g_strdup_printf("seed %u, %s: %s", seed, hc->name, args);

    g_free(args);
    return text;
}

/* One line, printable, bounded, the program's own. */
static void
check_one_line(HostileCase *hc, const gchar *err, const gchar *what)
{
    gsize length = strlen(err);
    const gchar *p;

    ck_assert_msg(length > 0 && err[length-1] == '\n' && !memchr(err, '\n', length - 1),
                  "%s: expected one line, got: %s", what, err);
    ck_assert_msg(g_str_has_prefix(err, hc->prefix), "%s: not the program's message: %s", what, err);
    ck_assert_msg(g_utf8_validate(err, -1, NULL) && g_utf8_strlen(err, -1) <= MESSAGE_MAX_CHARS,
                  "%s: message not short valid UTF-8 (%" G_GSIZE_FORMAT " bytes)", what, length);
    for (p = err; p < err + length - 1; p++)
        ck_assert_msg((guchar)*p >= 0x20 && *p != 0x7f, "%s: control byte in message", what);
}

/* Every image channel of a .gwy output has only finite values; with
 * needs_mask the result (channel 1) has a mask. */
static void
check_finite_output(const gchar *path, gboolean needs_mask, const gchar *what)
{
    gchar *contents = NULL;
    gsize length = 0, pos = 0;
    GObject *object;
    GwyDataField *field;
    gint id, n, i, channels = 0;
    gchar key[32];

    ck_assert_msg(g_file_get_contents(path, &contents, &length, NULL), "%s: no output %s", what, path);
    ck_assert_msg(length > 4 && memcmp(contents, "GWYP", 4) == 0, "%s: %s is not .gwy", what, path);
    object = gwy_serializable_deserialize((const guchar*)contents + 4, length - 4, &pos);
    ck_assert_msg(object && GWY_IS_CONTAINER(object), "%s: %s does not deserialise", what, path);
    for (id = 0; id < 64; id++) {
        g_snprintf(key, sizeof(key), "/%d/data", id);
        if (!gwy_container_gis_object_by_name(GWY_CONTAINER(object), key, &field))
            continue;
        channels++;
        n = gwy_data_field_get_xres(field)*gwy_data_field_get_yres(field);
        for (i = 0; i < n; i++)
            ck_assert_msg(isfinite(gwy_data_field_get_data_const(field)[i]),
                          "%s: channel %d of %s has a non-finite value at %d", what, id, path, i);
    }
    ck_assert_msg(channels > 0, "%s: %s holds no image channel", what, path);
    ck_assert_msg(!needs_mask || gwy_container_contains_by_name(GWY_CONTAINER(object), "/1/mask"),
                  "%s: the missing pixels are not masked in the result", what);
    g_object_unref(object);
    g_free(contents);
}

static gboolean
is_listed(GPtrArray *paths, const gchar *path)
{
    guint i;

    for (i = 0; i < paths->len; i++) {
        if (gwy_strequal(g_ptr_array_index(paths, i), path))
            return TRUE;
    }
    return FALSE;
}

/* Nothing in the case's folder but its inputs, kept files and (after a
 * success) its outputs. */
static void
check_no_leftovers(HostileCase *hc, gboolean succeeded, const gchar *what)
{
    const gchar *name;
    gchar *path;
    GDir *dir = g_dir_open(hc->dir, 0, NULL);

    ck_assert_ptr_nonnull(dir);
    while ((name = g_dir_read_name(dir))) {
        path = case_file(hc, name);
        ck_assert_msg(is_listed(hc->inputs, path) || is_listed(hc->kept, path)
                      || (succeeded && is_listed(hc->outputs, path)),
                      "%s: left behind: %s", what, name);
        g_free(path);
    }
    g_dir_close(dir);
}

static void
judge_case(HostileCase *hc, const CaseRun *run, GPtrArray *sums_before)
{
    gchar *what = describe(hc), *sum;
    gboolean succeeded = (run->status == 0);
    guint i;

    ck_assert_msg(run->status != 124, "%s: still running after %d s", what, CASE_SECONDS);
    ck_assert_msg(run->status >= 0, "%s: killed by signal %d: %s", what, -run->status, run->err);
    if (hc->expect == EXPECT_SUCCESS)
        ck_assert_msg(succeeded, "%s: failed (%d): %s", what, run->status, run->err);
    if (hc->expect == EXPECT_FAILURE)
        ck_assert_msg(!succeeded, "%s: succeeded", what);
    if (!succeeded) {
        check_one_line(hc, run->err, what);
        if (hc->must_say)
            ck_assert_msg(strstr(run->err, hc->must_say), "%s: message does not say '%s': %s",
                          what, hc->must_say, run->err);
    }
    for (i = 0; i < hc->inputs->len; i++) {
        sum = checksum_of(g_ptr_array_index(hc->inputs, i));
        ck_assert_msg(gwy_strequal(sum, g_ptr_array_index(sums_before, i)), "%s: input %s changed",
                      what, (const gchar*)g_ptr_array_index(hc->inputs, i));
        g_free(sum);
    }
    for (i = 0; succeeded && i < hc->outputs->len; i++) {
        if (g_str_has_suffix(g_ptr_array_index(hc->outputs, i), ".gwy"))
            check_finite_output(g_ptr_array_index(hc->outputs, i), hc->needs_mask, what);
    }
    check_no_leftovers(hc, succeeded, what);
    g_free(what);
}

static gchar*
make_scratch(const gchar *what)
{
    gchar *scratch = g_strdup_printf(TEST_BUILDDIR "/tests/scratch-hostile-%s-XXXXXX", what);

    ck_assert_ptr_nonnull(g_mkdtemp(scratch));
    return scratch;
}

/* Runs the case (argv without its terminator) and judges it, the inputs'
 * checksums taken before. */
static void
run_and_judge(HostileCase *hc, const gchar *home)
{
    GPtrArray *sums = g_ptr_array_new_with_free_func(g_free);
    CaseRun run;
    guint j;

    for (j = 0; j < hc->inputs->len; j++)
        g_ptr_array_add(sums, checksum_of(g_ptr_array_index(hc->inputs, j)));
    g_ptr_array_add(hc->argv, NULL);
    run_case(hc, home, &run);
    g_ptr_array_remove_index(hc->argv, hc->argv->len - 1);
    judge_case(hc, &run, sums);
    g_free(run.err);
    g_ptr_array_free(sums, TRUE);
}

START_TEST(test_generated_cases)
{
    gchar *scratch = make_scratch("cases"), *home = g_build_filename(scratch, "home", NULL);
    GRand *rng = g_rand_new_with_seed(seed);
    HostileCase *hc;
    guint i, k, passed = 0;

    g_mkdir(home, 0700);
    for (i = 0; i < N_CASES; i++) {
        k = g_rand_int_range(rng, 0, G_N_ELEMENTS(case_kinds));
        hc = case_new(scratch, i, case_kinds[k].name, case_kinds[k].program);
        case_kinds[k].make(hc, rng);
        run_and_judge(hc, home);
        passed++;
        case_free(hc);
    }
    printf("test-hostile-input: %u of %d generated cases passed (seed %u)\n", passed, N_CASES, seed);
    g_rand_free(rng);
    test_remove_tree(scratch);
    g_free(home);
    g_free(scratch);
}
END_TEST

/* A run that warns and then fails prints the failure's line alone: the
 * warnings were printed as they arose, two lines where one explains
 * (seed 4018615478: a stripe left out, then 69 % of the pixels missing).
 * The image has no timing, so the table's times give a warning; then the
 * output's folder is missing, or too many pixels are. */
START_TEST(test_warning_then_failure)
{
    static const gchar table_text[] = "stripe,dx,dy,t_image,t_local\n0,1,0,1,40\n1,1,0,20,41\n";
    gchar *scratch = make_scratch("warn"), *home = g_build_filename(scratch, "home", NULL);
    GRand *rng = g_rand_new_with_seed(seed);
    gchar *input, *table, *output;
    HostileCase *hc;
    gint k;

    g_mkdir(home, 0700);
    for (k = 0; k < 2; k++) {
        hc = case_new(scratch, k, "warning then failure", TOOL_PATH);
        input = write_image(hc, rng, "image.gwy", 32, 32, k ? 0.7 : 0.0);
        table = case_file(hc, "t.csv");
        write_bytes(table, table_text, strlen(table_text));
        g_ptr_array_add(hc->inputs, g_strdup(table));
        output = case_file(hc, k ? "out.gwy" : "no/such/folder/out.gwy");
        add_args(hc, "-o", output, "-d", table, "-m", "continuous", input, NULL);
        hc->expect = EXPECT_FAILURE;
        hc->must_say = k ? "missing" : "cannot write";
        run_and_judge(hc, home);
        g_free(input);
        g_free(table);
        g_free(output);
        case_free(hc);
    }
    g_rand_free(rng);
    test_remove_tree(scratch);
    g_free(home);
    g_free(scratch);
}
END_TEST

/* Killed runs. */

static gint
count_temporaries(const gchar *dirname)
{
    const gchar *name;
    GDir *dir = g_dir_open(dirname, 0, NULL);
    gint n = 0;

    while (dir && (name = g_dir_read_name(dir)))
        n += safe_output_is_temp_name(name);
    if (dir)
        g_dir_close(dir);
    return n;
}

/* A compensation long enough to be interrupted at a random moment. */
static HostileCase*
slow_case(const gchar *scratch, GRand *rng, gint index)
{
    HostileCase *hc = case_new(scratch, index, "killed run", TOOL_PATH);
    gchar *input = write_image(hc, rng, "big.gwy", 2048, 2048, 0.0);
    gchar *table = write_table(hc, rng, "drift.csv", 32);

    hc->sound_input = TRUE;

    add_output(hc, "-o", "out.gwy");
    add_output(hc, "--write-drift", "used.csv");
    add_args(hc, "-d", table, "-m", "continuous", input, NULL);
    g_ptr_array_add(hc->argv, NULL);
    g_free(input);
    g_free(table);
    return hc;
}

static gint
run_and_signal(HostileCase *hc, const gchar *home, gint signum, gulong delay_us)
{
    gchar **envp = child_environment_for(home, hc->sound_input);
    gint status;
    GPid pid;

    ck_assert(g_spawn_async(hc->dir, (gchar**)hc->argv->pdata, envp,
                            G_SPAWN_DO_NOT_REAP_CHILD | G_SPAWN_STDOUT_TO_DEV_NULL
                            | G_SPAWN_STDERR_TO_DEV_NULL, NULL, NULL, &pid, NULL));
    g_usleep(delay_us);
    kill(pid, signum);
    waitpid(pid, &status, 0);
    g_strfreev(envp);
    return status;
}

/* SIGTERM, SIGINT, SIGHUP or SIGQUIT at a random moment: the run either
 * finished (all its outputs) or left nothing at all (SIGQUIT left its
 * temporary file before it was caught too).  No core file is written for
 * SIGQUIT's default action. */
START_TEST(test_terminated_runs)
{
    static const gint signals[] = { SIGTERM, SIGINT, SIGHUP, SIGQUIT };
    struct rlimit no_core = { 0, 0 };
    gchar *scratch = make_scratch("term"), *home = g_build_filename(scratch, "home", NULL);
    GRand *rng = g_rand_new_with_seed(seed ^ 0x5eed);
    HostileCase *hc;
    gint i, status, signum, finished = 0;
    guint k, written;
    gchar *what;

    g_mkdir(home, 0700);
    setrlimit(RLIMIT_CORE, &no_core);
    for (i = 0; i < 8; i++) {
        hc = slow_case(scratch, rng, i);
        signum = signals[i % G_N_ELEMENTS(signals)];
        status = run_and_signal(hc, home, signum, g_rand_int_range(rng, 0, 1500000));
        what = g_strdup_printf("seed %u, signal %d", seed, signum);
        ck_assert_msg((WIFEXITED(status) && WEXITSTATUS(status) == 0)
                      || (WIFSIGNALED(status) && WTERMSIG(status) == signum),
                      "%s: ended with status %d", what, status);
        finished += WIFEXITED(status);
        ck_assert_msg(count_temporaries(hc->dir) == 0, "%s: temporaries left", what);
        /* A signal after the commit finds all outputs written. */
        written = 0;
        for (k = 0; k < hc->outputs->len; k++)
            written += g_file_test(g_ptr_array_index(hc->outputs, k), G_FILE_TEST_EXISTS);
        ck_assert_msg(written == 0 || written == hc->outputs->len, "%s: half an output set left",
                      what);
        check_no_leftovers(hc, written > 0, what);
        g_free(what);
        case_free(hc);
    }
    printf("test-hostile-input: 8 signalled runs clean (%d had finished first)\n", finished);
    g_rand_free(rng);
    test_remove_tree(scratch);
    g_free(home);
    g_free(scratch);
}
END_TEST

/* SIGKILL cannot be caught: what it leaves is swept by the next run that
 * writes the same output, and a live run's temporary is left alone. */
START_TEST(test_killed_run_swept)
{
    gchar *scratch = make_scratch("kill"), *home = g_build_filename(scratch, "home", NULL);
    GRand *rng = g_rand_new_with_seed(seed ^ 0x9);
    HostileCase *hc;
    gchar *stale, *live, *name;
    CaseRun run;

    g_mkdir(home, 0700);
    hc = slow_case(scratch, rng, 0);
    run_and_signal(hc, home, SIGKILL, g_rand_int_range(rng, 0, 1500000));
    name = g_strdup_printf(".out.gwy.%d.AbCdEf" SAFE_OUTPUT_SUFFIX, (gint)test_dead_pid());
    stale = case_file(hc, name);
    write_bytes(stale, "half", 4);
    g_free(name);
    name = g_strdup_printf(".out.gwy.%d.GhIjKl" SAFE_OUTPUT_SUFFIX, (gint)getpid());
    live = case_file(hc, name);
    write_bytes(live, "busy", 4);
    g_ptr_array_add(hc->kept, g_strdup(live));
    g_free(name);

    g_ptr_array_remove_index(hc->argv, hc->argv->len - 1);
    g_ptr_array_add(hc->argv, NULL);
    run_case(hc, home, &run);
    ck_assert_msg(run.status == 0, "seed %u: the run after a SIGKILL failed: %s", seed, run.err);
    ck_assert_msg(!g_file_test(stale, G_FILE_TEST_EXISTS), "seed %u: a dead run's temporary stays",
                  seed);
    ck_assert_msg(g_file_test(live, G_FILE_TEST_EXISTS), "seed %u: a live run's temporary was removed",
                  seed);
    ck_assert_int_eq(count_temporaries(hc->dir), 1);
    check_no_leftovers(hc, TRUE, "after SIGKILL");
    g_free(run.err);
    g_free(stale);
    g_free(live);
    case_free(hc);
    g_rand_free(rng);
    test_remove_tree(scratch);
    g_free(home);
    g_free(scratch);
}
END_TEST

static Suite*
hostile_suite(void)
{
    TCase *tc;
    Suite *suite = test_suite_new("hostile-input", "core", &tc);

    tcase_set_timeout(tc, 60*N_CASES);
    tcase_add_test(tc, test_generated_cases);
    tcase_add_test(tc, test_warning_then_failure);
    tcase_add_test(tc, test_terminated_runs);
    tcase_add_test(tc, test_killed_run_swept);
    return suite;
}

int
main(void)
{
    gwy_type_init();
    /* Data fields must deserialise, or outputs would be judged empty. */
    gwy_process_type_init();
    seed = test_seed_from_env("test-hostile-input");
    return test_run_suite(hostile_suite());
}
