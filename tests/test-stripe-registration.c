/*
 *  Tests of the stripe registration against a reference frame.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <check.h>
#include <fftw3.h>
#include <libprocess/gwyprocess.h>
#include "stripe-registration.h"
#include "registration-frames.h"
#include "test-common.h"

static guint32 test_seed;



typedef struct {
    gdouble rms;
    gdouble max;
    gint accepted;
    gint stripes;
} Errors;

static void
register_pair(const FramePair *pair, gint n, StripeShift *shifts)
{
    GError *error = NULL;
    gboolean ok;

    ok = stripe_registration_measure(pair->image, pair->reference, pair->xres, pair->yres, n, NULL, shifts, &error);
    ck_assert_msg(ok, "registration failed: %s", error ? error->message : "?");
}

static void
add_errors(const FramePair *pair, gint n, Errors *errors)
{
    StripeShift *shifts = g_new(StripeShift, n);
    gdouble *tx = g_new(gdouble, n), *ty = g_new(gdouble, n);
    gdouble sum = errors->rms*errors->rms*errors->accepted;
    gint s;

    register_pair(pair, n, shifts);
    frame_pair_stripe_truth(pair, n, tx, ty);
    /* A rejected stripe has no value (the table leaves it blank; its dx,
     * dy are diagnostics): the errors are those of the values given, and
     * how many are given is asserted on its own.  A stripe drifted more
     * than half off the reference is rightly rejected (seed 3996725253:
     * 59 % off, diagnostics 1.57 px from the truth). */
    for (s = 0; s < n; s++) {
        gdouble e = hypot(shifts[s].dx - tx[s], shifts[s].dy - ty[s]);

        if (!shifts[s].accepted)
            continue;
        sum += e*e;
        errors->max = MAX(errors->max, e);
        errors->accepted++;
    }
    errors->stripes += n;
    errors->rms = errors->accepted ? sqrt(sum/errors->accepted) : 0.0;
    g_free(shifts);
    g_free(tx);
    g_free(ty);
}

static void
check_random_pairs(gint xres, gint yres, gint n, gint pairs)
{
    FramePairSpec spec;
    Errors errors = { 0, 0, 0, 0 };
    gint i;

    frame_pair_spec_init(&spec);
    spec.xres = xres;
    spec.yres = yres;
    for (i = 0; i < pairs; i++) {
        FramePair *pair = frame_pair_generate(&spec, test_seed + i);

        add_errors(pair, n, &errors);
        frame_pair_free(pair);
    }
    printf("%dx%d, N = %d, %d pairs: rms %.4f px, max %.4f px, %d of %d accepted\n",
           xres, yres, n, pairs, errors.rms, errors.max, errors.accepted, errors.stripes);
    ck_assert_msg(errors.rms <= 0.15, "rms error %g px > 0.15 px (seed %u)", errors.rms, test_seed);
    ck_assert_msg(errors.max < 1.0, "max error %g px >= 1 px (seed %u)", errors.max, test_seed);
    ck_assert_msg(errors.accepted >= 0.9*errors.stripes, "only %d of %d stripes accepted (seed %u)",
                  errors.accepted, errors.stripes, test_seed);
}

START_TEST(test_random_drift_pairs)
{
    check_random_pairs(256, 256, 16, 10);
}
END_TEST

/* How a hole in the reference is given: NaN pixels, or filled with the
 * frame's mean and marked in a mask, as Gwyddion's importers give what a
 * file lacks (registered with masked pixels excluded). */
typedef enum {
    HOLE_NAN,
    HOLE_MASKED,
} HoleKind;

/* The fields' registration of pair, the reference's pixels in the
 * rectangle missing as kind says. */
static void
register_with_hole(const FramePair *pair, HoleKind kind, gint r0, gint c0, gint h, gint w,
                   gint n, StripeShift *shifts)
{
    GwyDataField *image = gwy_data_field_new(pair->xres, pair->yres, pair->xres, pair->yres, FALSE);
    GwyDataField *reference = gwy_data_field_new_alike(image, FALSE);
    GwyDataField *mask = gwy_data_field_new_alike(image, TRUE);
    StripeRegistrationOptions options;
    gdouble *ref = gwy_data_field_get_data(reference), mean;
    GError *error = NULL;
    gint r, c;

    memcpy(gwy_data_field_get_data(image), pair->image, pair->xres*pair->yres*sizeof(gdouble));
    memcpy(ref, pair->reference, pair->xres*pair->yres*sizeof(gdouble));
    mean = gwy_data_field_get_avg(reference);
    for (r = r0; r < r0 + h; r++) {
        for (c = c0; c < c0 + w; c++) {
            ref[r*pair->xres + c] = (kind == HOLE_NAN) ? NAN : mean;
            gwy_data_field_set_val(mask, c, r, 1.0);
        }
    }
    gwy_data_field_invalidate(reference);
    stripe_registration_options_init(&options);
    if (kind == HOLE_MASKED) {
        options.reference_mask = mask;
        options.masking = GWY_MASK_EXCLUDE;
    }
    ck_assert_msg(stripe_registration_measure_fields(image, reference, n, &options, shifts, &error),
                  "registration failed: %s", error ? error->message : "?");
    g_object_unref(mask);
    g_object_unref(reference);
    g_object_unref(image);
}

/* Missing pixels in the reference read as 0 in the conditioned frames;
 * the sub-pixel match must leave out the pixels whose reference sample
 * reaches them.  A hole of 20-40 px at a random place in the reference of
 * each pair, under the random drift: the stripes whose content meets it
 * are held to what the others give (before the fix: rms 0.20 px, 0.84 px
 * at worst over 20 pairs, against 0.036 px elsewhere). */
static void
check_reference_holes(HoleKind kind)
{
    enum { N = 16, PAIRS = 6 };
    FramePairSpec spec;
    GRand *rng = g_rand_new_with_seed(test_seed ^ 0x401eu);
    gdouble sum2 = 0.0, worst = 0.0;
    gint i, s, met = 0, given = 0;

    frame_pair_spec_init(&spec);
    for (i = 0; i < PAIRS; i++) {
        FramePair *pair = frame_pair_generate(&spec, test_seed + 104729u*i);
        gint w = g_rand_int_range(rng, 20, 41), h = g_rand_int_range(rng, 20, 41);
        gint r0 = g_rand_int_range(rng, 40, pair->yres - 40 - h), c0 = g_rand_int_range(rng, 40, pair->xres - 40 - w);
        StripeShift shifts[N];
        gdouble tx[N], ty[N];

        register_with_hole(pair, kind, r0, c0, h, w, N, shifts);
        frame_pair_stripe_truth(pair, N, tx, ty);
        for (s = 0; s < N; s++) {
            gint first = s*pair->yres/N, end = (s + 1)*pair->yres/N;
            gdouble e = hypot(shifts[s].dx - tx[s], shifts[s].dy - ty[s]);

            /* The stripe's content lies ty rows higher in the reference. */
            if (first - ty[s] - 2 >= r0 + h || end - ty[s] + 2 <= r0)
                continue;
            met++;
            if (!shifts[s].accepted)
                continue;
            given++;
            sum2 += e*e;
            worst = MAX(worst, e);
        }
        frame_pair_free(pair);
    }
    g_rand_free(rng);
    printf("reference holes (%s): %d of %d stripes meeting them given, rms %.4f px, worst %.4f px\n",
           kind == HOLE_NAN ? "NaN" : "masked", given, met, given ? sqrt(sum2/given) : 0.0, worst);
    ck_assert_msg(given >= 0.8*met, "only %d of %d stripes meeting a hole given (seed %u)", given, met,
                  test_seed);
    ck_assert_msg(sqrt(sum2/MAX(given, 1)) <= 0.08, "rms %g px on stripes meeting a hole (seed %u)",
                  sqrt(sum2/MAX(given, 1)), test_seed);
    ck_assert_msg(worst <= 0.3, "a stripe meeting a hole %g px off (seed %u)", worst, test_seed);
}

