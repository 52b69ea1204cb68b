/*
 *  The core pieces of the hostile-input defence, on seeded random input:
 *  missing pixels in both compensation modes, the linear stripe fill
 *  against the nearest-stripe rule, message excerpts, the .gwy screening
 *  on every truncation of a real file, and the sweep of dead runs'
 *  temporaries.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <math.h>
#include <string.h>
#include <errno.h>
#include <unistd.h>
#include <sys/wait.h>
#include <glib/gstdio.h>
#include <gio/gio.h>
#include <libgwyddion/gwyddion.h>
#include <libprocess/gwyprocess.h>
#include "stripe-geometry.h"
#include "paper-compensate.h"
#include "continuous-compensate.h"
#include "drift-table.h"
#include "missing-data.h"
#include "quoted-input.h"
#include "file-screening.h"
#include "safe-output.h"
#include "test-common.h"

static guint32 seed;

/* The fill is the nearest-stripe rule, stripe by stripe. */
START_TEST(test_stripe_fill_is_nearest_rule)
{
    GRand *rng = g_rand_new_with_seed(seed);
    gint trial, n, s, src;

    for (trial = 0; trial < 300; trial++) {
        gdouble p = g_rand_double(rng);
        gboolean *has, any = FALSE;
        gdouble *dx, *dy;

        n = g_rand_int_range(rng, 1, 200);
        has = g_new(gboolean, n);
        dx = g_new(gdouble, n);
        dy = g_new(gdouble, n);
        for (s = 0; s < n; s++) {
            has[s] = (g_rand_double(rng) < p);
            any = any || has[s];
            dx[s] = has[s] ? s + 0.5 : NAN;
            dy[s] = has[s] ? -s : NAN;
        }
        ck_assert_int_eq(stripe_drift_fill_missing(n, has, dx, dy), any);
        for (s = 0; any && s < n; s++) {
            src = stripe_drift_nearest_source(s, n, has);
            ck_assert_msg(dx[s] == src + 0.5 && dy[s] == -src,
                          "seed %u, trial %d: stripe %d of %d took %g, nearest is %d", seed, trial,
                          s, n, dx[s], src);
        }
        g_free(has);
        g_free(dx);
        g_free(dy);
    }
    g_rand_free(rng);
}
END_TEST

static gdouble*
random_image(GRand *rng, gint n, gdouble missing)
{
    static const gdouble specials[3] = { NAN, INFINITY, -INFINITY };
    gdouble *a = g_new(gdouble, n);
    gint i;

    for (i = 0; i < n; i++)
        a[i] = g_rand_double(rng) < missing ? specials[g_rand_int_range(rng, 0, 3)]
                                            : g_rand_double_range(rng, -1, 1);
    return a;
}

/* Paper mode: missing sources give the fill value and the mask; every
 * other pixel is what the image without them gives, bit for bit. */
START_TEST(test_paper_missing_pixels)
{
    GRand *rng = g_rand_new_with_seed(seed ^ 1);
    gint trial;

    for (trial = 0; trial < 100; trial++) {
        gint xres = g_rand_int_range(rng, 1, 40), yres = g_rand_int_range(rng, 1, 40);
        gint n = g_rand_int_range(rng, 1, yres + 1), s, i, npx = xres*yres;
        gint *dx = g_new(gint, n), *dy = g_new(gint, n);
        gdouble *a = random_image(rng, npx, g_rand_double_range(rng, 0, 0.4));
        gdouble *clean = missing_data_filled_copy(a, npx, 0.0);
        gdouble *r = g_new(gdouble, npx), *m = g_new(gdouble, npx);
        gdouble *rc = g_new(gdouble, npx), *mc = g_new(gdouble, npx);
        gdouble *marks = g_new(gdouble, npx), *mr = g_new(gdouble, npx), *mm = g_new(gdouble, npx);
        gdouble fill = paper_image_mean(a, xres, yres);

        for (s = 0; s < n; s++) {
            dx[s] = g_rand_int_range(rng, -5, 6);
            dy[s] = g_rand_int_range(rng, -5, 6);
        }
        for (i = 0; i < npx; i++)
            marks[i] = isfinite(a[i]) ? 0.0 : 1.0;
        ck_assert(isfinite(fill));
        paper_compensate(a, xres, yres, n, dx, dy, fill, r, m);
        paper_compensate(clean, xres, yres, n, dx, dy, fill, rc, mc);
        /* Where each output pixel's source was missing. */
        paper_compensate(marks, xres, yres, n, dx, dy, 0.0, mr, mm);
        for (i = 0; i < npx; i++) {
            ck_assert_msg(isfinite(r[i]), "seed %u: a non-finite result", seed);
            if (mr[i] > 0.5)
                ck_assert(r[i] == fill && m[i] == 1.0);
            else {
                ck_assert(memcmp(r + i, rc + i, sizeof(gdouble)) == 0);
                ck_assert(m[i] == mc[i]);
            }
        }
        g_free(dx);
        g_free(dy);
        g_free(a);
        g_free(clean);
        g_free(r);
        g_free(m);
        g_free(rc);
        g_free(mc);
        g_free(marks);
        g_free(mr);
        g_free(mm);
    }
    g_rand_free(rng);
}
END_TEST

