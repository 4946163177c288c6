# hairobb: `make test` runs every test, `make check` the quick tier (a C99
# compiler only: no Embree, clang, sanitizers or apt-get), `make bench` the
# benchmark on the built-in fur scene, `make examples` builds the examples.
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
         $(B)/test_save $(B)/test_motion
CHECK_TESTS = $(QUICK) $(B)/check_test_secondary
# `make test`: the quick tier's programs and those needing Embree (and furBall_A)
TESTS = $(QUICK) $(B)/test_secondary $(B)/test_accuracy $(B)/test_far $(B)/test_scenes $(B)/test_threads $(B)/test_bases
# the same tests again under AddressSanitizer + UndefinedBehaviorSanitizer
# (any report aborts the test), the threads test under ThreadSanitizer, and
# the fuzzers (clang); named first, as the longest, since the tests run two
# at a time on 2 cores
SANITIZED = $(B)/fuzz_build_60s $(B)/asan_test_options $(B)/fuzz_hair_30s $(B)/fuzz_load_30s $(B)/asan_test_unit_w8 $(B)/asan_test_stress \
            $(B)/tsan_test_threads $(B)/asan_test_reference $(B)/asan_test_save_w4
ASAN      = -O1 -g -fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer
TSAN      = -O1 -g -fsanitize=thread
# libFuzzer targets (clang): 60 s in `make test`, `make fuzz` for a long run
FUZZCC    = clang
FUZZ      = -std=c99 -O1 -g -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=all -ffp-contract=off -I.
FUZZ_SECONDS ?= 1800

.PHONY: all test check deps compile-matrix bench profile examples clean fuzz tree-hashes
all: $(TESTS) $(SANITIZED) $(B)/bench examples

deps:
	@sh tests/install_deps.sh

$(B):
	@mkdir -p $(B)

$(B)/test_reference: tests/test_reference.c tests/reference.h | $(B)
	$(CC) $(BASE) $(ARCH) $< -o $@ $(LIBS)

# white-box tests on 4-wide and on 8-wide nodes
# (their counting allocators lock a pthread mutex: builds allocate on several threads)
$(B)/test_unit: tests/test_unit.c hairobb.h tests/reference.h tests/scenes.h tests/test_data.h tests/check.h | $(B)
	$(CC) $(BASE) $(ARCH) -DHAIROBB_NODE_WIDTH=4 $< -o $@ $(LIBS) -lpthread

$(B)/test_unit_w8: tests/test_unit.c hairobb.h tests/reference.h tests/scenes.h tests/test_data.h tests/check.h | $(B)
	$(CC) $(BASE) $(ARCH) -DHAIROBB_NODE_WIDTH=8 $< -o $@ $(LIBS) -lpthread

# refit: a tree built on one pose refitted to others, against fresh builds and the reference (8- and 4-wide)
$(B)/test_refit: tests/test_refit.c hairobb.h tests/reference.h tests/scenes.h tests/test_data.h tests/check.h | $(B)
	$(CC) $(BASE) $(ARCH) -DHAIROBB_NODE_WIDTH=8 $< -o $@ $(LIBS)
$(B)/test_refit_w4: tests/test_refit.c hairobb.h tests/reference.h tests/scenes.h tests/test_data.h tests/check.h | $(B)
	$(CC) $(BASE) $(ARCH) -DHAIROBB_NODE_WIDTH=4 $< -o $@ $(LIBS)

# motion blur: moving fur at random ray times against the reference, errors, refit, save/load
$(B)/test_motion: tests/test_motion.c hairobb.h tests/reference.h tests/ref_bases.h tests/test_data.h tests/check.h | $(B)
	$(CC) $(BASE) $(ARCH) $< -o $@ $(LIBS) -lpthread

# black-box: every combination of build options against the reference
$(B)/test_options: tests/test_options.c hairobb.h tests/reference.h tests/scenes.h tests/test_data.h tests/check.h | $(B)
	$(CC) $(BASE) $(ARCH) $< -o $@ $(LIBS) -lpthread

# threads: builds on 1 and 4 threads equal, 4 threads tracing one BVH
$(B)/test_threads: tests/test_threads.c hairobb.h tests/scenes.h tests/test_data.h tests/check.h | $(B)
	$(CC) $(BASE) $(ARCH) $< -o $@ $(LIBS)

$(B)/asan_test_reference: tests/test_reference.c tests/reference.h | $(B)
	$(CC) $(WARN) $(ASAN) -ffp-contract=off -I. $(ARCH) $< -o $@ $(LIBS)
