#!/bin/sh
# Tests of the public drift benchmark (docs/benchmark.md): `simscan
# benchmark` writes the same bytes for the same seed and other bytes for
# another; `simscan score` gives 0 for the truth itself, the right figure
# for a known offset (drawn at random, seeded), a failure naming the fault
# for each malformed result, and scores the series correction's corrected
# frames; bad command lines exit non-zero with one line and leave nothing.
# Without ../shared the measured-sample cases are skipped by the generator
# (listed in benchmark.json); this test needs none of them.
# Copyright (C) 2026 The gwy-localscan authors.
# SPDX-License-Identifier: GPL-2.0-or-later
. "$(dirname "$0")/shell-test-common.sh"
simscan=${SIMSCAN:-./simscan/simscan}
tool=${GWY_LOCALSCAN:-./tools/gwy-localscan}
make_absolute tool simscan
# The member $2 of case $3 of method $4 in the scores JSON $1.
score_of() {
    awk -v member="\"$2\"" -v name="\"$3\"" -v method="\"$4\"" '
        $1 == "\"name\"" { in_method = ($3 == method || $3 == method ",") }
        in_method && $1 == "\"case\"" { in_case = ($3 == name || $3 == name ",") }
        in_method && in_case && $1 == member { v = $3; sub(",", "", v); print v; exit }
    ' "$1"
}

draw_seed 1000000
# Measured samples left out: the test is the same with and without them.
export LOCALSCAN_MEASURED_DIR="$tmp/no-measured-data"

check
"$simscan" benchmark -o "$tmp/a" --seed "$seed" 2>"$tmp/err" \
    || fail "benchmark exited $?: $(cat "$tmp/err")"
"$simscan" benchmark -o "$tmp/b" --seed "$seed" 2>/dev/null
"$simscan" benchmark -o "$tmp/c" --seed $((seed + 1)) 2>/dev/null
check
diff -r "$tmp/a" "$tmp/b" >/dev/null || fail "seed $seed twice: different files"
check
cmp -s "$tmp/a/01-constant/frame-000.gwy" "$tmp/c/01-constant/frame-000.gwy" \
    && fail "seeds $seed and $((seed + 1)): the same frames"
cases=$(sed -n '/"cases"/,/]/p' "$tmp/a/benchmark.json" | sed -n 's/^ *"\([^"]*\)",*$/\1/p')
check
[ "$(echo "$cases" | wc -w)" -ge 12 ] || fail "only $(echo "$cases" | wc -w) cases"
check
grep -q '"reason" : "measured data absent' "$tmp/a/benchmark.json" \
    || fail "the measured-sample cases are not listed as skipped"
for name in $cases; do
    check
    [ -f "$tmp/a/$name/truth.csv" ] && [ -f "$tmp/a/$name/case.json" ] \
        && [ -f "$tmp/a/$name/truth.gwy" ] && [ -f "$tmp/a/$name/frame-000.gwy" ] \
        || fail "$name: files missing"
done

# The truth scores 0; an offset (ox, oy) drawn from the seed scores its
# length on every line; malformed results fail with the fault named.
ox=$(awk -v s="$seed" 'BEGIN { srand(s); printf "%.3f", -2 + 4*rand() }')
oy=$(awk -v s="$seed" 'BEGIN { srand(s + 7); printf "%.3f", -2 + 4*rand() }')
expected=$(awk -v x="$ox" -v y="$oy" 'BEGIN { printf "%.6f", sqrt(x*x + y*y) }')
echo "offset ($ox, $oy) px: expected $expected px"
for name in $cases; do
    mkdir -p "$tmp/r/truth/$name" "$tmp/r/offset/$name" "$tmp/r/bad/$name"
    cp "$tmp/a/$name/truth.csv" "$tmp/r/truth/$name/trajectory.csv"
    awk -F, -v x="$ox" -v y="$oy" 'BEGIN { OFS = "," }
        /^#/ || /^frame/ { print; next }
        { $4 = sprintf("%.6f", $4 + x); $5 = sprintf("%.6f", $5 + y); print }' \
        "$tmp/a/$name/truth.csv" > "$tmp/r/offset/$name/trajectory.csv"
done
bad=$tmp/r/bad
sed 's/^frame,row,t_s,dx_px,dy_px$/frame,row,time,dx,dy/' "$tmp/a/01-constant/truth.csv" \
    > "$bad/01-constant/trajectory.csv"
sed '10s/,[^,]*$/,nan/' "$tmp/a/02-settling/truth.csv" > "$bad/02-settling/trajectory.csv"
sed '20d' "$tmp/a/03-oscillation/truth.csv" > "$bad/03-oscillation/trajectory.csv"
awk 'NR == 30 { print } { print }' "$tmp/a/05-acceleration/truth.csv" \
    > "$bad/05-acceleration/trajectory.csv"
