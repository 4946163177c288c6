# cross_tier.sh - what the Windows and AArch64 tiers share (sourced by
# tests/run_windows.sh and tests/run_arm64.sh): the skip when their tools
# are missing, the sum of their programs' counts, the comparison of
# hits_hash with this machine's build, and the closing line.
passed=0; failed=0; skipped=0

# tier_missing WHY: the tier's tools are missing; a failure where
# HAIROBB_REQUIRE_CROSS=1 (CI), else a skip. Exits.
tier_missing() {
    if [ "${HAIROBB_REQUIRE_CROSS:-0}" = 1 ]; then
        echo "FAIL $1 (HAIROBB_REQUIRE_CROSS is set)"
        echo "0 passed, 1 failed, 0 skipped"
        exit 1
    fi
    echo "SKIP $1"
    echo "0 passed, 0 failed, 1 skipped"
    exit 0
}

# tier_count PROGRAM RUNNER OUTPUT STATUS: one program's counts (its line
# "N passed, M failed[, K skipped]") added to the tier's; no such line, or
# an exit status other than 0, is a failure.
tier_count() {
    line=$(grep -E '^[0-9]+ passed, [0-9]+ failed' "$3" 2> /dev/null | tail -n 1)
    rc=$(cat "$4" 2> /dev/null || echo "not run")
    grep -E '^(FAIL|SKIP) ' "$3" 2> /dev/null | sed "s|^|$1 ($2): |"
    if [ -z "$line" ] || [ "$rc" != 0 ]; then
        echo "FAIL $1 under $2: exit $rc, ${line:-no summary line} ($3)"
        failed=$((failed + 1))
        [ -z "$line" ] && return
    else
        echo "ok: $1 under $2: $line"
    fi
    n=${line%% passed*}; f=${line#*, }; f=${f%% failed*}
    case $line in *skipped*) s=${line##*, }; s=${s%% skipped*} ;; *) s=0 ;; esac
    passed=$((passed + n)); failed=$((failed + f)); skipped=$((skipped + s))
}

# tier_same_hits NATIVE OTHER RUNNER WHAT: hits_hash's lines must be the
# same from both builds.
tier_same_hits() {
    cat "$2"
    if [ -s "$1" ] && cmp -s "$1" "$2"; then
        echo "PASS hits_hash under $3: the same trees and hits as $4 ($(wc -l < "$1") scene and option sets)"
        passed=$((passed + 1))
    else
        echo "FAIL hits_hash under $3 differs from $4:"
        diff "$1" "$2"
        failed=$((failed + 1))
    fi
}

# tier_end NAME START: the closing lines; the exit status.
tier_end() {
    echo "$1: $(($(date +%s) - $2)) s"
    echo "$passed passed, $failed failed, $skipped skipped"
    [ "$failed" = 0 ]
}
