# pdftrace - examples, tests and checks.
#
#   make                  build the examples into build/
#   make run              render the default Cornell box to out/cornell.ppm and out/cornell.pfm
#   make run-all          also render the other examples into out/
#   make test             build and run the test runner, then again without threads and
#                         under AddressSanitizer + UndefinedBehaviorSanitizer
#   make nothreads-test   only the test runner built with -DPDFTRACE_NO_THREADS
#   make exr-test         build the test runner with OpenEXR (build/test_runner_exr) and run
#                         its exr section (needs libopenexr-dev)
#   make OPENEXR=1 ...    build the examples and test runners with PDFTRACE_OPENEXR (EXR output
#                         and input through OpenEXRCore; needs libopenexr-dev). Default 0.
#   make EMBREE=1 ...     build the examples and test runners with PDFTRACE_EMBREE (Embree 3
#                         traversal, pdftrace.h section 5b; needs libembree-dev). Default 0.
#                         Either or both: make OPENEXR=1 EMBREE=1 test (use a separate BUILD=
#                         per combination, or let the options stamp rebuild on a change).
#   make check-warnings   compile the examples (and so the implementation) with gcc and clang
#                         at -std=c99 -Wall -Wextra -pedantic -Werror, and the header as C++
#   make validate         render every scene in scenes/ with pdftrace and POV-Ray, compare them and
#                         write validation/out/index.html (needs povray, libopenexr-dev, libpng-dev)
#   make validate-refs    re-render the slow POV-Ray references stored in scenes/ref/ (~12 min)
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

# Added to every build: the header lives at the top level; the library wants -lm and pthreads.
PT_CPPFLAGS := -I.
PT_THREADS  ?= -pthread
PT_LDLIBS   := -lm

# The sanitizer build of the tests (added after CFLAGS, so its -O1 wins).
SANFLAGS ?= -O1 -g -fsanitize=address,undefined -fno-sanitize-recover=all

# check-warnings: the compilers and flags it uses.
WARN_CC      ?= gcc clang
WARN_CXX     ?= g++ clang++
WARN_CFLAGS  ?= -std=c99 -O2 -Wall -Wextra -pedantic -Werror
WARN_CXXFLAGS ?= -x c++ -O2 -Wall -Wextra -pedantic -Werror

# make run: samples per pixel and any other options for build/cornell.
RUN_SPP  ?= 128
RUN_ARGS ?=

# OpenEXR (pdftrace.h section 11): only the include dirs of the OpenEXR .pc file are taken
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
# Rebuild the examples and runners when OPENEXR or EMBREE changes (the file is rewritten only then).
OPT_STAMP := $(BUILD)/options
OPT_VALUE := OPENEXR=$(OPENEXR) EMBREE=$(EMBREE)

