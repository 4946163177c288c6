# hairobb: `make test` runs every test, `make check` the quick tier (a C99
# compiler only: no Embree, clang, sanitizers or apt-get), `make bench` the
# benchmark on the built-in fur scene, `make figures` the runs behind
# the docs' figures, `make examples` builds the examples.
# the test programs build on every core, and run as many at once (tests/run_all.sh)
MAKEFLAGS += -j$(shell nproc 2>/dev/null || echo 2)
CC       ?= cc
# target flags: none by default, as a renderer's default build has it (the
# x86-64 baseline, with the AVX2 kernels picked at run time); e.g.
# ARCH=-march=native compiles everything for this CPU
ARCH     ?=
# no FMA contraction: the SIMD and plain C paths must round identically
CFLAGS   ?= -O2 -g
WARN      = -std=c99 -Wall -Wextra -pedantic
BASE      = $(WARN) $(CFLAGS) -ffp-contract=off -I.
LIBS      = -lm -pthread
EMBREE    = -lembree3
B         = build

# The quick tier (`make check`): a C99 compiler and make, nothing else.
# test_secondary is built there without its Embree comparison, and test_simd
# (SSE4.1 and AVX2 builds) only where the compiler targets x86.
X86    := $(filter x86_64% i386% i486% i586% i686% amd64%,$(shell $(CC) -dumpmachine 2>/dev/null))
QUICK  = $(B)/test_options $(B)/test_conservative $(if $(X86),$(B)/test_simd $(B)/test_simd_w8) $(B)/test_unit \
         $(B)/test_unit_w8 $(B)/test_stress $(B)/test_reference $(B)/test_hair $(B)/test_filter $(B)/test_refit $(B)/test_refit_w4 \
         $(B)/test_save $(B)/test_motion $(B)/test_instances $(B)/test_groups
CHECK_TESTS = $(QUICK) $(B)/check_test_secondary
# `make test`: the quick tier's programs and those needing Embree (and furBall_A)
TESTS = $(QUICK) $(B)/test_secondary $(B)/test_accuracy $(B)/test_far $(B)/test_scenes $(B)/test_threads $(B)/test_bases $(B)/test_round
# the same tests again under AddressSanitizer + UndefinedBehaviorSanitizer
# (any report aborts the test), the threads test under ThreadSanitizer, and
# the fuzzers (clang); named first, as the longest, since the tests run two
# at a time on 2 cores
SANITIZED = $(B)/fuzz_build_45s $(B)/asan_test_options $(B)/fuzz_scene_30s $(B)/fuzz_groups_30s $(B)/fuzz_hair_30s $(B)/fuzz_load_30s \
            $(B)/asan_test_round $(B)/asan_test_unit_w8 \
            $(B)/asan_test_stress $(B)/tsan_test_threads $(B)/asan_test_reference $(B)/asan_test_save_w4 $(B)/asan_test_instances \
            $(B)/asan_test_groups
ASAN      = -O1 -g -fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer
TSAN      = -O1 -g -fsanitize=thread
# libFuzzer targets (clang): 30-45 s in `make test`, `make fuzz` for a long run
FUZZCC    = clang
FUZZ      = -std=c99 -O1 -g -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=all -ffp-contract=off -I.
FUZZ_SECONDS ?= 1800

.PHONY: all test check deps compile-matrix bench profile instructions ab examples clean fuzz tree-hashes figures
all: $(TESTS) $(SANITIZED) $(B)/bench examples

deps:
	@sh tests/install_deps.sh

$(B):
	@mkdir -p $(B)