START_TEST(test_reference_hole)
{
    check_reference_holes(HOLE_NAN);
}
END_TEST

/* The same holes filled and masked, the masked pixels excluded: without
 * the mask the filled patch is a flat feature of the reference alone. */
START_TEST(test_masked_reference)
{
    check_reference_holes(HOLE_MASKED);
}
END_TEST

/* Scattered missing pixels: a frame's share of them, at places drawn at
 * random (a hostile-input run found 11 of 16 stripes registered with this
 * share of the reference missing, 16 without). */
#define SCATTERED_SHARE 0.2

/* Where the scattered missing pixels lie and how they are given. */
typedef enum {
    SCATTERED_IN_REFERENCE,   /* NaN and infinities in the reference */
    SCATTERED_IN_IMAGE,       /* masked pixels of the image (excluded),
                                 filled with its mean as importers fill */
    SCATTERED_IN_BOTH,        /* NaN in both frames */
    SCATTERED_PLACES
} ScatteredPlace;

static const gchar *const scattered_place_names[SCATTERED_PLACES] = {
    "in the reference", "masked in the image", "in both frames",
};

typedef struct {
    gint given;               /* stripes given with missing pixels */
    gint clean_given;         /* the same pairs' stripes given without */
    gint compared;            /* given both ways */
    gdouble sum2_clean;       /* squared distance from the clean shift */
    gdouble worst_clean;
    gdouble sum2_truth;       /* squared error (centre rows' drift) */
    gdouble worst_truth;
} ScatteredTally;

/* share of the n values of data, drawn by rng, become missing: NaN, or
 * one of the infinities for one in four; missing (may be NULL) marks
 * them. */
static void
scatter_missing(gdouble *data, gint n, gdouble share, GRand *rng, gboolean *missing)
{
    static const gdouble specials[4] = { NAN, NAN, NAN, INFINITY };
    gint *order = g_new(gint, n), count = (gint)(share*n + 0.5), k, j, t;

    for (k = 0; k < n; k++)
        order[k] = k;
    /* The first count of a partial Fisher-Yates shuffle. */
    for (k = 0; k < count; k++) {
        j = g_rand_int_range(rng, k, n);
        t = order[k];
        order[k] = order[j];
        order[j] = t;
        data[order[k]] = (g_rand_boolean(rng) ? 1.0 : -1.0)*specials[g_rand_int_range(rng, 0, 4)];
        if (missing)
            missing[order[k]] = TRUE;
    }
    g_free(order);
}

/* The image's pixels marked in missing masked (excluded) and filled with
 * the mean of the others, registered against reference. */
static void
register_masked_image(const FramePair *pair, const gdouble *image, const gdouble *reference,
                      const gboolean *missing, gint n, StripeShift *shifts)
{
    gint npx = pair->xres*pair->yres, k, kept = 0;
    GwyDataField *ifield = gwy_data_field_new(pair->xres, pair->yres, pair->xres, pair->yres, FALSE);
    GwyDataField *rfield = gwy_data_field_new_alike(ifield, FALSE);
    GwyDataField *mask = gwy_data_field_new_alike(ifield, TRUE);
    gdouble *idata = gwy_data_field_get_data(ifield), *m = gwy_data_field_get_data(mask), mean = 0.0;
    StripeRegistrationOptions options;
    GError *error = NULL;

    for (k = 0; k < npx; k++) {
        if (!missing[k]) {
            mean += image[k];
            kept++;
        }
    }
    mean /= MAX(kept, 1);
    for (k = 0; k < npx; k++) {
        idata[k] = missing[k] ? mean : image[k];
        m[k] = missing[k] ? 1.0 : 0.0;
    }
    memcpy(gwy_data_field_get_data(rfield), reference, npx*sizeof(gdouble));
    stripe_registration_options_init(&options);
    options.image_mask = mask;
    options.masking = GWY_MASK_EXCLUDE;
    ck_assert_msg(stripe_registration_measure_fields(ifield, rfield, n, &options, shifts, &error),
                  "registration failed: %s", error ? error->message : "?");
    g_object_unref(mask);
    g_object_unref(rfield);
    g_object_unref(ifield);
}

/* The pair registered with scattered missing pixels placed as place says. */
static void
register_scattered(const FramePair *pair, ScatteredPlace place, GRand *rng, gint n, StripeShift *shifts)
{
    gint npx = pair->xres*pair->yres;
    gdouble *image = g_memdup2(pair->image, npx*sizeof(gdouble));
    gdouble *reference = g_memdup2(pair->reference, npx*sizeof(gdouble));
    gboolean *missing = g_new0(gboolean, npx);
    GError *error = NULL;

    if (place != SCATTERED_IN_IMAGE)
        scatter_missing(reference, npx, SCATTERED_SHARE, rng, NULL);
    if (place != SCATTERED_IN_REFERENCE)
        scatter_missing(image, npx, SCATTERED_SHARE, rng, missing);
    if (place == SCATTERED_IN_IMAGE)
        register_masked_image(pair, image, reference, missing, n, shifts);
    else {
        ck_assert_msg(stripe_registration_measure(image, reference, pair->xres, pair->yres, n, NULL, shifts,
                                                  &error),
                      "registration failed: %s", error ? error->message : "?");
    }
    g_free(missing);
    g_free(reference);
    g_free(image);
}

/* Adds the pair's stripes registered with missing pixels (shifts) against
 * the same without (clean) and the truth; each pair must keep all its clean
 * stripes but one. */
static void
tally_scattered(const gchar *place, const StripeShift *clean, const StripeShift *shifts, gint n,
                const gdouble *tx, const gdouble *ty, ScatteredTally *tally)
{
    gint s, given = 0, clean_given = 0;
    gdouble e;

    for (s = 0; s < n; s++) {
        clean_given += clean[s].accepted;
        if (!shifts[s].accepted)
            continue;
        given++;
        e = hypot(shifts[s].dx - tx[s], shifts[s].dy - ty[s]);
        tally->sum2_truth += e*e;
        tally->worst_truth = MAX(tally->worst_truth, e);
        if (!clean[s].accepted)
            continue;
        e = hypot(shifts[s].dx - clean[s].dx, shifts[s].dy - clean[s].dy);
        tally->sum2_clean += e*e;
        tally->worst_clean = MAX(tally->worst_clean, e);
        tally->compared++;
    }
    tally->given += given;
    tally->clean_given += clean_given;
    ck_assert_msg(given >= clean_given - 1, "missing pixels %s: %d of %d stripes given, %d without (seed %u)",
                  place, given, n, clean_given, test_seed);
}

/* Rows of the reference missing across its width, over where stripe s's
 * content lies and margin rows beyond, and the rest missing at random as
 * in the reference above: that stripe has nothing to match and must stay
 * empty, not take what the restored pixels or the filters' reach would
 * give it. */
static void
check_absent_content(const FramePair *pair, gint s, gint n, const gdouble *ty, GRand *rng)
{
    gint npx = pair->xres*pair->yres, margin = 2, r0, r1, k;
    gint first = s*pair->yres/n, end = (s + 1)*pair->yres/n;
    gdouble *reference = g_memdup2(pair->reference, npx*sizeof(gdouble));
    StripeShift *shifts = g_new(StripeShift, n);

    scatter_missing(reference, npx, SCATTERED_SHARE, rng, NULL);
    r0 = MAX(0, (gint)floor(first - ty[s]) - margin);
    r1 = MIN(pair->yres, (gint)ceil(end - ty[s]) + margin);
    for (k = r0*pair->xres; k < r1*pair->xres; k++)
        reference[k] = NAN;
    ck_assert(stripe_registration_measure(pair->image, reference, pair->xres, pair->yres, n, NULL, shifts, NULL));
    ck_assert_msg(!shifts[s].accepted, "stripe %d given (%.2f, %.2f) px with its content missing from the "
                  "reference (seed %u)", s, shifts[s].dx, shifts[s].dy, test_seed);
    g_free(shifts);
    g_free(reference);
}

