#!/bin/sh
# The public drift benchmark end to end (docs/benchmark.md): writes the
# cases with `simscan benchmark`, runs this project's series correction
# (`gwy-localscan series`, as a user runs it) and the peers' methods
# (bench/benchmark-baselines) on every case, and scores them all with
# `simscan score`.  Prints the times and the table; with -d it also puts
# the table, the seed and the versions into docs/benchmark.md between its
# result markers.
#
#   bench/run-benchmark.sh [-b BUILDDIR] [-o OUTDIR] [-s SEED] [-z small|full] [-d]
#
# BUILDDIR is the configured build (default _build), OUTDIR where cases and
# results go (default BUILDDIR/benchmark-run; an earlier run there is
# replaced, anything else refused).
#
# Copyright (C) 2026 The gwy-localscan authors.
# SPDX-License-Identifier: GPL-2.0-or-later
set -eu

srcdir=$(cd "$(dirname "$0")/.." && pwd)
builddir=$srcdir/_build
outdir=
seed=1
size=small
update_docs=no
while getopts b:o:s:z:d opt; do
    case $opt in
        b) builddir=$(cd "$OPTARG" && pwd) ;;
        o) outdir=$OPTARG ;;
        s) seed=$OPTARG ;;
        z) size=$OPTARG ;;
        d) update_docs=yes ;;
        *) echo "usage: $0 [-b BUILDDIR] [-o OUTDIR] [-s SEED] [-z small|full] [-d]" >&2
           exit 2 ;;
    esac
done
outdir=${outdir:-$builddir/benchmark-run}
simscan=$builddir/simscan/simscan
localscan=$builddir/tools/gwy-localscan
baselines=$builddir/bench/benchmark-baselines
for prog in "$simscan" "$localscan" "$baselines"; do
    if [ ! -x "$prog" ]; then
        echo "run-benchmark: $prog is not built (make -C $builddir && make -C $builddir bench/benchmark-baselines)" >&2
        exit 1
    fi
done
: "${LOCALSCAN_MEASURED_DIR:=$srcdir/../shared/data/measured}"
export LOCALSCAN_MEASURED_DIR

now() { date +%s.%N; }
elapsed() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.1f", b - a }'; }

# Replaced only when it is an earlier run's (or empty): a mistyped -o must
# not remove anything else.
if [ -e "$outdir" ] && [ -n "$(ls -A "$outdir" 2>/dev/null)" ] \
   && [ ! -f "$outdir/cases/benchmark.json" ]; then
    echo "run-benchmark: $outdir is not an earlier benchmark run; give another -o" >&2
    exit 1
fi
rm -rf "$outdir"
mkdir -p "$outdir/results/series"
start=$(now)
"$simscan" benchmark -o "$outdir/cases" --seed "$seed" --size "$size"
generated=$(now)
echo "cases written in $(elapsed "$start" "$generated") s"

# This project: every case as a user runs it.
cases=$(sed -n '/"cases"/,/]/p' "$outdir/cases/benchmark.json" | sed -n 's/^ *"\([^"]*\)",*$/\1/p')
for name in $cases; do
    out=$outdir/results/series/$name
    mkdir -p "$out"
    t0=$(now)
    if ! "$localscan" series -o "$out/corrected.gwy" --trajectory "$out/trajectory.csv" \
            --json "$out/result.json" "$outdir/cases/$name"/frame-*.gwy \
            2> "$out/stderr.txt"; then
        echo "$name: series correction failed: $(head -1 "$out/stderr.txt")"
    fi
    echo "$name: series $(elapsed "$t0" "$(now)") s"
done
series_done=$(now)

