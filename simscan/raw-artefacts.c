/*
 *  What raw instrument channels carry on top of the sample (a plane, line
 *  offsets, a bow, 1/f noise in scan time, frame-fixed texture): added to
 *  simulated frames by the tests, the studies and `simscan benchmark`.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "config.h"
#include <math.h>
#include "raw-artefacts.h"

gdouble
sim_raw_gaussian(GRand *rng)
{
    gdouble u = g_rand_double(rng), v = g_rand_double(rng);

    return sqrt(-2.0*log(1.0 - u))*cos(2.0*G_PI*v);
}

/* 1/f noise along a series of len samples: octaves of random phase, each
 * octave's amplitude falling by sqrt(2) as its frequency doubles. */
static void
add_wander(gdouble *out, gint len, gdouble rms, GRand *rng)
{
    gint octave, i;

    for (octave = 0; (1 << octave) < len/2; octave++) {
        gdouble f = (1 << octave)/(gdouble)len, a = rms*pow(0.5, 0.5*octave);
        gdouble phase = g_rand_double_range(rng, 0.0, 2.0*G_PI);

        for (i = 0; i < len; i++)
            out[i] += a*sin(2.0*G_PI*f*i + phase);
    }
}

/* An instrument's 1/f noise is a time series sampled in raster order: a
 * line takes milliseconds, so within it the noise hardly moves, and it
 * shows between lines (offsets wandering from line to line).  The scanner
 * adds a plane and a bow along x. */
void
sim_raw_artefacts_add(gdouble *data, gint xres, gint yres, gdouble size, GRand *rng)
{
    gdouble tilt_x = g_rand_double_range(rng, -1.0, 1.0)*size*4.0/xres;
    gdouble tilt_y = g_rand_double_range(rng, -1.0, 1.0)*size*4.0/yres;
    gdouble bow = g_rand_double_range(rng, -1.0, 1.0)*size*2.0;
    gdouble *line_wander = g_new0(gdouble, yres);
    gint r, c;

    add_wander(line_wander, yres, 0.5*size, rng);
    for (r = 0; r < yres; r++) {
        gdouble *row = data + (gsize)r*xres;
        gdouble offset = line_wander[r] + 0.3*size*sim_raw_gaussian(rng);

        for (c = 0; c < xres; c++) {
            gdouble x = 2.0*c/(xres - 1) - 1.0;

            row[c] += tilt_x*c + tilt_y*r + bow*x*x + offset;
        }
    }
    g_free(line_wander);
}

/* A pattern fixed to the frame, separable 1/f along x and y over every
 * octave: what differs between the frames beyond noise and looks like
 * texture at every scale. */
void
sim_raw_undulation_add(gdouble *data, gint xres, gint yres, gdouble size, GRand *rng)
{
    gdouble *along_x = g_new0(gdouble, xres), *along_y = g_new0(gdouble, yres);
    gint r, c;

    add_wander(along_x, xres, 0.3*size, rng);
    add_wander(along_y, yres, 0.3*size, rng);
    for (r = 0; r < yres; r++) {
        for (c = 0; c < xres; c++)
            data[(gsize)r*xres + c] += along_x[c]*along_y[r]/(0.3*size);
    }
    g_free(along_y);
    g_free(along_x);
}