static void
print_scattered(const gchar *place, const ScatteredTally *tally)
{
    printf("scattered missing pixels %s: %d stripes given, %d without; from the clean shifts rms %.4f px, "
           "worst %.4f px; from the truth rms %.4f px, worst %.4f px\n", place, tally->given,
           tally->clean_given, sqrt(tally->sum2_clean/MAX(tally->compared, 1)), tally->worst_clean,
           sqrt(tally->sum2_truth/MAX(tally->given, 1)), tally->worst_truth);
}

/* The figures of a run of test_scattered_missing.  Over 151 runs of 4
 * pairs every stripe given without the missing pixels was given with them;
 * the rms from the clean shifts was at most 0.040, 0.035 and 0.055 px
 * (reference, image, both; median 0.032, 0.029, 0.044), from the truth
 * 0.061, 0.056 and 0.071 px (clean 0.037); the worst stripe 0.17, 0.13 and
 * 0.25 px from its clean shift, 0.26, 0.21 and 0.29 px from the truth. */
static void
assert_scattered_figures(const gchar *place, const ScatteredTally *tally)
{
    gdouble rms_clean = sqrt(tally->sum2_clean/MAX(tally->compared, 1));
    gdouble rms_truth = sqrt(tally->sum2_truth/MAX(tally->given, 1));

    ck_assert_msg(rms_clean <= 0.07, "missing pixels %s: rms %g px from the clean shifts (seed %u)",
                  place, rms_clean, test_seed);
    ck_assert_msg(tally->worst_clean <= 0.4, "missing pixels %s: a stripe %g px from its clean shift "
                  "(seed %u)", place, tally->worst_clean, test_seed);
    ck_assert_msg(rms_truth <= 0.09, "missing pixels %s: rms %g px (seed %u)", place, rms_truth, test_seed);
    ck_assert_msg(tally->worst_truth <= 0.5, "missing pixels %s: a stripe %g px off (seed %u)",
                  place, tally->worst_truth, test_seed);
}

/* Missing pixels carry no weight and take no more than theirs: a fifth
 * of a frame's pixels missing at random, in the reference, masked in the
 * image or in both, leaves every pair all the stripes it gives without
 * them but one, 0.03-0.05 px rms from their clean shifts (before the
 * conditioning restored them among data: up to 5 of 16 stripes lost with
 * the reference's missing, those given 0.24 px rms from the clean shifts;
 * with both frames' none given).  A stripe whose content is missing from
 * the reference stays empty. */
START_TEST(test_scattered_missing)
{
    enum { N = 16, PAIRS = 4 };
    GRand *rng = test_rand_salted(test_seed, 0x5ca7);
    ScatteredTally tally[SCATTERED_PLACES];
    FramePairSpec spec;
    gint i, place;

    gwy_clear(tally, SCATTERED_PLACES);
    frame_pair_spec_init(&spec);
    for (i = 0; i < PAIRS; i++) {
        FramePair *pair = frame_pair_generate(&spec, test_seed + 65537u*i);
        StripeShift clean[N], shifts[N];
        gdouble tx[N], ty[N];

        frame_pair_stripe_centre_truth(pair, N, tx, ty);
        register_pair(pair, N, clean);
        for (place = 0; place < SCATTERED_PLACES; place++) {
            register_scattered(pair, place, rng, N, shifts);
            tally_scattered(scattered_place_names[place], clean, shifts, N, tx, ty, tally + place);
        }
        check_absent_content(pair, g_rand_int_range(rng, 2, N - 2), N, ty, rng);
        frame_pair_free(pair);
    }
    for (place = 0; place < SCATTERED_PLACES; place++) {
        print_scattered(scattered_place_names[place], tally + place);
        assert_scattered_figures(scattered_place_names[place], tally + place);
    }
    g_rand_free(rng);
}
END_TEST

/* Masks that do not fit, or leave nothing, are refused with a message. */
START_TEST(test_bad_masks)
{
    GwyDataField *image = gwy_data_field_new(64, 64, 64, 64, TRUE);
    GwyDataField *reference = gwy_data_field_new_alike(image, TRUE);
    GwyDataField *small = gwy_data_field_new(64, 60, 64, 60, TRUE);
    GwyDataField *full = gwy_data_field_new_alike(image, FALSE);
    StripeRegistrationOptions options;
    StripeShift shifts[4];
    GError *error = NULL;

    gwy_data_field_fill(full, 1.0);
    stripe_registration_options_init(&options);
    options.masking = GWY_MASK_EXCLUDE;
    options.reference_mask = small;
    ck_assert(!stripe_registration_measure_fields(image, reference, 4, &options, shifts, &error));
    ck_assert_str_eq(error->message,
                     "The reference's mask (64 x 60 px) does not have the reference's size (64 x 64 px).");
    g_clear_error(&error);
    options.reference_mask = NULL;
    options.image_mask = full;
    ck_assert(!stripe_registration_measure_fields(image, reference, 4, &options, shifts, &error));
    ck_assert_str_eq(error->message, "The image's mask covers every pixel: with masked pixels excluded, "
                     "nothing is left to register.");
    g_clear_error(&error);
    /* Only the masked pixels are data: none is excluded (and the flat
     * frames give no stripe); an empty mask leaves nothing. */
    options.masking = GWY_MASK_INCLUDE;
    ck_assert_msg(stripe_registration_measure_fields(image, reference, 4, &options, shifts, &error),
                  "%s", error ? error->message : "?");
    ck_assert_int_eq(stripe_registration_count_accepted(shifts, 4), 0);
    options.image_mask = NULL;
    options.reference_mask = reference;
    ck_assert(!stripe_registration_measure_fields(image, reference, 4, &options, shifts, &error));
    ck_assert_str_eq(error->message, "Only masked pixels are used, and the reference's mask has none.");
    g_clear_error(&error);
    /* Ignored masks do not matter, whatever their size. */
    options.masking = GWY_MASK_IGNORE;
    options.reference_mask = small;
    ck_assert_msg(stripe_registration_measure_fields(image, reference, 4, &options, shifts, &error),
                  "%s", error ? error->message : "?");
    g_object_unref(full);
    g_object_unref(small);
    g_object_unref(reference);
    g_object_unref(image);
}
END_TEST

