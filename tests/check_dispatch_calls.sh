#!/bin/sh
# The AVX2 copy of the kernels must not call the library's baseline code: a
# call from AVX2 code into SSE code made the pieces intersector and the
# shared-rotation nodes 2x slower (bench, 2026-12-01). Lists every call out
# of a *_avx2 function of the dispatch build into a hairobb__ function that
# is not *_avx2 (libm calls and the user's filter are allowed).
obj=${1:-build/simd_dispatch_w8.o}
if ! command -v objdump >/dev/null 2>&1; then echo "objdump missing"; echo "0 passed, 1 failed"; exit 1; fi
# a call's target: the symbol of its relocation, or the function it names
calls=$(objdump -dr --no-show-raw-insn "$obj" | awk '
    /^[0-9a-f]+ <.*>:$/ { f = ($2 ~ /_avx2>:$/) ? $2 : ""; pending = 0; next }
    f == "" { next }
    pending && /R_X86_64_/ { t = $NF; sub(/[-+]0x[0-9a-f]+$/, "", t); print f, "<" t ">"; pending = 0; next }
    pending { print f, target; pending = 0 }
    /call/ { target = $NF; if (target ~ /\+0x[0-9a-f]+>$/) pending = 1; else print f, target }')
call_count=$(printf '%s\n' "$calls" | awk 'NF' | wc -l)
bad=$(printf '%s\n' "$calls" | awk '$2 ~ /^<hairobb__/ && $2 !~ /_avx2(\.[a-z]+\.[0-9]+)*>$/' | sort -u)
avx2=$(objdump -d "$obj" | grep -c '_avx2>:$')
if ! objdump -d "$obj" | grep -Eq '<hairobb__traverse_avx2(\.[a-z]+\.[0-9]+)*>:$'; then
    echo "FAIL: $obj has no hairobb__traverse_avx2 (is it the dispatch build?)"; echo "0 passed, 1 failed"; exit 1
fi
if [ -n "$bad" ]; then
    echo "FAIL: AVX2 kernels call baseline code:"; printf '%s\n' "$bad"; echo "0 passed, 1 failed"; exit 1
fi
echo "$avx2 AVX2 kernel functions in $obj, $call_count calls out of them, none into baseline code"
echo "1 passed, 0 failed"
