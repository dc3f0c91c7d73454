# pdftrace - examples, tests and checks.
#
#   make                  build build/pdftrace (tools/pdftrace.c, the command-line renderer) and
#                         the examples into build/
#   make run              render the default Cornell box to out/cornell.ppm and out/cornell.pfm,
#                         and out/cornell.png when built with libpng
#   make run-all          also render the other examples into out/
#   make test             build and run the test runner, then again without threads and
#                         under AddressSanitizer + UndefinedBehaviorSanitizer; every runner ends
#                         with "N passed, M failed, K skipped" (a skipped test is not a pass)
#   make nothreads-test   only the test runner built with -DPDFTRACE_NO_THREADS (and -DPDFTRACE_NO_SIMD)
#   make tsan-test        the tests that render from several threads (and one scene from several at once), built with
#                         ThreadSanitizer (build/test_runner_tsan; not part of make test)
#   make cli-test         only the pdftrace command's tests (tests/cli/pdftrace.sh; part of make test)
#   make exr-test         build the test runner with OpenEXR (build/test_runner_exr) and run
#                         its exr section (needs libopenexr-dev)
#   make OPENEXR=1 ...    build the examples and test runners with PDFTRACE_OPENEXR (EXR output
#                         and input through OpenEXRCore; needs libopenexr-dev). Default 0.
#   make PNG=0|1 ...      PNG output (pdftrace_png.h, libpng) in build/pdftrace, build/cornell and
#                         the test runners: auto (default) when pkg-config finds libpng, 0 off,
#                         1 on (an error without libpng)
#   make TOOL_EXR=0|1 ... OpenEXR output in build/pdftrace: auto (default) when pkg-config finds
#                         OpenEXR, unless OPENEXR=0 is given on the command line; 0 off, 1 on
#   make MPI=1 ...        build build/pdftrace with PDFTRACE_MPI (pdftrace_mpi.h): it then runs under
#                         mpirun, one render split over the ranks, bit-identical to one process
#                         (docs/mpi.md; needs libopenmpi-dev, or MPICH with MPI_CFLAGS/MPI_LIBS). Default 0.
#   make mpi-test         build $(BUILD)/pdftrace_mpi and compare 1, 2 and 3 ranks on localhost byte for
#                         byte, and the failing-rank cases (tests/mpi/mpi_test.sh; SKIP without MPI)
#   make bench-mpi        1 rank x 2 threads against 2 ranks x 1 thread, and the gather's time as the
#                         image grows (bench/mpi.sh, bench/mpi_gather.c -> $(BUILD)/bench-mpi/; needs MPI)
#   make EMBREE=1 ...     build the examples and test runners with PDFTRACE_EMBREE (Embree 3
#                         traversal, pdftrace.h section 5b; needs libembree-dev). Default 0.
#                         Either or both: make OPENEXR=1 EMBREE=1 test (use a separate BUILD=
#                         per combination, or let the options stamp rebuild on a change).
#   make fuzz             build the libFuzzer targets (clang, libclang-rt-14-dev) for the scene
#                         loader, the OBJ loader, the POV-Ray exporter and the EXR reader
#                         (tests/fuzz/) and run each for
#                         FUZZ_SECONDS (default 60) from tests/fuzz/corpus/<target>/; new inputs go
#                         to $(BUILD)/fuzz-corpus/, crashes to $(BUILD)/fuzz-artifacts/
#   make fuzz-merge       minimise tests/fuzz/corpus/<target>/ plus $(BUILD)/fuzz-corpus/<target>/
#                         into tests/fuzz/corpus/<target>/ (libFuzzer -set_cover_merge=1)
#   make fptrap-test      render every scenes/*.scene and the built-in test scenes at low spp
#                         with FE_INVALID and FE_DIVBYZERO trapping (glibc; part of make test)
#   make bench-bvh        rays/s of the built-in BVH and of Embree side by side (Cornell box and a
#                         generated 1M-triangle terrain), build time, memory, the AUTO crossover:
#                         bench/bvh.c -> bench/out/bvh.md and bench/out/bvh.csv (needs
#                         libembree-dev; ~5 min; BENCH_BVH_ARGS=--quick for a short run)
#   make bench-batched    samples/s of the scalar and the batched integrator side by side (Cornell
#                         box, door, closed room; 1 and 2 threads; EMBREE=1: Embree too):
#                         bench/batched.c -> bench/out/batched.md (~3 min)
#   make bench-simd       rays/s of the built-in BVH at each SIMD level this CPU has, one thread:
#                         bench/bvh.c --levels -> bench/out/simd.md and simd.csv (~5 min)
#   make build/ptsky      the procedural sky tool (tools/sky.c; docs/sky.md)
#   make sky-check        regenerate scenes/sky.pfm into $(BUILD)/sky.pfm with build/ptsky and cmp them
#   make check-warnings   compile the examples and tools/pdftrace.c (and so the implementation)
#                         with gcc and clang at -std=c99 -Wall -Wextra -pedantic -Werror, with
#                         and without libpng and OpenEXR, and the headers as C++; first
#                         tests/lint_headers.sh: no comment over 25 lines in a header's
#                         implementation, no function over 150 lines
#   make validate         render every scene in scenes/ with pdftrace and POV-Ray, and every scene in
#                         scenes/ and bench/scenes/ with Mitsuba 3, compare them and write
#                         validation/out/index.html (needs povray, libopenexr-dev, libpng-dev; the
#                         Mitsuba rows print SKIP until make mitsuba-install; ~15 min)
#   make mitsuba-install  a Python venv in $(BUILD)/mitsuba-venv (or MITSUBA_VENV=DIR) with
#                         mitsuba 3.9 from PyPI (needs python3, python3-venv; libllvm19 for the
#                         fast llvm_ad_rgb variant, else the slower scalar_rgb)
#   make validate-mitsuba only the Mitsuba rows of make validate (VALIDATE_SCENES="a b" for some)
#   make validate-mitsuba-ci  the Mitsuba rows of direct-quad, glass, cornell, cornell-guided, lights, env, rough-metal, rough-plastic, rough-glass and textured (< 8 min)
#   make validate-refs    re-render the slow POV-Ray references stored in scenes/ref/ (~12 min)
#   make bench            error against time for every scene and strategy, POV-Ray on the same
#                         axes, adaptive sampling, skips, and throughput (samples/s and rays/s per
#                         SIMD level and against Mitsuba 3 at equal depth) -> bench/out/ (summary.md, CSV,
#                         PNG plots by gnuplot; ~25 min on 2 cores; BENCH_OUT, BENCH_ARGS)
#   make bench-quick      the same in under 4 minutes -> $(BUILD)/bench-quick/
#   make bench-headline   the 600x600 Cornell box (scenes/cornell.scene) at its own settings against
#                         Mitsuba 3 at equal time and equal error -> $(BUILD)/bench-headline/
#                         (needs make mitsuba-install; MITSUBA_VENV)
#   make bench-refs       re-render the benchmark's reference images in bench/ref/ (~30 min)
#   make stress          the numerical stress cases at full size (~1-2 min CPU): a table
#                         case | metric | bound | result, non-zero exit on any failing row
#   make install          install pdftrace*.h into $(PREFIX)/include, build/pdftrace into
#                         $(PREFIX)/bin and a generated pdftrace.pc into $(PREFIX)/lib/pkgconfig
#                         (PREFIX=/usr/local by default; DESTDIR=... stages the files below it)
#   make uninstall        remove what make install wrote (same PREFIX and DESTDIR)
#   make install-check    make install into a temporary prefix, then build and run a program
#                         with cc $(pkg-config --cflags pdftrace) ... $(pkg-config --libs pdftrace)
#   make clean            remove build/ and out/
#   make help             this text
#
# Every variable set with ?= in the Makefile can be overridden, e.g.
#   make CC=clang CFLAGS='-O3 -g' RUN_SPP=256

CFLAGS   ?= -std=c99 -O3 -Wall -Wextra -pedantic
CXXFLAGS ?= -O2 -Wall -Wextra -pedantic
CPPFLAGS ?=
LDFLAGS  ?=
LDLIBS   ?=

BUILD ?= build
OUT   ?= out

# The header family (pdftrace.h, pdftrace_scene.h, pdftrace_exr.h) lives at the top level.
PT_HEADERS := $(wildcard pdftrace*.h)
# Added to every build: the headers live at the top level; the library wants -lm and pthreads.
PT_CPPFLAGS := -I.
PT_THREADS  ?= -pthread
PT_LDLIBS   := -lm