/* The one-call path the tool and the module use gives a px table. */
START_TEST(test_table_for_fields)
{
    FramePairSpec spec;
    FramePair *pair;
    GwyDataField *image, *reference;
    DriftTable *table;
    GError *error = NULL;
    gdouble tx[8], ty[8];
    gint s;

    frame_pair_spec_init(&spec);
    spec.xres = spec.yres = 128;
    pair = frame_pair_generate(&spec, test_seed);
    frame_pair_stripe_centre_truth(pair, 8, tx, ty);
    image = gwy_data_field_new(128, 128, 1e-6, 1e-6, FALSE);
    reference = gwy_data_field_new_alike(image, FALSE);
    memcpy(gwy_data_field_get_data(image), pair->image, 128*128*sizeof(gdouble));
    memcpy(gwy_data_field_get_data(reference), pair->reference, 128*128*sizeof(gdouble));
    table = stripe_registration_table_for_fields(image, reference, 8, NULL, TRUE, NULL, &error);
    ck_assert_msg(table, "%s", error ? error->message : "?");
    ck_assert_int_eq(table->n_stripes, 8);
    /* Whole pixels are the exact shifts rounded (drift_px_round()), and the
     * exact shifts lie within their stated uncertainty of the truth at the
     * stripe's centre row, which is what a stripe's shift stands for.
     * Against the mean of its rows, the first stripe, where the drift bends
     * most, was 0.27 px off at sigma 0.11 px (seed 47002177) and 0.25 px
     * off at sigma 0.074 px (seed 330001760), where the centre row's truth
     * was 0.057 px away. */
    for (s = 0; s < 8; s++) {
        gdouble exact, sigma;

        if (!table->rows[s].has_drift)
            continue;
        ck_assert(drift_table_get_extra(table, s, "dx_exact", &exact));
        ck_assert(drift_table_get_extra(table, s, "sigma_px", &sigma));
        ck_assert(table->rows[s].dx == drift_px_round(exact));
        ck_assert_msg(fabs(exact - tx[s]) <= MAX(3.0*sigma, 0.15), "stripe %d: dx %g, truth %g, sigma %g",
                      s, exact, tx[s], sigma);
    }
    drift_table_free(table);
    g_object_unref(image);
    g_object_unref(reference);
    frame_pair_free(pair);
}
END_TEST

START_TEST(test_non_square_images)
{
    check_random_pairs(320, 192, 12, 3);
    check_random_pairs(160, 300, 10, 3);
}
END_TEST

/* A whole-pixel shift is where a peak model fitted to the correlation map
 * errs most on the lopsided peak of a 16-row stripe (a 3x3 quadratic put
 * single stripes up to 0.1 px off, 0.023 px rms); the match on the
 * interpolated reference is exact without noise.  With this noise (0.02) it
 * gave at most 0.046 px per stripe and 0.018 px rms per pair over 300
 * seeds. */
START_TEST(test_integer_shift)
{
    FramePairSpec spec;
    FramePair *pair;
    StripeShift shifts[16];
    gdouble sum = 0.0, rms;
    gint s;

    frame_pair_spec_init(&spec);
    spec.drift = FALSE;
    spec.shift_x = 3.0;
    spec.shift_y = -2.0;
    spec.noise = 0.02;
    pair = frame_pair_generate(&spec, test_seed);
    register_pair(pair, 16, shifts);
    for (s = 0; s < 16; s++) {
        /* The last stripe has its bottom rows off the reference and near
         * its edge, fewer rows to match and a larger stated uncertainty
         * (seed 47002016: 0.075 px off, sigma 0.049 px). */
        gdouble bound = MAX(0.06, 3.0*shifts[s].sigma);

        ck_assert_msg(fabs(shifts[s].dx - 3.0) <= bound && fabs(shifts[s].dy + 2.0) <= bound,
                      "stripe %d: (%g, %g) instead of (3, -2), sigma %g (seed %u)", s, shifts[s].dx,
                      shifts[s].dy, shifts[s].sigma, test_seed);
        ck_assert(shifts[s].accepted);
        sum += (shifts[s].dx - 3.0)*(shifts[s].dx - 3.0) + (shifts[s].dy + 2.0)*(shifts[s].dy + 2.0);
    }
    rms = sqrt(sum/16);
    printf("integer shift (3, -2): rms error %.4f px\n", rms);
    ck_assert_msg(rms <= 0.03, "rms error %g px for an integer shift (seed %u)", rms, test_seed);
    frame_pair_free(pair);
}
END_TEST

/* The image is the reference moved by whole pixels by hand, independently
 * of the generator: content at (r, c) must appear at (r + dy, c + dx). */
START_TEST(test_sign_convention)
{
    const gdouble SIGN_TOLERANCE = 0.015;
    enum { RES = 128, DX = 5, DY = 2, N = 8 };
    FramePairSpec spec;
    FramePair *pair;
    gdouble *image = g_new(gdouble, RES*RES);
    StripeShift shifts[N];
    GError *error = NULL;
    gint r, c, s;

    frame_pair_spec_init(&spec);
    spec.xres = spec.yres = RES;
    spec.drift = FALSE;
    pair = frame_pair_generate(&spec, test_seed);
    for (r = 0; r < RES; r++) {
        for (c = 0; c < RES; c++)
            image[(r*RES) + c] = pair->reference[CLAMP(r - DY, 0, RES-1)*RES + CLAMP(c - DX, 0, RES-1)];
    }
    ck_assert(stripe_registration_measure(image, pair->reference, RES, RES, N, NULL, shifts, &error));
    /* Stripe 0 holds the repeated edge rows.  The others are the reference
     * itself moved by whole pixels, which the match on the interpolated
     * reference finds exactly but for the repeated edge rows and columns,
     * which the two frames' conditioning sees differently (0.0084 px at
     * most over seeds 1-300, 0.01001 px at seed 351611332; 0.0006 px
     * without conditioning). */
    for (s = 1; s < N; s++) {
        ck_assert_msg(fabs(shifts[s].dx - DX) <= SIGN_TOLERANCE && fabs(shifts[s].dy - DY) <= SIGN_TOLERANCE,
                      "stripe %d: (%g, %g) instead of (%d, %d)", s, shifts[s].dx, shifts[s].dy, DX, DY);
    }
    frame_pair_free(pair);
    g_free(image);
}
END_TEST

/* Rows 96-143 of the surface are flat: stripe 7 (rows 112-127) sees only
 * noise however it drifts (drift scale 0.3 keeps |dy| below ~4 px). */
START_TEST(test_featureless_stripe_rejected)
{
    FramePairSpec spec;
    FramePair *pair;
    StripeShift shifts[16];
    gint s;

    frame_pair_spec_init(&spec);
    spec.drift_scale = 0.3;
    spec.flat_from = 96;
    spec.flat_to = 144;
    pair = frame_pair_generate(&spec, test_seed);
    register_pair(pair, 16, shifts);
    printf("featureless stripe 7: score %.3f (peak %.3f, rival %.3f)\n",
           shifts[7].score, shifts[7].peak, shifts[7].rival);
    ck_assert_msg(shifts[7].score < 0.1, "featureless stripe scored %g", shifts[7].score);
    ck_assert(!shifts[7].accepted);
    for (s = 0; s < 5; s++)
        ck_assert_msg(shifts[s].accepted && shifts[s].score > 0.5, "textured stripe %d scored %g",
                      s, shifts[s].score);
    frame_pair_free(pair);
}
END_TEST

/* A stripe whose own rows are featureless (noise only) between rough
 * rows (texture 60 times the noise), registered as a series registers its
 * frames and as the reference mode does: the narrow blur carries the
 * rough rows' fringe into it, which correlates well with its counterpart
 * but holds the shift across the rows poorly, so it is not measured
 * (stripe-fringe.c); the rough stripes are.  The featureless band, one
 * row wider than the stripe on either side, and the sub-pixel shift are
 * drawn, FRINGE_DRAWS times: without that rejection about every other
 * draw measured the stripe in a series, 0.1 to 2.8 px off, and 7 to 10
 * of the 12 in the reference mode (seeds 1-4), up to 1 px off. */
#define FRINGE_DRAWS 12
#define FRINGE_STRIPES 16
#define FRINGE_ROWS (128/FRINGE_STRIPES)

/* Rough rows but for the band [flat_from, flat_to) of the surface, the
 * image shifted by (shift_x, shift_y). */
static FramePair*
flat_band_pair(GRand *rng, gint flat_from, gint flat_to, gdouble shift_x, gdouble shift_y)
{
    FramePairSpec spec;

    frame_pair_spec_init(&spec);
    spec.xres = spec.yres = 128;
    spec.particle_density = 0.0;
    spec.roughness = 0.4;
    spec.drift = FALSE;
    spec.shift_x = shift_x;
    spec.shift_y = shift_y;
    spec.flat_from = flat_from;
    spec.flat_to = flat_to;
    return frame_pair_generate(&spec, g_rand_int(rng));
}