$(B)/asan_test_unit_w8: tests/test_unit.c hairobb.h tests/reference.h tests/scenes.h tests/test_data.h tests/check.h | $(B)
	$(CC) $(WARN) $(ASAN) -ffp-contract=off -I. $(ARCH) -DHAIROBB_NODE_WIDTH=8 $< -o $@ $(LIBS)
$(B)/asan_test_options: tests/test_options.c hairobb.h tests/reference.h tests/scenes.h tests/test_data.h tests/check.h | $(B)
	$(CC) $(WARN) $(ASAN) -ffp-contract=off -I. $(ARCH) -DCROSSED_RAYS=1024 $< -o $@ $(LIBS)
$(B)/asan_test_stress: tests/test_stress.c hairobb.h tests/reference.h tests/scenes.h tests/test_data.h tests/check.h | $(B)
	$(CC) $(WARN) $(ASAN) -ffp-contract=off -I. $(ARCH) $< -o $@ $(LIBS)
# 4-wide (test_save runs 8-wide), one scene's round trips: the loader's bounds under ASan
$(B)/asan_test_save_w4: tests/test_save.c hairobb.h tests/reference.h tests/scenes.h tests/test_data.h tests/check.h | $(B)
	$(CC) $(WARN) $(ASAN) -ffp-contract=off -I. $(ARCH) -DHAIROBB_NODE_WIDTH=4 -DSAVE_SCENES=1 $< -o $@ $(LIBS)
$(B)/tsan_test_threads: tests/test_threads.c hairobb.h tests/scenes.h tests/test_data.h tests/check.h | $(B)
	$(CC) $(WARN) $(TSAN) -ffp-contract=off -I. $(ARCH) $< -o $@ $(LIBS)

$(B)/fuzz_%: tests/fuzz_%.c tests/fuzz_checks.h hairobb.h | $(B) deps
	$(FUZZCC) $(FUZZ) $< -o $@ $(LIBS)
$(B)/fuzz_build_60s: $(B)/fuzz_build tests/fuzz_run.sh
	@printf '#!/bin/sh\nexec sh tests/fuzz_run.sh $(B)/fuzz_build tests/fuzz_corpus/bvh_build 60\n' > $@ && chmod +x $@
$(B)/fuzz_hair_30s: $(B)/fuzz_hair tests/fuzz_run.sh
	@printf '#!/bin/sh\nexec sh tests/fuzz_run.sh $(B)/fuzz_hair tests/fuzz_corpus/hair_read 30\n' > $@ && chmod +x $@
# saved BVHs, checksum fixed up, loaded over a fixed scene (scenes.h)
$(B)/fuzz_load: tests/scenes.h
$(B)/fuzz_load_30s: $(B)/fuzz_load tests/fuzz_run.sh
	@printf '#!/bin/sh\nexec sh tests/fuzz_run.sh $(B)/fuzz_load tests/fuzz_corpus/bvh_load 30\n' > $@ && chmod +x $@
# long runs: FUZZ_SECONDS each
fuzz: $(B)/fuzz_build $(B)/fuzz_hair $(B)/fuzz_load
	sh tests/fuzz_run.sh $(B)/fuzz_build tests/fuzz_corpus/bvh_build $(FUZZ_SECONDS)
	sh tests/fuzz_run.sh $(B)/fuzz_hair tests/fuzz_corpus/hair_read $(FUZZ_SECONDS)
	sh tests/fuzz_run.sh $(B)/fuzz_load tests/fuzz_corpus/bvh_load $(FUZZ_SECONDS)

$(B)/test_scenes: tests/test_scenes.c tests/scenes.h tests/test_data.h tests/embree_wrap.h | $(B) deps
	$(CC) $(BASE) $(ARCH) $< -o $@ $(EMBREE) $(LIBS)

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
$(B)/test_simd: tests/test_simd.c $(B)/simd_plain_w4.o $(B)/simd_sse_w4.o $(B)/simd_avx_w4.o $(B)/simd_dispatch_w4.o tests/scenes.h tests/test_data.h | $(B)
	$(CC) $(BASE) $(ARCH) $(filter %.c %.o,$^) -o $@ $(LIBS)
$(B)/test_simd_w8: tests/test_simd.c $(B)/simd_plain_w8.o $(B)/simd_sse_w8.o $(B)/simd_avx_w8.o $(B)/simd_dispatch_w8.o tests/scenes.h tests/test_data.h | $(B)
	$(CC) $(BASE) $(ARCH) $(filter %.c %.o,$^) -o $@ $(LIBS)

$(B)/test_accuracy: tests/test_accuracy.c hairobb.h tests/reference.h tests/scenes.h tests/test_data.h tests/embree_wrap.h | $(B) deps
	$(CC) $(BASE) $(ARCH) $< -o $@ $(EMBREE) $(LIBS)

