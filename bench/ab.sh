#!/bin/sh
# make ab: the working tree's hairobb.h against another commit's, in one
# process (bench/ab.c).
# usage: sh bench/ab.sh BASE [ab options]   (BASE: a commit, default HEAD)
#   e.g. make ab AB_BASE=HEAD~3 AB="--scene combed,crossing:500k --rounds 21"
#   builds: make ab AB_BASE=main AB="--builds --scene combed,combed:2M --rounds 21"
set -e
base=${1:-HEAD}
[ $# -gt 0 ] && shift
B=build/ab
mkdir -p $B/base
# the base copy keeps its own file name: the header includes itself by it
git show "$base:hairobb.h" > $B/base/hairobb.h
FLAGS="-std=c99 -O2 -g -ffp-contract=off -I. ${CFLAGS_AB:-}"
${CC:-cc} $FLAGS -DAB_HEADER="\"$B/base/hairobb.h\"" -D'AB_NAME(x)=ab_base_##x' -c bench/ab_copy.c -o $B/base.o
${CC:-cc} $FLAGS -DAB_HEADER='"hairobb.h"' -D'AB_NAME(x)=ab_test_##x' -c bench/ab_copy.c -o $B/test.o
${CC:-cc} $FLAGS bench/ab.c $B/base.o $B/test.o -o $B/ab -lm -pthread
echo "base: $(git rev-parse --short "$base"), test: the working tree ($(git rev-parse --short HEAD)$(git diff --quiet HEAD -- hairobb.h || echo ', changed'))"
$B/ab "$@"