/* Continuous mode with constant whole-pixel drift is paper mode: the
 * missing pixels land where paper mode puts them, filled and masked, and
 * every value is finite for every kernel. */
START_TEST(test_continuous_missing_pixels)
{
    static const GwyInterpolationType kernels[] = {
        GWY_INTERPOLATION_ROUND, GWY_INTERPOLATION_LINEAR, GWY_INTERPOLATION_KEY,
        GWY_INTERPOLATION_BSPLINE, GWY_INTERPOLATION_OMOMS,
    };
    GRand *rng = g_rand_new_with_seed(seed ^ 2);
    gint trial;

    for (trial = 0; trial < 20; trial++) {
        gint xres = g_rand_int_range(rng, 8, 40), yres = g_rand_int_range(rng, 8, 40), i;
        gint npx = xres*yres, vx = g_rand_int_range(rng, -3, 4), vy = g_rand_int_range(rng, -3, 4);
        GwyInterpolationType kernel = kernels[g_rand_int_range(rng, 0, G_N_ELEMENTS(kernels))];
        gdouble *a = random_image(rng, npx, g_rand_double_range(rng, 0, 0.4));
        gdouble *r = g_new(gdouble, npx), *m = g_new(gdouble, npx);
        gdouble *pr = g_new(gdouble, npx), *pm = g_new(gdouble, npx);
        gchar *text = g_strdup_printf("stripe,dx,dy\n0,%d,%d\n1,%d,%d\n", vx, vy, vx, vy);
        DriftTable *table = drift_table_parse(text, -1, "constant.csv", NULL);
        gint dx[1] = { vx }, dy[1] = { vy };
        GError *error = NULL;

        ck_assert_ptr_nonnull(table);
        ck_assert_msg(continuous_compensate_table(a, xres, yres, table, 1.0, 1.0, NULL, kernel, 0.25,
                                                  r, m, &error),
                      "seed %u: %s", seed, error ? error->message : "?");
        paper_compensate(a, xres, yres, 1, dx, dy, 0.25, pr, pm);
        for (i = 0; i < npx; i++) {
            ck_assert_msg(isfinite(r[i]), "seed %u, kernel %d: non-finite at %d", seed, kernel, i);
            if (pm[i] > 0.5)
                ck_assert_msg(m[i] == 1.0 && r[i] == 0.25, "seed %u: pixel %d not filled", seed, i);
        }
        drift_table_free(table);
        g_free(text);
        g_free(a);
        g_free(r);
        g_free(m);
        g_free(pr);
        g_free(pm);
    }
    g_rand_free(rng);
}
END_TEST

START_TEST(test_missing_refused_past_half)
{
    gdouble a[4] = { 1.0, NAN, INFINITY, 2.0 }, b[4] = { NAN, NAN, -INFINITY, 2.0 };
    GError *error = NULL;

    ck_assert(missing_data_check(a, 2, 2, "a", NULL));
    ck_assert(!missing_data_check(b, 2, 2, "b", &error));
    ck_assert(strstr(error->message, "3 of its 4 pixels are missing"));
    g_error_free(error);
    ck_assert(paper_image_mean(a, 2, 2) == 1.5);
}
END_TEST