/* The pair registered as a series registers its frames (around no
 * shift) or, with reference_mode, as the reference mode does (the whole
 * frame searched). */
static void
register_fringe_pair(const FramePair *pair, gboolean reference_mode, StripeShift *shifts)
{
    StripeRegistrationFrame *image, *reference;
    gdouble px[FRINGE_STRIPES], py[FRINGE_STRIPES];
    GError *error = NULL;
    gint s;

    if (reference_mode) {
        ck_assert(stripe_registration_measure(pair->image, pair->reference, pair->xres, pair->yres,
                                              FRINGE_STRIPES, NULL, shifts, &error));
        return;
    }
    image = stripe_registration_frame_new(pair->image, pair->xres, pair->yres, 1.0);
    reference = stripe_registration_frame_new(pair->reference, pair->xres, pair->yres, 1.0);
    ck_assert(image && reference);
    for (s = 0; s < FRINGE_STRIPES; s++)
        px[s] = py[s] = 0.0;
    ck_assert(stripe_registration_measure_around_frames(image, reference, FRINGE_STRIPES, px, py,
                                                        4.0, 0.0,
                                                        STRIPE_REGISTRATION_DEFAULT_MIN_SCORE,
                                                        FALSE, shifts, &error));
    stripe_registration_frame_free(image);
    stripe_registration_frame_free(reference);
}

static const gchar *fringe_mode_names[2] = { "series", "reference mode" };

/* The pair registered in both modes: stripe flat not measured, every
 * stripe beyond its neighbours measured within 0.5 px; what is printed
 * names the case. */
static void
check_fringe_pair(const FramePair *pair, gint flat, const gchar *what)
{
    StripeShift shifts[FRINGE_STRIPES];
    gdouble tx[FRINGE_STRIPES], ty[FRINGE_STRIPES];
    gint s, mode;

    frame_pair_stripe_truth(pair, FRINGE_STRIPES, tx, ty);
    for (mode = 0; mode < 2; mode++) {
        register_fringe_pair(pair, mode, shifts);
        printf("%s: stripe %2d %s: accepted %d, peak %.3f, off by (%.3f, %.3f) px\n",
               fringe_mode_names[mode], flat, what, shifts[flat].accepted, shifts[flat].peak,
               shifts[flat].dx - tx[flat], shifts[flat].dy - ty[flat]);
        ck_assert_msg(!shifts[flat].accepted, "%s: stripe %d %s measured (seed %u)",
                      fringe_mode_names[mode], flat, what, test_seed);
        /* The stripes either side share featureless rows and their edge,
         * and may or may not be measured; so may those whose rows
         * shifted back leave the reference. */
        for (s = 0; s < FRINGE_STRIPES; s++) {
            if (abs(s - flat) <= 1 || s*FRINGE_ROWS - ty[s] < 0.0
                || (s + 1)*FRINGE_ROWS - 1 - ty[s] > pair->yres - 1)
                continue;
            ck_assert_msg(shifts[s].accepted,
                          "%s: rough stripe %d not measured (stripe %d %s, dy %.2f px, seed %u)",
                          fringe_mode_names[mode], s, flat, what, ty[s], test_seed);
            ck_assert_msg(hypot(shifts[s].dx - tx[s], shifts[s].dy - ty[s]) < 0.5,
                          "%s: rough stripe %d off by (%g, %g) px (seed %u)",
                          fringe_mode_names[mode], s, shifts[s].dx - tx[s],
                          shifts[s].dy - ty[s], test_seed);
        }
    }
}

START_TEST(test_fringe_stripe_not_measured)
{
    GRand *rng = test_rand_salted(test_seed, 41);
    FramePair *pair;
    gdouble sx, sy;
    gint k, flat;

    for (k = 0; k < FRINGE_DRAWS; k++) {
        flat = g_rand_int_range(rng, 3, FRINGE_STRIPES - 3);
        sx = g_rand_double_range(rng, -0.5, 0.5);
        sy = g_rand_double_range(rng, -0.5, 0.5);
        pair = flat_band_pair(rng, flat*FRINGE_ROWS - 1, (flat + 1)*FRINGE_ROWS + 1, sx, sy);
        check_fringe_pair(pair, flat, "between rough rows");
        frame_pair_free(pair);
    }
    g_rand_free(rng);
}
END_TEST

/* The same stripe where only the reference frame's rows under it are
 * featureless: the image lies dy = 0.2 to 0.5 px lower or higher, and the
 * band covers exactly the reference rows wholly under the stripe's rows
 * shifted back, and one more, so that the image's first row is a rough
 * one.  The match then rests on the reference's fringe alone, which holds
 * the shift as poorly.  A series' frame 0 whose first rows showed a
 * particle cut by the frame's edge, and whose third row missed its rim by
 * a few hundredths of a pixel where the other frames' caught it, read
 * 0.5 px off as the reference of every pair with it, and the fit
 * reported a 0.5 px jump that was not there (test-series-correction seed
 * 62000021, case 10).  With the image judged alone, both modes measured
 * such a stripe in 12 of 12 draws (seeds 1-4, 7 and 9), up to 1 px off;
 * with the reference's rows taken shifted the wrong way, in 5 to 9 of
 * them.  Shifts beyond half a pixel are not drawn: a
 * match on the fringe alone can misread its shift by most of a pixel,
 * which brings a rough row under the stripe (docs/registration.md). */
START_TEST(test_fringe_in_reference_frame_not_measured)
{
    GRand *rng = test_rand_salted(test_seed, 43);
    FramePair *pair;
    gdouble sx, sy;
    gint k, flat, lo, hi;

    for (k = 0; k < FRINGE_DRAWS; k++) {
        flat = g_rand_int_range(rng, 3, FRINGE_STRIPES - 3);
        sx = g_rand_double_range(rng, -0.5, 0.5);
        sy = g_rand_double_range(rng, 0.2, 0.5)*(g_rand_boolean(rng) ? 1.0 : -1.0);
        lo = flat*FRINGE_ROWS;
        hi = lo + FRINGE_ROWS;
        pair = flat_band_pair(rng, (gint)ceil(lo - sy), (gint)floor(hi - 1 - sy) + 2, sx, sy);
        check_fringe_pair(pair, flat, "on the reference's fringe");
        frame_pair_free(pair);
    }
    g_rand_free(rng);
}
END_TEST

/* A strong lattice with almost nothing else: every stripe matches many
 * lattice positions equally well, so nearly all must be rejected. */
START_TEST(test_periodic_texture_lowers_score)
{
    FramePairSpec spec;
    FramePair *pair;
    StripeShift shifts[16];
    gint s, accepted;
    gdouble score = 0.0;

    frame_pair_spec_init(&spec);
    spec.lattice = 1.0;
    spec.particle_density = 0.0;
    spec.roughness = 0.02;
    pair = frame_pair_generate(&spec, test_seed);
    register_pair(pair, 16, shifts);
    for (s = 0; s < 16; s++)
        score += shifts[s].score/16;
    accepted = stripe_registration_count_accepted(shifts, 16);
    printf("lattice: mean score %.3f, %d accepted\n", score, accepted);
    ck_assert_msg(score < 0.1, "mean score %g on a pure lattice", score);
    ck_assert_msg(accepted <= 1, "%d lattice stripes accepted", accepted);
    frame_pair_free(pair);
}
END_TEST

/* Lines along y with a faint roughness, searched within a third of their
 * period (a user's --search), so that no alias of the lines is in reach:
 * the correlation is a ridge along dy, whose maxima have no dip between
 * them and so are no rivals of each other; what locates a stripe along the
 * lines is the roughness alone.  Whatever is given must be within its
 * stated uncertainty (3 sigma, or 1 px).  The grating's period, the
 * roughness and the drift are drawn from the seed. */
