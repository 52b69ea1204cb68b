#!/bin/sh
# Tests of the simscan command line: same seed, same bytes; the drift table
# travels inside the .gwy; every bad option exits non-zero with one line and
# leaves no output; --help lists every option.
# Copyright (C) 2026 The gwy-localscan authors.
# SPDX-License-Identifier: GPL-2.0-or-later
. "$(dirname "$0")/shell-test-common.sh"
simscan=${SIMSCAN:-./simscan/simscan}
make_absolute simscan

draw_seed
small="--xres 128 --yres 128 --size 2.5 --stripes 8 --noise 0.2 --seed $seed"

# Same seed, same bytes; another seed, other bytes.
for run in a b; do
    "$simscan" $small -q -o "$tmp/$run.gwy" --table "$tmp/$run.csv" \
        --json "$tmp/$run.json" || fail "run $run exited with $?"
done
check
for ext in gwy csv json; do
    cmp -s "$tmp/a.$ext" "$tmp/b.$ext" || fail "same seed, different .$ext"
done
check
"$simscan" $small --seed $((seed ^ 1)) -q -o "$tmp/c.gwy" || fail "seed ^ 1 run"
cmp -s "$tmp/a.gwy" "$tmp/c.gwy" && fail "another seed gave the same .gwy"

# The .gwy is Gwyddion's format and carries the table simscan wrote.
check
[ "$(head -c 4 "$tmp/a.gwy")" = "GWYP" ] || fail ".gwy lacks the GWYP magic"
check
grep -q "Local-scan drift table" "$tmp/a.gwy" || fail "no stored drift table"
check
grep -qF "$(sed -n 2p "$tmp/a.csv")" "$tmp/a.gwy" \
    || fail "the stored table differs from the CSV"
check
head -n 1 "$tmp/a.csv" | grep -q '^stripe,dx,dy,dx_exact,dy_exact,t_image,t_local,x,y,lines$' \
    || fail "CSV header: $(head -n 1 "$tmp/a.csv")"
check
[ "$(grep -c '^[0-9]' "$tmp/a.csv")" -eq 8 ] || fail "CSV has not 8 stripes"

# simscan "$@" (the case $1 names) must be refused: non-zero, exactly one
# line on stderr, no e.* output (nor its temporary .e.*) written.
refused_case() {
    what=$1
    shift
    "$simscan" "$@" >"$tmp/out" 2>"$tmp/err"
    status=$?
    check
    [ $status -ne 0 ] || fail "$what exited 0"
    [ "$(wc -l <"$tmp/err")" -eq 1 ] || fail "$what: stderr is not one line: $(cat "$tmp/err")"
    if ls -A "$tmp" | grep -q '^\.\{0,1\}e\.'; then
        fail "$what left output: $(ls -A "$tmp")"
    fi
}

# Bad options: refused.
bad_case() {
    rm -f "$tmp"/e.* "$tmp"/.e.*
    refused_case "$*" "$@" -o "$tmp/e.gwy" --table "$tmp/e.csv" --json "$tmp/e.json"
}
bad_case --stripes 0
bad_case --stripes 300
bad_case --bogus
bad_case --drift wobble
bad_case --velocity 1
bad_case --velocity 1,nan
bad_case --seed -1
bad_case --xres 4
bad_case --preset nope
bad_case --size 0
bad_case --direction sideways
bad_case --ls-threshold 1.5
bad_case --radius abc
bad_case --sample "$tmp/missing.gwy"
# FILE:ID with an id past the int range (atoi made channel 0 of it).
bad_case --sample "$tmp/a.gwy:4294967296"
bad_case unexpected-argument
# Not-a-number and out-of-range values are refused, not taken for "not
# given" (these options' defaults depend on a measured sample).
bad_case --radius nan
bad_case --radius inf
bad_case --ls-rmax nan
bad_case --xres -2147483648
bad_case --yres 99999999999999999999
# Absurd scenes are refused before anything is simulated.
bad_case --size 1e6
bad_case --size 1000 --density 10
bad_case --size 2 --radius 2000
bad_case --xres 8192 --yres 4096
# A value that is not text in the locale's encoding: the refusal names the
# option, not only GLib's "Invalid byte sequence in conversion input".
# $1 the message's prefix, $2 the option, the rest simscan's arguments.
not_text_case() {
    who=$1
    option=$2
    shift 2
    LC_ALL=C "$simscan" "$@" >"$tmp/out" 2>"$tmp/err"
    status=$?
    check
    [ $status -ne 0 ] || fail "$option=<bytes> exited 0"
    check
    grep -q "^$who: the value of $option is not text" "$tmp/err" \
        || fail "$option=<bytes>: $(cat "$tmp/err")"
}
rm -f "$tmp"/e.*
not_text_case simscan --drift "--drift=$(printf '\377')" -o "$tmp/e.gwy"
not_text_case simscan --velocity "--velocity=$(printf '\376\377')" -o "$tmp/e.gwy"
not_text_case "simscan benchmark" --size benchmark "--size=$(printf '\377')" -o "$tmp/bench-e"
check
[ ! -e "$tmp/bench-e" ] && [ ! -e "$tmp/e.gwy" ] || fail "a refused value left output"