/* A finite value too large for arithmetic (the mean of values near the
 * largest double overflowed, and the result held infinite pixels) is
 * refused by its value, wherever it lies; 1e150 itself is kept. */
START_TEST(test_values_beyond_range_refused)
{
    GRand *rng = g_rand_new_with_seed(seed ^ 5);
    enum { N = 4096 };
    gdouble *a = g_new(gdouble, N), v;
    GError *error = NULL;
    gchar *expected;
    gint i, at;

    for (i = 0; i < N; i++)
        a[i] = g_rand_double_range(rng, -1e-9, 1e-9);
    a[g_rand_int_range(rng, 0, N)] = MISSING_DATA_VALUE_MAX;
    a[g_rand_int_range(rng, 0, N)] = NAN;
    ck_assert(missing_data_check(a, 64, 64, "a", NULL));
    at = g_rand_int_range(rng, 0, N);
    v = (g_rand_boolean(rng) ? 1.0 : -1.0)*pow(10.0, g_rand_double_range(rng, 150.01, 308.25));
    a[at] = v;
    ck_assert(!missing_data_check(a, 64, 64, "the image", &error));
    ck_assert(g_error_matches(error, MISSING_DATA_ERROR, MISSING_DATA_ERROR_RANGE));
    expected = g_strdup_printf("the image holds the value %g, beyond 1e+150 in magnitude: no arithmetic on "
                               "such values stays finite", v);
    ck_assert_str_eq(error->message, expected);
    g_clear_error(&error);
    g_free(expected);
    g_free(a);
    g_rand_free(rng);
}
END_TEST

/* A program killed while writing many outputs at once (simscan benchmark
 * writes every file of its cases as one set) leaves none of their
 * temporary files: 32 were remembered, the rest were left behind. */
START_TEST(test_killed_with_many_temporaries)
{
    gchar *dir = g_dir_make_tmp("test-hostile-core-XXXXXX", NULL);
    GRand *rng = g_rand_new_with_seed(seed ^ 6);
    gint n = g_rand_int_range(rng, 200, 1200), status, i, fds[2];
    const gchar *name;
    GDir *listing;
    gint left = 0;
    GPid pid;
    gchar c;

    ck_assert_int_eq(pipe(fds), 0);
    pid = fork();
    if (pid == 0) {
        for (i = 0; i < n; i++) {
            gchar *target = g_strdup_printf("%s/out-%04d.gwy", dir, i);
            gint fd;
            gchar *tmp = safe_output_temp_new(target, "", &fd);

            if (!tmp)
                _exit(3);
            close(fd);
            g_free(tmp);
            g_free(target);
        }
        if (write(fds[1], "x", 1) != 1)
            _exit(4);
        pause();
        _exit(5);
    }
    /* The write end closed here: a child that died early ends the read. */
    close(fds[1]);
    ck_assert_int_eq(read(fds[0], &c, 1), 1);
    kill(pid, SIGTERM);
    waitpid(pid, &status, 0);
    ck_assert(WIFSIGNALED(status) && WTERMSIG(status) == SIGTERM);
    listing = g_dir_open(dir, 0, NULL);
    while ((name = g_dir_read_name(listing)))
        left++;
    g_dir_close(listing);
    ck_assert_msg(!left, "%d of %d temporary files left behind", left, n);
    g_rmdir(dir);
    close(fds[0]);
    g_free(dir);
    g_rand_free(rng);
}
END_TEST

