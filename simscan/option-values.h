/*
 *  Numbers given on simscan's command lines: parsed strictly (the whole
 *  text, finite, in range), with one-line messages naming the option.
 *  Copyright (C) 2026 The gwy-localscan authors.
 *  SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef SIMSCAN_OPTION_VALUES_H
#define SIMSCAN_OPTION_VALUES_H

#include <glib.h>

G_BEGIN_DECLS

/* Messages read "--OPTION: what" (option without the dashes). */
gboolean  option_value_refuse        (const gchar *option,
                                      const gchar *what,
                                      GError **error);

/* value within [min, max], or (min, max] when min_open; NaN and infinities
 * never are. */
gboolean  option_value_check_range   (gdouble value,
                                      gdouble min,
                                      gdouble max,
                                      gboolean min_open,
                                      const gchar *option,
                                      GError **error);

/* text is one number (C locale) in the range of check_range. */
gboolean  option_value_parse_double  (const gchar *text,
                                      gdouble min,
                                      gdouble max,
                                      gboolean min_open,
                                      const gchar *option,
                                      gdouble *value,
                                      GError **error);

/* text is one decimal integer from min to max. */
gboolean  option_value_parse_int     (const gchar *text,
                                      gint min,
                                      gint max,
                                      const gchar *option,
                                      gint *value,
                                      GError **error);

/* Prints error as "PREFIX: message", one printable line of bounded length
 * whatever the message quotes (quoted-input.h). */
void     simscan_print_error          (const gchar *prefix,
                                       const GError *error);

G_END_DECLS

#endif
