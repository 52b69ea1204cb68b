#!/bin/sh
# Gwyddion's own programs read what gwy-localscan writes: the command
# compensates a Gwyddion Simple Field (.gsf) input, gwyddion-thumbnailer
# renders the source and the new channel of OUT.gwy to PNGs of the expected
# size, and `gwyddion --check` finds nothing wrong in it (exit 0, silent),
# nor in what simscan writes, nor in gwy-localscan's result of that.
# Copyright (C) 2026 The gwy-localscan authors.
# SPDX-License-Identifier: GPL-2.0-or-later
. "$(dirname "$0")/shell-test-common.sh"
tool=${GWY_LOCALSCAN:-./tools/gwy-localscan}
simscan=${SIMSCAN:-./simscan/simscan}
thumbnailer=$(command -v gwyddion-thumbnailer)
gwyddion=$(command -v gwyddion)

[ -n "$thumbnailer" ] || skip_all "gwyddion-thumbnailer is not installed"

# A 64 x 48 image of 8 x 8 blocks with heights 0..4 nm, float32 little
# endian after a NUL-padded text header (perl is part of every Debian).
write_gsf() {
    header='Gwyddion Simple Field 1.0
XRes = 64
YRes = 48
XReal = 6.4e-08
YReal = 4.8e-08
XYUnits = m
ZUnits = m
Title = Blocks
'
    printf '%s' "$header" >"$1"
    pad=$((4 - $(printf '%s' "$header" | wc -c) % 4))
    head -c "$pad" /dev/zero >>"$1"
    perl -e 'for $r (0..47) { for $c (0..63) { print pack("f<", (int($r/8) + int($c/8)) % 5 * 1e-9) } }' >>"$1"
}

# Width and height from a PNG's IHDR chunk, "W H"; empty if not a PNG.
png_size() {
    signature=$(od -An -tx1 -N8 "$1" | tr -d ' \n')
    [ "$signature" = 89504e470d0a1a0a ] || return 0
    od -An -tu1 -j16 -N8 "$1" | awk '{ print $1*16777216 + $2*65536 + $3*256 + $4, $5*16777216 + $6*65536 + $7*256 + $8 }'
}

write_gsf "$tmp/in.gsf"
printf 'stripe,dx,dy\n0,-2,0\n1,-3,0\n2,,\n3,-5,-1\n4,-6,-1\n5,-7,-2\n' >"$tmp/drift.csv"

check
"$tool" -d "$tmp/drift.csv" -o "$tmp/out.gwy" "$tmp/in.gsf" 2>"$tmp/err" \
    || fail "gwy-localscan on a .gsf input exited with $?: $(cat "$tmp/err")"
[ -s "$tmp/out.gwy" ] || { echo "FAIL: no OUT.gwy, cannot go on"; exit 1; }

# Channel 0 is the source, channel 1 the compensated one.  64 x 48 pixels
# fit a 32 pixel box as 32 x 24 (the thumbnailer never enlarges).
for id in 0 1; do
    check
    "$thumbnailer" -c $id gnome2 32 "$tmp/out.gwy" "$tmp/thumb$id.png" 2>"$tmp/err" \
        || fail "gwyddion-thumbnailer -c $id exited with $?: $(cat "$tmp/err")"
    size=$(png_size "$tmp/thumb$id.png")
    check
    [ "$size" = "32 24" ] || fail "thumbnail of channel $id: size '$size', expected '32 24'"
done
check
if cmp -s "$tmp/thumb0.png" "$tmp/thumb1.png"; then
    fail "the compensated channel's thumbnail is the source's"
fi

# A channel that does not exist must not render.
check
if "$thumbnailer" -c 2 gnome2 32 "$tmp/out.gwy" "$tmp/thumb2.png" 2>/dev/null \
        && [ -n "$(png_size "$tmp/thumb2.png")" ]; then
    fail "gwyddion-thumbnailer rendered channel 2, which gwy-localscan never wrote"
fi

# gwyddion --check reports every item it does not know (the drift table and
# simscan's particle list live in the channels' metadata, which it knows)
# and exits 1 on any problem: it must exit 0 and say nothing.
gwyddion_check() {
    check
    "$gwyddion" --check "$1" >"$tmp/check" 2>&1
    status=$?
    if [ $status -ne 0 ] || [ -s "$tmp/check" ]; then
        fail "gwyddion --check $2 exited with $status: $(cat "$tmp/check")"
    fi
}

if [ -n "$gwyddion" ]; then
    gwyddion_check "$tmp/out.gwy" "of gwy-localscan's output"
    check
    if "$simscan" --seed 7 --xres 64 --yres 64 -q -o "$tmp/sim.gwy" 2>"$tmp/err"; then
        gwyddion_check "$tmp/sim.gwy" "of simscan's output"
        check
        "$tool" -o "$tmp/sim-out.gwy" "$tmp/sim.gwy" 2>"$tmp/err" \
            || fail "gwy-localscan on simscan's output exited with $?: $(cat "$tmp/err")"
        gwyddion_check "$tmp/sim-out.gwy" "of gwy-localscan's result of simscan's output"
    else
        fail "simscan exited with $?: $(cat "$tmp/err")"
    fi
else
    skip_part "gwyddion --check (gwyddion is not installed)"
fi

finish