START_TEST(test_grating_honest)
{
    FramePairSpec spec;
    FramePair *pair;
    StripeShift shifts[16];
    StripeRegistrationOptions options;
    gdouble tx[16], ty[16], e, worst = 0.0;
    GRand *rng = g_rand_new_with_seed(test_seed ^ 0x9a7u);
    GError *error = NULL;
    gint s, accepted = 0;

    frame_pair_spec_init(&spec);
    spec.particle_density = 0.0;
    spec.roughness = g_rand_double_range(rng, 0.002, 0.2);
    spec.grating = 1.0;
    spec.lattice_period = g_rand_double_range(rng, 36.0, 72.0);
    spec.drift_scale = 0.3;
    pair = frame_pair_generate(&spec, test_seed);
    stripe_registration_options_init(&options);
    options.search_x = options.search_y = spec.lattice_period/3.0;
    ck_assert_msg(stripe_registration_measure(pair->image, pair->reference, pair->xres, pair->yres, 16,
                                              &options, shifts, &error),
                  "registration failed: %s", error ? error->message : "?");
    frame_pair_stripe_truth(pair, 16, tx, ty);
    for (s = 0; s < 16; s++) {
        if (!shifts[s].accepted)
            continue;
        accepted++;
        e = hypot(shifts[s].dx - tx[s], shifts[s].dy - ty[s]);
        worst = MAX(worst, e);
        ck_assert_msg(e <= MAX(1.0, 3.0*shifts[s].sigma),
                      "grating stripe %d off by %g px, sigma %g (seed %u)", s, e, shifts[s].sigma, test_seed);
    }
    printf("grating (period %.1f px, roughness %.3f): %d stripes accepted, worst %.3f px, all within "
           "their uncertainty\n", spec.lattice_period, spec.roughness, accepted, worst);
    frame_pair_free(pair);
    g_rand_free(rng);
}
END_TEST

/* A shift of about half a stripe in y puts half the first or the last
 * stripe off the reference: its peak lies on the edge of the shifts the
 * search considers (half the rows on the reference), and is found there. */
START_TEST(test_stripe_half_off_reference)
{
    enum { N = 16 };
    FramePairSpec spec;
    FramePair *pair;
    StripeShift shifts[N];
    GRand *rng = g_rand_new_with_seed(test_seed);
    gdouble worst = 0.0, e;
    gint s, edge;

    frame_pair_spec_init(&spec);
    spec.drift = FALSE;
    spec.noise = 0.02;
    /* 16-row stripes: 8 px leaves exactly half a stripe on the reference. */
    spec.shift_y = g_rand_double_range(rng, 8.05, 8.95)*(g_rand_boolean(rng) ? 1.0 : -1.0);
    spec.shift_x = g_rand_double_range(rng, -4.0, 4.0);
    pair = frame_pair_generate(&spec, test_seed);
    register_pair(pair, N, shifts);
    edge = (spec.shift_y > 0.0) ? 0 : N-1;
    for (s = 0; s < N; s++) {
        e = hypot(shifts[s].dx - spec.shift_x, shifts[s].dy - spec.shift_y);
        worst = MAX(worst, e);
        ck_assert_msg(e <= 0.1, "stripe %d: (%g, %g) instead of (%g, %g) (seed %u)",
                      s, shifts[s].dx, shifts[s].dy, spec.shift_x, spec.shift_y, test_seed);
    }
    printf("shift (%.2f, %.2f), edge stripe %d: score %.3f, max error %.4f px\n",
           spec.shift_x, spec.shift_y, edge, shifts[edge].score, worst);
    ck_assert_msg(shifts[edge].accepted, "edge stripe %d rejected (score %g, seed %u)",
                  edge, shifts[edge].score, test_seed);
    frame_pair_free(pair);
    g_rand_free(rng);
}
END_TEST

static void
fill_shift(StripeShift *shift, gdouble dx, gdouble dy, gdouble score, gboolean accepted)
{
    memset(shift, 0, sizeof(StripeShift));
    shift->dx = dx;
    shift->dy = dy;
    shift->score = score;
    shift->accepted = accepted;
}

START_TEST(test_table)
{
    StripeShift shifts[3];
    DriftTable *table;
    gchar *text;
    gdouble value;

    fill_shift(shifts + 0, -1.26, 0.4, 0.9, TRUE);
    fill_shift(shifts + 1, 7.0, 3.0, 0.05, FALSE);
    fill_shift(shifts + 2, 2.5, -0.51, 0.8, TRUE);
    table = stripe_registration_to_table(shifts, 3, FALSE);
    ck_assert_int_eq(table->n_stripes, 3);
    ck_assert_int_eq(table->unit, DRIFT_UNIT_PX);
    ck_assert(table->rows[0].has_drift && !table->rows[1].has_drift && table->rows[2].has_drift);
    ck_assert(fabs(table->rows[0].dx + 1.26) < 1e-12 && fabs(table->rows[2].dy + 0.51) < 1e-12);
    ck_assert(drift_table_get_extra(table, 0, "dx_exact", &value) && fabs(value + 1.26) < 1e-12);
    ck_assert(drift_table_get_extra(table, 1, "score", &value) && fabs(value - 0.05) < 1e-12);
    ck_assert(!drift_table_get_extra(table, 1, "dx_exact", &value));
    text = drift_table_to_string(table);
    ck_assert_msg(strstr(text, "stripe,dx,dy,dx_exact,dy_exact,score"), "header in:\n%s", text);
    ck_assert_msg(strstr(text, "\n1,,,"), "blank row 1 in:\n%s", text);
    g_free(text);
    drift_table_free(table);

    table = stripe_registration_to_table(shifts, 3, TRUE);
    ck_assert(table->rows[0].dx == -1.0 && table->rows[0].dy == 0.0);
    ck_assert(table->rows[2].dx == 3.0 && table->rows[2].dy == -1.0);
    ck_assert(drift_table_get_extra(table, 2, "dx_exact", &value) && fabs(value - 2.5) < 1e-12);
    ck_assert(!table->rows[1].has_drift);
    drift_table_free(table);
}
END_TEST

/* Pairs offset by up to 35 % of the frame in x and 30 % in y (either sign),
 * the drift changing smoothly over the frame, a jump of 3-10 px between
 * two rows in half of the pairs, with raw-channel artefacts and a
 * frame-fixed undulation of the given sizes drawn anew for each frame (0:
 * none).  Stripes holding the jump row are left out of the figures (their
 * truth is a mean of two drifts). */
typedef struct {
    gint in_reference;    /* stripes whose content lies in the reference */
    gint measured;        /* of those, accepted */
    gint wrong_outside;   /* stripes outside it accepted more than 1 px and
                             3 sigma off */
    gint beyond_3_sigma;  /* measured stripes off by more than 3 (6) times */
    gint beyond_6_sigma;  /* their stated uncertainty */
    gdouble sum2;         /* squared errors of the measured */
    gdouble worst;
} RawTally;

static gboolean
truly_in_reference(const FramePair *pair, gint first, gint end, gdouble dx, gdouble dy)
{
    gdouble rows = MIN(end, pair->yres + dy) - MAX(first, dy), cols = pair->xres - fabs(dx);

    return rows > 0.0 && cols > 0.0 && rows*cols >= 0.5*(end - first)*(gdouble)pair->xres;
}

