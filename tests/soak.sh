#!/bin/sh
# Soak of the seeded tests: runs every seeded test program of a configured
# build over many seeds, one run at a time at the lowest priority, and
# prints per program the seeds run, the failures and the failing seeds
# (LOCALSCAN_TEST_SEED=N repeats one).  A failing seed is a bug of the
# product to be fixed there, never a seed to avoid.
#
#   tests/soak.sh [-b BUILDDIR] [-n SEEDS] [-f FIRST] [-s STRIDE] [TEST...]
#
# BUILDDIR is the configured build (default _build); SEEDS the number of
# seeds per program (500); the seeds are FIRST, FIRST + STRIDE, ... (FIRST
# drawn at random and printed unless given; STRIDE 4, since
# test-continuous-simscan runs four consecutive simulator seeds from its
# seed).  TEST names programs or scripts under BUILDDIR/tests (or the
# source's tests/ for scripts); without any, every seeded one, fastest
# first.  The environment is the one `make check` gives the tests.
# Exit status 0 when no run failed; skipped runs (exit 77) are counted
# apart.
#
# Copyright (C) 2026 The gwy-localscan authors.
# SPDX-License-Identifier: GPL-2.0-or-later
set -u

srcdir=$(cd "$(dirname "$0")/.." && pwd)
builddir=$srcdir/_build
seeds=500
first=
stride=4
while getopts b:n:f:s: opt; do
    case $opt in
        b) builddir=$(cd "$OPTARG" && pwd) || exit 2 ;;
        n) seeds=$OPTARG ;;
        f) first=$OPTARG ;;
        s) stride=$OPTARG ;;
        *) echo "usage: $0 [-b BUILDDIR] [-n SEEDS] [-f FIRST] [-s STRIDE] [TEST...]" >&2
           exit 2 ;;
    esac
done
shift $((OPTIND - 1))
if [ ! -f "$builddir/Makefile" ]; then
    echo "soak: $builddir is not a configured build (run ./quickstart check first)" >&2
    exit 2
fi
[ -n "$first" ] || first=$(od -An -N3 -tu4 /dev/urandom | tr -d ' ')

# Every program whose source takes LOCALSCAN_TEST_SEED through the shared
# helper (or the frame-pair one), roughly fastest first; the GUI tests last.
if [ $# -eq 0 ]; then
    set -- test-drift-model test-median test-jump-votes test-series-graph test-drift-fit test-trajectory-csv test-preview-field test-simscan-scanner \
        test-local-scan test-gwy-stream-save test-hostile-core \
        test-simscan-measured-sample test-continuous-compensate \
        test-drift-trajectory test-drift-fit-creep test-continuous-blocks \
        test-height-keeping test-frame-series test-benchmark.sh \
        test-continuous-simscan test-stripe-registration test-registration-binning \
        test-paper-compensate test-module-immediate test-simscan-cli.sh \
        test-series-command.sh test-series-module test-series-correction \
        test-hostile-input test-module-dialog test-gui-dialog.sh \
        test-hidden-effects test-gwy-localscan
fi

# What AM_TESTS_ENVIRONMENT (tests/Makefile.inc) sets.
HOME=$builddir/tests/home
LOCALSCAN_MEASURED_DIR=${LOCALSCAN_MEASURED_DIR:-$srcdir/../shared/data/measured}
LOCALSCAN_MODULE=$builddir/modules/.libs/localscan.so
CK_DEFAULT_TIMEOUT=${CK_DEFAULT_TIMEOUT:-600}
export HOME LOCALSCAN_MEASURED_DIR LOCALSCAN_MODULE CK_DEFAULT_TIMEOUT
mkdir -p "$HOME"
log=$builddir/tests/soak.log
: > "$log"

echo "soak: $seeds seeds per program, $first + $stride k; log $log"
printf '%-32s %6s %6s %8s  %s\n' test seeds skips failures "failing seeds"
status=0
for name in "$@"; do
    case $name in
        *.sh) program=$srcdir/tests/$name ;;
        *) program=$builddir/tests/$name ;;
    esac
    if [ ! -x "$program" ]; then
        echo "soak: $program is not built (make -C $builddir check builds it)" >&2
        status=1
        continue
    fi
    failures=0
    skips=0
    failing=
    k=0
    while [ $k -lt "$seeds" ]; do
        seed=$(( (first + stride*k) % 4294967296 ))
        (cd "$builddir" && LOCALSCAN_TEST_SEED=$seed nice -n 19 "$program") \
            > "$builddir/tests/soak-run.log" 2>&1
        rc=$?
        if [ $rc -eq 77 ]; then
            skips=$((skips + 1))
        elif [ $rc -ne 0 ]; then
            failures=$((failures + 1))
            failing="$failing $seed"
            { echo "=== $name LOCALSCAN_TEST_SEED=$seed exit $rc"
              cat "$builddir/tests/soak-run.log"; } >> "$log"
        fi
        k=$((k + 1))
    done
    [ $failures -eq 0 ] || status=1
    printf '%-32s %6d %6d %8d %s\n' "$name" "$seeds" "$skips" "$failures" "$failing"
done
rm -f "$builddir/tests/soak-run.log"
exit $status
