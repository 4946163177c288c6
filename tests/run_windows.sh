#!/bin/sh
# make test's Windows tier: the quick tier's core programs (all but
# test_options, the longest, whose combinations the Linux run covers) and
# test_threads,
# built with mingw-w64 (x86-64, static: the library's Win32 threads, its
# AVX2 dispatch under mingw's gcc) and run under wine; and hits_hash, whose
# trees and hits must equal this machine's own build's to the bit (the
# scenes come from a file the native build writes). Closing line
# "N passed, M failed, K skipped", summed from the programs' own.
# A machine without x86_64-w64-mingw32-gcc or wine skips the tier, saying
# so; with HAIROBB_REQUIRE_CROSS=1 (CI: .ci/run) that is a failure.
# usage: sh tests/run_windows.sh [build dir]
B=${1:-build}
W=$B/windows
WINCC=${WINCC:-x86_64-w64-mingw32-gcc}
PROGRAMS="test_threads test_unit test_conservative test_save test_refit test_motion test_stress test_reference
          test_hair test_filter hits_hash"
FLAGS="-std=c99 -Wall -Wextra -pedantic -O2 -ffp-contract=off -I. -include tests/windows_port.h"
jobs=$(nproc 2>/dev/null || echo 2)
. tests/cross_tier.sh

if ! command -v "$WINCC" > /dev/null 2>&1 || ! command -v wine > /dev/null 2>&1; then
    tier_missing "the Windows tier: $WINCC or wine is missing (sudo apt-get install gcc-mingw-w64-x86-64 wine64)"
fi
mkdir -p "$W" || exit 1
start=$(date +%s)

# the programs, as many built at once as there are cores
printf '%s\n' $PROGRAMS | xargs -P "$jobs" -I{} sh -c \
    "$WINCC $FLAGS tests/{}.c -o $W/{}.exe -static -pthread -lm > $W/{}.build.log 2>&1 || echo 'build failed: {}'"
cc -std=c99 -O2 -ffp-contract=off -I. tests/hits_hash.c -o "$W/hits_hash_native" -lm -pthread || echo "build failed: hits_hash (native)"
echo "built with $("$WINCC" --version | head -n 1) in $(($(date +%s) - start)) s"

# wine's own prefix under the build directory: nothing written to $HOME
WINEPREFIX=$(cd "$W" && pwd)/wine-prefix
WINEDEBUG=-all
export WINEPREFIX WINEDEBUG
began=$(date +%s)
wine cmd /c exit > /dev/null 2>&1   # makes the prefix once, before the programs run at once
echo "wine $(wine --version 2>/dev/null): prefix ready in $(($(date +%s) - began)) s"

"$W/hits_hash_native" --write "$W/scenes.bin" && "$W/hits_hash_native" "$W/scenes.bin" > "$W/hits_native.txt"
for p in $PROGRAMS; do rm -f "$W/$p.out" "$W/$p.rc"; done
printf '%s\n' $PROGRAMS | grep -v hits_hash | xargs -P "$jobs" -I{} sh -c "wine $W/{}.exe > $W/{}.out 2>&1; echo \$? > $W/{}.rc"
wine "$W/hits_hash.exe" "$W/scenes.bin" 2> /dev/null | tr -d '\r' > "$W/hits_windows.txt"

for p in $PROGRAMS; do
    [ "$p" = hits_hash ] && continue
    tr -d '\r' < "$W/$p.out" > "$W/$p.txt" 2> /dev/null
    tier_count "$p.exe" wine "$W/$p.txt" "$W/$p.rc"
done
tier_same_hits "$W/hits_native.txt" "$W/hits_windows.txt" wine "this machine's build"
tier_end "Windows tier" "$start"