# ---- Test programs ---------------------------------------------------------
# What each checks (the comment at the top of its source says more):
#   test_reference     the double-precision reference intersectors themselves
#                      (the ribbon's, and the tube's: tests/ref_tube.h)
#   test_unit          white-box: frames, hair space, node bounds, traversal,
#                      bad input, failing allocations, cancelling
#   test_options       every combination of build options against the reference
#   test_conservative  traversal conservativeness: an instrumented header
#                      records the leaves reached
#   test_stress        numerical stress: radii, degenerate segments, hard rays, joints
#   test_refit         a tree built on one pose refitted to others, against
#                      fresh builds and the reference
#   test_motion        motion blur: moving fur at random ray times against the
#                      reference, errors, refit, save/load
#   test_filter        the any-hit filter against the reference
#   test_save          BVHs saved and loaded: round trips traced to the bit, bad
#                      bytes, other hair
#   test_instances     instances of BVHs under a top level against the
#                      references over the hair placed in world space
#   test_groups        several hair groups in one BVH against one BVH over
#                      the same hair: ids, masks, filters, refit, motion
#   test_hair          the .hair reader against the tests' own, bad files, a BVH
#                      from a loaded file
#   test_simd          the tracing code compiled four ways (below), to the bit
#   test_threads       builds on 1 and 4 threads equal, 4 threads tracing one BVH
#   test_secondary     secondary rays leaving a hit: the self-intersection rule,
#                      contact shadows
#   test_accuracy      t and hit/miss against the reference and Embree
#   test_far           hair far from the origin
#   test_bases         curve bases against Embree's flat curves of each basis
#                      and the reference
#   test_scenes        the tests' scenes, .hair loader and Embree wrapper
#   test_round         round curves: the tube reference (tests/ref_tube.h)
#                      against Embree's round curves on the same rays
# A second build of one source is named by what differs: _w4/_w8 the node
# width, check_ without Embree (make check), asan_/tsan_ under a sanitizer.
# Every test program depends on the header and every shared test header;
# its flags beyond the build's own are TEST_FLAGS_<name>.
TEST_HEADERS = hairobb.h tests/check.h tests/compare.h tests/random.h tests/test_alloc.h tests/test_data.h tests/scratch.h \
               tests/reference.h tests/ref_tube.h tests/ref_bases.h tests/scenes.h tests/embree_wrap.h
TEST_FLAGS_test_unit            = -DHAIROBB_NODE_WIDTH=4
TEST_FLAGS_test_unit_w8         = -DHAIROBB_NODE_WIDTH=8
TEST_FLAGS_test_refit           = -DHAIROBB_NODE_WIDTH=8
TEST_FLAGS_test_refit_w4        = -DHAIROBB_NODE_WIDTH=4
TEST_FLAGS_check_test_secondary = -DTESTS_NO_EMBREE
TEST_FLAGS_asan_test_unit_w8    = -DHAIROBB_NODE_WIDTH=8
TEST_FLAGS_asan_test_options    = -DCROSSED_RAYS=1024
# 4-wide (test_save runs 8-wide), one scene's round trips: the loader's bounds under ASan
TEST_FLAGS_asan_test_save_w4    = -DHAIROBB_NODE_WIDTH=4 -DSAVE_SCENES=1
TEST_CC = $(CC) $(BASE) $(ARCH) $(TEST_FLAGS_$(@F)) $(filter %.c %.o,$^) -o $@

# build/test_NAME from tests/test_NAME.c; a second build from the source named
$(B)/test_%: tests/test_%.c $(TEST_HEADERS) | $(B)
	$(TEST_CC) $(LIBS)
$(B)/test_unit_w8 $(B)/test_refit_w4 $(B)/test_simd_w8 $(B)/check_test_secondary: $(TEST_HEADERS) | $(B)
	$(TEST_CC) $(LIBS)
$(B)/test_unit_w8 $(B)/asan_test_unit_w8: tests/test_unit.c
$(B)/test_refit_w4: tests/test_refit.c
$(B)/test_simd_w8: tests/test_simd.c
$(B)/check_test_secondary: tests/test_secondary.c
# those comparing with Embree
$(B)/test_secondary $(B)/test_accuracy $(B)/test_far $(B)/test_bases $(B)/test_scenes $(B)/test_round: $(B)/%: tests/%.c $(TEST_HEADERS) | $(B) deps
	$(TEST_CC) $(EMBREE) $(LIBS)

# under AddressSanitizer + UndefinedBehaviorSanitizer, and ThreadSanitizer:
# -O1 and the sanitizer in place of CFLAGS
$(B)/asan_%: $(TEST_HEADERS) | $(B)
	$(CC) $(WARN) $(ASAN) -ffp-contract=off -I. $(ARCH) $(TEST_FLAGS_$(@F)) $(filter %.c,$^) -o $@ $(if $(filter %round,$@),$(EMBREE)) $(LIBS)
$(B)/tsan_%: $(TEST_HEADERS) | $(B)
	$(CC) $(WARN) $(TSAN) -ffp-contract=off -I. $(ARCH) $(filter %.c,$^) -o $@ $(LIBS)