# The sanitizer build of the tests (added after CFLAGS, so its -O1 wins). gcc's undefined omits
# float-cast-overflow (a float out of an integer's range converted to it), hence named here.
SANFLAGS ?= -O1 -g -fsanitize=address,undefined,float-cast-overflow -fno-sanitize-recover=all
# make test also builds the runner with clang under ASan+UBSan when clang is installed (its
# undefined includes float-cast-overflow; its checks differ from gcc's), else prints SKIP.
SAN_CLANG      ?= clang
SAN_CLANG_PATH := $(shell command -v $(SAN_CLANG) 2>/dev/null)
# make tsan-test: ThreadSanitizer, and the runner's filters (one run each) for the tests that
# render from several threads: pt_render's own threads, a host parallel_for, several renders
# of one scene at once (render.concurrent_renders), and Embree's with EMBREE=1.
TSANFLAGS ?= -O1 -g -fsanitize=thread
TSAN_TESTS ?= render.threads_bit_identical render.progressive_equals_single render.cancellation_and_progress \
              render.concurrent_renders render.render_counts adaptive.threads_bit_identical \
              sampler.render_deterministic materials.furnace_spheres embree.embree_fp_state \
              guide.render_threads_bit_identical guide.guide_order_independent lights.env_threads \
              split.split_adaptive_equals_whole

# check-warnings: the compilers and flags it uses.
WARN_CC      ?= gcc clang
WARN_CXX     ?= g++ clang++
WARN_CFLAGS  ?= -std=c99 -O2 -Wall -Wextra -pedantic -Werror
WARN_CXXFLAGS ?= -x c++ -O2 -Wall -Wextra -pedantic -Werror

# make run: samples per pixel and any other options for build/cornell (Sobol points: 32 spp take
# about the time 128 independent ones took, at lower error; docs/design.md, "Defaults").
RUN_SPP  ?= 32
RUN_ARGS ?=

# OpenEXR (pdftrace_exr.h; -DPDFTRACE_OPENEXR makes the programs include it): only the include dirs of the OpenEXR .pc file are taken
# (its libs list the C++ libraries); only the C library OpenEXRCore is linked.
OPENEXR       ?= 0
EXR_INCLUDES  ?= $(or $(shell pkg-config --cflags-only-I OpenEXR 2>/dev/null),-I/usr/include/OpenEXR -I/usr/include/Imath)
EXR_LIBS      ?= -lOpenEXRCore-3_1
EXR_FLAGS     := -DPDFTRACE_OPENEXR $(patsubst -I%,-isystem %,$(EXR_INCLUDES))
ifeq ($(OPENEXR),1)
PT_CPPFLAGS += $(EXR_FLAGS)
PT_LDLIBS   := $(EXR_LIBS) $(PT_LDLIBS)
endif
# Embree 3 (pdftrace.h section 5b): header embree3/rtcore.h, library -lembree3 (no .pc file).
EMBREE          ?= 0
EMBREE_INCLUDES ?=
EMBREE_LIBS     ?= -lembree3
EMBREE_FLAGS    := -DPDFTRACE_EMBREE $(patsubst -I%,-isystem %,$(EMBREE_INCLUDES))
EMBREE_HEADER   ?= $(or $(patsubst -I%,%,$(firstword $(EMBREE_INCLUDES))),/usr/include)/embree3/rtcore.h
ifeq ($(EMBREE),1)
PT_CPPFLAGS += $(EMBREE_FLAGS)
PT_LDLIBS   := $(EMBREE_LIBS) $(PT_LDLIBS)
endif
# PNG output (pdftrace_png.h; -DPDFTRACE_PNG makes the programs include it) through libpng, for
# build/pdftrace, build/cornell and the test runners: auto = when pkg-config finds libpng.
PNG       ?= auto
PNG_FOUND := $(shell pkg-config --exists libpng 2>/dev/null && echo 1)
ifeq ($(PNG),auto)
PNG_ON := $(if $(PNG_FOUND),1,0)
else ifeq ($(PNG),1)
PNG_ON := 1
$(if $(PNG_FOUND),,$(error PNG=1: pkg-config finds no libpng (apt-get install libpng-dev pkg-config)))
else ifeq ($(PNG),0)
PNG_ON := 0
else
$(error PNG must be auto, 0 or 1, not '$(PNG)')
endif
PNG_FLAGS := $(if $(PNG_FOUND),-DPDFTRACE_PNG $(shell pkg-config --cflags libpng))
PNG_LIBS  := $(if $(PNG_FOUND),$(shell pkg-config --libs libpng))
PNG_CPPFLAGS := $(if $(filter 1,$(PNG_ON)),$(PNG_FLAGS))
PNG_LDLIBS   := $(if $(filter 1,$(PNG_ON)),$(PNG_LIBS))
# MPI (pdftrace_mpi.h): compile and link flags from Open MPI's mpicc wrapper (MPICH: set
# MPI_CFLAGS and MPI_LIBS from `mpicc -show`). MPI=1 puts them into build/pdftrace; make mpi-test
# builds $(BUILD)/pdftrace_mpi with them whatever MPI says.
MPI        ?= 0
MPICC      ?= mpicc
MPIRUN     ?= mpirun
MPI_FOUND  := $(shell command -v $(MPICC) >/dev/null 2>&1 && command -v $(MPIRUN) >/dev/null 2>&1 && echo 1)
MPI_CFLAGS ?= $(patsubst -I%,-isystem %,$(shell $(MPICC) --showme:compile 2>/dev/null))
MPI_LIBS   ?= $(shell $(MPICC) --showme:link 2>/dev/null)
MPI_INSTALL := apt-get install -y libopenmpi-dev openmpi-bin
ifeq ($(MPI),1)
$(if $(MPI_FOUND),,$(error MPI=1: no $(MPICC) and $(MPIRUN) ($(MPI_INSTALL))))
else ifneq ($(MPI),0)
$(error MPI must be 0 or 1, not '$(MPI)')
endif
# build/pdftrace's OpenEXR output: auto = when pkg-config finds OpenEXR, unless OPENEXR=0 is
# given on the command line (OPENEXR's own default, 0, is for the test runners and examples).
TOOL_EXR  ?= $(if $(filter command line,$(origin OPENEXR)),$(OPENEXR),auto)
EXR_FOUND := $(shell pkg-config --exists OpenEXR 2>/dev/null && echo 1)
ifeq ($(TOOL_EXR),auto)
TOOL_EXR_ON := $(if $(EXR_FOUND),1,0)
else ifeq ($(TOOL_EXR),1)
TOOL_EXR_ON := 1
else ifeq ($(TOOL_EXR),0)
TOOL_EXR_ON := 0
else
$(error TOOL_EXR must be auto, 0 or 1, not '$(TOOL_EXR)')
endif
# (with OPENEXR=1 the EXR flags are in PT_CPPFLAGS already)
TOOL_CPPFLAGS := $(PNG_CPPFLAGS) $(if $(filter 1,$(TOOL_EXR_ON)),$(if $(filter 1,$(OPENEXR)),,$(EXR_FLAGS)))
TOOL_LDLIBS   := $(PNG_LDLIBS) $(if $(filter 1,$(TOOL_EXR_ON)),$(if $(filter 1,$(OPENEXR)),,$(EXR_LIBS)))
TOOL_MPI_CPPFLAGS := $(TOOL_CPPFLAGS) -DPDFTRACE_MPI $(MPI_CFLAGS)
TOOL_MPI_LDLIBS   := $(TOOL_LDLIBS) $(MPI_LIBS)
ifeq ($(MPI),1)
TOOL_CPPFLAGS := $(TOOL_MPI_CPPFLAGS)
TOOL_LDLIBS   := $(TOOL_MPI_LDLIBS)
endif
# Rebuild the examples and runners when an option changes (the file is rewritten only then).
OPT_STAMP := $(BUILD)/options
OPT_VALUE := OPENEXR=$(OPENEXR) EMBREE=$(EMBREE) PNG=$(PNG_ON) TOOL_EXR=$(TOOL_EXR_ON) MPI=$(MPI)

