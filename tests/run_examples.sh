#!/bin/sh
# Runs the examples cheaply (a few seconds): minimal, the renderer on its
# built-in fur at 160x160 (ribbons, then round curves), groom (three hair
# groups in one BVH), embree_swap on its built-in patch. Each must exit
# 0; the render must hit more than 5% of its pixels and write a PNG that is
# not one flat colour (a flat 160x160 PNG compresses to well under 1 KB).
# Usage: sh tests/run_examples.sh [build dir]. Closing line "N passed, M failed".
B=${1:-build}
passed=0; failed=0
check() {   # check NAME CONDITION-STATUS
    if [ "$2" = 0 ]; then echo "ok: $1"; passed=$((passed + 1)); else echo "FAILED: $1"; failed=$((failed + 1)); fi
}

out=$("$B/minimal" 2>&1); rc=$?
printf '%s\n' "$out"
printf '%s\n' "$out" | grep -q '^hit segment' ; hit=$?
check "minimal runs and hits" $((rc + hit))

rm -f "$B/render_test.png"
"$B/render" -w 160 -h 160 -o "$B/render_test.png" > "$B/render_test.log" 2>&1; rc=$?
out=$(tr '\r' '\n' < "$B/render_test.log" | grep -v '^tracing')   # the progress line overwrites itself with \r
printf '%s\n' "$out"
pct=$(printf '%s\n' "$out" | sed -n 's/.*, \([0-9.]*\)% of pixels hit.*/\1/p')
size=$(wc -c < "$B/render_test.png" 2>/dev/null || echo 0)
echo "render_test.png: $size bytes, ${pct:-?}% of pixels hit"
check "render exits 0" $rc
[ -n "$pct" ] && awk "BEGIN { exit !($pct > 5) }"; check "render hits > 5% of pixels" $?
[ "$size" -gt 4000 ]; check "render_test.png is a real picture (> 4000 bytes)" $?

rm -f "$B/render_round.png"
"$B/render" -w 160 -h 160 --round -o "$B/render_round.png" > "$B/render_round.log" 2>&1; rc=$?
pct=$(tr '\r' '\n' < "$B/render_round.log" | sed -n 's/.*, \([0-9.]*\)% of pixels hit.*/\1/p')
echo "render_round.png (round curves): ${pct:-?}% of pixels hit"
check "render --round exits 0" $rc
[ -n "$pct" ] && awk "BEGIN { exit !($pct > 5) }"; check "render --round hits > 5% of pixels" $?

out=$("$B/groom" 2>&1); rc=$?
printf '%s\n' "$out"
check "groom: three groups in one BVH, each seen, before and after one moves" $rc

out=$("$B/embree_swap" 2>&1); rc=$?
printf '%s\n' "$out"
check "embree_swap agrees with Embree (hit/miss within 2%)" $rc

echo "$passed passed, $failed failed"
[ "$failed" = 0 ]
