#!/bin/sh
# The AVX2 copy of the kernels (>>dispatch) renames, by one #define each,
# every name the kernel region defines. A name missing from the list is a
# redefinition error at compile time; this check also finds the names the
# list keeps that nothing defines any more, and says which either way.
# The kernel region: from "#endif /* !HAIROBB__KERNEL_PASS */" (after >>rays)
# to the next "#ifndef HAIROBB__KERNEL_PASS" (before >>tracing_api). The
# NEON branch's own helpers (hairobb__v4_mask_bits) are left out: the AVX2
# copy is x86's, where that branch is not compiled.
header=${1:-hairobb.h}
tmp=${TMPDIR:-/tmp}/check_dispatch_list.$$
trap 'rm -f "$tmp".*' EXIT
awk '
    /^#endif \/\* !HAIROBB__KERNEL_PASS \*\// && !started { inside = 1; started = 1; next }
    inside && /^#ifndef HAIROBB__KERNEL_PASS/ { inside = 0 }
    !inside { next }
    # a function defined or declared at file scope
    /^(static|HAIROBB__INLINE|HAIROBB__NOINLINE|HAIROBB__COLD|HAIROBB__TARGET_AVX2)/ {
        line = $0
        if (match(line, /hairobb__[a-z0-9_]+\(/)) print substr(line, RSTART, RLENGTH - 1)
    }
    # a type: "typedef struct hairobb__x {", "} hairobb__x;", "typedef T hairobb__x;"
    /^typedef struct hairobb__[a-z0-9_]+/ { match($0, /hairobb__[a-z0-9_]+/); print substr($0, RSTART, RLENGTH) }
    /^} hairobb__[a-z0-9_]+;/ { match($0, /hairobb__[a-z0-9_]+/); print substr($0, RSTART, RLENGTH) }
    /^typedef [^(]* hairobb__[a-z0-9_]+;/ { n = split($0, w, /[ ;]/); for (i = n; i > 0; --i) if (w[i] ~ /^hairobb__/) { print w[i]; break } }
' "$header" | sort -u | grep -vx -e hairobb__v4_mask_bits > "$tmp.defined"
awk '/^#define hairobb__[a-z0-9_]+ hairobb__[a-z0-9_]+_avx2$/ { print $2 }' "$header" | sort > "$tmp.listed"
sort -u "$tmp.listed" > "$tmp.listed_unique"
defined=$(wc -l < "$tmp.defined")
missing=$(comm -23 "$tmp.defined" "$tmp.listed_unique")
stale=$(comm -13 "$tmp.defined" "$tmp.listed_unique")
twice=$(uniq -d "$tmp.listed")
if [ "$defined" -lt 50 ]; then
    echo "FAIL: found only $defined names in the kernel region of $header (has its layout changed?)"
    echo "0 passed, 1 failed"; exit 1
fi
fail=0
if [ -n "$missing" ]; then echo "FAIL: defined in the kernels but not renamed for AVX2:"; printf '  %s\n' $missing; fail=1; fi
if [ -n "$stale" ]; then echo "FAIL: renamed for AVX2 but defined nowhere in the kernels:"; printf '  %s\n' $stale; fail=1; fi
if [ -n "$twice" ]; then echo "FAIL: renamed twice:"; printf '  %s\n' $twice; fail=1; fi
if [ $fail = 1 ]; then echo "0 passed, 1 failed"; exit 1; fi
echo "$defined names defined in the kernel region, each renamed once for the AVX2 copy, none renamed in vain"
echo "1 passed, 0 failed"
