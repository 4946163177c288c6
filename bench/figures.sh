#!/bin/sh
# figures.sh - `make figures`: the run behind the figures the docs quote.
#
#   sh bench/figures.sh               runs the bench (about 16 minutes on 2 cores), saves
#                                     its output as bench/results/figures-YYYY-MM-DD.txt (UTC),
#                                     then writes the pages' generated regions from that file
#   sh bench/figures.sh --from FILE   writes the pages from a stored run (seconds, no bench)
#   FIGURES_QUICK=1 sh bench/figures.sh
#                                     a smoke test of this script: small scenes, one round; the
#                                     run and copies of the pages go to build/figures/quick/,
#                                     the pages themselves are not touched
#
# The run is three invocations of build/bench (below): the trace-speed target
# scenes against Embree (and their memory), round curves against Embree's
# (and accuracy against the exact references), and build time in rounds. Each
# writes its TSV; the results file holds a header (commit, machine, compiler,
# Embree, load, duration, commands), each invocation's output and its TSV, so
# that `--from` rebuilds the pages from the committed file alone.
#
# The pages: in README.md and docs/benchmarking.md, a generated region is
#   <!-- figures:NAME -->
#   ...
#   <!-- /figures -->
# and only what lies between the two lines is replaced, by the fragment NAME
# that bench/figures.awk writes (run, trace-speed, memory, round, accuracy,
# build; glance for the README). Edit the text around a region, never inside.
#
# POSIX sh and awk (Debian's dash and mawk), git, and build/bench (make bench's
# dependencies); nothing else.
set -eu
cd "$(dirname "$0")/.."

BENCH=build/bench
WORK=build/figures
RESULTS=bench/results
PAGES="README.md docs/benchmarking.md"

# What the docs quote: the target scenes (combed fur at three sizes, the two
# files, curly and crossing hair), each library's defaults and peers. Rounds
# and resolution keep the whole run near 16 minutes on 2 cores (Zen 5): the
# trace run about 5 (most of it making and building combed 10M), the round
# curves about 4, the builds about 8 (combed 10M's three builds take 40 s a
# round). At 11, 11 and 7 rounds it took 11.5 minutes.
TARGETS=combed,combed:2M,combed:10M,furball,straight,curly:500k,crossing:500k
ROUND_SCENES=combed,combed:2M,furball,straight,curly:500k,crossing:500k
TRACE_ROUNDS=21 ROUND_ROUNDS=21 BUILD_ROUNDS=11 RES=512 ACCURACY=16384
OUT_DIR=$RESULTS
if [ "${FIGURES_QUICK:-}" = 1 ]; then
    TARGETS=combed:20k,crossing:20k ROUND_SCENES=combed:20k,crossing:20k
    TRACE_ROUNDS=1 ROUND_ROUNDS=1 BUILD_ROUNDS=1 RES=64 ACCURACY=1024
    OUT_DIR=$WORK/quick
fi
CMD_TRACE="$BENCH --scene $TARGETS --variants default,no-copy,embree-r4,embree-compact,embree-avx2 --threads 1,2 --rounds $TRACE_ROUNDS --res $RES --accuracy-rays 0 --quiet --tsv $WORK/trace.tsv"
CMD_ROUND="$BENCH --scene $ROUND_SCENES --variants tubes --threads 1,2 --rounds $ROUND_ROUNDS --res $RES --accuracy-rays $ACCURACY --quiet --tsv $WORK/round.tsv --png $WORK/round.png"
CMD_BUILDS="$BENCH --builds --scene $TARGETS --rounds $BUILD_ROUNDS --quiet --tsv $WORK/builds.tsv"

die() { echo "figures: $*" >&2; exit 1; }

# "MODEL (family F, model M), N cores, AVX-512: yes|no", from /proc/cpuinfo
machine() {
    awk -F: -v cores="$(getconf _NPROCESSORS_ONLN 2>/dev/null || echo '?')" '
        function trim(s) { sub(/^[ \t]+/, "", s); sub(/[ \t]+$/, "", s); return s }
        $1 ~ /^model name/ && name == "" { name = trim($2) }
        $1 ~ /^cpu family/ && family == "" { family = trim($2) }
        $1 ~ /^model[ \t]*$/ && model == "" { model = trim($2) }
        $1 ~ /^flags/ && avx512 == "" { avx512 = ($2 ~ /(^| )avx512f( |$)/) ? "yes" : "no" }
        END { if (name == "") name = "unknown CPU"
              printf "%s (family %s, model %s), %s cores, AVX-512: %s\n", name, family, model, cores,
                     avx512 == "" ? "unknown" : avx512 }' /proc/cpuinfo 2>/dev/null || echo "unknown machine"
}

loadavg() { cut -d' ' -f1-3 /proc/loadavg 2>/dev/null || echo unknown; }

# the other benchmark jobs on the machine (they skew the timings)
other_jobs() {
    if command -v pgrep >/dev/null 2>&1; then
        jobs=$(pgrep -f 'build/bench|valgrind' | grep -v "^$$\$" | tr '\n' ' ')
        [ -n "$jobs" ] && echo "pids $jobs" || echo none
    else
        echo "unknown (no pgrep)"
    fi
}

# ---- the run -----------------------------------------------------------------