cp "$tmp/a/06-creep/truth.csv" "$bad/06-creep/trajectory.csv"
printf 'not a gwy file' > "$bad/06-creep/corrected.gwy"
cp "$tmp/a/07-random-walk/truth.csv" "$bad/07-random-walk/trajectory.csv"
printf '0\n99\n' > "$bad/07-random-walk/flagged.txt"
awk -F, 'BEGIN { OFS = "," } NR == 12 { $4 = "1e200" } { print }' \
    "$tmp/a/09-raw-channel/truth.csv" > "$bad/09-raw-channel/trajectory.csv"
cp "$tmp/a/10-missing-pixels/truth.csv" "$bad/10-missing-pixels/trajectory.csv"
printf '{"frames":[{"index":4294967296,"flagged":true}]}' \
    > "$bad/10-missing-pixels/result.json"
cp "$tmp/a/11-disturbed-frame/truth.csv" "$bad/11-disturbed-frame/trajectory.csv"
printf '{"frames":[{"index":1,"flagged":"yes"}]}' \
    > "$bad/11-disturbed-frame/result.json"

check
"$simscan" score --truth "$tmp/a" --json "$tmp/scores.json" "$tmp/r/truth" \
    "$tmp/r/offset" "$bad" >"$tmp/out" 2>"$tmp/err" \
    || fail "score exited $?: $(cat "$tmp/err")"
for name in $cases; do
    check
    v=$(score_of "$tmp/scores.json" trajectory_rms_px "$name" truth)
    [ "$v" = "0.0" ] || [ "$v" = "0" ] || fail "$name: the truth scores '$v', not 0"
    check
    v=$(score_of "$tmp/scores.json" trajectory_worst_px "$name" offset)
    awk -v v="$v" -v e="$expected" 'BEGIN { exit !(v != "" && v - e < 2e-6 && e - v < 2e-6) }' \
        || fail "$name: offset scores worst '$v', not $expected"
    check
    v=$(score_of "$tmp/scores.json" trajectory_rms_px "$name" offset)
    awk -v v="$v" -v e="$expected" 'BEGIN { exit !(v != "" && v - e < 2e-6 && e - v < 2e-6) }' \
        || fail "$name: offset scores rms '$v', not $expected"
done
expect_failure() {
    check
    grep -q "^$1, bad: failed: .*$2" "$tmp/out" \
        || fail "$1: no failure saying '$2': $(grep "^$1, bad" "$tmp/out")"
}
expect_failure 01-constant "the header is not"
expect_failure 02-settling "not a finite number"
expect_failure 03-oscillation "is missing"
expect_failure 05-acceleration "given twice"
expect_failure 06-creep "corrected.gwy"
expect_failure 07-random-walk "flagged.txt line 2"
expect_failure 08-large-offset "trajectory.csv absent"
expect_failure 09-raw-channel "beyond"
expect_failure 10-missing-pixels "result.json frame 0"
expect_failure 11-disturbed-frame "no flagged true or false"

# The scores are never written into a folder score reads: --json over the
# manifest replaced it (the next score failed), --svg over a case's truth,
# also through a link; refused with one line, the manifest unchanged.
sum_before=$(cksum <"$tmp/a/benchmark.json")
ln -s "$tmp/a/benchmark.json" "$tmp/scores-link.json"
for out in "--json $tmp/a/benchmark.json" "--svg $tmp/a/01-constant/truth.csv" \
           "--json $tmp/r/truth/x.json" "--json $tmp/scores-link.json"; do
    check
    # shellcheck disable=SC2086
    "$simscan" score --truth "$tmp/a" $out "$tmp/r/truth" >"$tmp/out" 2>"$tmp/err" \
        && fail "score $out was not refused"
    [ "$(wc -l <"$tmp/err")" -eq 1 ] && grep -q "folder .*: write it elsewhere, that folder is read" "$tmp/err" \
        || fail "score $out: $(cat "$tmp/err")"
done
check
[ "$(cksum <"$tmp/a/benchmark.json")" = "$sum_before" ] || fail "the manifest changed"
[ ! -e "$tmp/r/truth/x.json" ] || fail "a score was written into a result folder"
rm -f "$tmp/scores-link.json"

