# What every shell test shares, sourced first thing by each:
#   . "$(dirname "$0")/shell-test-common.sh"
# A scratch folder $tmp removed on exit; fail and check, which count the
# failures and the checks; the seed from LOCALSCAN_TEST_SEED (or drawn)
# printed so that a failure can be repeated; parts that cannot run reported
# as SKIPPED; and the summary with automake's exit status: 1 after a
# failure, else 77 (SKIP) when a part could not run, else 0.
# Copyright (C) 2026 The gwy-localscan authors.
# SPDX-License-Identifier: GPL-2.0-or-later
set -u
test_name=$(basename "$0" .sh)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
failures=0
checks=0
skipped=0

fail() {
    echo "FAIL: $*"
    failures=$((failures + 1))
}

check() {
    checks=$((checks + 1))
}

# Makes the paths held by the named variables absolute, so that they still
# work when a test changes folder.
make_absolute() {
    for v in "$@"; do
        eval "p=\$$v"
        case $p in /*) ;; *) eval "$v=\$(pwd)/\$p" ;; esac
    done
}

# Sets seed from LOCALSCAN_TEST_SEED, else at random, reduced modulo $1 when
# given (for tools that take no larger seed), and prints it.
draw_seed() {
    seed=${LOCALSCAN_TEST_SEED:-$(od -An -N4 -tu4 /dev/urandom | tr -d ' ')}
    [ $# -eq 0 ] || seed=$((seed % $1))
    echo "$test_name: seed $seed (LOCALSCAN_TEST_SEED overrides)"
}

# A part that cannot run here: said, and counted so the test is no PASS.
skip_part() {
    echo "$test_name: SKIPPED: $*"
    skipped=$((skipped + 1))
}

# Nothing of the test can run here.
skip_all() {
    echo "$test_name: SKIPPED: $*"
    exit 77
}

finish() {
    echo "$test_name: $checks checks, $failures failures, $skipped parts skipped"
    [ $failures -eq 0 ] || exit 1
    [ $skipped -eq 0 ] || exit 77
    exit 0
}
