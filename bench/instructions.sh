#!/bin/sh
# make instructions: hairobb's instructions a ray on bench/instructions.c's
# scene and rays (combed 200k, 128x128 camera rays, 1 thread), ribbons and
# round curves, counted by callgrind: exact and repeatable whatever else the
# machine runs, so two versions compare by a difference of a few
# instructions. The dumps stay in build/instructions.SHAPE.out
# (callgrind_annotate reads them). make profile is the fuller split.
set -e
B=build
sh bench/need_valgrind.sh instructions
for shape in ribbon round; do
    valgrind --tool=callgrind --callgrind-out-file=$B/instructions.$shape.out "--toggle-collect=trace_rays*" \
        $B/instructions $shape > $B/instructions.$shape.txt 2> $B/instructions.$shape.log
    collected=$(sed -n 's/.*Collected : \([0-9]*\).*/\1/p' $B/instructions.$shape.log)
    rays=$(sed -n 's/.*: \([0-9]*\) rays.*/\1/p' $B/instructions.$shape.txt)
    awk -v collected="$collected" -v rays="$rays" -v shape="$shape" \
        'BEGIN { printf "%s: %.1f instructions a ray (%d rays)\n", shape, collected / rays, rays }'
done