/* Whatever the bytes, an excerpt is short, valid and printable. */
START_TEST(test_excerpts)
{
    GRand *rng = g_rand_new_with_seed(seed ^ 3);
    gchar *text, *q, *line;
    gint trial, length, i;
    const gchar *p;

    q = quoted_input_excerpt("1.5x", -1);
    ck_assert_str_eq(q, "1.5x");
    g_free(q);
    for (trial = 0; trial < 200; trial++) {
        length = trial < 5 ? 10 << 20 : g_rand_int_range(rng, 0, 5000);
        text = g_new(gchar, length + 1);
        for (i = 0; i < length; i++)
            text[i] = (gchar)g_rand_int_range(rng, 1, 256);
        text[length] = '\0';
        q = quoted_input_excerpt(text, length);
        line = quoted_input_message_line(text);
        ck_assert(g_utf8_validate(q, -1, NULL) && g_utf8_validate(line, -1, NULL));
        /* 40 characters, each at most \uXXXX, and "...". */
        ck_assert_int_le(strlen(q), QUOTED_INPUT_EXCERPT_CHARS*6 + 3);
        ck_assert_int_le(strlen(line), QUOTED_INPUT_MESSAGE_CHARS*6 + 3);
        for (p = q; *p; p++)
            ck_assert((guchar)*p >= 0x20 && *p != 0x7f);
        ck_assert(!strchr(line, '\n') && !strchr(line, '\r'));
        g_free(q);
        g_free(line);
        g_free(text);
    }
    g_rand_free(rng);
}
END_TEST

/* Where needle first occurs in haystack, NULL if nowhere. */
static guint8*
find_bytes(guint8 *haystack, gsize len, const guint8 *needle, gsize n)
{
    gsize i;

    for (i = 0; i + n <= len; i++) {
        if (memcmp(haystack + i, needle, n) == 0)
            return haystack + i;
    }
    return NULL;
}

/* A real .gwy passes; every shorter prefix of it is refused, and random
 * damage is refused or passed without reading outside the bytes. */
START_TEST(test_screening_truncations)
{
    GwyContainer *container = gwy_container_new();
    GwyDataField *field = gwy_data_field_new(5, 3, 5e-9, 3e-9, TRUE);
    GByteArray *bytes = g_byte_array_new();
    GRand *rng = g_rand_new_with_seed(seed ^ 4);
    GError *error = NULL;
    guint8 *copy;
    guint len, i;

    gwy_container_set_object_by_name(container, "/0/data", field);
    gwy_container_set_const_string_by_name(container, "/0/data/title", (const guchar*)"Height");
    g_byte_array_append(bytes, (const guint8*)"GWYP", 4);
    gwy_serializable_serialize(G_OBJECT(container), bytes);
    ck_assert(file_screening_check_bytes("x.gwy", bytes->data, bytes->len, NULL));
    for (len = 0; len < bytes->len; len++) {
        copy = g_memdup2(bytes->data, MAX(len, 1));
        ck_assert_msg(!file_screening_check_bytes("x.gwy", copy, len, &error),
                      "a %u of %u byte prefix passed", len, bytes->len);
        ck_assert(g_str_has_prefix(error->message, "x.gwy: ") && !strchr(error->message, '\n'));
        g_clear_error(&error);
        g_free(copy);
    }
    for (i = 0; i < 2000; i++) {
        copy = g_memdup2(bytes->data, bytes->len);
        copy[g_rand_int_range(rng, 4, bytes->len)] = (guint8)g_rand_int_range(rng, 0, 256);
        file_screening_check_bytes("x.gwy", copy, bytes->len, NULL);
        g_free(copy);
    }
    /* A width of 0, less or NaN, which Gwyddion would take for 1 m. */
    for (i = 0; i < 3; i++) {
        static const gdouble widths[3] = { 0.0, -5e-9, NAN };
        guint8 *at;

        copy = g_memdup2(bytes->data, bytes->len);
        at = find_bytes(copy, bytes->len, (const guint8*)"xreal\0d", 7);
        ck_assert(at != NULL);
        memcpy(at + 7, widths + i, sizeof(gdouble));
        ck_assert(!file_screening_check_bytes("x.gwy", copy, bytes->len, &error));
        ck_assert_msg(strstr(error->message, "physical width or height is not a positive number"),
                      "%s", error->message);
        g_clear_error(&error);
        g_free(copy);
    }
    ck_assert(!file_screening_check_bytes("x.gwy", (const guint8*)"not gwy", 7, NULL));
    ck_assert(file_screening_check_bytes("x.txt", (const guint8*)"1 2\n3 4\n", 8, NULL));
    g_rand_free(rng);
    g_byte_array_free(bytes, TRUE);
    g_object_unref(field);
    g_object_unref(container);
}
END_TEST

