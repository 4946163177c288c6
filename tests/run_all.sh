#!/bin/sh
# Runs the test programs given, as many at once as there are cores (the
# first named start first: name the longest first), prints each one's output
# in the order given, then every SKIP line again and the closing line
# "total: N passed, M failed, K skipped"; exits nonzero if any program
# failed. Each program ends with "N passed, M failed[, K skipped]".
# usage: run_all.sh PROGRAM...   (JOBS=n to change the number at once)
dir=build/test_output
mkdir -p "$dir" || exit 1
jobs=${JOBS:-$(nproc 2>/dev/null || getconf _NPROCESSORS_ONLN 2>/dev/null || echo 2)}
start=$(date +%s)

# one program: its output to $dir/NAME.out, its exit status to $dir/NAME.rc
run_one() {
    name=$(basename "$1")
    began=$(date +%s)
    "$1" > "$dir/$name.out" 2>&1
    echo $? > "$dir/$name.rc"
    line=$(grep -E '^[0-9]+ passed, [0-9]+ failed' "$dir/$name.out" | tail -n 1)
    echo "finished $name in $(($(date +%s) - began)) s: ${line:-no summary line}"
}
if [ "${1:-}" = --one ]; then run_one "$2"; exit 0; fi

for t in "$@"; do rm -f "$dir/$(basename "$t").out" "$dir/$(basename "$t").rc"; done
printf '%s\n' "$@" | xargs -P "$jobs" -n 1 sh "$0" --one

passed=0; failed=0; skipped=0; status=0
for t in "$@"; do
    name=$(basename "$t")
    echo "== $t"
    cat "$dir/$name.out" 2>/dev/null
    rc=$(cat "$dir/$name.rc" 2>/dev/null || echo "not run")
    line=$(grep -E '^[0-9]+ passed, [0-9]+ failed' "$dir/$name.out" 2>/dev/null | tail -n 1)
    if [ -z "$line" ]; then
        echo "$t: no summary line (exit $rc)"; failed=$((failed + 1)); status=1; continue
    fi
    p=${line%% passed*}; f=${line#*, }; f=${f%% failed*}
    case $line in *skipped*) s=${line##*, }; s=${s%% skipped*} ;; *) s=0 ;; esac
    passed=$((passed + p)); failed=$((failed + f)); skipped=$((skipped + s))
    [ "$rc" = 0 ] || { echo "$t: exit $rc"; status=1; }
done
if [ "$skipped" -gt 0 ]; then
    echo "skipped, and why:"
    for t in "$@"; do
        grep '^SKIP ' "$dir/$(basename "$t").out" 2>/dev/null | sed "s|^|  $(basename "$t"): |"
    done
fi
echo "total: $passed passed, $failed failed, $skipped skipped ($# programs, $(($(date +%s) - start)) s on $jobs at once)"
[ "$failed" = 0 ] || status=1
exit $status