EXAMPLES     := minimal cornell custom_pdf
EXAMPLE_BINS := $(EXAMPLES:%=$(BUILD)/%)
TEST_SRCS    := $(wildcard tests/*.c) tests/stress/stress_cases.c
TEST_HDRS    := $(wildcard tests/*.h) $(wildcard tests/stress/*.h) tests/fuzz/pov_check.h tests/fuzz/mitsuba_check.h

.PHONY: all run run-all test test-bins cli-test nothreads-test tsan-test exr-test check-warnings clean help validate validate-refs validate-mitsuba validate-mitsuba-ci mitsuba-install bench bench-quick bench-headline bench-refs bench-bvh bench-simd bench-batched stress install uninstall install-check FORCE

all: $(BUILD)/pdftrace $(EXAMPLE_BINS)

$(BUILD) $(OUT):
	mkdir -p $@

$(OPT_STAMP): FORCE | $(BUILD)
	@echo '$(OPT_VALUE)' | cmp -s - $@ || echo '$(OPT_VALUE)' > $@

$(BUILD)/%: examples/%.c $(PT_HEADERS) $(OPT_STAMP) | $(BUILD)
	$(CC) $(PT_CPPFLAGS) $(CPPFLAGS) $(CFLAGS) $(PT_THREADS) $(LDFLAGS) -o $@ $< $(LDLIBS) $(PT_LDLIBS)

# build/cornell writes PNG too when PNG is on.
$(BUILD)/cornell: PT_CPPFLAGS += $(PNG_CPPFLAGS)
$(BUILD)/cornell: PT_LDLIBS := $(PNG_LDLIBS) $(PT_LDLIBS)

# The command-line renderer: PNG per PNG, OpenEXR per TOOL_EXR, Embree per EMBREE.
$(BUILD)/pdftrace: tools/pdftrace.c $(PT_HEADERS) $(OPT_STAMP) | $(BUILD)
	$(CC) $(PT_CPPFLAGS) $(TOOL_CPPFLAGS) $(CPPFLAGS) $(CFLAGS) $(PT_THREADS) $(LDFLAGS) -o $@ $< $(LDLIBS) $(TOOL_LDLIBS) $(PT_LDLIBS)

# The command with MPI, whatever MPI says (make mpi-test, make bench-mpi).
$(BUILD)/pdftrace_mpi: tools/pdftrace.c $(PT_HEADERS) $(OPT_STAMP) | $(BUILD)
	@test -n "$(MPI_FOUND)" || { echo "$@: needs MPI ($(MPI_INSTALL))" >&2; exit 1; }
	$(CC) $(PT_CPPFLAGS) $(TOOL_MPI_CPPFLAGS) $(CPPFLAGS) $(CFLAGS) $(PT_THREADS) $(LDFLAGS) -o $@ $< $(LDLIBS) $(TOOL_MPI_LDLIBS) $(PT_LDLIBS)

# make mpi-test: tests/mpi/mpi_test.sh (prints SKIP, and succeeds, without MPI).
.PHONY: mpi-test bench-mpi
mpi-test:
ifeq ($(MPI_FOUND),1)
	$(MAKE) --no-print-directory $(BUILD)/pdftrace_mpi
	MPIRUN=$(MPIRUN) tests/mpi/mpi_test.sh $(BUILD)/pdftrace_mpi scenes $(BUILD)/mpi-work
else
	@echo "SKIP mpi-test: no MPI ($(MPICC) and $(MPIRUN) not found; as root: $(MPI_INSTALL))"
endif

# make bench-mpi: bench/mpi.sh (the command at 1 x 2 and 2 x 1) and bench/mpi_gather.c.
$(BUILD)/bench_mpi_gather: bench/mpi_gather.c $(PT_HEADERS) | $(BUILD)
	@test -n "$(MPI_FOUND)" || { echo "$@: needs MPI ($(MPI_INSTALL))" >&2; exit 1; }
	$(CC) -I. $(MPI_CFLAGS) $(CPPFLAGS) $(CFLAGS) $(PT_THREADS) $(LDFLAGS) -o $@ $< $(LDLIBS) $(MPI_LIBS) -lm
bench-mpi:
ifeq ($(MPI_FOUND),1)
	$(MAKE) --no-print-directory $(BUILD)/pdftrace_mpi $(BUILD)/bench_mpi_gather
	MPIRUN=$(MPIRUN) bench/mpi.sh $(BUILD)/pdftrace_mpi $(BUILD)/bench_mpi_gather $(BUILD)/bench-mpi
else
	@echo "SKIP bench-mpi: no MPI ($(MPICC) and $(MPIRUN) not found; as root: $(MPI_INSTALL))"
endif

# ptsky (tools/sky.c, docs/sky.md): a procedural sky map; PFM always, OpenEXR per TOOL_EXR
# (the same test as TOOL_CPPFLAGS's, without PNG, which ptsky does not write).
SKY_CPPFLAGS := $(if $(filter 1,$(TOOL_EXR_ON)),$(if $(filter 1,$(OPENEXR)),,$(EXR_FLAGS)))
SKY_LDLIBS   := $(if $(filter 1,$(TOOL_EXR_ON)),$(if $(filter 1,$(OPENEXR)),,$(EXR_LIBS)))
$(BUILD)/ptsky: tools/sky.c $(PT_HEADERS) $(OPT_STAMP) | $(BUILD)
	$(CC) $(PT_CPPFLAGS) $(SKY_CPPFLAGS) $(CPPFLAGS) $(CFLAGS) $(PT_THREADS) $(LDFLAGS) -o $@ $< $(LDLIBS) $(SKY_LDLIBS) $(PT_LDLIBS)

# make sky-check: scenes/sky.pfm is byte for byte what build/ptsky makes from SKY_ARGS.
SKY_ARGS := --size 256x128 --sun-elevation 38.671875 --sun-azimuth 45.703125 --turbidity 3 --sky-scale 0.025
.PHONY: sky-check
sky-check: $(BUILD)/ptsky
	./$(BUILD)/ptsky $(BUILD)/sky.pfm $(SKY_ARGS)
	cmp $(BUILD)/sky.pfm scenes/sky.pfm
	@echo "sky-check: $(BUILD)/sky.pfm is identical to scenes/sky.pfm"

RUN_PNG := $(if $(filter 1,$(PNG_ON)),-o $(OUT)/cornell.png)
run: $(BUILD)/cornell | $(OUT)
	$(BUILD)/cornell --spp $(RUN_SPP) $(RUN_ARGS) -o $(OUT)/cornell.ppm -o $(OUT)/cornell.pfm $(RUN_PNG)
ifneq ($(PNG_ON),1)
	@echo "$(if $(filter 0,$(PNG)),PNG=0: skipping $(OUT)/cornell.png,no libpng: skipping $(OUT)/cornell.png (apt-get install libpng-dev))"
endif

run-all: run $(EXAMPLE_BINS) | $(OUT)
	$(BUILD)/minimal $(OUT)/minimal.ppm
	$(BUILD)/custom_pdf $(OUT)/custom_pdf.ppm $(OUT)/custom_pdf_unguided.ppm

# ---- tests: one runner from all tests/*.c (tests/test_main.c defines PDFTRACE_IMPLEMENTATION)

define need_tests
	@test -n "$(TEST_SRCS)" || { echo "error: no tests/*.c found" >&2; exit 1; }
endef

# The runners test PNG output when PNG is on (output.png_round_trip; a SKIP note otherwise).
$(BUILD)/test_runner: $(TEST_SRCS) $(TEST_HDRS) $(PT_HEADERS) $(OPT_STAMP) | $(BUILD)
	$(need_tests)
	$(CC) $(PT_CPPFLAGS) $(PNG_CPPFLAGS) $(CPPFLAGS) $(CFLAGS) $(PT_THREADS) $(LDFLAGS) -o $@ $(TEST_SRCS) $(LDLIBS) $(PNG_LDLIBS) $(PT_LDLIBS)

$(BUILD)/test_runner_asan: $(TEST_SRCS) $(TEST_HDRS) $(PT_HEADERS) $(OPT_STAMP) | $(BUILD)
	$(need_tests)
	$(CC) $(PT_CPPFLAGS) $(PNG_CPPFLAGS) $(CPPFLAGS) $(CFLAGS) $(SANFLAGS) $(PT_THREADS) $(LDFLAGS) -o $@ $(TEST_SRCS) $(LDLIBS) $(PNG_LDLIBS) $(PT_LDLIBS)

$(BUILD)/test_runner_asan_clang: $(TEST_SRCS) $(TEST_HDRS) $(PT_HEADERS) $(OPT_STAMP) | $(BUILD)
	$(need_tests)
	$(SAN_CLANG) $(PT_CPPFLAGS) $(PNG_CPPFLAGS) $(CPPFLAGS) $(CFLAGS) $(SANFLAGS) $(PT_THREADS) $(LDFLAGS) -o $@ $(TEST_SRCS) $(LDLIBS) $(PNG_LDLIBS) $(PT_LDLIBS)

# Without threads: no -pthread at all, to show the library does not need it. Also without SIMD
# (PDFTRACE_NO_SIMD), so that the scalar BVH code other architectures get is tested too.
$(BUILD)/test_runner_nothreads: $(TEST_SRCS) $(TEST_HDRS) $(PT_HEADERS) $(OPT_STAMP) | $(BUILD)
	$(need_tests)
	$(CC) $(PT_CPPFLAGS) $(PNG_CPPFLAGS) $(CPPFLAGS) -DPDFTRACE_NO_THREADS -DPDFTRACE_NO_SIMD $(CFLAGS) $(LDFLAGS) -o $@ $(TEST_SRCS) $(LDLIBS) $(PNG_LDLIBS) $(PT_LDLIBS)

# Always with OpenEXR, whatever OPENEXR says; `make exr-test` runs only its exr section.
# The unit tests in GNU C for this machine's CPU (FMA where it has one, so a * b + c may contract):
# make test runs the sections that compare vector and scalar code bit for bit with it.
FMA_CFLAGS ?= -std=gnu11 -O2 -march=native
$(BUILD)/test_runner_fma: $(TEST_SRCS) $(TEST_HDRS) $(PT_HEADERS) $(OPT_STAMP) | $(BUILD)
	$(need_tests)
	$(CC) $(PT_CPPFLAGS) $(CPPFLAGS) $(FMA_CFLAGS) $(PT_THREADS) $(LDFLAGS) -o $@ $(TEST_SRCS) $(LDLIBS) $(PT_LDLIBS)

$(BUILD)/test_runner_exr: $(TEST_SRCS) $(TEST_HDRS) $(PT_HEADERS) | $(BUILD)
	$(need_tests)
	$(CC) -I. $(EXR_FLAGS) $(CPPFLAGS) $(CFLAGS) $(PT_THREADS) $(LDFLAGS) -o $@ $(TEST_SRCS) $(LDLIBS) $(EXR_LIBS) -lm

exr-test: $(BUILD)/test_runner_exr $(BUILD)/fuzz_replay_exr
	PT_FUZZ_FPTRAP=1 ./$(BUILD)/fuzz_replay_exr tests/fuzz/corpus
	./$(BUILD)/test_runner_exr exr

# ---- scene files and POV-Ray validation (validation/ptv.c). OpenEXR (POV-Ray's +FE output) and
# libpng (the report's images) are optional: found with pkg-config, else left out (the scene
# tests still run; the POV-Ray comparisons print SKIP). Only OpenEXR's C library is linked.
PTV_EXR_LIBS ?= -lOpenEXRCore-3_1
PTV_HAVE_EXR := $(shell pkg-config --exists OpenEXR 2>/dev/null && echo yes)
PTV_HAVE_PNG := $(shell pkg-config --exists libpng 2>/dev/null && echo yes)
PTV_CPPFLAGS :=
PTV_LDLIBS   :=
ifeq ($(PTV_HAVE_EXR),yes)
PTV_CPPFLAGS += -DPTV_HAVE_EXR $(patsubst -I%,-isystem %,$(shell pkg-config --cflags-only-I OpenEXR))
PTV_LDLIBS   += $(PTV_EXR_LIBS)
endif
ifeq ($(PTV_HAVE_PNG),yes)
PTV_CPPFLAGS += -DPTV_HAVE_PNG $(shell pkg-config --cflags libpng)
PTV_LDLIBS   += $(shell pkg-config --libs libpng)
endif

$(BUILD)/ptv: validation/ptv.c validation/ptv_common.h $(PT_HEADERS) | $(BUILD)
	$(CC) $(PT_CPPFLAGS) $(PTV_CPPFLAGS) $(CPPFLAGS) $(CFLAGS) $(PT_THREADS) $(LDFLAGS) -o $@ $< $(LDLIBS) $(PTV_LDLIBS) $(PT_LDLIBS)

# scenes/mesh.obj is committed; this remakes it.
scenes/mesh.obj: validation/gen_mesh.c | $(BUILD)
	$(CC) $(CFLAGS) -o $(BUILD)/gen_mesh $< -lm
	$(BUILD)/gen_mesh $@

validate: $(BUILD)/ptv $(BUILD)/pdftrace
	@test "$(PTV_HAVE_EXR)" = yes || { echo "make validate: needs OpenEXR (apt-get install libopenexr-dev)" >&2; exit 1; }
	$(MITSUBA_ENV) validation/validate.sh $(BUILD)/ptv validation/out

# ---- Mitsuba 3 as the second reference (validation/mitsuba_render.py renders the XML that
# pdftrace --export-mitsuba writes). Optional like POV-Ray: without the venv every Mitsuba
# row prints SKIP. The version is pinned to major.minor; DRJIT_LIBLLVM_PATH is found at run time.
MITSUBA_VENV    ?= $(BUILD)/mitsuba-venv
MITSUBA_VERSION ?= 3.9.*
MITSUBA_ENV      = PDFTRACE=$(BUILD)/pdftrace MITSUBA_PY=$(MITSUBA_VENV)/bin/python
VALIDATE_SCENES ?=
VALIDATE_CI_SCENES ?= direct-quad glass cornell cornell-guided lights env rough-metal rough-plastic rough-glass textured

mitsuba-install:
	@command -v python3 >/dev/null || { echo "make mitsuba-install: needs python3 (apt-get install python3 python3-venv)" >&2; exit 1; }
	@test -x $(MITSUBA_VENV)/bin/python || python3 -c 'import venv, ensurepip' 2>/dev/null || \
	    { echo "make mitsuba-install: python3 cannot make a venv (apt-get install python3-venv)" >&2; exit 1; }
	test -x $(MITSUBA_VENV)/bin/python || python3 -m venv $(MITSUBA_VENV)
	$(MITSUBA_VENV)/bin/python -m pip install --disable-pip-version-check -q 'mitsuba==$(MITSUBA_VERSION)'
	$(MITSUBA_VENV)/bin/python validation/mitsuba_render.py --check

validate-mitsuba: $(BUILD)/ptv $(BUILD)/pdftrace
	$(MITSUBA_ENV) validation/validate.sh $(BUILD)/ptv validation/out --mitsuba-only $(VALIDATE_SCENES)

validate-mitsuba-ci: $(BUILD)/ptv $(BUILD)/pdftrace
	$(MITSUBA_ENV) validation/validate.sh $(BUILD)/ptv $(BUILD)/validate-mitsuba-ci --mitsuba-only $(VALIDATE_CI_SCENES)

validate-refs: $(BUILD)/ptv
	validation/validate-refs.sh $(BUILD)/ptv

# ---- benchmarks (bench/bench.c): error against time for every scene and strategy, POV-Ray on
# the same axes, adaptive sampling, the scene-feature skips. Built like ptv (OpenEXR and libpng
# when present; without OpenEXR the POV-Ray part SKIPs). gnuplot (gnuplot-nox) draws the plots;
# without it the plots SKIP and the data and plots.gp are still written.
BENCH_OUT  ?= bench/out
BENCH_ARGS ?=
# Mitsuba 3 on the same axes (bench/mitsuba_series.py run by the venv's Python; without it the
# Mitsuba parts SKIP with the install command). The headline's 600x600 reference is cached here.
BENCH_MITSUBA = --mitsuba-python $(MITSUBA_VENV)/bin/python --cache $(BUILD)/bench-cache

$(BUILD)/bench: bench/bench.c validation/ptv_common.h $(PT_HEADERS) | $(BUILD)
	$(CC) $(PT_CPPFLAGS) $(PTV_CPPFLAGS) $(CPPFLAGS) $(CFLAGS) $(PT_THREADS) $(LDFLAGS) -o $@ $< $(LDLIBS) $(PTV_LDLIBS) $(PT_LDLIBS)

bench: $(BUILD)/bench
	./$(BUILD)/bench run --out $(BENCH_OUT) $(BENCH_MITSUBA) $(BENCH_ARGS)

bench-quick: $(BUILD)/bench
	./$(BUILD)/bench run --quick --out $(BUILD)/bench-quick $(BENCH_MITSUBA) $(BENCH_ARGS)

bench-headline: $(BUILD)/bench
	./$(BUILD)/bench run --parts headline --out $(BUILD)/bench-headline $(BENCH_MITSUBA) $(BENCH_ARGS)

bench-refs: $(BUILD)/bench
	./$(BUILD)/bench refs

# make test builds its programs TEST_JOBS at a time, then runs the runners TEST_JOBS at a time
# through tests/run_jobs.sh (the machine this targets has two cores): the scene-file runner
# (malformed inputs, scenes/ loading, scenes/cornell.scene through build/pdftrace = build/cornell's
# built-in box, and the fast POV-Ray comparisons when povray is installed), the pdftrace command's
# tests (tests/cli/pdftrace.sh: outputs, errors, help, --export-pov, --preview-every, overrides),
# the fuzz corpus replay (tests/fuzz/corpus, with FP traps where glibc has them, and under
# ASan+UBSan), the FP-trap renders of the scene suite, and the unit-test runners: plain, without
# threads, and under ASan+UBSan (gcc, and clang when installed), each sanitizer runner in two
# parts (the pdf section, the rest) so the two cores end together, and the vector-against-scalar
# sections built for this CPU in GNU C (test_runner_fma). The jobs are listed longest
# first; the logs are printed in that order, and the last line adds up every job's
# "N passed, M failed, K skipped".
TEST_JOBS ?= 2
SAN_ENV := ASAN_OPTIONS=detect_leaks=1:abort_on_error=0 UBSAN_OPTIONS=print_stacktrace=1
TEST_BINS := $(BUILD)/ptv $(BUILD)/pdftrace $(BUILD)/cornell $(BUILD)/test_runner $(BUILD)/test_runner_nothreads \
      $(BUILD)/test_runner_asan $(if $(SAN_CLANG_PATH),$(BUILD)/test_runner_asan_clang) $(BUILD)/fuzz_replay \
      $(BUILD)/fuzz_replay_asan $(BUILD)/fptrap $(BUILD)/test_runner_fma
CLANG_SAN_JOBS := $(if $(SAN_CLANG_PATH),\
    asan-clang-rest '$(SAN_ENV) ./$(BUILD)/test_runner_asan_clang --skip pdf.',\
    asan-clang 'echo "SKIP the clang ASan+UBSan runner: $(SAN_CLANG) is not installed (apt-get install clang)"; echo "0 passed, 0 failed, 1 skipped"')
test-bins: $(TEST_BINS)

test:
	@$(MAKE) --no-print-directory -j$(TEST_JOBS) test-bins
	mkdir -p $(BUILD)/ptv-work
	tests/run_jobs.sh $(TEST_JOBS) $(BUILD)/test-logs \
	    asan-gcc-rest '$(SAN_ENV) ./$(BUILD)/test_runner_asan --skip pdf.' \
	    nothreads './$(BUILD)/test_runner_nothreads' \
	    $(CLANG_SAN_JOBS) \
	    plain './$(BUILD)/test_runner' \
	    asan-gcc-pdf '$(SAN_ENV) ./$(BUILD)/test_runner_asan pdf.' \
	    $(if $(SAN_CLANG_PATH),asan-clang-pdf '$(SAN_ENV) ./$(BUILD)/test_runner_asan_clang pdf.') \
	    scenes './$(BUILD)/ptv test scenes $(BUILD)/ptv-work $(BUILD)/pdftrace $(BUILD)/cornell' \
	    fuzz-asan '$(SAN_ENV) ./$(BUILD)/fuzz_replay_asan tests/fuzz/corpus' \
	    cli 'tests/cli/pdftrace.sh $(BUILD)/pdftrace scenes $(BUILD)/cli-work' \
	    fuzz 'PT_FUZZ_FPTRAP=1 ./$(BUILD)/fuzz_replay tests/fuzz/corpus' \
	    fptrap './$(BUILD)/fptrap scenes/*.scene' \
	    fma './$(BUILD)/test_runner_fma render.batched internals.'

# ---- make stress: the numerical stress cases at full size (tests/stress/; the same cases run
# small in the runner's `stress` section). Prints case | metric | bound | result; non-zero exit
# on any failing row. STRESS_ARGS: a case filter (sweep, spawn, tiny, watertight, edges, lights, slivers, guiding,
# degenerate).
STRESS_SRCS := tests/stress/stress_main.c tests/stress/stress_cases.c tests/test_util.c
STRESS_ARGS ?=

$(BUILD)/stress: $(STRESS_SRCS) $(TEST_HDRS) $(PT_HEADERS) | $(BUILD)
	$(CC) $(PT_CPPFLAGS) $(CPPFLAGS) $(CFLAGS) $(PT_THREADS) $(LDFLAGS) -o $@ $(STRESS_SRCS) $(LDLIBS) $(PT_LDLIBS)

stress: $(BUILD)/stress
	./$(BUILD)/stress $(STRESS_ARGS)

nothreads-test: $(BUILD)/test_runner_nothreads
	./$(BUILD)/test_runner_nothreads

$(BUILD)/test_runner_tsan: $(TEST_SRCS) $(TEST_HDRS) $(PT_HEADERS) $(OPT_STAMP) | $(BUILD)
	$(need_tests)
	$(CC) $(PT_CPPFLAGS) $(CPPFLAGS) $(CFLAGS) $(TSANFLAGS) $(PT_THREADS) $(LDFLAGS) -o $@ $(TEST_SRCS) $(LDLIBS) $(PT_LDLIBS)

# A reported race fails the run (exit code 66).
tsan-test: $(BUILD)/test_runner_tsan
	@set -e; for f in $(TSAN_TESTS); do \
	    echo "TSAN_OPTIONS=halt_on_error=1 ./$(BUILD)/test_runner_tsan $$f"; \
	    TSAN_OPTIONS=halt_on_error=1 ./$(BUILD)/test_runner_tsan $$f; \
	done

# Only the pdftrace command's tests (part of make test).
cli-test: $(BUILD)/pdftrace
	tests/cli/pdftrace.sh $(BUILD)/pdftrace scenes $(BUILD)/cli-work

# ---- make bench-bvh (bench/bvh.c): always built with Embree, whatever EMBREE says.
BENCH_BVH_ARGS ?=
$(BUILD)/bench_bvh: bench/bvh.c $(PT_HEADERS) | $(BUILD)
	@test -f "$(EMBREE_HEADER)" || { echo "make bench-bvh: needs Embree 3 (apt-get install libembree-dev)" >&2; exit 1; }
	$(CC) -I. $(EMBREE_FLAGS) $(CPPFLAGS) $(CFLAGS) $(PT_THREADS) $(LDFLAGS) -o $@ $< $(LDLIBS) $(EMBREE_LIBS) -lm

bench-bvh: $(BUILD)/bench_bvh
	./$(BUILD)/bench_bvh $(BENCH_BVH_ARGS) bench/out

# rays/s of the built-in BVH at each SIMD level (scalar, SSE2 4-wide, AVX2 8-wide, AVX-512 16-wide)
bench-simd: $(BUILD)/bench_bvh
	./$(BUILD)/bench_bvh --levels $(BENCH_BVH_ARGS) bench/out

# ---- make bench-batched (bench/batched.c): samples/s of the scalar and the batched integrator,
# paired; with EMBREE=1 the Embree backend too.
BENCH_BATCHED_ARGS ?=
$(BUILD)/bench_batched: bench/batched.c $(PT_HEADERS) $(OPT_STAMP) | $(BUILD)
	$(CC) -I. $(if $(filter 1,$(EMBREE)),$(EMBREE_FLAGS)) $(CPPFLAGS) $(CFLAGS) $(PT_THREADS) $(LDFLAGS) -o $@ $< $(LDLIBS) $(if $(filter 1,$(EMBREE)),$(EMBREE_LIBS)) -lm

bench-batched: $(BUILD)/bench_batched
	./$(BUILD)/bench_batched $(if $(filter 1,$(EMBREE)),--embree) $(BENCH_BATCHED_ARGS) bench/out

# ---- warnings: each example is a complete program with the implementation included.
# The PDFTRACE_STATIC build is checked too (its functions are marked unused under gcc/clang,
# so a file need not call every one).

check-warnings: | $(BUILD)
	@echo "tests/lint_headers.sh $(PT_HEADERS) (comments <= 25 lines after IMPLEMENTATION, functions <= 150 lines)"
	@sh tests/lint_headers.sh $(PT_HEADERS)
	@set -e; for cc in $(WARN_CC); do \
	    for ex in $(EXAMPLES); do \
	        echo "$$cc $(WARN_CFLAGS) examples/$$ex.c"; \
	        $$cc $(WARN_CFLAGS) $(PT_CPPFLAGS) $(PT_THREADS) -c examples/$$ex.c -o $(BUILD)/warn-$$cc-$$ex.o; \
	    done; \
	    echo "$$cc $(WARN_CFLAGS) -DPDFTRACE_NO_THREADS -DPDFTRACE_NO_SIMD examples/minimal.c"; \
	    $$cc $(WARN_CFLAGS) -DPDFTRACE_NO_THREADS -DPDFTRACE_NO_SIMD $(PT_CPPFLAGS) -c examples/minimal.c -o $(BUILD)/warn-$$cc-nothreads.o; \
	    for o in -O1 -Og -Os; do \
	        echo "$$cc $(WARN_CFLAGS) $$o tools/pdftrace.c (other optimisation levels: other flow analysis)"; \
	        $$cc $(WARN_CFLAGS) $$o $(PT_CPPFLAGS) $(PT_THREADS) -c tools/pdftrace.c -o $(BUILD)/warn-$$cc-tool$$o.o; \
	    done; \
	    echo "$$cc $(WARN_CFLAGS) -DPDFTRACE_STATIC examples/minimal.c"; \
	    $$cc $(WARN_CFLAGS) -DPDFTRACE_STATIC $(PT_CPPFLAGS) $(PT_THREADS) -c examples/minimal.c -o $(BUILD)/warn-$$cc-static.o; \
	    echo "$$cc $(WARN_CFLAGS) bench/bench.c (with and without OpenEXR/libpng)"; \
	    $$cc $(WARN_CFLAGS) $(PT_CPPFLAGS) $(PT_THREADS) -c bench/bench.c -o $(BUILD)/warn-$$cc-bench.o; \
	    $$cc $(WARN_CFLAGS) $(PT_CPPFLAGS) $(PTV_CPPFLAGS) $(PT_THREADS) -c bench/bench.c -o $(BUILD)/warn-$$cc-bench-libs.o; \
	done; \
	for cc in $(WARN_CC); do \
	    echo "$$cc $(WARN_CFLAGS) tests/fuzz/harness.c tests/fuzz/replay.c tests/fptrap/fptrap.c"; \
	    $$cc $(WARN_CFLAGS) -I. -Itests/fuzz $(PT_THREADS) -c tests/fuzz/harness.c -o $(BUILD)/warn-$$cc-fuzz-harness.o; \
	    $$cc $(WARN_CFLAGS) -I. -Itests/fuzz -c tests/fuzz/replay.c -o $(BUILD)/warn-$$cc-fuzz-replay.o; \
	    $$cc $(WARN_CFLAGS) -I. -Itests/fuzz -c tests/fuzz/fuzz_target.c -DPT_FUZZ_ENTRY=pt_fuzz_scene -o $(BUILD)/warn-$$cc-fuzz-target.o; \
	    $$cc $(WARN_CFLAGS) -I. $(PT_THREADS) -c tests/fptrap/fptrap.c -o $(BUILD)/warn-$$cc-fptrap.o; \
	    echo "$$cc $(WARN_CFLAGS) tests/stress/*.c (make stress)"; \
	    for f in tests/stress/stress_main.c tests/stress/stress_cases.c; do \
	        $$cc $(WARN_CFLAGS) $(PT_CPPFLAGS) $(PT_THREADS) -c $$f -o $(BUILD)/warn-$$cc-$$(basename $$f .c).o; \
	    done; \
	done; \
	for cxx in $(WARN_CXX); do \
	    echo "$$cxx $(WARN_CXXFLAGS) examples/cpp_check.cpp (then run it)"; \
	    $$cxx $(WARN_CXXFLAGS) $(PT_CPPFLAGS) $(PT_THREADS) examples/cpp_check.cpp -o $(BUILD)/cpp_check-$$cxx $(PT_LDLIBS); \
	    ./$(BUILD)/cpp_check-$$cxx; \
	done; \
	if [ -f "$(patsubst -I%,%,$(firstword $(EXR_INCLUDES)))/openexr.h" ]; then \
	    for cc in $(WARN_CC); do \
	        echo "$$cc $(WARN_CFLAGS) -DPDFTRACE_OPENEXR tools/pdftrace.c tests/test_exr.c"; \
	        $$cc $(WARN_CFLAGS) -I. $(EXR_FLAGS) $(PT_THREADS) -c tools/pdftrace.c -o $(BUILD)/warn-$$cc-exr.o; \
	        $$cc $(WARN_CFLAGS) -I. $(EXR_FLAGS) -c tests/test_exr.c -o $(BUILD)/warn-$$cc-test-exr.o; \
	        $$cc $(WARN_CFLAGS) -I. -Itests/fuzz $(EXR_FLAGS) $(PT_THREADS) -c tests/fuzz/harness.c -o $(BUILD)/warn-$$cc-fuzz-harness-exr.o; \
	    done; \
	    for cxx in $(WARN_CXX); do \
	        echo "$$cxx $(WARN_CXXFLAGS) -DPDFTRACE_OPENEXR examples/cpp_check.cpp (pdftrace_exr.h as C++)"; \
	        $$cxx $(WARN_CXXFLAGS) -I. $(EXR_FLAGS) $(PT_THREADS) -c examples/cpp_check.cpp -o $(BUILD)/cpp_check-exr-$$cxx.o; \
	    done; \
	else \
	    echo "SKIP the PDFTRACE_OPENEXR variants: no openexr.h (apt-get install libopenexr-dev)"; \
	fi; \
	if [ -f "$(EMBREE_HEADER)" ]; then \
	    for cc in $(WARN_CC); do \
	        echo "$$cc $(WARN_CFLAGS) -DPDFTRACE_EMBREE examples/cornell.c tests/test_embree.c (then link)"; \
	        $$cc $(WARN_CFLAGS) -I. $(EMBREE_FLAGS) $(PT_THREADS) examples/cornell.c -o $(BUILD)/warn-$$cc-embree $(EMBREE_LIBS) -lm; \
	        $$cc $(WARN_CFLAGS) -I. $(EMBREE_FLAGS) -c tests/test_embree.c -o $(BUILD)/warn-$$cc-test-embree.o; \
	        echo "$$cc $(WARN_CFLAGS) -DPDFTRACE_EMBREE bench/bvh.c"; \
	        $$cc $(WARN_CFLAGS) -I. $(EMBREE_FLAGS) $(PT_THREADS) -c bench/bvh.c -o $(BUILD)/warn-$$cc-bench-bvh.o; \
	        echo "$$cc $(WARN_CFLAGS) -DPDFTRACE_EMBREE -DPDFTRACE_NO_THREADS -DPDFTRACE_STATIC examples/minimal.c"; \
	        $$cc $(WARN_CFLAGS) -I. $(EMBREE_FLAGS) -DPDFTRACE_NO_THREADS -DPDFTRACE_STATIC -c examples/minimal.c -o $(BUILD)/warn-$$cc-embree-static.o; \
	    done; \
	    for cxx in $(WARN_CXX); do \
	        echo "$$cxx $(WARN_CXXFLAGS) -DPDFTRACE_EMBREE examples/cpp_check.cpp (the optional Embree section; then run it)"; \
	        $$cxx $(WARN_CXXFLAGS) -I. $(EMBREE_FLAGS) $(PT_THREADS) examples/cpp_check.cpp -o $(BUILD)/cpp_check-embree-$$cxx $(EMBREE_LIBS) -lm; \
	        ./$(BUILD)/cpp_check-embree-$$cxx; \
	    done; \
	else \
	    echo "SKIP the PDFTRACE_EMBREE variants: no $(EMBREE_HEADER) (apt-get install libembree-dev)"; \
	fi; \
	echo "tools/pdftrace.c without PNG and OpenEXR, and the PDFTRACE_PNG variants (pdftrace_png.h):"; \
	for cc in $(WARN_CC); do \
	    echo "$$cc $(WARN_CFLAGS) tools/pdftrace.c"; \
	    $$cc $(WARN_CFLAGS) -I. $(PT_THREADS) -c tools/pdftrace.c -o $(BUILD)/warn-$$cc-tool.o; \
	done; \
	if [ -n "$(PNG_FOUND)" ]; then \
	    for cc in $(WARN_CC); do \
	        echo "$$cc $(WARN_CFLAGS) -DPDFTRACE_PNG tools/pdftrace.c (and with OpenEXR) examples/cornell.c tests/test_output.c"; \
	        $$cc $(WARN_CFLAGS) -I. $(PNG_FLAGS) $(PT_THREADS) -c tools/pdftrace.c -o $(BUILD)/warn-$$cc-tool-png.o; \
	        if [ -f "$(patsubst -I%,%,$(firstword $(EXR_INCLUDES)))/openexr.h" ]; then \
	            $$cc $(WARN_CFLAGS) -I. $(PNG_FLAGS) $(EXR_FLAGS) $(PT_THREADS) -c tools/pdftrace.c -o $(BUILD)/warn-$$cc-tool-png-exr.o; \
	        fi; \
	        $$cc $(WARN_CFLAGS) -I. $(PNG_FLAGS) $(PT_THREADS) -c examples/cornell.c -o $(BUILD)/warn-$$cc-cornell-png.o; \
	        $$cc $(WARN_CFLAGS) -I. $(PNG_FLAGS) -c tests/test_output.c -o $(BUILD)/warn-$$cc-test-output-png.o; \
	    done; \
	    for cxx in $(WARN_CXX); do \
	        echo "$$cxx $(WARN_CXXFLAGS) -DPDFTRACE_PNG examples/cpp_check.cpp (pdftrace_png.h as C++; then run it)"; \
	        $$cxx $(WARN_CXXFLAGS) -I. $(PNG_FLAGS) $(PT_THREADS) examples/cpp_check.cpp -o $(BUILD)/cpp_check-png-$$cxx $(PNG_LIBS) -lm; \
	        ./$(BUILD)/cpp_check-png-$$cxx; \
	    done; \
	else \
	    echo "SKIP the PDFTRACE_PNG variants: pkg-config finds no libpng (apt-get install libpng-dev)"; \
	fi; \
	if [ -n "$(MPI_FOUND)" ]; then \
	    for cc in $(WARN_CC); do \
	        echo "$$cc $(WARN_CFLAGS) -DPDFTRACE_MPI tools/pdftrace.c bench/mpi_gather.c (pdftrace_mpi.h)"; \
	        $$cc $(WARN_CFLAGS) -I. -DPDFTRACE_MPI $(MPI_CFLAGS) $(PT_THREADS) -c tools/pdftrace.c -o $(BUILD)/warn-$$cc-tool-mpi.o; \
	        $$cc $(WARN_CFLAGS) -I. $(MPI_CFLAGS) $(PT_THREADS) -c bench/mpi_gather.c -o $(BUILD)/warn-$$cc-mpi-gather.o; \
	    done; \
	    for cxx in $(WARN_CXX); do \
	        echo "$$cxx $(WARN_CXXFLAGS) pdftrace_mpi.h as C++"; \
	        printf '#define PDFTRACE_IMPLEMENTATION\n#define PDFTRACE_MPI_IMPLEMENTATION\n#include "pdftrace_mpi.h"\n' | \
	            $$cxx $(WARN_CXXFLAGS) -I. $(MPI_CFLAGS) $(PT_THREADS) -c - -o $(BUILD)/warn-$$cxx-mpi.o; \
	    done; \
	else \
	    echo "SKIP the PDFTRACE_MPI variants: no $(MPICC) ($(MPI_INSTALL))"; \
	fi; \
	echo "the family headers' implementations in files of their own, linked with the core's:"; \
	for cc in $(WARN_CC); do \
	    printf '#define PDFTRACE_SCENE_IMPLEMENTATION\n#include "pdftrace_scene.h"\n' | \
	        $$cc $(WARN_CFLAGS) -I. -x c -c - -o $(BUILD)/warn-$$cc-scene-alone.o; \
	    $$cc $(WARN_CFLAGS) -I. $(PT_THREADS) -c examples/minimal.c -o $(BUILD)/warn-$$cc-core-alone.o; \
	    $$cc $(PT_THREADS) -o $(BUILD)/warn-$$cc-family $(BUILD)/warn-$$cc-core-alone.o $(BUILD)/warn-$$cc-scene-alone.o -lm; \
	    if [ -f "$(patsubst -I%,%,$(firstword $(EXR_INCLUDES)))/openexr.h" ]; then \
	        printf '#define PDFTRACE_EXR_IMPLEMENTATION\n#include "pdftrace_exr.h"\n' | \
	            $$cc $(WARN_CFLAGS) -I. $(EXR_FLAGS) -x c -c - -o $(BUILD)/warn-$$cc-exr-alone.o; \
	    fi; \
	    if [ -n "$(PNG_FOUND)" ]; then \
	        printf '#define PDFTRACE_PNG_IMPLEMENTATION\n#include "pdftrace_png.h"\n' | \
	            $$cc $(WARN_CFLAGS) -I. $(PNG_FLAGS) -x c -c - -o $(BUILD)/warn-$$cc-png-alone.o; \
	        $$cc $(PT_THREADS) -o $(BUILD)/warn-$$cc-family-png $(BUILD)/warn-$$cc-core-alone.o $(BUILD)/warn-$$cc-scene-alone.o \
	            $(BUILD)/warn-$$cc-png-alone.o $(PNG_LIBS) -lm; \
	    fi; \
	    echo "  $$cc: pdftrace_scene.h, pdftrace_exr.h and pdftrace_png.h alone: clean; linked with the core: no duplicate symbols"; \
	done; \
	echo "the default build includes no Embree header:"; \
	for cc in $(WARN_CC); do \
	    if $$cc -M -I. $(PT_THREADS) examples/cornell.c tools/pdftrace.c tests/test_main.c | grep -i embree; then \
	        echo "FAILED: $$cc's default build of pdftrace.h includes an Embree header" >&2; exit 1; \
	    fi; \
	done; \
	echo "  no embree in the dependencies of examples/cornell.c, tools/pdftrace.c and tests/test_main.c"; \
	echo "check-warnings: all clean"

# ---- make install: the headers, the pdftrace command and a pkg-config file. The library is
# header-only, so the .pc file has no library to link, only what the implementation needs.
PREFIX  ?= /usr/local
DESTDIR ?=
INSTALL ?= install
INSTALL_HEADERS := $(wildcard pdftrace*.h)
# every header install may have written, for uninstall (also those not in this tree)
UNINSTALL_HEADERS := $(sort $(notdir $(INSTALL_HEADERS)) pdftrace.h pdftrace_scene.h pdftrace_exr.h)
# The command is installed once its source exists; $(BUILD)/pdftrace is built from tools/pdftrace.c.
INSTALL_BIN := $(if $(wildcard tools/pdftrace.c),$(BUILD)/pdftrace)
pt_version_part = $(shell awk '$$1 ~ /define$$/ && $$2 == "PDFTRACE_VERSION_$(1)" { print $$3 }' pdftrace.h)
PT_VERSION := $(call pt_version_part,MAJOR).$(call pt_version_part,MINOR).$(call pt_version_part,PATCH)

install: $(INSTALL_BIN) | $(BUILD)
	@test -n "$(INSTALL_HEADERS)" || { echo "make install: no pdftrace*.h here" >&2; exit 1; }
	printf '%s\n' 'prefix=$(PREFIX)' 'exec_prefix=$${prefix}' 'includedir=$${prefix}/include' \
	    'bindir=$${exec_prefix}/bin' '' 'Name: pdftrace' \
	    'Description: Monte Carlo path tracer built around probability density functions (header-only C99)' \
	    'Version: $(PT_VERSION)' 'Cflags: -I$${includedir}' \
	    'Libs: -lm -pthread' > $(BUILD)/pdftrace.pc
	$(INSTALL) -d '$(DESTDIR)$(PREFIX)/include' '$(DESTDIR)$(PREFIX)/lib/pkgconfig'
	$(INSTALL) -m 644 $(INSTALL_HEADERS) '$(DESTDIR)$(PREFIX)/include/'
	$(INSTALL) -m 644 $(BUILD)/pdftrace.pc '$(DESTDIR)$(PREFIX)/lib/pkgconfig/pdftrace.pc'
ifneq ($(INSTALL_BIN),)
	$(INSTALL) -d '$(DESTDIR)$(PREFIX)/bin'
	$(INSTALL) -m 755 $(INSTALL_BIN) '$(DESTDIR)$(PREFIX)/bin/pdftrace'
endif

uninstall:
	rm -f $(UNINSTALL_HEADERS:%='$(DESTDIR)$(PREFIX)/include/%') '$(DESTDIR)$(PREFIX)/bin/pdftrace' \
	    '$(DESTDIR)$(PREFIX)/lib/pkgconfig/pdftrace.pc'

install-check:
	MAKE='$(MAKE)' CC='$(CC)' BUILD='$(BUILD)' tests/install/check.sh

clean:
	rm -rf $(BUILD) $(OUT)

help:
	@sed -n '2,/^$$/p' Makefile | sed -n 's/^# \{0,1\}//p'

# ---- fuzzing (tests/fuzz/, issue 7). libFuzzer targets need clang with -fsanitize=fuzzer
# (Debian: clang and libclang-rt-14-dev); the EXR target needs libopenexr-dev (skipped without
# it). The corpus replay is built with the normal compiler and runs inside make test.
FUZZ_CC      ?= clang
FUZZ_SECONDS ?= 60
FUZZ_FLAGS   ?= -std=c99 -O1 -g -ftrapping-math -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=all
# Programs that run with FP traps enabled (the replay, fptrap): gcc's default; clang's default
# FP model ("ignore exceptions") may divide in unused SIMD lanes (0/0 in the padding lanes of
# a vectorised 1/dir) and trap where the source does not.
FPTRAP_FLAGS ?= -ftrapping-math
FUZZ_ARGS    ?= -timeout=10 -rss_limit_mb=2048 -print_final_stats=1
FUZZ_HAVE_EXR := $(shell [ -f "$(patsubst -I%,%,$(firstword $(EXR_INCLUDES)))/openexr.h" ] && echo yes)
FUZZ_TARGETS := scene obj pov $(if $(FUZZ_HAVE_EXR),exr)
FUZZ_SRCS    := tests/fuzz/harness.c tests/fuzz/harness.h tests/fuzz/pov_check.h tests/fuzz/mitsuba_check.h
FUZZ_MAXLEN_scene := 8192
FUZZ_MAXLEN_obj   := 16384
FUZZ_MAXLEN_pov   := 8192
FUZZ_MAXLEN_exr   := 16384
FUZZ_DICT_scene := -dict=tests/fuzz/scene.dict
FUZZ_DICT_obj   := -dict=tests/fuzz/obj.dict
FUZZ_DICT_pov   := -dict=tests/fuzz/scene.dict
FUZZ_DICT_exr   :=

.PHONY: fuzz fuzz-build fuzz-merge fptrap-test

$(BUILD)/fuzz_%: tests/fuzz/fuzz_target.c $(FUZZ_SRCS) $(PT_HEADERS) | $(BUILD)
	$(FUZZ_CC) $(FUZZ_FLAGS) -I. -Itests/fuzz $(if $(FUZZ_HAVE_EXR),$(EXR_FLAGS)) -DPT_FUZZ_ENTRY=pt_fuzz_$* \
	    -o $@ tests/fuzz/harness.c tests/fuzz/fuzz_target.c $(if $(FUZZ_HAVE_EXR),$(EXR_LIBS)) -lm -pthread

fuzz-build: $(FUZZ_TARGETS:%=$(BUILD)/fuzz_%)

# Every target runs even if an earlier one found a crash; the exit status says whether any did.
# FE_INVALID and FE_DIVBYZERO trap (glibc) unless FUZZ_FPTRAP=0. One target: FUZZ_TARGETS=pov.
FUZZ_FPTRAP ?= 1
fuzz: fuzz-build
	@status=0; for t in $(FUZZ_TARGETS); do \
	    mkdir -p $(BUILD)/fuzz-corpus/$$t $(BUILD)/fuzz-artifacts; \
	    seeds=; case $$t in scene) ml=$(FUZZ_MAXLEN_scene); d='$(FUZZ_DICT_scene)';; obj) ml=$(FUZZ_MAXLEN_obj); d='$(FUZZ_DICT_obj)';; \
	                pov) ml=$(FUZZ_MAXLEN_pov); d='$(FUZZ_DICT_pov)'; seeds=tests/fuzz/corpus/scene;; \
	                *) ml=$(FUZZ_MAXLEN_exr); d='$(FUZZ_DICT_exr)';; esac; \
	    echo "== fuzz $$t for $(FUZZ_SECONDS) s"; \
	    PT_FUZZ_FPTRAP=$(FUZZ_FPTRAP) ./$(BUILD)/fuzz_$$t -max_total_time=$(FUZZ_SECONDS) -max_len=$$ml $$d $(FUZZ_ARGS) \
	        -artifact_prefix=$(BUILD)/fuzz-artifacts/$$t- $(BUILD)/fuzz-corpus/$$t tests/fuzz/corpus/$$t $$seeds || status=1; \
	done; \
	if [ $$status != 0 ]; then echo "make fuzz: crashes in $(BUILD)/fuzz-artifacts/"; ls $(BUILD)/fuzz-artifacts; fi; \
	exit $$status

fuzz-merge: fuzz-build
	@set -e; for t in $(FUZZ_TARGETS); do \
	    rm -rf $(BUILD)/fuzz-merge-$$t; mkdir -p $(BUILD)/fuzz-merge-$$t $(BUILD)/fuzz-corpus/$$t; \
	    ./$(BUILD)/fuzz_$$t -set_cover_merge=1 $(BUILD)/fuzz-merge-$$t tests/fuzz/corpus/$$t $(BUILD)/fuzz-corpus/$$t; \
	    echo "fuzz-merge $$t: $$(ls $(BUILD)/fuzz-merge-$$t | wc -l) files in $(BUILD)/fuzz-merge-$$t (review, then copy)"; \
	done

# Corpus replay: the harnesses on every committed input, normal compiler / ASan+UBSan / EXR.
FUZZ_REPLAY_SRCS := tests/fuzz/replay.c tests/fuzz/harness.c
$(BUILD)/fuzz_replay: $(FUZZ_REPLAY_SRCS) $(FUZZ_SRCS) $(PT_HEADERS) $(OPT_STAMP) | $(BUILD)
	$(CC) $(PT_CPPFLAGS) -Itests/fuzz $(CPPFLAGS) $(CFLAGS) $(FPTRAP_FLAGS) $(PT_THREADS) $(LDFLAGS) -o $@ $(FUZZ_REPLAY_SRCS) $(LDLIBS) $(PT_LDLIBS)
$(BUILD)/fuzz_replay_asan: $(FUZZ_REPLAY_SRCS) $(FUZZ_SRCS) $(PT_HEADERS) $(OPT_STAMP) | $(BUILD)
	$(CC) $(PT_CPPFLAGS) -Itests/fuzz $(CPPFLAGS) $(CFLAGS) $(SANFLAGS) $(PT_THREADS) $(LDFLAGS) -o $@ $(FUZZ_REPLAY_SRCS) $(LDLIBS) $(PT_LDLIBS)
$(BUILD)/fuzz_replay_exr: $(FUZZ_REPLAY_SRCS) $(FUZZ_SRCS) $(PT_HEADERS) | $(BUILD)
	$(CC) -I. -Itests/fuzz $(EXR_FLAGS) $(CPPFLAGS) $(CFLAGS) $(PT_THREADS) $(LDFLAGS) -o $@ $(FUZZ_REPLAY_SRCS) $(LDLIBS) $(EXR_LIBS) -lm

# FP-trap test (issue 7 item 6): scene files and built-in scenes with FE_INVALID|FE_DIVBYZERO
# trapping. Built with the normal compiler and flags (what users run).
$(BUILD)/fptrap: tests/fptrap/fptrap.c $(PT_HEADERS) | $(BUILD)
	$(CC) -I. $(CPPFLAGS) $(CFLAGS) $(FPTRAP_FLAGS) -g $(PT_THREADS) $(LDFLAGS) -o $@ $< $(LDLIBS) -lm

fptrap-test: $(BUILD)/fptrap
	./$(BUILD)/fptrap scenes/*.scene