run() {
    [ -x "$BENCH" ] || make "$BENCH" || die "cannot build $BENCH"
    mkdir -p "$WORK" "$OUT_DIR"
    if command -v git >/dev/null 2>&1 && git rev-parse --short HEAD >/dev/null 2>&1; then
        commit=$(git rev-parse --short HEAD)
        [ -z "$(git status --porcelain)" ] || commit="$commit-dirty"
    else
        commit=unknown
    fi
    start=$(date -u +%s)
    date=$(date -u '+%Y-%m-%d %H:%M UTC')
    file="$OUT_DIR/figures-$(date -u +%Y-%m-%d).txt"
    load_before=$(loadavg)
    others=$(other_jobs)
    body="$WORK/body.txt"
    : > "$body"
    for name in trace round builds; do
        case $name in
            trace) cmd=$CMD_TRACE ;;
            round) cmd=$CMD_ROUND ;;
            builds) cmd=$CMD_BUILDS ;;
        esac
        echo "figures: $cmd" >&2
        rm -f "$WORK/$name.tsv"
        echo "::figures:: run $name: $cmd" >> "$body"
        # the commands hold no quoting: split on spaces
        $cmd >> "$body" 2>&1 || die "'$cmd' failed (its output: $body)"
        [ -s "$WORK/$name.tsv" ] || die "'$cmd' wrote no $WORK/$name.tsv"
        echo "::figures:: tsv $name" >> "$body"
        cat "$WORK/$name.tsv" >> "$body"
    done
    seconds=$(( $(date -u +%s) - start ))
    # "gcc 12.2.0 with `FLAGS`; hairobb runs its AVX2 kernels (built: SSE2 AVX2)", or the line as printed
    compiler=$(sed -n -e 's/^compiler: \(.*\), flags: \(.*[^ ]\) *, SIMD: \([^ ]*\) (paths: \(.*\))$/\1 with `\2`; hairobb runs its \3 kernels (built: \4)/p' \
                      -e 't' -e 's/^compiler: //p' "$body" | head -n 1)
    embree=$(sed -n 's/^hairobb [0-9.]*, Embree \([^;]*\);.*/\1/p' "$body" | head -n 1)
    {
        echo "# make figures (bench/figures.sh): the runs behind the generated tables of docs/benchmarking.md and README.md"
        echo "# commit: $commit"
        echo "# date: $date"
        echo "# machine: $(machine)"
        echo "# compiler: ${compiler:-unknown}"
        echo "# embree: ${embree:-unknown}"
        echo "# load: $load_before before the run (1, 5, 15 min), $(loadavg) after it; each command's own line below gives it before that command"
        echo "# other benchmark jobs at the start: $others"
        echo "# duration: $((seconds / 60)) min $((seconds % 60)) s"
        echo "# command trace: $CMD_TRACE"
        echo "# command round: $CMD_ROUND"
        echo "# command builds: $CMD_BUILDS"
        cat "$body"
        echo "::figures:: end"
    } > "$file"
    echo "figures: $file ($((seconds / 60)) min $((seconds % 60)) s)" >&2
    generate "$file"
}

# ---- the pages ---------------------------------------------------------------

# generate FILE: the fragments from FILE's TSVs, then each page's regions
generate() {
    file=$1
    [ -r "$file" ] || die "cannot read $file"
    gen="$WORK/gen"
    rm -rf "$gen"
    mkdir -p "$gen"
    field() { sed -n "s/^# $1: //p" "$file" | head -n 1; }
    for name in trace round builds; do
        awk -v name="$name" '$0 == "::figures:: tsv " name { on = 1; next } /^::figures:: / { on = 0 } on' \
            "$file" > "$gen/$name.tsv"
        [ -s "$gen/$name.tsv" ] || die "$file holds no TSV of the $name run"
    done
    awk -f bench/figures.awk -v out="$gen" -v file="$file" -v commit="$(field commit)" -v date="$(field date)" \
        -v machine="$(field machine)" -v compiler="$(field compiler)" -v embree="$(field embree)" \
        -v duration="$(field duration)" -v cmd_trace="$(field 'command trace')" \
        -v cmd_round="$(field 'command round')" -v cmd_builds="$(field 'command builds')" \
        kind=trace "$gen/trace.tsv" kind=round "$gen/round.tsv" kind=builds "$gen/builds.tsv"
    for page in $PAGES; do
        target=$page
        if [ "${FIGURES_QUICK:-}" = 1 ]; then
            target="$WORK/quick/$page"
            mkdir -p "$(dirname "$target")"
        fi
        awk -v dir="$gen" -v page="$page" '
            function fail(message) { print "figures: " page ":" FNR ": " message > "/dev/stderr"; failed = 1; exit 1 }
            /^<!-- figures:[a-z-]+ -->$/ {
                if (inside) fail("a region opens inside another")
                print
                name = $0; sub(/^<!-- figures:/, "", name); sub(/ -->$/, "", name)
                fragment = dir "/" name ".md"
                if ((getline line < fragment) <= 0) fail("no generated figures named " name)
                do print line; while ((getline line < fragment) > 0)
                close(fragment)
                inside = 1; regions++
                next
            }
            /^<!-- \/figures -->$/ { if (!inside) fail("a region closes that was not opened"); inside = 0; print; next }
            !inside { print }
            END { if (failed) exit 1
                  if (inside) fail("a region is not closed")
                  printf "figures: %s: %d region%s\n", page, regions, regions == 1 ? "" : "s" > "/dev/stderr" }
        ' "$page" > "$WORK/page.tmp" || die "$page left as it was"
        mv "$WORK/page.tmp" "$target"
    done
}

case "${1:-}" in
    "") run ;;
    --from) [ $# -eq 2 ] || die "usage: sh bench/figures.sh [--from FILE]"; generate "$2" ;;
    *) die "usage: sh bench/figures.sh [--from FILE]" ;;
esac
