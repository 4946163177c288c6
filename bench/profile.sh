#!/bin/sh
# make profile: instructions per ray of hairobb and of Embree on the same
# rays, counted by callgrind (exact and repeatable, whatever else the machine
# is doing), split by where they go, with the nodes, leaves and segments a
# ray visits. Decide speed work from these counts; confirm in wall-clock
# time with the bench's rounds.
#
# usage: sh bench/profile.sh [bench options]
#   default: --scene combed --res 256 --variants default,embree-r4 (all ray kinds)
#   e.g. make profile PROFILE="--scene combed,straight --variants default,pieces8,embree-r4"
# Writes build/profile/: the dumps, the bench's outputs, and profile.md (the table).
B=build
out=$B/profile
set -e
sh bench/need_valgrind.sh profile
rm -rf "$out"
mkdir -p "$out"
# the defaults for what the caller leaves out (--scene adds scenes: given twice, one would run twice)
args="--profile --quiet --accuracy-rays 0"
case " $* " in *" --scene"*) ;; *) args="$args --scene combed" ;; esac
case " $* " in *" --res"*) ;; *) args="$args --res 256" ;; esac
case " $* " in *" --variants"*) ;; *) args="$args --variants default,embree-r4" ;; esac
args="$args $*"
# the baseline build, not position-independent so that the dumps' addresses
# are the binary's own (valgrind runs no AVX-512; the dispatch picks AVX2, as
# Embree does under it)
valgrind --tool=callgrind --collect-atstart=no --dump-instr=yes --compress-strings=no --compress-pos=no \
    --callgrind-out-file="$out/callgrind.out" $B/bench_profile $args > "$out/bench.txt" 2> "$out/valgrind.txt"
$B/bench_counted $args > "$out/counts.txt"
dumps=$(ls "$out"/callgrind.out.* | sort -t. -k3 -n)
# each address of the bench binary, with the functions it was inlined from
awk '/^ob=/ { mine = index($0, "bench_profile") > 0 } /^calls=/ { getline; next } mine && /^0x/ { print $1 }' $dumps |
    sort -u | addr2line -a -i -f -e $B/bench_profile > "$out/chains.txt"
head -n 4 "$out/bench.txt"
# each scene's line: its segments, strands and their order (procedural scenes: groom unless --strand-order)
grep -A1 '^=== scene' "$out/bench.txt" | grep -v '^--$'
echo "callgrind: instructions per ray, 1 thread, the same rays for every variant ($out/profile.md)"
awk -f bench/profile.awk "$out/counts.txt" "$out/chains.txt" $dumps | tee "$out/profile.md"
