#!/bin/sh
# The project's demo ('make demo'): the paper's Figure 6 and Section IV
# simulations, compensated by gwy-localscan from the drift table simscan
# stored in the file, with pictures and particle-centre errors.
# Usage: demo.sh BUILDDIR   (writes BUILDDIR/demo-output)
# Copyright (C) 2026 The gwy-localscan authors.
# SPDX-License-Identifier: GPL-2.0-or-later
set -eu
build=${1:?usage: demo.sh BUILDDIR}
simscan="$build/simscan/simscan"
localscan="$build/tools/gwy-localscan"
out="$build/demo-output"
# gwy-localscan loads the freshly built module, not an installed copy.
LOCALSCAN_MODULE="$build/modules/.libs/localscan.so"
export LOCALSCAN_MODULE
# Headless Gwyddion keeps its settings here, away from the user's.
HOME="$out/home"
export HOME
mkdir -p "$out" "$HOME"

run_preset() {
    preset=$1
    echo
    echo "=== simscan --preset $preset"
    "$simscan" --preset "$preset" -o "$out/$preset.gwy" \
        --table "$out/$preset-drift.csv" --json "$out/$preset.json"
    if [ ! -x "$localscan" ]; then
        echo "demo: $localscan is not built; compensation skipped" >&2
        return 1
    fi
    echo
    echo "=== gwy-localscan -o $preset-compensated.gwy $preset.gwy" \
         "(drift table read from the file)"
    "$localscan" -o "$out/$preset-compensated.gwy" "$out/$preset.gwy"
    echo
    echo "=== simscan compare: particle-centre distances from their true places," \
         "before and after gwy-localscan"
    "$simscan" compare "$out/$preset-compensated.gwy" \
        --before-png "$out/$preset-before.png" \
        --after-png "$out/$preset-after.png" \
        --truth-png "$out/$preset-truth.png"
}

run_preset figure6
run_preset paper
echo
echo "=== simscan sweep: error against N, drift during the local scans included"
"$simscan" sweep --velocity 0.8,0.2 --ls-rmax 300 --ls-overhead 0.25 \
    --spacing 500 --count 80 --seed 2 --n-list 1,2,4,8,16,32,64,128 \
    --plot "$out/sweep.png"
echo
echo "demo: files in $out"
ls "$out"
echo
echo "demo: PRESET-before.png, PRESET-after.png and PRESET-truth.png share one" \
     "grey scale (printed under each)"
echo "and are enlarged to 512 px; red rings mark where each particle truly is," \
     "blue the pixels the"
echo "compensation filled.  In figure6 the particles stray from their rings" \
     "by 1 to 16 px before"
echo "and sit in them after; the paper's drift (about 1 px) is barely visible" \
     "by eye, see the numbers."