static void
register_raw_pair(guint32 seed, gdouble artefacts, gdouble undulation, RawTally *tally)
{
    enum { N = 16 };
    GRand *rng = g_rand_new_with_seed(seed);
    FramePairSpec spec;
    FramePair *pair;
    StripeShift shifts[N];
    gdouble tx[N], ty[N], e;
    gint s, first, end;

    frame_pair_spec_init(&spec);
    spec.drift = FALSE;
    spec.shift_x = g_rand_double_range(rng, 0.05, 0.35)*spec.xres*(g_rand_boolean(rng) ? 1 : -1);
    spec.shift_y = g_rand_double_range(rng, 0.05, 0.30)*spec.yres*(g_rand_boolean(rng) ? 1 : -1);
    spec.velocity_x = g_rand_double_range(rng, -0.02, 0.02);
    spec.velocity_y = g_rand_double_range(rng, -0.02, 0.02);
    if (g_rand_boolean(rng)) {
        gdouble size = g_rand_double_range(rng, 3.0, 10.0), angle = g_rand_double_range(rng, 0.0, 2.0*G_PI);

        spec.jump_row = g_rand_int_range(rng, spec.yres/4, 3*spec.yres/4);
        spec.jump_x = size*cos(angle);
        spec.jump_y = size*sin(angle);
    }
    pair = frame_pair_generate(&spec, seed);
    if (artefacts > 0.0)
        frame_pair_add_raw_artefacts(pair, artefacts, seed);
    if (undulation > 0.0)
        frame_pair_add_undulation(pair, undulation, seed);
    register_pair(pair, N, shifts);
    frame_pair_stripe_truth(pair, N, tx, ty);
    for (s = 0; s < N; s++) {
        first = s*spec.yres/N;
        end = (s + 1)*spec.yres/N;
        if (spec.jump_row > first && spec.jump_row < end)
            continue;
        e = hypot(shifts[s].dx - tx[s], shifts[s].dy - ty[s]);
        if (!truly_in_reference(pair, first, end, tx[s], ty[s])) {
            /* Stripes about half on the reference are measured, as
             * imprecisely as the rest: a wrong value is one its sigma
             * does not cover. */
            tally->wrong_outside += (shifts[s].accepted && e > 1.0 && e > 3.0*shifts[s].sigma);
            continue;
        }
        tally->in_reference++;
        if (!shifts[s].accepted)
            continue;
        tally->measured++;
        tally->beyond_3_sigma += (e > 3.0*shifts[s].sigma);
        tally->beyond_6_sigma += (e > 6.0*shifts[s].sigma);
        tally->sum2 += e*e;
        tally->worst = MAX(tally->worst, e);
    }
    frame_pair_free(pair);
    g_rand_free(rng);
}

static void
print_raw_tally(const gchar *what, const RawTally *tally)
{
    printf("%s: %d of %d stripes in the reference measured, rms %.4f px, worst %.4f px, "
           "%d beyond 3 sigma, %d beyond 6; %d stripes outside the reference given a value its "
           "sigma does not cover\n", what, tally->measured, tally->in_reference,
           tally->measured ? sqrt(tally->sum2/tally->measured) : 0.0, tally->worst,
           tally->beyond_3_sigma, tally->beyond_6_sigma, tally->wrong_outside);
}

/* PAIRS pairs (register_raw_pair) from test_seed, with raw-channel
 * artefacts of a size drawn from 0.5 to max_artefacts and a frame-fixed
 * undulation from 0.1 to max_undulation (0: none); prints the tally. */
static void
register_raw_pairs(const gchar *what, gdouble max_artefacts, gdouble max_undulation, guint32 salt,
                   RawTally *tally)
{
    enum { PAIRS = 8 };
    GRand *rng = g_rand_new_with_seed(test_seed ^ salt);
    gdouble artefacts, undulation;
    gint i;

    gwy_clear(tally, 1);
    for (i = 0; i < PAIRS; i++) {
        artefacts = (max_artefacts > 0.0) ? g_rand_double_range(rng, 0.5, max_artefacts) : 0.0;
        undulation = (max_undulation > 0.0) ? g_rand_double_range(rng, 0.1, max_undulation) : 0.0;
        register_raw_pair(test_seed + 7919u*i, artefacts, undulation, tally);
    }
    print_raw_tally(what, tally);
    g_rand_free(rng);
}

/* What issue 9 asks of pairs offset by up to a third of the frame: at
 * least 95 % of the stripes whose content lies in the reference measured,
 * rms at most 0.05 px, none off by more than 1 px.  The rms is the
 * population's (100 pairs: 0.040-0.041 px); the 100 or so stripes of one
 * run scatter about it (0.033-0.050 px, median 0.041, over 600 runs), so
 * one run is held to 0.06 px, which an error grown by half fails in most
 * runs. */
static void
assert_large_offset_figures(const RawTally *tally)
{
    gdouble rms = sqrt(tally->sum2/MAX(tally->measured, 1));

    ck_assert_msg(tally->measured >= 0.95*tally->in_reference,
                  "only %d of %d stripes in the reference measured (seed %u)", tally->measured,
                  tally->in_reference, test_seed);
    ck_assert_msg(rms <= 0.06, "rms %g px (seed %u)", rms, test_seed);
    ck_assert_msg(tally->worst <= 1.0, "a stripe %g px off (seed %u)", tally->worst, test_seed);
}

/* The search over any offset, on pairs without raw-channel artefacts.  A
 * band mostly off the reference once led two stripes 26 and 31 px astray
 * (seed 1774757575; reject_bands_gaining_overlap). */
START_TEST(test_large_offsets)
{
    RawTally tally;

    register_raw_pairs("large offsets", 0.0, 0.0, 0, &tally);
    assert_large_offset_figures(&tally);
}
END_TEST

/* The same pairs as raw channels: a plane, line offsets, a bow and 1/f
 * noise in scan time, different in the two frames, of a size drawn from
 * half to three times the particles' height.  Conditioning takes them out
 * (on 100 pairs of size 1 and of size 3: 100 % measured, rms 0.040-0.041
 * px, worst 0.17 px, as on clean pairs); without the column-trend fit and
 * the x trend of the match 15 % and 2 % of the stripes were measured. */
START_TEST(test_raw_artefacts)
{
    RawTally tally;

    register_raw_pairs("raw artefacts", 3.0, 0.0, 0x7a3u, &tally);
    assert_large_offset_figures(&tally);
}
END_TEST

/* Frame-fixed texture at every scale, unlike either frame's content and as
 * strong as the sample's roughness or more, looks like the sample to any
 * registration; what is asked here is honesty: a value it gives is
 * within its stated uncertainty (fewer stripes are measured, and those
 * less precisely).  Not yet always: 2 runs in 330 had one stripe matched
 * 12-23 px off on that texture beyond 6 sigma (seeds 61000497, 61001071;
 * issue 9 is open on it), none of 1580 runs two, so more than one such
 * stripe fails. */
START_TEST(test_undulation_honest)
{
    RawTally tally;

    register_raw_pairs("frame-fixed undulation", 3.0, 1.0, 0x0ddu, &tally);
    ck_assert_msg(tally.beyond_6_sigma <= 1, "%d stripes beyond 6 sigma (seed %u)",
                  tally.beyond_6_sigma, test_seed);
}
END_TEST

