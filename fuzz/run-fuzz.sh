#!/bin/sh
# Runs every libFuzzer harness for SECONDS each (default 30) from the
# corpus in fuzz/corpus, with libFuzzer seed SEED (default: drawn and
# printed, so a failing run can be repeated).  New inputs go to a scratch
# copy, never into the repository; a crash leaves its input in
# fuzz/_out/crashes and fails the run.  Builds the harnesses first
# (fuzz/build-fuzzers.sh).
set -eu
top=$(cd "$(dirname "$0")/.." && pwd)
seconds=${1:-30}
seed=${2:-$(od -An -N4 -tu4 /dev/urandom | tr -d ' ')}
out=$top/fuzz/_out
"$top/fuzz/build-fuzzers.sh" "$out" >/dev/null
mkdir -p "$out/crashes"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT INT TERM
echo "fuzzing ${seconds} s per harness, seed $seed (fuzz/run-fuzz.sh $seconds $seed repeats)"
status=0
for name in drift-table file-screening scan-timing-meta; do
    mkdir -p "$work/$name"
    cp "$top/fuzz/corpus/$name/"* "$work/$name/"
    if "$out/fuzz-$name" -seed="$seed" -max_total_time="$seconds" -timeout=10 \
        -rss_limit_mb=2048 -max_len=65536 -print_final_stats=1 \
        -artifact_prefix="$out/crashes/$name-" "$work/$name" > "$work/$name.log" 2>&1; then
        execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$work/$name.log")
        echo "fuzz-$name: $execs runs, no crash"
    else
        echo "fuzz-$name: FAILED (input in $out/crashes):"
        grep -A20 "ERROR\|==ERROR\|deadly\|runtime error" "$work/$name.log" | head -40
        status=1
    fi
done
exit $status