# One output unwritable: none of the others is left behind.
rm -f "$tmp"/e.*
"$simscan" $small -q -o "$tmp/e.gwy" --table "$tmp/no/such/dir/e.csv" \
    2>"$tmp/err"
status=$?
check
[ $status -ne 0 ] || fail "an unwritable table exited 0"
if ls -A "$tmp" | grep -q 'e\.gwy'; then
    fail "unwritable table left the .gwy: $(ls -A "$tmp")"
fi

# simscan fit: three frames of one sample drifting at (1, 0.5) nm/s, 100 s
# apart, and a pair of frames of 3 lines (too short to register), written
# as Gwyddion's serialised GwyContainer (the format simscan writes).  10
# particles per um^2 (16 in a frame): at the default 4 (6 in a frame) seed
# 470000636 drew a frame whose 4 local scans all found none, and simscan
# rightly refused to write it.
fit_frames="$tmp/f0.gwy $tmp/f1.gwy $tmp/f2.gwy"
for k in 0 1 2; do
    "$simscan" -q --xres 64 --yres 64 --size 1.25 --stripes 4 --density 10 --seed $seed \
        --velocity 1,0.5 --offset $((100 * k)),$((50 * k)) -o "$tmp/f$k.gwy" \
        || fail "frame $k exited non-zero"
done
# write_gwy FILE ID XRES YRES noise|white|particles: one channel, id ID, of
# hemispheres 3 px in radius on a flat ground, of small noise (a pattern
# repeated every 13 pixels), or of white noise drawn from the file's name.
write_gwy() {
    python3 - "$@" <<'PY'
import math, struct, sys
def obj(name, comps):
    body = b''.join(comps)
    return name.encode() + b'\0' + struct.pack('<I', len(body)) + body
def comp(name, kind, payload):
    return name.encode() + b'\0' + kind.encode() + payload
path, cid, xres, yres, kind = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4]), sys.argv[5]
dx = 1e-6 / 32
data = [((i * 7919 + len(path)) % 13) * 1e-10 for i in range(xres * yres)]
if kind == 'white':
    import random
    rng = random.Random(path)
    data = [rng.gauss(0, 1e-10) for i in range(xres * yres)]