$(B)/asan_test_reference: tests/test_reference.c
$(B)/asan_test_instances: tests/test_instances.c
$(B)/asan_test_groups: tests/test_groups.c
# round curves' stress and degenerate segments (and their Embree comparison)
$(B)/asan_test_round: tests/test_round.c | deps
$(B)/asan_test_options: tests/test_options.c
$(B)/asan_test_stress: tests/test_stress.c
$(B)/asan_test_save_w4: tests/test_save.c
$(B)/tsan_test_threads: tests/test_threads.c

# the same tracing code compiled four ways (plain C, SSE4.1, AVX2, and the
# x86-64 baseline that dispatches to AVX2 at run time) for each node width:
# simd_<path>_w<width>.o, the width fixed so the trees match
SIMD_FLAGS_plain    = -DHAIROBB_NO_SIMD
SIMD_FLAGS_sse      = -msse4.1 -mno-avx
SIMD_FLAGS_avx      = -mavx2
SIMD_FLAGS_dispatch =
simd_path  = $(word 1,$(subst _, ,$*))
simd_width = $(subst w,,$(word 2,$(subst _, ,$*)))
.PRECIOUS: $(B)/simd_%.o
$(B)/simd_%.o: tests/simd_variant.c tests/simd_variant.h hairobb.h | $(B)
	$(CC) $(BASE) $(SIMD_FLAGS_$(simd_path)) -DHAIROBB_NODE_WIDTH=$(simd_width) -DVARIANT=trace_$(simd_path) -c $< -o $@
$(B)/test_simd: $(B)/simd_plain_w4.o $(B)/simd_sse_w4.o $(B)/simd_avx_w4.o $(B)/simd_dispatch_w4.o
$(B)/test_simd_w8: $(B)/simd_plain_w8.o $(B)/simd_sse_w8.o $(B)/simd_avx_w8.o $(B)/simd_dispatch_w8.o

# libFuzzer targets (tests/fuzz/, clang): `make test` runs each for some
# seconds over its seeds (tests/fuzz/corpus/), `make fuzz` for a long run
$(B)/fuzz_%: tests/fuzz/fuzz_%.c tests/fuzz/fuzz_checks.h hairobb.h | $(B) deps
	$(FUZZCC) $(FUZZ) $< -o $@ $(LIBS)
# saved BVHs, checksum fixed up, loaded over a fixed scene (scenes.h)
$(B)/fuzz_load: tests/scenes.h tests/random.h
# hair, tubes, paths, filters, refit, save and load; scenes of instances
$(B)/fuzz_build $(B)/fuzz_scene: tests/fuzz/fuzz_input.h
# a script running fuzzer $< over corpus $(1) for $(2) seconds
fuzz_script = @printf '\#!/bin/sh\nexec sh tests/fuzz/fuzz_run.sh $< tests/fuzz/corpus/$(1) $(2)\n' > $@ && chmod +x $@
$(B)/fuzz_build_45s: $(B)/fuzz_build tests/fuzz/fuzz_run.sh
	$(call fuzz_script,bvh_build,45)
$(B)/fuzz_scene_30s: $(B)/fuzz_scene tests/fuzz/fuzz_run.sh
	$(call fuzz_script,scene,30)
$(B)/fuzz_groups_30s: $(B)/fuzz_groups tests/fuzz/fuzz_run.sh
	$(call fuzz_script,groups,30)
$(B)/fuzz_hair_30s: $(B)/fuzz_hair tests/fuzz/fuzz_run.sh
	$(call fuzz_script,hair_read,30)
$(B)/fuzz_load_30s: $(B)/fuzz_load tests/fuzz/fuzz_run.sh
	$(call fuzz_script,bvh_load,30)
# long runs: FUZZ_SECONDS each
fuzz: $(B)/fuzz_build $(B)/fuzz_scene $(B)/fuzz_groups $(B)/fuzz_hair $(B)/fuzz_load
	sh tests/fuzz/fuzz_run.sh $(B)/fuzz_build tests/fuzz/corpus/bvh_build $(FUZZ_SECONDS)
	sh tests/fuzz/fuzz_run.sh $(B)/fuzz_scene tests/fuzz/corpus/scene $(FUZZ_SECONDS)
	sh tests/fuzz/fuzz_run.sh $(B)/fuzz_groups tests/fuzz/corpus/groups $(FUZZ_SECONDS)
	sh tests/fuzz/fuzz_run.sh $(B)/fuzz_hair tests/fuzz/corpus/hair_read $(FUZZ_SECONDS)
	sh tests/fuzz/fuzz_run.sh $(B)/fuzz_load tests/fuzz/corpus/bvh_load $(FUZZ_SECONDS)