$(B)/test_far: tests/test_far.c hairobb.h tests/reference.h tests/scenes.h tests/test_data.h tests/embree_wrap.h | $(B) deps
	$(CC) $(BASE) $(ARCH) $< -o $@ $(EMBREE) $(LIBS)

# numerical stress: radii, degenerate segments, hard rays, joints
$(B)/test_stress: tests/test_stress.c hairobb.h tests/reference.h tests/scenes.h tests/test_data.h tests/check.h | $(B)
	$(CC) $(BASE) $(ARCH) $< -o $@ $(LIBS)

# traversal conservativeness: an instrumented header records the leaves reached
$(B)/test_conservative: tests/test_conservative.c hairobb.h tests/reference.h tests/scenes.h tests/test_data.h tests/check.h | $(B)
	$(CC) $(BASE) $(ARCH) $< -o $@ $(LIBS)

# curve bases against Embree's flat curves of each basis and the reference
$(B)/test_bases: tests/test_bases.c hairobb.h tests/reference.h tests/ref_bases.h tests/scenes.h tests/test_data.h tests/embree_wrap.h | $(B) deps
	$(CC) $(BASE) $(ARCH) $< -o $@ $(EMBREE) $(LIBS)

# the any-hit filter against the reference
$(B)/test_filter: tests/test_filter.c hairobb.h tests/reference.h tests/scenes.h tests/test_data.h tests/check.h | $(B)
	$(CC) $(BASE) $(ARCH) $< -o $@ $(LIBS)

# secondary rays leaving a hit: the self-intersection rule, contact shadows
$(B)/test_secondary: tests/test_secondary.c hairobb.h tests/reference.h tests/scenes.h tests/test_data.h tests/embree_wrap.h | $(B) deps
	$(CC) $(BASE) $(ARCH) $< -o $@ $(EMBREE) $(LIBS)
$(B)/check_test_secondary: tests/test_secondary.c hairobb.h tests/reference.h tests/scenes.h tests/test_data.h tests/check.h | $(B)
	$(CC) $(BASE) $(ARCH) -DTESTS_NO_EMBREE $< -o $@ $(LIBS)

# BVHs saved and loaded: round trips traced to the bit, bad bytes, other hair
$(B)/test_save: tests/test_save.c hairobb.h tests/reference.h tests/scenes.h tests/test_data.h tests/check.h | $(B)
	$(CC) $(BASE) $(ARCH) $< -o $@ $(LIBS)

# the .hair reader against the tests' own, bad files, a BVH from a loaded file
$(B)/test_hair: tests/test_hair.c hairobb.h tests/reference.h tests/scenes.h tests/test_data.h tests/check.h | $(B)
	$(CC) $(BASE) $(ARCH) $< -o $@ $(LIBS)

# the bench, and its two builds for `make profile` (below)
BENCH_FLAGS_bench         = -DBENCH_CFLAGS='"$(BASE) $(ARCH)"'
BENCH_FLAGS_bench_counted = -DBENCH_COUNTS
BENCH_FLAGS_bench_profile = -fno-pie -no-pie
# (its parts: bench/bench.h; hairobb's implementation is in bench/harness.c)
BENCH_SOURCES = bench/bench.c bench/options.c bench/variants.c bench/memory.c bench/scenes.c bench/harness.c \
                bench/accuracy.c bench/report.c bench/tsv_chart.c bench/mode_scenes.c bench/mode_builds.c \
                bench/mode_motion.c bench/mode_animate.c bench/mode_save_load.c
$(B)/bench $(B)/bench_counted $(B)/bench_profile: $(BENCH_SOURCES) bench/bench.h bench/alloc_meter.h hairobb.h tests/reference.h tests/scenes.h tests/test_data.h tests/embree_wrap.h | $(B) deps
	$(CC) $(BASE) $(ARCH) $(BENCH_FLAGS_$(@F)) $(BENCH_SOURCES) -o $@ $(EMBREE) -lpthread $(LIBS)

# Same trees: a hash of each tree (scenes x option sets x 1 and 2 build
# threads, bench/tree_hash.c) from the default 8-wide build, 4-wide and plain
# C; `make tree-hashes` writes them to build/tree-hashes.txt (diff it against
# bench/results/tree-hashes-*.txt). --memory: peak transient build bytes.
TREE_HASH_FLAGS_tree_hash       =
TREE_HASH_FLAGS_tree_hash_w4    = -DHAIROBB_NODE_WIDTH=4
TREE_HASH_FLAGS_tree_hash_plain = -DHAIROBB_NO_SIMD
$(B)/tree_hash $(B)/tree_hash_w4 $(B)/tree_hash_plain: bench/tree_hash.c bench/alloc_meter.h hairobb.h tests/scenes.h tests/test_data.h | $(B)
	$(CC) $(BASE) $(ARCH) $(TREE_HASH_FLAGS_$(@F)) $< -o $@ $(LIBS)