START_TEST(test_bad_arguments)
{
    GwyDataField *image = gwy_data_field_new(64, 64, 64, 64, TRUE);
    GwyDataField *reference = gwy_data_field_new(64, 60, 64, 60, TRUE);
    StripeShift shifts[65];
    GError *error = NULL;
    gdouble *data;

    ck_assert(!stripe_registration_measure_fields(image, reference, 4, NULL, shifts, &error));
    ck_assert(g_error_matches(error, STRIPE_REGISTRATION_ERROR, STRIPE_REGISTRATION_ERROR_SIZE));
    ck_assert_str_eq(error->message, "The reference (64 x 60 px) does not have the image's size (64 x 64 px).");
    g_clear_error(&error);

    data = gwy_data_field_get_data(image);
    ck_assert(!stripe_registration_measure(data, data, 64, 64, 65, NULL, shifts, &error));
    ck_assert(g_error_matches(error, STRIPE_REGISTRATION_ERROR, STRIPE_REGISTRATION_ERROR_STRIPES));
    ck_assert_str_eq(error->message, "The number of stripes (65) must be between 1 and the image's 64 rows.");
    g_clear_error(&error);
    ck_assert(!stripe_registration_measure(data, data, 64, 64, 0, NULL, shifts, &error));
    ck_assert(g_error_matches(error, STRIPE_REGISTRATION_ERROR, STRIPE_REGISTRATION_ERROR_STRIPES));
    g_clear_error(&error);

    /* Missing pixels carry no weight; only a frame with none valid is
     * refused. */
    data[100] = NAN;
    ck_assert(stripe_registration_measure(data, data, 64, 64, 4, NULL, shifts, &error));
    for (gint k = 0; k < 64*64; k++)
        data[k] = NAN;
    ck_assert(!stripe_registration_measure(data, data, 64, 64, 4, NULL, shifts, &error));
    ck_assert(g_error_matches(error, STRIPE_REGISTRATION_ERROR, STRIPE_REGISTRATION_ERROR_VALUE));
    ck_assert_str_eq(error->message, "The image has no valid pixel (all are NaN or infinite).");
    g_clear_error(&error);
    ck_assert(!stripe_registration_measure(data, data, 3, 3, 1, NULL, shifts, &error));
    ck_assert(g_error_matches(error, STRIPE_REGISTRATION_ERROR, STRIPE_REGISTRATION_ERROR_SIZE));
    g_clear_error(&error);

    g_object_unref(image);
    g_object_unref(reference);
}
END_TEST

/* A shift beyond the blind search (a quarter of the side, 64 px) is found
 * when each stripe is searched around a rough prediction of it, as the
 * frame-series fit does with shifts chained across frames; searched around
 * a wrong prediction, the stripes find nothing they trust. */
START_TEST(test_search_around_prediction)
{
    enum { N = 16 };
    FramePairSpec spec;
    FramePair *pair;
    StripeShift shifts[N];
    GError *error = NULL;
    gdouble tx[N], ty[N], px[N], py[N], sum = 0.0, worst = 0.0, e;
    gint s;

    frame_pair_spec_init(&spec);
    spec.drift = FALSE;
    spec.shift_x = 72.3;
    spec.shift_y = 1.5;
    spec.velocity_x = 0.02;
    spec.velocity_y = -0.01;
    pair = frame_pair_generate(&spec, test_seed);
    frame_pair_stripe_truth(pair, N, tx, ty);
    for (s = 0; s < N; s++) {
        /* Off by up to 3 px, as a chained prediction may be. */
        px[s] = tx[s] + 3.0*sin(1.7*s);
        py[s] = ty[s] - 3.0*cos(0.9*s);
    }
    ck_assert(stripe_registration_measure_around(pair->image, pair->reference, pair->xres, pair->yres, N,
                                                 px, py, 8.0, STRIPE_REGISTRATION_DEFAULT_MIN_SCORE,
                                                 shifts, &error));
    for (s = 0; s < N; s++) {
        e = hypot(shifts[s].dx - tx[s], shifts[s].dy - ty[s]);
        sum += e*e;
        worst = MAX(worst, e);
        ck_assert_msg(shifts[s].accepted, "stripe %d not accepted (score %g)", s, shifts[s].score);
    }
    printf("around a prediction 3 px off (shift 72, 1.5 px): rms %.4f px, max %.4f px\n",
           sqrt(sum/N), worst);
    ck_assert_msg(sqrt(sum/N) <= 0.15 && worst < 1.0, "rms %g px, max %g px (seed %u)", sqrt(sum/N), worst,
                  test_seed);

    for (s = 0; s < N; s++)
        px[s] = py[s] = 0.0;
    ck_assert(stripe_registration_measure_around(pair->image, pair->reference, pair->xres, pair->yres, N,
                                                 px, py, 8.0, STRIPE_REGISTRATION_DEFAULT_MIN_SCORE,
                                                 shifts, &error));
    for (s = 0; s < N; s++) {
        ck_assert_msg(fabs(shifts[s].dx) <= 8.0 && fabs(shifts[s].dy) <= 8.0,
                      "stripe %d left its window: (%g, %g)", s, shifts[s].dx, shifts[s].dy);
    }
    printf("around a wrong prediction: %d of %d accepted\n", stripe_registration_count_accepted(shifts, N), N);
    /* A chance peak of the texture may pass now and then (up to 2 of 16 in
     * 30 seeds tried); most stripes must not. */
    ck_assert_int_le(stripe_registration_count_accepted(shifts, N), 4);

    px[3] = NAN;
    ck_assert(!stripe_registration_measure_around(pair->image, pair->reference, pair->xres, pair->yres, N,
                                                  px, py, 8.0, 0.25, shifts, &error));
    ck_assert(g_error_matches(error, STRIPE_REGISTRATION_ERROR, STRIPE_REGISTRATION_ERROR_VALUE));
    ck_assert_str_eq(error->message, "The predicted shift of stripe 3 is not a finite number within the frame.");
    g_clear_error(&error);
    frame_pair_free(pair);
}
END_TEST

/* A flat image has no texture at all: nothing is accepted, nothing crashes. */
START_TEST(test_flat_image)
{
    gdouble *flat = g_new0(gdouble, 64*64);
    StripeShift shifts[4];
    GError *error = NULL;

    GwyDataField *field = gwy_data_field_new(64, 64, 64, 64, TRUE);

    ck_assert(stripe_registration_measure(flat, flat, 64, 64, 4, NULL, shifts, &error));
    ck_assert_int_eq(stripe_registration_count_accepted(shifts, 4), 0);
    ck_assert(!stripe_registration_table_for_fields(field, field, 4, NULL, TRUE, NULL, &error));
    ck_assert(g_error_matches(error, STRIPE_REGISTRATION_ERROR, STRIPE_REGISTRATION_ERROR_NO_MATCH));
    g_clear_error(&error);
    g_object_unref(field);
    g_free(flat);
}
END_TEST

static Suite*
registration_suite(void)
{
    TCase *tc;
    Suite *suite = test_suite_new("stripe-registration", "core", &tc);

    tcase_add_test(tc, test_random_drift_pairs);
    tcase_add_test(tc, test_reference_hole);
    tcase_add_test(tc, test_masked_reference);
    tcase_add_test(tc, test_scattered_missing);
    tcase_add_test(tc, test_bad_masks);
    tcase_add_test(tc, test_non_square_images);
    tcase_add_test(tc, test_integer_shift);
    tcase_add_test(tc, test_sign_convention);
    tcase_add_test(tc, test_stripe_half_off_reference);
    tcase_add_test(tc, test_featureless_stripe_rejected);
    tcase_add_test(tc, test_fringe_stripe_not_measured);
    tcase_add_test(tc, test_fringe_in_reference_frame_not_measured);
    tcase_add_test(tc, test_periodic_texture_lowers_score);
    tcase_add_test(tc, test_grating_honest);
    tcase_add_test(tc, test_search_around_prediction);
    tcase_add_test(tc, test_table);
    tcase_add_test(tc, test_table_for_fields);
    tcase_add_test(tc, test_bad_arguments);
    tcase_add_test(tc, test_large_offsets);
    tcase_add_test(tc, test_raw_artefacts);
    tcase_add_test(tc, test_undulation_honest);
    tcase_add_test(tc, test_flat_image);
    return suite;
}

int
main(void)
{
    gint status;

    test_seed = test_seed_from_env("test-stripe-registration");
    status = test_run_suite(registration_suite());
    fftw_cleanup();
    return status;
}