/* Compressed input (a .axz is gzipped XML) passes whole, and every cut
 * of it is refused: a loader read what it could of a cut .axz and the
 * tools corrected part of its channels as if it were the file. */
START_TEST(test_screening_gzip_truncations)
{
    GConverter *deflater = G_CONVERTER(g_zlib_compressor_new(G_ZLIB_COMPRESSOR_FORMAT_GZIP, 6));
    GRand *rng = g_rand_new_with_seed(seed ^ 5);
    GString *text = g_string_new("<?xml version=\"1.0\"?><Document>");
    GError *error = NULL;
    gsize nread, nwritten, cap, len;
    guint8 *packed;
    guint i;

    for (i = 0; i < 4000; i++)
        g_string_append_printf(text, "<v>%u</v>", g_rand_int(rng));
    g_string_append(text, "</Document>");
    cap = text->len + 1024;
    packed = g_malloc(cap);
    ck_assert_int_eq(g_converter_convert(deflater, text->str, text->len, packed, cap,
                                         G_CONVERTER_INPUT_AT_END, &nread, &nwritten, NULL),
                     G_CONVERTER_FINISHED);
    ck_assert(file_screening_check_bytes("film.axz", packed, nwritten, NULL));
    for (i = 0; i < 200; i++) {
        len = (i < 20) ? 2 + i : (gsize)g_rand_int_range(rng, 2, nwritten);
        ck_assert_msg(!file_screening_check_bytes("film.axz", packed, len, &error),
                      "a %" G_GSIZE_FORMAT " of %" G_GSIZE_FORMAT " byte prefix passed", len, nwritten);
        ck_assert_str_eq(error->message, "film.axz: truncated or corrupt: its compressed data do "
                         "not decompress to their end");
        g_clear_error(&error);
    }
    /* Several members (bgzip, pigz) pass, as does zero padding after the
     * last; a cut second member or anything else after one does not. */
    {
        guint8 *two = g_malloc(2*nwritten + 16);
        static const gchar *const tails[] = { "", "\0\0\0\0", "junk" };

        memcpy(two, packed, nwritten);
        memcpy(two + nwritten, packed, nwritten);
        ck_assert(file_screening_check_bytes("film.axz", two, 2*nwritten, NULL));
        ck_assert(!file_screening_check_bytes("film.axz", two, 2*nwritten - 9, &error));
        ck_assert(strstr(error->message, "truncated or corrupt"));
        g_clear_error(&error);
        for (i = 1; i < G_N_ELEMENTS(tails); i++) {
            memcpy(two + nwritten, tails[i], 4);
            ck_assert(file_screening_check_bytes("film.axz", two, nwritten + 4, &error) == (i == 1));
            if (i == 2)
                ck_assert_str_eq(error->message, "film.axz: corrupt: something else than "
                                 "compressed data follows them");
            g_clear_error(&error);
        }
        g_free(two);
    }
    g_free(packed);
    g_string_free(text, TRUE);
    g_rand_free(rng);
    g_object_unref(deflater);
}
END_TEST