# The paper's per-stripe mode as a recorded series allows it: no local
# scans exist, so each frame's 8 stripes are registered against frame 0
# (`gwy-localscan --reference`, paper mode: whole pixels), frame 0 taken as
# drift-free.  Stripes without a value take the nearest stripe's.
LOCALSCAN_MODULE=${LOCALSCAN_MODULE:-$builddir/modules/.libs/localscan.so}
export LOCALSCAN_MODULE
stripes=8
for name in $cases; do
    out=$outdir/results/stripes/$name
    mkdir -p "$out"
    json=$outdir/cases/$name/case.json
    yres=$(sed -n 's/^ *"yres" : \([0-9]*\).*/\1/p' "$json")
    lt=$(sed -n 's/^ *"line_time_s" : \([-0-9.e]*\).*/\1/p' "$json")
    echo "frame,row,t_s,dx_px,dy_px" > "$out/trajectory.csv"
    k=0
    for frame in "$outdir/cases/$name"/frame-*.gwy; do
        if [ $k -eq 0 ]; then
            printf 'stripe,dx,dy\n' > "$out/table.csv"
            s=0
            while [ $s -lt $stripes ]; do echo "$s,0,0" >> "$out/table.csv"; s=$((s + 1)); done
        elif ! "$localscan" -m paper --reference "$outdir/cases/$name/frame-000.gwy" \
                --stripes $stripes --write-drift "$out/table.csv" -o "$out/frame.gwy" \
                "$frame" 2>> "$out/stderr.txt"; then
            echo "$name: frame $k: per-stripe registration failed: $(tail -1 "$out/stderr.txt")"
            rm -f "$out/trajectory.csv"
            break
        fi
        awk -F, -v k=$k -v yres="$yres" -v lt="$lt" -v n=$stripes '
            /^#/ || /^stripe/ { next }
            { have[$1] = ($2 != ""); dx[$1] = $2; dy[$1] = $3 }
            END {
                for (s = 0; s < n; s++) {
                    best = -1
                    for (d = 0; d < n && best < 0; d++) {
                        if (s - d >= 0 && have[s - d]) best = s - d
                        else if (s + d < n && have[s + d]) best = s + d
                    }
                    if (best < 0) exit 1
                    for (r = int(s*yres/n); r < int((s + 1)*yres/n); r++)
                        printf "%d,%d,%.6f,%s,%s\n", k, r, (k*yres + r + 0.25)*lt, dx[best], dy[best]
                }
            }' "$out/table.csv" >> "$out/trajectory.csv" || { rm -f "$out/trajectory.csv"; break; }
        k=$((k + 1))
    done
    rm -f "$out/frame.gwy" "$out/table.csv"
done
stripes_done=$(now)

"$baselines" "$outdir/cases" "$outdir/results"
baselines_done=$(now)

"$simscan" score --truth "$outdir/cases" --json "$outdir/scores.json" \
    --svg "$outdir/benchmark.svg" \
    "$outdir/results/series" "$outdir/results/rigid" \
    "$outdir/results/gwyddion-drift" "$outdir/results/stripes" > "$outdir/scores.txt"
scored=$(now)
cat "$outdir/scores.txt"
echo
total=$(awk -v a="$(elapsed "$start" "$generated")" -v b="$(elapsed "$baselines_done" "$scored")" 'BEGIN { printf "%.1f", a + b }')
times="generate $(elapsed "$start" "$generated") s, series $(elapsed "$generated" "$series_done") s, stripes $(elapsed "$series_done" "$stripes_done") s, baselines $(elapsed "$stripes_done" "$baselines_done") s, score $(elapsed "$baselines_done" "$scored") s; generate + score $total s"
echo "$times"

if [ "$update_docs" = yes ]; then
    doc=$srcdir/docs/benchmark.md
    gwyver=$(pkg-config --modversion gwyddion 2>/dev/null || echo unknown)
    version=$(sed -n 's/.*"benchmark_version" : "\([^"]*\)".*/\1/p' "$outdir/cases/benchmark.json")
    skipped=$(sed -n 's/.*"name" : "\([^"]*\)".*/\1/p' "$outdir/cases/benchmark.json" | tr '\n' ' ')
    {
        sed -n '1,/<!-- results start -->/p' "$doc"
        echo
        generator=$(sed -n 's/.*"generator" : "\([^"]*\)".*/\1/p' "$outdir/cases/benchmark.json")
        echo "Benchmark version $version, \`--size $size --seed $seed\`, written by $generator; Gwyddion $gwyver."
        [ -n "$skipped" ] && echo "Skipped (measured sample absent): $skipped."
        echo
        echo "Trajectory RMS / corrected-frame residual, px (— where the method gives no corrected frames):"
        echo
        sed -n '/^| case/,$p' "$outdir/scores.txt"
        echo
        echo "![Trajectory RMS per case and method](figures/benchmark.svg)"
        echo
        echo "Times on this machine ($(nproc) cores): $times."
        echo
        echo "Regenerated by \`make benchmark\` (bench/run-benchmark.sh -d)."
        echo
        sed -n '/<!-- results end -->/,$p' "$doc"
    } > "$doc.new"
    mv "$doc.new" "$doc"
    cp "$outdir/benchmark.svg" "$srcdir/docs/figures/benchmark.svg"
    echo "docs/benchmark.md updated"
fi
