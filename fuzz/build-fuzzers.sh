#!/bin/sh
# Builds the libFuzzer harnesses with clang (ASan + UBSan) into DIR
# (default fuzz/_out); they compile the core sources they test directly.
# Needs clang and a configured build for config.h (BUILD, default _build).
set -eu
top=$(cd "$(dirname "$0")/.." && pwd)
out=${1:-$top/fuzz/_out}
build=${BUILD:-$top/_build}
mkdir -p "$out"
flags="-g -O1 -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=undefined
       -I$build -I$top/modules/core $(pkg-config --cflags gwyddion glib-2.0)"
libs="$(pkg-config --libs gwyddion glib-2.0) -lm"
core=$top/modules/core
clang $flags -o "$out/fuzz-drift-table" "$top/fuzz/fuzz-drift-table.c" \
    "$core/drift-table.c" "$core/stripe-geometry.c" "$core/quoted-input.c" $libs
clang $flags -o "$out/fuzz-file-screening" "$top/fuzz/fuzz-file-screening.c" \
    "$core/file-screening.c" $libs
clang $flags -o "$out/fuzz-scan-timing-meta" "$top/fuzz/fuzz-scan-timing-meta.c" \
    "$core/scan-timing-meta.c" "$core/scan-timing.c" $libs
echo "fuzzers in $out"