# the bench, and its two builds for `make profile` (below)
BENCH_FLAGS_bench         = -DBENCH_CFLAGS='"$(BASE) $(ARCH)"'
BENCH_FLAGS_bench_counted = -DBENCH_COUNTS
BENCH_FLAGS_bench_profile = -fno-pie -no-pie
# (its parts: bench/bench.h; hairobb's implementation is in bench/harness.c;
# what it shares with the tests: BENCH_TEST_HEADERS)
BENCH_SOURCES = bench/bench.c bench/options.c bench/variants.c bench/memory.c bench/scenes.c bench/layout.c bench/harness.c \
                bench/accuracy.c bench/report.c bench/tsv_chart.c bench/mode_scenes.c bench/mode_builds.c \
                bench/mode_motion.c bench/mode_animate.c bench/mode_save_load.c bench/mode_groups.c bench/progress.c
BENCH_TEST_HEADERS = tests/compare.h tests/embree_wrap.h tests/random.h tests/reference.h tests/ref_tube.h tests/scenes.h \
                     tests/test_alloc.h tests/test_data.h
$(B)/bench $(B)/bench_counted $(B)/bench_profile: $(BENCH_SOURCES) bench/bench.h hairobb.h $(BENCH_TEST_HEADERS) | $(B) deps
	$(CC) $(BASE) $(ARCH) $(BENCH_FLAGS_$(@F)) $(BENCH_SOURCES) -o $@ $(EMBREE) -lpthread $(LIBS)

# Same trees: a hash of each tree (scenes x option sets x 1 and 2 build
# threads, bench/tree_hash.c) from the default 8-wide build, 4-wide and plain
# C; `make tree-hashes` writes them to build/tree-hashes.txt (diff it against
# bench/results/tree-hashes-*.txt). --memory: peak transient build bytes.
TREE_HASH_FLAGS_tree_hash       =
TREE_HASH_FLAGS_tree_hash_w4    = -DHAIROBB_NODE_WIDTH=4
TREE_HASH_FLAGS_tree_hash_plain = -DHAIROBB_NO_SIMD
$(B)/tree_hash $(B)/tree_hash_w4 $(B)/tree_hash_plain: bench/tree_hash.c hairobb.h tests/compare.h tests/random.h tests/scenes.h \
                                                     tests/test_alloc.h tests/test_data.h | $(B)
	$(CC) $(BASE) $(ARCH) $(TREE_HASH_FLAGS_$(@F)) $< -o $@ $(LIBS)
# instructions a ray of moving hair under callgrind (bench/motion_cost.c)
$(B)/motion_cost: bench/motion_cost.c hairobb.h tests/random.h tests/scenes.h | $(B)
	$(CC) $(BASE) $< -o $@ $(LIBS)
tree-hashes: $(B)/tree_hash $(B)/tree_hash_w4 $(B)/tree_hash_plain
	@for p in tree_hash tree_hash_w4 tree_hash_plain; do echo "== $$p"; $(B)/$$p || exit 1; done > $(B)/tree-hashes.txt
	@echo "tree hashes: $(B)/tree-hashes.txt"

# The header must compile clean as users compile it: gcc and clang, C99 and
# C++11, -Werror with the conversion and shadow warnings a renderer's build
# may turn on, static, plain C; and mingw-w64 and aarch64 gcc where make
# test installed them. Each compiler is a part of its own (build/matrix-NAME,
# written when it passed), so that make -j compiles them side by side.
MATRIX_FLAGS = "" "-DHAIROBB_STATIC" "-DHAIROBB_NO_SIMD" "-DHAIROBB_NO_DISPATCH" "-msse4.1" "-mavx" "-mavx2" \
               "-mavx2 -DHAIROBB_NODE_WIDTH=8" "-DHAIROBB_NODE_WIDTH=8" "-DHAIROBB_NO_SIMD -DHAIROBB_NODE_WIDTH=8" \
               "-DHAIROBB_NO_THREADS" "-DHAIROBB_NO_STDIO"
