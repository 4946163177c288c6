#!/bin/sh
# Runs each test program, then prints the total as the closing line
# "N passed, M failed"; exits nonzero if any program failed.
passed=0; failed=0; status=0
for t in "$@"; do
    echo "== $t"
    out=$("$t" 2>&1); rc=$?
    printf '%s\n' "$out"
    line=$(printf '%s\n' "$out" | grep -E '^[0-9]+ passed, [0-9]+ failed' | tail -n 1)
    if [ -z "$line" ]; then
        echo "$t: no summary line (exit $rc)"; failed=$((failed + 1)); status=1; continue
    fi
    p=${line%% passed*}; f=${line#*, }; f=${f%% failed*}
    passed=$((passed + p)); failed=$((failed + f))
    [ "$rc" = 0 ] || status=1
done
echo "total: $passed passed, $failed failed"
[ "$failed" = 0 ] || status=1
exit $status