# instructions a ray of moving hair under callgrind (bench/motion_cost.c)
$(B)/motion_cost: bench/motion_cost.c hairobb.h tests/scenes.h | $(B)
	$(CC) $(BASE) $< -o $@ $(LIBS)
tree-hashes: $(B)/tree_hash $(B)/tree_hash_w4 $(B)/tree_hash_plain
	@for p in tree_hash tree_hash_w4 tree_hash_plain; do echo "== $$p"; $(B)/$$p || exit 1; done > $(B)/tree-hashes.txt
	@echo "tree hashes: $(B)/tree-hashes.txt"

# The header must compile clean as users compile it: gcc and clang, C99 and
# C++11, -Werror, static, plain C.
compile-matrix: | $(B)
	@printf '#define HAIROBB_IMPLEMENTATION\n#include "hairobb.h"\nint main(void){return 0;}\n' > $(B)/matrix.c
	@set -e; for cc in gcc clang; do command -v $$cc >/dev/null || continue; \
	  for flags in "" "-DHAIROBB_STATIC" "-DHAIROBB_NO_SIMD" "-DHAIROBB_NO_DISPATCH" "-msse4.1" "-mavx" "-mavx2" "-mavx2 -DHAIROBB_NODE_WIDTH=8" "-DHAIROBB_NODE_WIDTH=8" "-DHAIROBB_NO_SIMD -DHAIROBB_NODE_WIDTH=8" "-DHAIROBB_NO_THREADS" "-DHAIROBB_NO_STDIO"; do \
	    $$cc $(WARN) -Werror -O2 $$flags -I. -c $(B)/matrix.c -o $(B)/matrix.o; \
	    $$cc -x c++ -std=c++11 -Wall -Wextra -pedantic -Werror -O2 $$flags -I. -c $(B)/matrix.c -o $(B)/matrix.o; \
	    echo "compile-matrix: $$cc $$flags (C99 and C++11) clean"; done; done
	@# runtime dispatch includes the header again by its own name: HAIROBB_SELF renames it
	@mkdir -p $(B)/renamed && cp hairobb.h $(B)/renamed/third_party_hair.h
	@printf '#define HAIROBB_IMPLEMENTATION\n#include "renamed/third_party_hair.h"\nint main(void){return 0;}\n' > $(B)/matrix_renamed.c
	@set -e; for cc in gcc clang; do command -v $$cc >/dev/null || continue; \
	  $$cc $(WARN) -Werror -O2 '-DHAIROBB_SELF="third_party_hair.h"' -c $(B)/matrix_renamed.c -o $(B)/matrix.o; \
	  echo "compile-matrix: $$cc with the header renamed (HAIROBB_SELF) clean"; done

# the AVX2 kernels of the dispatch build call no baseline code (objdump)
$(B)/check_dispatch_calls: tests/check_dispatch_calls.sh $(B)/simd_dispatch_w8.o
	@printf '#!/bin/sh\nexec sh tests/check_dispatch_calls.sh $(B)/simd_dispatch_w8.o\n' > $@ && chmod +x $@

test: deps $(TESTS) $(SANITIZED) compile-matrix examples $(B)/run_examples $(B)/check_dispatch_calls $(B)/motion_cost
	@sh tests/run_all.sh $(SANITIZED) $(TESTS) $(B)/run_examples $(B)/check_dispatch_calls

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

examples: $(B)/minimal $(B)/render $(B)/embree_swap

$(B)/minimal: examples/minimal.c hairobb.h | $(B)
	$(CC) $(BASE) $(ARCH) $< -o $@ $(LIBS)

# the renderer writes its PNG with stb_image_write.h (libstb-dev)
$(B)/render: examples/render.c hairobb.h | $(B) deps
	$(CC) $(BASE) $(ARCH) $< -o $@ $(LIBS)

$(B)/embree_swap: examples/embree_swap.c hairobb.h | $(B) deps
	$(CC) $(BASE) $(ARCH) $< -o $@ $(EMBREE) $(LIBS)

# `make test` runs the examples too (a few seconds): minimal, a 160x160
# render of the built-in fur, embree_swap
$(B)/run_examples: tests/run_examples.sh $(B)/minimal $(B)/render $(B)/embree_swap
	@printf '#!/bin/sh\nexec sh tests/run_examples.sh $(B)\n' > $@ && chmod +x $@

clean:
	rm -rf $(B)