# Windows (mingw-w64: Win32 threads, dispatch) and AArch64 (the NEON path)
MATRIX_FLAGS_mingw   = "" "-DHAIROBB_NO_SIMD" "-mavx2" "-DHAIROBB_NO_THREADS"
MATRIX_FLAGS_aarch64 = "" "-DHAIROBB_NO_SIMD" "-DHAIROBB_NODE_WIDTH=8"
MATRIX_WARN          = -Wconversion -Wsign-conversion -Wshadow
MATRIX_CC_mingw      = x86_64-w64-mingw32-gcc
MATRIX_CXX_mingw     = x86_64-w64-mingw32-g++
MATRIX_CC_aarch64    = aarch64-linux-gnu-gcc
MATRIX_CXX_aarch64   = aarch64-linux-gnu-g++
compile-matrix: $(B)/matrix-gcc $(B)/matrix-clang $(B)/matrix-mingw $(B)/matrix-aarch64
$(B)/matrix.c: | $(B)
	@printf '#define HAIROBB_IMPLEMENTATION\n#include "hairobb.h"\nint main(void){return 0;}\n' > $@
# gcc and clang: every flag set, and the header renamed (runtime dispatch
# includes it again by its own name: HAIROBB_SELF renames it)
$(B)/matrix-gcc $(B)/matrix-clang: $(B)/matrix-%: $(B)/matrix.c hairobb.h
	@set -e; cc=$*; if ! command -v $$cc >/dev/null; then echo "compile-matrix: $$cc missing, left out"; exit 0; fi; \
	  for flags in $(MATRIX_FLAGS); do \
	    $$cc $(WARN) $(MATRIX_WARN) -Werror -O2 $$flags -I. -c $(B)/matrix.c -o $@.o; \
	    $$cc -x c++ -std=c++11 -Wall -Wextra -pedantic $(MATRIX_WARN) -Werror -O2 $$flags -I. -c $(B)/matrix.c -o $@.o; \
	    echo "compile-matrix: $$cc $$flags (C99 and C++11) clean"; done; \
	  mkdir -p $@-renamed && cp hairobb.h $@-renamed/third_party_hair.h; \
	  printf '#define HAIROBB_IMPLEMENTATION\n#include "third_party_hair.h"\nint main(void){return 0;}\n' > $@-renamed/matrix.c; \
	  $$cc $(WARN) $(MATRIX_WARN) -Werror -O2 '-DHAIROBB_SELF="third_party_hair.h"' -I$@-renamed -c $@-renamed/matrix.c -o $@.o; \
	  echo "compile-matrix: $$cc with the header renamed (HAIROBB_SELF) clean"; touch $@
$(B)/matrix-mingw $(B)/matrix-aarch64: $(B)/matrix-%: $(B)/matrix.c hairobb.h
	@set -e; cc=$(MATRIX_CC_$*); cxx=$(MATRIX_CXX_$*); \
	  if ! command -v $$cc >/dev/null || ! command -v $$cxx >/dev/null; then \
	    echo "compile-matrix: $$cc or $$cxx missing, the $* builds left out"; exit 0; fi; \
	  for flags in $(MATRIX_FLAGS_$*); do \
	    $$cc $(WARN) $(MATRIX_WARN) -Werror -O2 $$flags -I. -c $(B)/matrix.c -o $@.o; \
	    $$cxx -x c++ -std=c++11 -Wall -Wextra -pedantic $(MATRIX_WARN) -Werror -O2 $$flags -I. -c $(B)/matrix.c -o $@.o; \
	    echo "compile-matrix: $$cc $$flags (C99 and C++11) clean"; done; touch $@

# the Windows tier (tests/run_windows.sh): the quick tier's core programs and
# test_threads built with mingw-w64 and run under wine, and the same trees
# and hits as this machine's build; it builds its programs when it runs
$(B)/run_windows: tests/run_windows.sh | $(B)
	@printf '#!/bin/sh\nexec sh tests/run_windows.sh $(B)\n' > $@ && chmod +x $@
# the AArch64 tier (tests/run_arm64.sh): the NEON path against plain C under
# qemu, and the same trees and hits as this machine's 4-wide build
$(B)/run_arm64: tests/run_arm64.sh | $(B)
	@printf '#!/bin/sh\nexec sh tests/run_arm64.sh $(B)\n' > $@ && chmod +x $@