# The series correction's own result on one case: its corrected frames are
# scored against the drift-free truth, well under a pixel.  $1 holds the
# cases, $2 gets the result and $3 the scores.
score_series_on_constant() {
    s=$2/series/01-constant
    mkdir -p "$s"
    check
    "$tool" series -o "$s/corrected.gwy" --trajectory "$s/trajectory.csv" \
        --json "$s/result.json" "$1/01-constant"/frame-*.gwy 2>"$tmp/err" \
        || fail "gwy-localscan series on $1/01-constant: $(cat "$tmp/err")"
    "$simscan" score --truth "$1" --json "$3" "$2/series" >/dev/null 2>&1
    check
    v=$(score_of "$3" frame_rms_px 01-constant series)
    awk -v v="$v" 'BEGIN { exit !(v != "" && v != "null" && v < 0.3) }' \
        || fail "series on $1/01-constant: corrected frames $v px from the truth"
    check
    v=$(score_of "$3" flags_false 01-constant series)
    [ "$v" = "0.0" ] || [ "$v" = "0" ] || fail "series on $1/01-constant: $v clean frames flagged"
}
score_series_on_constant "$tmp/a" "$tmp/r" "$tmp/series.json"
# A known case: on seed 188 the judge read one stripe of every frame
# 0.5-1.3 px off (0.326 px), its texture a particle cut by the stripe's top
# border and a rate over its rows fitted to those rows alone.
"$simscan" benchmark -o "$tmp/k188" --seed 188 2>/dev/null
score_series_on_constant "$tmp/k188" "$tmp/rk188" "$tmp/k188.json"

# A truth whose drift-free frame is not the case's size is the truth's
# fault: one line, exit 1 (the method's corrected frames are never read
# against it).
cp -r "$tmp/a" "$tmp/bt"
cp "$tmp/a/14-movie/truth.gwy" "$tmp/bt/01-constant/truth.gwy"
check
if "$simscan" score --truth "$tmp/bt" "$tmp/r/series" >"$tmp/out" 2>"$tmp/err"; then
    fail "a truth.gwy of the wrong size: exit 0"
fi
grep -q "no drift-free frame of 128x128" "$tmp/err" \
    || fail "a truth.gwy of the wrong size: $(cat "$tmp/err")"
# JSON and plot are written both or neither.
mkdir "$tmp/plot.svg"
check
if "$simscan" score --truth "$tmp/a" --json "$tmp/both.json" --svg "$tmp/plot.svg" \
        "$tmp/r/truth" >"$tmp/out" 2>"$tmp/err"; then
    fail "--svg onto a folder: exit 0"
fi
[ ! -e "$tmp/both.json" ] || fail "--svg failed but the JSON was written"
check
"$simscan" score --truth "$tmp/a" --svg "$tmp/p.svg" "$tmp/r/truth" "$tmp/r/offset" \
    >/dev/null 2>&1 && grep -q "</svg>" "$tmp/p.svg" || fail "no SVG written"

# Bad command lines: one line, non-zero, nothing written.
mkdir "$tmp/full" && echo keep > "$tmp/full/x"
for args in "-o $tmp/full" "-o $tmp/new --size huge" "-o $tmp/new --seed -3" \
            "--seed 1" "-o $tmp/new extra"; do
    check
    # shellcheck disable=SC2086
    if "$simscan" benchmark $args >"$tmp/out" 2>"$tmp/err"; then
        fail "benchmark $args: exit 0"
    fi
    [ "$(wc -l < "$tmp/err")" -eq 1 ] || fail "benchmark $args: not one line: $(cat "$tmp/err")"
    [ ! -e "$tmp/new" ] || fail "benchmark $args: left $tmp/new"
done
check
[ "$(cat "$tmp/full/x")" = keep ] && [ "$(ls "$tmp/full" | wc -l)" -eq 1 ] \
    || fail "a non-empty folder was touched"
# A manifest naming a case outside its folder, a case description with
# absurd sizes: refused with one line.
mkdir -p "$tmp/evil/c1"
printf '{"benchmark_version":"1","seed":1,"size":"small","cases":["../a"]}' > "$tmp/evil/benchmark.json"
mkdir -p "$tmp/huge/c1"
printf '{"benchmark_version":"1","seed":1,"size":"small","cases":["c1"]}' > "$tmp/huge/benchmark.json"
printf '{"frames":100000,"xres":64,"yres":65536,"line_time_s":1,"pixel_m":[1e-9,1e-9],"p0_px":[0,0],"drift":{},"disturbed_frames":[]}' \
    > "$tmp/huge/c1/case.json"
mkdir -p "$tmp/other/truth"
for args in "--truth $tmp/r/truth $tmp/r/truth" "--truth $tmp/a" "$tmp/r/truth" \
            "--truth $tmp/evil $tmp/r/truth" "--truth $tmp/huge $tmp/r/truth" \
            "--truth $tmp/a $tmp/a/benchmark.json" "--truth $tmp/a $tmp/no-such" \
            "--truth $tmp/a $tmp/r/truth $tmp/other/truth"; do
    check
    # shellcheck disable=SC2086
    if "$simscan" score $args >"$tmp/out" 2>"$tmp/err"; then
        fail "score $args: exit 0"
    fi
    [ "$(wc -l < "$tmp/err")" -eq 1 ] || fail "score $args: not one line: $(cat "$tmp/err")"
done

finish