if kind == 'particles':
    data = [0.0] * (xres * yres)
    for cy in range(8, yres - 4, 12):
        for cx in range(8 + (cy // 12) % 2 * 6, xres - 4, 12):
            for i in range(cy - 3, cy + 4):
                for j in range(cx - 3, cx + 4):
                    d2 = (i - cy) ** 2 + (j - cx) ** 2
                    if d2 < 9:
                        data[i * xres + j] = math.sqrt(9 - d2) * dx
field = obj('GwyDataField', [
    comp('xres', 'i', struct.pack('<i', xres)),
    comp('yres', 'i', struct.pack('<i', yres)),
    comp('xreal', 'd', struct.pack('<d', xres * dx)),
    comp('yreal', 'd', struct.pack('<d', yres * dx)),
    comp('data', 'D', struct.pack('<I', len(data))
         + struct.pack('<%dd' % len(data), *data))])
with open(path, 'wb') as fh:
    fh.write(b'GWYP' + obj('GwyContainer', [comp('/%d/data' % cid, 'o', field)]))
PY
}
write_gwy "$tmp/tiny0.gwy" 0 16 3 noise
write_gwy "$tmp/tiny-frame1.gwy" 0 16 3 noise

# Every JSON simscan writes parses as strict JSON (no NaN or Infinity).
strict_json() {
    python3 -c 'import json, sys
def refuse(name):
    raise ValueError("not JSON: " + name)
json.load(open(sys.argv[1]), parse_constant=refuse)' "$1"
}
"$simscan" fit --line-time 1 --frame-times 0,100,200 $fit_frames \
    --json "$tmp/fit.json" || fail "fit of three frames exited non-zero"
check
strict_json "$tmp/fit.json" || fail "fit JSON does not parse: $(cat "$tmp/fit.json")"
check
grep -q '"effect"' "$tmp/fit.json" || fail "fit JSON has no effect"
# Its report written to a full disk (or a closed pipe) is an error like
# any other: one line, exit 1 (it exited 0, the report lost).
if [ -w /dev/full ]; then
    check
    "$simscan" fit --line-time 1 --frame-times 0,100,200 $fit_frames >/dev/full 2>"$tmp/err" \
        && fail "fit to a full standard output exited 0"
    [ "$(wc -l <"$tmp/err")" -eq 1 ] && grep -q "^simscan fit: cannot write to the standard output: " "$tmp/err" \
        || fail "fit to a full standard output: $(cat "$tmp/err")"
fi
check
strict_json "$tmp/a.json" || fail "simscan's JSON does not parse"

# A bad fit option: non-zero, one line naming what is wrong, no JSON.
fit_bad_case() {
    expect=$1
    shift
    rm -f "$tmp/fit-e.json"
    "$simscan" fit "$@" --json "$tmp/fit-e.json" >"$tmp/out" 2>"$tmp/err"
    status=$?
    check
    [ $status -ne 0 ] || fail "fit $* exited 0"
    [ "$(wc -l <"$tmp/err")" -eq 1 ] || fail "fit $*: stderr is not one line: $(cat "$tmp/err")"
    grep -q -- "$expect" "$tmp/err" || fail "fit $*: message does not say '$expect': $(cat "$tmp/err")"
    [ ! -e "$tmp/fit-e.json" ] || fail "fit $* wrote its JSON"
}
fit_timing="--line-time 1 --frame-times 0,100,200"
fit_bad_case "--line-time must be a number of seconds" --line-time 0 --frame-times 0,100,200 $fit_frames
fit_bad_case "--line-time must be a number of seconds" --line-time -0 --frame-times 0,100,200 $fit_frames
fit_bad_case "--line-time must be a number of seconds" --line-time nan --frame-times 0,100,200 $fit_frames
fit_bad_case "--bic-margin" $fit_timing --bic-margin nan $fit_frames
fit_bad_case "--bic-margin" $fit_timing --bic-margin -1 $fit_frames
fit_bad_case "--blocks" $fit_timing --blocks 0 $fit_frames
fit_bad_case "--blocks" $fit_timing --blocks -2 $fit_frames
fit_bad_case "--blocks" $fit_timing --blocks 17 $fit_frames
fit_bad_case "--channels" $fit_timing --channels 4294967296 $fit_frames
fit_bad_case "3 lines" --line-time 1 --frame-times 0,100 --blocks 1 \
    "$tmp/tiny0.gwy" "$tmp/tiny-frame1.gwy"
fit_bad_case "3 lines" --line-time 1 --frame-times 0,100 \
    "$tmp/tiny0.gwy" "$tmp/tiny-frame1.gwy"

# Frames of white noise match a few blocks by chance: the fit says that it
# rests on few measurements, on stderr and in the notes (it chose a jump of
# 825 nm from 4 of 48 blocks, and said nothing).  The particles' frames
# register every block and get no such warning.
for k in 0 1 2; do
    write_gwy "$tmp/white$k.gwy" 0 64 64 white
done
"$simscan" fit $fit_timing --json "$tmp/white.json" "$tmp"/white[012].gwy 2>"$tmp/err" \
    || fail "fit of white noise exited non-zero: $(cat "$tmp/err")"
check
grep -q "^simscan fit: warning: only [0-9]* of 48 measurements could be used" "$tmp/err" \
    || fail "fit of white noise: no warning: $(cat "$tmp/err")"
check
grep -q '"only [0-9]* of 48 measurements could be used' "$tmp/white.json" \
    || fail "fit of white noise: no note in the JSON"
"$simscan" fit $fit_timing --json "$tmp/fit.json" $fit_frames 2>"$tmp/err"
check
[ ! -s "$tmp/err" ] || fail "fit of three good frames: $(cat "$tmp/err")"

# An output that is a folder: refused before any output is renamed.
rm -f "$tmp"/e.*
mkdir "$tmp/e-folder"
refused_case "a folder as --json" $small -q -o "$tmp/e.gwy" --table "$tmp/e.csv" \
    --json "$tmp/e-folder"
rmdir "$tmp/e-folder"

# No output may be an input or another output: refused with one line, the
# input unchanged, nothing written.
same_file_case() {
    keep=$1
    shift
    cp "$keep" "$tmp/keep.copy"
    "$simscan" "$@" >"$tmp/out" 2>"$tmp/err"
    status=$?
    check
    [ $status -ne 0 ] || fail "$* exited 0"
    [ "$(wc -l <"$tmp/err")" -eq 1 ] || fail "$*: stderr is not one line: $(cat "$tmp/err")"
    grep -q "same file\|would overwrite" "$tmp/err" \
        || fail "$*: message does not name the clash: $(cat "$tmp/err")"
    cmp -s "$keep" "$tmp/keep.copy" || fail "$* changed $keep"
}
same_file_case "$tmp/f0.gwy" fit --line-time 1 --frame-times 0,100,200 \
    $fit_frames --json "$tmp/f0.gwy"
same_file_case "$tmp/f1.gwy" fit --line-time 1 --frame-times 0,100,200 \
    $fit_frames --json "$tmp/../$(basename "$tmp")/f1.gwy"
same_file_case "$tmp/a.gwy" --sample "$tmp/a.gwy" -q -o "$tmp/a.gwy"
same_file_case "$tmp/a.gwy" --sample "$tmp/a.gwy:0" -q --json "$tmp/./a.gwy"
ln "$tmp/a.gwy" "$tmp/a-link.gwy"
same_file_case "$tmp/a.gwy" --sample "$tmp/a.gwy" -q --table "$tmp/a-link.gwy"
rm -f "$tmp/a-link.gwy"
same_file_case "$tmp/a.gwy" compare "$tmp/a.gwy" --after-png "$tmp/a.gwy"
for pair in "-o X --table X" "-o X --json ./X" "--table X --json X"; do
    rm -f "$tmp/X"
    (cd "$tmp" && "$simscan" $small -q $pair) 2>"$tmp/err"
    status=$?
    check
    [ $status -ne 0 ] || fail "$pair exited 0"
    [ ! -e "$tmp/X" ] || fail "$pair wrote X"
    grep -q "are the same file" "$tmp/err" || fail "$pair: $(cat "$tmp/err")"
done
(cd "$tmp" && "$simscan" compare a.gwy --before-png P.png --truth-png ./P.png) \
    2>"$tmp/err"
check
grep -q "are the same file" "$tmp/err" || fail "compare, one picture twice: $(cat "$tmp/err")"

# --help lists every option.
"$simscan" --help >"$tmp/help" || fail "--help exited non-zero"
for opt in preset sample radius radius-spread count density spacing \
        roughness correlation xres yres size line-time direction noise \
        tip-radius drift velocity offset settle-velocity tau amplitude \
        period phase jump-time jump-step walk-sigma walk-dt stripes \
        ls-points ls-speed ls-rmax ls-overhead ls-delay ls-threshold \
        prefer-whole-particles seed output table json quiet; do
    check
    grep -q -- "--$opt" "$tmp/help" || fail "--help does not list --$opt"
done
# ... and the limits of the scene.
for limit in "at most 1000000" "8 to 16384" "at most 16777216" "at most 1000,"; do
    check
    grep -q -- "$limit" "$tmp/help" || fail "--help does not state the limit '$limit'"
done

# --prefer-whole-particles reaches the local scans.  Figure 6 with seed 31
# (fixed: a layout where the rules differ) has grains cut by stripe
# boundaries nearest some stripes' centres: the paper's rule (the default)
# scans them and marks them '*', the option scans other particles.
"$simscan" --preset figure6 --seed 31 --table "$tmp/f6-closest.csv" \
    >"$tmp/f6-closest.out" || fail "figure6 seed 31 exited non-zero"
"$simscan" --preset figure6 --seed 31 --prefer-whole-particles -q \
    --table "$tmp/f6-whole.csv" || fail "--prefer-whole-particles exited non-zero"
check
grep -q "closest to the stripe's centre (the paper's rule)" "$tmp/f6-closest.out" \
    || fail "the report does not name the paper's particle choice"
check
[ "$(grep -c '  \*$' "$tmp/f6-closest.out")" -ge 1 ] \
    || fail "no stripe marked as measured on a cut grain: $(cat "$tmp/f6-closest.out")"
check
# Columns x, y (8 and 9) are the scanned particle's displayed centre.
differ=$(paste -d '|' "$tmp/f6-closest.csv" "$tmp/f6-whole.csv" | grep '^[0-9]' \
    | awk -F'|' '{ split($1, a, ","); split($2, b, ",");
                   if (a[8] != b[8] || a[9] != b[9]) n++ } END { print n+0 }')
[ "$differ" -ge 1 ] && [ "$differ" -le 8 ] \
    || fail "--prefer-whole-particles changed the particle of $differ stripes"

# A measured sample: its own size and resolution, a radius from its
# particles, local scans that find them; --size does not apply to it.
measured=${LOCALSCAN_MEASURED_DIR:-$(dirname "$0")/../../shared/data/measured}/particles-film/PTO_110_Virgin0001.gwy
if [ -r "$measured" ]; then
    "$simscan" --sample "$measured:0" --table "$tmp/m.csv" >"$tmp/m.out" \
        || fail "--sample exited non-zero"
    check
    grep -q "256 x 256 px over 10 x 10 um" "$tmp/m.out" \
        || fail "--sample: not scanned over the sample: $(head -n 1 "$tmp/m.out")"
    check
    grep -q "particle radius 6[0-9]\.[0-9] nm" "$tmp/m.out" \
        || fail "--sample: radius not from the particles: $(grep radius "$tmp/m.out")"
    check
    [ "$(grep -c '^[0-9]*,-\{0,1\}[0-9]' "$tmp/m.csv")" -ge 10 ] \
        || fail "--sample: fewer than 10 stripes measured: $(cat "$tmp/m.csv")"
    bad_case --sample "$measured" --size 5
else
    skip_part "the --sample checks: measured data absent ($measured)"
fi

# A sample whose only channel has a high id (not the first 4097) is found.
write_gwy "$tmp/high-id.gwy" 5000 64 64 particles
"$simscan" --sample "$tmp/high-id.gwy" -q --table "$tmp/high-id.csv" 2>"$tmp/err" \
    || fail "--sample with channel id 5000: $(cat "$tmp/err")"
check
[ "$(grep -c '^[0-9]*,-\{0,1\}[0-9]' "$tmp/high-id.csv")" -ge 4 ] \
    || fail "--sample with channel id 5000: too few stripes measured"

# simscan compare on files gwy-localscan compensated (when it is built
# and LOCALSCAN_MODULE points at the module).
localscan=$(dirname "$simscan")/../tools/gwy-localscan
if [ -x "$localscan" ] && [ -r "${LOCALSCAN_MODULE:-}" ]; then
    "$localscan" -o "$tmp/a-paper.gwy" "$tmp/a.gwy" || fail "gwy-localscan (paper) exited non-zero"
    # The pictures are written all or none.
    mkdir "$tmp/p-folder"
    "$simscan" compare "$tmp/a-paper.gwy" --before-png "$tmp/p-before.png" \
        --after-png "$tmp/p-folder" >"$tmp/out" 2>"$tmp/err"
    status=$?
    check
    [ $status -ne 0 ] || fail "compare with a folder as --after-png exited 0"
    check
    [ ! -e "$tmp/p-before.png" ] || fail "compare left --before-png although --after-png failed"
    rmdir "$tmp/p-folder"
    # What compare says was done is what the channel's log records.
    "$localscan" -m continuous -o "$tmp/a-cont.gwy" "$tmp/a.gwy" \
        || fail "gwy-localscan (continuous) exited non-zero"
    for mode in paper continuous; do
        [ $mode = paper ] && f="$tmp/a-paper.gwy" || f="$tmp/a-cont.gwy"
        "$simscan" compare "$f" --after-png "$tmp/p-after.png" >"$tmp/out" \
            || fail "compare ($mode) exited non-zero"
        check
        head -n 1 "$tmp/out" | grep -q "channel 2, $mode mode)" \
            || fail "compare of a $mode-mode file says: $(head -n 1 "$tmp/out")"
    done
else
    skip_part "the compare checks: $localscan or LOCALSCAN_MODULE missing"
fi

# The sweep runs and plots.
"$simscan" sweep $small --n-list 1,4 --plot "$tmp/s.png" >"$tmp/sweep" \
    || fail "sweep exited non-zero"
check
[ "$(head -c 4 "$tmp/s.png" | tail -c 3)" = "PNG" ] || fail "sweep plot is not a PNG"
check
[ "$(grep -c '^ *[14] ' "$tmp/sweep")" -eq 2 ] || fail "sweep table: $(cat "$tmp/sweep")"

finish