# the AVX2 kernels of the dispatch build call no baseline code (objdump)
$(B)/check_dispatch_calls: tests/check_dispatch_calls.sh $(B)/simd_dispatch_w8.o
	@printf '#!/bin/sh\nexec sh tests/check_dispatch_calls.sh $(B)/simd_dispatch_w8.o\n' > $@ && chmod +x $@

# every name the kernels define is renamed for the AVX2 copy, once, and none in vain
$(B)/check_dispatch_list: tests/check_dispatch_list.sh hairobb.h | $(B)
	@printf '#!/bin/sh\nexec sh tests/check_dispatch_list.sh hairobb.h\n' > $@ && chmod +x $@

test: deps $(TESTS) $(SANITIZED) compile-matrix examples $(B)/run_examples $(B)/check_dispatch_calls $(B)/check_dispatch_list \
      $(B)/motion_cost $(B)/run_windows $(B)/run_arm64
	@sh tests/run_all.sh $(B)/run_arm64 $(B)/run_windows $(SANITIZED) $(TESTS) $(B)/run_examples $(B)/check_dispatch_calls \
	    $(B)/check_dispatch_list

check: $(CHECK_TESTS)
	@$(if $(X86),,echo "test_simd left out: $(CC) does not target x86";) sh tests/run_all.sh $(CHECK_TESTS)

bench: $(B)/bench
	$(B)/bench

# instructions per ray under callgrind, hairobb against Embree, split by
# where they go (bench/profile.sh; PROFILE="..." adds bench options): the
# bench counting each ray's nodes, leaves and segments, and the bench at
# fixed addresses for addr2line
profile: $(B)/bench_profile $(B)/bench_counted
	sh bench/profile.sh $(PROFILE)

# the quick count for kernel work: hairobb's instructions a ray on combed
# 200k, 128x128 camera rays, ribbons and round curves, by callgrind
# (bench/instructions.sh; about 20 seconds)
instructions: $(B)/instructions
	sh bench/instructions.sh

$(B)/instructions: bench/instructions.c hairobb.h tests/scenes.h | $(B)
	$(CC) $(BASE) bench/instructions.c -o $@ $(LIBS)

# the working tree's hairobb.h against another commit's (AB_BASE, default
# HEAD), built into one program and timed in alternating passes over the
# same rays, or building in alternating rounds (AB="--builds ...") (bench/ab.c;
# AB="..." adds its options)
AB_BASE ?= HEAD
ab: | $(B)
	sh bench/ab.sh $(AB_BASE) $(AB)

# the figures the docs quote (bench/figures.sh): the target scenes against
# Embree, round curves and build time, about 16 minutes on 2 cores (not part
# of `make test`); saved as bench/results/figures-DATE.txt, and the generated
# regions of docs/benchmarking.md and README.md written from it.
# FIGURES_FROM=FILE writes the pages from a stored run, without running.
figures: $(if $(FIGURES_FROM),,$(B)/bench)
	sh bench/figures.sh $(if $(FIGURES_FROM),--from $(FIGURES_FROM))

examples: $(B)/minimal $(B)/render $(B)/embree_swap $(B)/groom

$(B)/minimal $(B)/groom: $(B)/%: examples/%.c hairobb.h | $(B)
	$(CC) $(BASE) $(ARCH) $< -o $@ $(LIBS)

# the renderer writes its PNG with stb_image_write.h (libstb-dev)
$(B)/render: examples/render.c hairobb.h | $(B) deps
	$(CC) $(BASE) $(ARCH) $< -o $@ $(LIBS)

$(B)/embree_swap: examples/embree_swap.c hairobb.h | $(B) deps
	$(CC) $(BASE) $(ARCH) $< -o $@ $(EMBREE) $(LIBS)

# `make test` runs the examples too (a few seconds): minimal, a 160x160
# render of the built-in fur, embree_swap, groom
$(B)/run_examples: tests/run_examples.sh $(B)/minimal $(B)/render $(B)/embree_swap $(B)/groom
	@printf '#!/bin/sh\nexec sh tests/run_examples.sh $(B)\n' > $@ && chmod +x $@

clean:
	rm -rf $(B)
