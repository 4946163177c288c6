#!/bin/sh
# Runs a libFuzzer target for some seconds over its seed corpus; new inputs
# go to a scratch directory beside the binary, not into the repository.
# Prints the tests' summary line ("N passed, M failed"); on a finding, the
# fuzzer's report (the crashing input is saved as crash-* in the current
# directory).
# usage: fuzz_run.sh TARGET SEED_DIR SECONDS
target=$1; seeds=$2; seconds=$3
scratch="$target.corpus"
mkdir -p "$scratch"
if "$target" -max_total_time="$seconds" -print_final_stats=1 "$scratch" "$seeds" > "$target.log" 2>&1; then
    runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$target.log")
    echo "$target: $runs inputs in $seconds s, no finding"
    echo "1 passed, 0 failed"
else
    tail -n 40 "$target.log"
    echo "0 passed, 1 failed"
    exit 1
fi