/* A dead run's temporary is swept, a live run's and other files stay. */
START_TEST(test_sweep)
{
    gchar *dir = g_strdup(TEST_BUILDDIR "/tests/scratch-hostile-core-XXXXXX");
    gchar *target, *dead, *live, *other, *mine;
    gint fd;
    GPid pid;

    ck_assert_ptr_nonnull(g_mkdtemp(dir));
    pid = test_dead_pid();
    target = g_build_filename(dir, "out.gwy", NULL);
    dead = g_strdup_printf("%s/.out.gwy.%d.aBcDeF" SAFE_OUTPUT_SUFFIX, dir, (gint)pid);
    live = g_strdup_printf("%s/.out.gwy.%d.gHiJkL" SAFE_OUTPUT_SUFFIX, dir, (gint)getppid());
    other = g_strdup_printf("%s/.other.gwy.%d.mNoPqR" SAFE_OUTPUT_SUFFIX, dir, (gint)pid);
    g_file_set_contents(dead, "x", 1, NULL);
    g_file_set_contents(live, "x", 1, NULL);
    g_file_set_contents(other, "x", 1, NULL);
    mine = safe_output_temp_new(target, "", &fd);
    ck_assert_ptr_nonnull(mine);
    close(fd);
    ck_assert(!g_file_test(dead, G_FILE_TEST_EXISTS));
    ck_assert(g_file_test(live, G_FILE_TEST_EXISTS) && g_file_test(other, G_FILE_TEST_EXISTS));
    ck_assert(safe_output_is_temp_name(strrchr(mine, '/') + 1));
    safe_output_discard(mine);
    ck_assert(!g_file_test(mine, G_FILE_TEST_EXISTS));
    g_unlink(live);
    g_unlink(other);
    g_rmdir(dir);
    g_free(mine);
    g_free(target);
    g_free(dead);
    g_free(live);
    g_free(other);
    g_free(dir);
}
END_TEST

/* An output name near the longest a file name may be still gets its
 * temporary beside it: the temporary's name carries the output's cut
 * short (a 235-character output name was refused with "File name too
 * long"), and the sweep finds a dead run's temporary by the same cut. */
START_TEST(test_long_output_name)
{
    gchar *dir = g_strdup(TEST_BUILDDIR "/tests/scratch-hostile-core-XXXXXX");
    gchar *base, *target, *mine, *dead, *cut;
    gint fd;
    GPid pid;

    ck_assert_ptr_nonnull(g_mkdtemp(dir));
    base = g_strnfill(251, 'x');
    memcpy(base + 247, ".gwy", 4);
    target = g_build_filename(dir, base, NULL);
    pid = test_dead_pid();
    mine = safe_output_temp_new(target, "old.", &fd);
    ck_assert_msg(mine != NULL, "no temporary beside a 251-byte name: %s", g_strerror(errno));
    close(fd);
    ck_assert_int_le(strlen(strrchr(mine, '/') + 1), 255);
    ck_assert(safe_output_is_temp_name(strrchr(mine, '/') + 1));
    /* A dead run's temporary, named with the same cut, is swept. */
    cut = g_strndup(strrchr(mine, '/') + 2, strchr(strrchr(mine, '/') + 2, '.') - (strrchr(mine, '/') + 2));
    ck_assert(g_str_has_prefix(base, cut) && strlen(cut) >= 150);
    dead = g_strdup_printf("%s/.%s.%d.aBcDeF" SAFE_OUTPUT_SUFFIX, dir, cut, (gint)pid);
    ck_assert(g_file_set_contents(dead, "x", 1, NULL));
    safe_output_sweep(target);
    ck_assert(!g_file_test(dead, G_FILE_TEST_EXISTS));
    safe_output_discard(mine);
    ck_assert(!g_file_test(mine, G_FILE_TEST_EXISTS));
    g_rmdir(dir);
    g_free(dead);
    g_free(cut);
    g_free(mine);
    g_free(target);
    g_free(base);
    g_free(dir);
}
END_TEST

static Suite*
hostile_core_suite(void)
{
    TCase *tc;
    Suite *suite = test_suite_new("hostile-core", "core", &tc);

    tcase_add_test(tc, test_stripe_fill_is_nearest_rule);
    tcase_add_test(tc, test_paper_missing_pixels);
    tcase_add_test(tc, test_continuous_missing_pixels);
    tcase_add_test(tc, test_missing_refused_past_half);
    tcase_add_test(tc, test_values_beyond_range_refused);
    tcase_add_test(tc, test_killed_with_many_temporaries);
    tcase_add_test(tc, test_excerpts);
    tcase_add_test(tc, test_screening_truncations);
    tcase_add_test(tc, test_screening_gzip_truncations);
    tcase_add_test(tc, test_sweep);
    tcase_add_test(tc, test_long_output_name);
    return suite;
}

int
main(void)
{
    gwy_process_type_init();
    seed = test_seed_from_env("test-hostile-core");
    return test_run_suite(hostile_core_suite());
}