EXAMPLES     := minimal cornell custom_pdf
EXAMPLE_BINS := $(EXAMPLES:%=$(BUILD)/%)
TEST_SRCS    := $(wildcard tests/*.c)
TEST_HDRS    := $(wildcard tests/*.h)

.PHONY: all run run-all test nothreads-test exr-test check-warnings clean help validate validate-refs FORCE

all: $(EXAMPLE_BINS)

$(BUILD) $(OUT):
	mkdir -p $@

$(OPT_STAMP): FORCE | $(BUILD)
	@echo '$(OPT_VALUE)' | cmp -s - $@ || echo '$(OPT_VALUE)' > $@

$(BUILD)/%: examples/%.c pdftrace.h $(OPT_STAMP) | $(BUILD)
	$(CC) $(PT_CPPFLAGS) $(CPPFLAGS) $(CFLAGS) $(PT_THREADS) $(LDFLAGS) -o $@ $< $(LDLIBS) $(PT_LDLIBS)

run: $(BUILD)/cornell | $(OUT)
	$(BUILD)/cornell --spp $(RUN_SPP) $(RUN_ARGS) -o $(OUT)/cornell.ppm -o $(OUT)/cornell.pfm

run-all: run $(EXAMPLE_BINS) | $(OUT)
	$(BUILD)/minimal $(OUT)/minimal.ppm
	$(BUILD)/custom_pdf $(OUT)/custom_pdf.ppm $(OUT)/custom_pdf_unguided.ppm

# ---- tests: one runner from all tests/*.c (tests/test_main.c defines PDFTRACE_IMPLEMENTATION)

define need_tests
	@test -n "$(TEST_SRCS)" || { echo "error: no tests/*.c found" >&2; exit 1; }
endef

$(BUILD)/test_runner: $(TEST_SRCS) $(TEST_HDRS) pdftrace.h $(OPT_STAMP) | $(BUILD)
	$(need_tests)
	$(CC) $(PT_CPPFLAGS) $(CPPFLAGS) $(CFLAGS) $(PT_THREADS) $(LDFLAGS) -o $@ $(TEST_SRCS) $(LDLIBS) $(PT_LDLIBS)

$(BUILD)/test_runner_asan: $(TEST_SRCS) $(TEST_HDRS) pdftrace.h $(OPT_STAMP) | $(BUILD)
	$(need_tests)
	$(CC) $(PT_CPPFLAGS) $(CPPFLAGS) $(CFLAGS) $(SANFLAGS) $(PT_THREADS) $(LDFLAGS) -o $@ $(TEST_SRCS) $(LDLIBS) $(PT_LDLIBS)

# Without threads: no -pthread at all, to show the library does not need it.
$(BUILD)/test_runner_nothreads: $(TEST_SRCS) $(TEST_HDRS) pdftrace.h $(OPT_STAMP) | $(BUILD)
	$(need_tests)
	$(CC) $(PT_CPPFLAGS) $(CPPFLAGS) -DPDFTRACE_NO_THREADS $(CFLAGS) $(LDFLAGS) -o $@ $(TEST_SRCS) $(LDLIBS) $(PT_LDLIBS)

# Always with OpenEXR, whatever OPENEXR says; `make exr-test` runs only its exr section.
$(BUILD)/test_runner_exr: $(TEST_SRCS) $(TEST_HDRS) pdftrace.h | $(BUILD)
	$(need_tests)
	$(CC) -I. $(EXR_FLAGS) $(CPPFLAGS) $(CFLAGS) $(PT_THREADS) $(LDFLAGS) -o $@ $(TEST_SRCS) $(LDLIBS) $(EXR_LIBS) -lm

exr-test: $(BUILD)/test_runner_exr
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

$(BUILD)/ptv: validation/ptv.c pdftrace.h | $(BUILD)
	$(CC) $(PT_CPPFLAGS) $(PTV_CPPFLAGS) $(CPPFLAGS) $(CFLAGS) $(PT_THREADS) $(LDFLAGS) -o $@ $< $(LDLIBS) $(PTV_LDLIBS) $(PT_LDLIBS)

# scenes/mesh.obj is committed; this remakes it.
scenes/mesh.obj: validation/gen_mesh.c | $(BUILD)
	$(CC) $(CFLAGS) -o $(BUILD)/gen_mesh $< -lm
	$(BUILD)/gen_mesh $@

validate: $(BUILD)/ptv
	@test "$(PTV_HAVE_EXR)" = yes || { echo "make validate: needs OpenEXR (apt-get install libopenexr-dev)" >&2; exit 1; }
	validation/validate.sh $(BUILD)/ptv validation/out

validate-refs: $(BUILD)/ptv
	validation/validate-refs.sh $(BUILD)/ptv

# The sanitizer run comes last, so the last line of `make test` is its "N passed, M failed".
# First the scene-file runner (malformed inputs, scenes/ loading, --scene = built-in box, and
# the fast POV-Ray comparisons when povray is installed).
test: $(BUILD)/ptv $(BUILD)/cornell $(BUILD)/test_runner $(BUILD)/test_runner_nothreads $(BUILD)/test_runner_asan
	mkdir -p $(BUILD)/ptv-work
	./$(BUILD)/ptv test scenes $(BUILD)/ptv-work $(BUILD)/cornell
	./$(BUILD)/test_runner
	./$(BUILD)/test_runner_nothreads
	ASAN_OPTIONS=detect_leaks=1:abort_on_error=0 UBSAN_OPTIONS=print_stacktrace=1 ./$(BUILD)/test_runner_asan

nothreads-test: $(BUILD)/test_runner_nothreads
	./$(BUILD)/test_runner_nothreads

# ---- warnings: each example is a complete program with the implementation included.
# The PDFTRACE_STATIC build is checked too (its functions are marked unused under gcc/clang,
# so a file need not call every one).

check-warnings: | $(BUILD)
	@set -e; for cc in $(WARN_CC); do \
	    for ex in $(EXAMPLES); do \
	        echo "$$cc $(WARN_CFLAGS) examples/$$ex.c"; \
	        $$cc $(WARN_CFLAGS) $(PT_CPPFLAGS) $(PT_THREADS) -c examples/$$ex.c -o $(BUILD)/warn-$$cc-$$ex.o; \
	    done; \
	    echo "$$cc $(WARN_CFLAGS) -DPDFTRACE_NO_THREADS examples/minimal.c"; \
	    $$cc $(WARN_CFLAGS) -DPDFTRACE_NO_THREADS $(PT_CPPFLAGS) -c examples/minimal.c -o $(BUILD)/warn-$$cc-nothreads.o; \
	    echo "$$cc $(WARN_CFLAGS) -DPDFTRACE_STATIC examples/minimal.c"; \
	    $$cc $(WARN_CFLAGS) -DPDFTRACE_STATIC $(PT_CPPFLAGS) $(PT_THREADS) -c examples/minimal.c -o $(BUILD)/warn-$$cc-static.o; \
	done; \
	for cxx in $(WARN_CXX); do \
	    echo "$$cxx $(WARN_CXXFLAGS) examples/cpp_check.cpp (then run it)"; \
	    $$cxx $(WARN_CXXFLAGS) $(PT_CPPFLAGS) $(PT_THREADS) examples/cpp_check.cpp -o $(BUILD)/cpp_check-$$cxx $(PT_LDLIBS); \
	    ./$(BUILD)/cpp_check-$$cxx; \
	    echo "$$cxx $(WARN_CXXFLAGS) -DPDFTRACE_SCENE_FILES examples/cpp_check.cpp (the optional scene-file section)"; \
	    $$cxx $(WARN_CXXFLAGS) -DPDFTRACE_SCENE_FILES $(PT_CPPFLAGS) $(PT_THREADS) -c examples/cpp_check.cpp -o $(BUILD)/cpp_check-scene-$$cxx.o; \
	done; \
	if [ -f "$(patsubst -I%,%,$(firstword $(EXR_INCLUDES)))/openexr.h" ]; then \
	    for cc in $(WARN_CC); do \
	        echo "$$cc $(WARN_CFLAGS) -DPDFTRACE_OPENEXR examples/cornell.c tests/test_exr.c"; \
	        $$cc $(WARN_CFLAGS) -I. $(EXR_FLAGS) $(PT_THREADS) -c examples/cornell.c -o $(BUILD)/warn-$$cc-exr.o; \
	        $$cc $(WARN_CFLAGS) -I. $(EXR_FLAGS) -c tests/test_exr.c -o $(BUILD)/warn-$$cc-test-exr.o; \
	    done; \
	    for cxx in $(WARN_CXX); do \
	        echo "$$cxx $(WARN_CXXFLAGS) -DPDFTRACE_OPENEXR examples/cpp_check.cpp (the optional EXR section)"; \
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
	echo "the default build includes no Embree header:"; \
	for cc in $(WARN_CC); do \
	    if $$cc -M -I. $(PT_THREADS) examples/cornell.c tests/test_main.c | grep -i embree; then \
	        echo "FAILED: $$cc's default build of pdftrace.h includes an Embree header" >&2; exit 1; \
	    fi; \
	done; \
	echo "  no embree in the dependencies of examples/cornell.c and tests/test_main.c"; \
	echo "check-warnings: all clean"

clean:
	rm -rf $(BUILD) $(OUT)

help:
	@sed -n '2,/^$$/p' Makefile | sed -n 's/^# \{0,1\}//p'
