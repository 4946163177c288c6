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
. tests/cross_tier.sh

if ! command -v "$ARMCC" > /dev/null 2>&1 || ! command -v qemu-aarch64 > /dev/null 2>&1; then
    tier_missing "the AArch64 tier: $ARMCC or qemu-aarch64 is missing (sudo apt-get install gcc-aarch64-linux-gnu libc6-dev-arm64-cross qemu-user)"
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

for p in $PROGRAMS; do
    tier_count "$p" qemu-aarch64 "$A/$p.out" "$A/$p.rc"
done
grep -h 'differ from plain C' "$A/test_simd.out" 2> /dev/null | head -n 3
tier_same_hits "$A/hits_native.txt" "$A/hits_arm64.txt" "qemu-aarch64 (NEON)" "this machine's 4-wide build"
tier_end "AArch64 tier" "$start"
