#!/bin/sh
# make test's AArch64 tier: the library's NEON path, built with
# aarch64-linux-gnu-gcc (static) and run under qemu-aarch64. test_simd at
# AArch64's node width, 4 (NEON against plain C, bit for bit, every scene,
# layout, basis and moving hair; 32x32 rays a case, qemu being slow; the
# 8-wide nodes are in the compile matrix, not run, to keep make test short),
# test_reference, and hits_hash, whose hits and trees must equal this
# machine's 4-wide build's to the bit (the scenes come from a file that
# the native build writes). Closing line "N passed, M failed, K skipped".
# A machine without the cross compiler or qemu skips the tier, saying so;
# with HAIROBB_REQUIRE_CROSS=1 (CI: .ci/run) that is a failure.
# usage: sh tests/run_arm64.sh [build dir]
B=${1:-build}
A=$B/arm64
ARMCC=${ARMCC:-aarch64-linux-gnu-gcc}
FLAGS="-std=c99 -Wall -Wextra -pedantic -O2 -ffp-contract=off -I."
jobs=$(nproc 2>/dev/null || echo 2)

if ! command -v "$ARMCC" > /dev/null 2>&1 || ! command -v qemu-aarch64 > /dev/null 2>&1; then
    why="the AArch64 tier: $ARMCC or qemu-aarch64 is missing (sudo apt-get install gcc-aarch64-linux-gnu libc6-dev-arm64-cross qemu-user)"
    if [ "${HAIROBB_REQUIRE_CROSS:-0}" = 1 ]; then
        echo "FAIL $why (HAIROBB_REQUIRE_CROSS is set)"
        echo "0 passed, 1 failed, 0 skipped"
        exit 1
    fi
    echo "SKIP $why"
    echo "0 passed, 0 failed, 1 skipped"
    exit 0
fi
mkdir -p "$A" || exit 1
start=$(date +%s)

# the copies of simd_variant.c, then the programs
{
    echo "$ARMCC $FLAGS -DHAIROBB_NO_SIMD -DHAIROBB_NODE_WIDTH=4 -DVARIANT=trace_plain -c tests/simd_variant.c -o $A/simd_plain_w4.o"
    echo "$ARMCC $FLAGS -DHAIROBB_NODE_WIDTH=4 -DVARIANT=trace_neon -c tests/simd_variant.c -o $A/simd_neon_w4.o"
    echo "$ARMCC $FLAGS tests/test_reference.c -o $A/test_reference -static -lm -pthread"
    echo "$ARMCC $FLAGS tests/hits_hash.c -o $A/hits_hash -static -lm -pthread"
    echo "cc $FLAGS -DHAIROBB_NODE_WIDTH=4 tests/hits_hash.c -o $A/hits_hash_native_w4 -lm -pthread"
} | xargs -P "$jobs" -I{} sh -c "{} || echo 'build failed: {}'"
$ARMCC $FLAGS -DSIDE=32 tests/test_simd.c $A/simd_plain_w4.o $A/simd_neon_w4.o -o $A/test_simd -static -lm -pthread ||
    echo "build failed: test_simd"
echo "built with $("$ARMCC" --version | head -n 1) in $(($(date +%s) - start)) s; $(qemu-aarch64 --version | head -n 1)"

"$A/hits_hash_native_w4" --write "$A/scenes.bin" && "$A/hits_hash_native_w4" "$A/scenes.bin" > "$A/hits_native.txt"
PROGRAMS="test_simd test_reference"
for p in $PROGRAMS; do rm -f "$A/$p.out" "$A/$p.rc"; done
printf '%s\n' $PROGRAMS | xargs -P "$jobs" -I{} sh -c "qemu-aarch64 $A/{} > $A/{}.out 2>&1; echo \$? > $A/{}.rc"
qemu-aarch64 "$A/hits_hash" "$A/scenes.bin" > "$A/hits_arm64.txt" 2> /dev/null

passed=0; failed=0; skipped=0
for p in $PROGRAMS; do
    line=$(grep -E '^[0-9]+ passed, [0-9]+ failed' "$A/$p.out" 2> /dev/null | tail -n 1)
    rc=$(cat "$A/$p.rc" 2> /dev/null || echo "not run")
    grep -E '^(FAIL|SKIP) ' "$A/$p.out" 2> /dev/null | sed "s|^|$p (AArch64): |"
    if [ -z "$line" ] || [ "$rc" != 0 ]; then
        echo "FAIL $p under qemu-aarch64: exit $rc, ${line:-no summary line} ($A/$p.out)"
        failed=$((failed + 1))
        [ -z "$line" ] && continue
    else
        echo "ok: $p under qemu-aarch64: $line"
    fi
    n=${line%% passed*}; f=${line#*, }; f=${f%% failed*}
    case $line in *skipped*) s=${line##*, }; s=${s%% skipped*} ;; *) s=0 ;; esac
    passed=$((passed + n)); failed=$((failed + f)); skipped=$((skipped + s))
done
grep -h 'differ from plain C' "$A/test_simd.out" 2> /dev/null | head -n 3
cat "$A/hits_arm64.txt"
if [ -s "$A/hits_native.txt" ] && cmp -s "$A/hits_native.txt" "$A/hits_arm64.txt"; then
    echo "PASS hits_hash under qemu-aarch64 (NEON): the same trees and hits as this machine's 4-wide build ($(wc -l < "$A/hits_native.txt") scene and option sets)"
    passed=$((passed + 1))
else
    echo "FAIL hits_hash under qemu-aarch64 differs from this machine's 4-wide build:"
    diff "$A/hits_native.txt" "$A/hits_arm64.txt"
    failed=$((failed + 1))
fi
echo "AArch64 tier: $(($(date +%s) - start)) s"
echo "$passed passed, $failed failed, $skipped skipped"
[ "$failed" = 0 ]
