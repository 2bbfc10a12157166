# radiosity — see README.md. `make check` installs what is missing, builds
# and runs every test; `make demo` renders a shipped scene.
CXX      ?= g++
PREFIX   ?= /usr/local
DESTDIR  ?=
PKGS     := glm stb libssh libcrypto cpp-httplib
# Line tables only (-g1): backtraces and a debugger's breakpoints name file
# and line, and make check builds in less time (full -g made a third of the
# compile); OPTFLAGS="-O2 -g" for a debugger's view of variables.
OPTFLAGS ?= -O2 -g1
# The test files themselves at -O0 (TESTFLAGS comes after OPTFLAGS): they
# compile in about half the time (67 s of CPU for all of them, 122 s
# at -O2) and spend their run in the library, which keeps OPTFLAGS (the
# unit tests took 25.9 s of CPU, 23.5 s with the tests at -O2).
TESTFLAGS ?= -O0
CXXFLAGS += $(OPTFLAGS) -std=c++17 -Wall -Wextra -MMD -MP
CPPFLAGS += $(shell pkg-config --cflags $(PKGS) 2>/dev/null)
# tinyexr (--format exr) has no pkg-config file: a header and one library.
LDLIBS   += $(shell pkg-config --libs $(PKGS) 2>/dev/null) -ltinyexr -lpthread
B        ?= build
PROG     ?= radiosity
NPROC    := $(shell nproc 2>/dev/null || echo 1)
# The sanitizer build (make check runs it too): the same sources under
# AddressSanitizer and UndefinedBehaviorSanitizer, any report fatal. Line
# tables only (-g1): reports still name file and line, and the tree builds
# in about two thirds of the time full debug information takes.
SAN      := -O1 -g1 -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=all

# Everything but main(): linked into the program and into the unit tests.
LIB_SRCS  := options.cpp app.cpp writers.cpp clock.cpp scene.cpp surface.cpp mesh.cpp divide.cpp split.cpp groups.cpp hemicube.cpp hemicube_cache.cpp subdivide.cpp solver.cpp shooters.cpp scheduler.cpp queues.cpp idle.cpp results.cpp image.cpp exr.cpp coding.cpp ffcodec.cpp protocol.cpp version.cpp inprocess.cpp pool.cpp pool_thread.cpp worker.cpp hosts.cpp crypto.cpp ssh.cpp connect.cpp source.cpp checkpoint.cpp progress.cpp svg.cpp errorchart.cpp files.cpp memory.cpp view.cpp viewserver.cpp
# Only for the unit tests and the benchmarks, never in the program.
SIM_SRCS  := sim.cpp
TEST_SRCS := $(wildcard tests/*_test.cpp)
LIB_OBJS  := $(LIB_SRCS:%.cpp=$(B)/%.o)
SIM_OBJS  := $(SIM_SRCS:%.cpp=$(B)/%.o)
TEST_OBJS := $(TEST_SRCS:tests/%.cpp=$(B)/tests/%.o)

all: $(PROG)

$(PROG): $(B)/radiosity.o $(LIB_OBJS)
	$(CXX) $(LDFLAGS) -o $@ $^ $(LDLIBS)

# The library first: of an inline function compiled into both a library
# and a test object the linker keeps the first, so the library's code runs
# as compiled for the library even where the tests are built with less
# optimisation (TESTFLAGS, the sanitizer tree).
$(B)/unit_tests: $(LIB_OBJS) $(SIM_OBJS) $(TEST_OBJS)
	$(CXX) $(LDFLAGS) -o $@ $^ $(LDLIBS) $(shell pkg-config --libs gtest_main)

$(B)/radiosity-bench: $(B)/bench/bench.o $(LIB_OBJS)
	$(CXX) $(LDFLAGS) -o $@ $^ $(LDLIBS)

# The column alone at any scene size; links only what a column needs.
$(B)/radiosity-column: $(B)/bench/column.o $(B)/clock.o $(B)/scene.o $(B)/surface.o $(B)/mesh.o $(B)/divide.o $(B)/groups.o $(B)/files.o $(B)/hemicube.o $(B)/hemicube_cache.o $(B)/memory.o $(B)/solver.o $(B)/shooters.o
	$(CXX) $(LDFLAGS) -o $@ $^ $(LDLIBS)

$(B)/radiosity-parallel: $(B)/bench/parallel.o $(LIB_OBJS) $(SIM_OBJS)
	$(CXX) $(LDFLAGS) -o $@ $^ $(LDLIBS)

$(B)/radiosity-waves: $(B)/bench/waves.o $(LIB_OBJS)
	$(CXX) $(LDFLAGS) -o $@ $^ $(LDLIBS)

$(B)/radiosity-master: $(B)/bench/master.o $(LIB_OBJS)
	$(CXX) $(LDFLAGS) -o $@ $^ $(LDLIBS)

# A worker that answers at once (bench/feed.sh): the master at a cluster's rate.
$(B)/radiosity-feed: $(B)/bench/feed.o $(LIB_OBJS)
	$(CXX) $(LDFLAGS) -o $@ $^ $(LDLIBS)

$(B)/radiosity-cluster: $(B)/bench/cluster.o $(LIB_OBJS) $(SIM_OBJS)
	$(CXX) $(LDFLAGS) -o $@ $^ $(LDLIBS)

$(B)/radiosity-throttle: $(B)/bench/throttle.o $(LIB_OBJS) $(SIM_OBJS)
	$(CXX) $(LDFLAGS) -o $@ $^ $(LDLIBS)

# Bytes per form factor of the column encoding against compressors
# (liblz4, libzstd: only this benchmark links them).
$(B)/radiosity-ffbytes: $(B)/bench/ffbytes.o $(LIB_OBJS)
	$(CXX) $(LDFLAGS) -o $@ $^ $(LDLIBS) -llz4 -lzstd

# The master's start-up (load, join, mesh, groups) in CPU seconds.
$(B)/radiosity-startup: $(B)/bench/startup_cpu.o $(B)/clock.o $(B)/scene.o $(B)/surface.o $(B)/mesh.o $(B)/groups.o $(B)/files.o $(B)/memory.o
	$(CXX) $(LDFLAGS) -o $@ $^ $(LDLIBS)

# Big generated scenes (rooms of boxes, tessellated shipped scenes) for
# benchmarks and tests; a stand-alone tool, linked with none of the program.
$(B)/scenegen: $(B)/bench/scenegen.o
	$(CXX) $(LDFLAGS) -o $@ $^

$(B)/bench/%.o: bench/%.cpp | $(B)/bench
	$(CXX) $(CPPFLAGS) -I. $(CXXFLAGS) -c -o $@ $<

# The column's inner loops (depth test, projection, occlusion test) are
# written to vectorise; -O2's cheap cost model leaves most of them scalar.
# Vectorising keeps each float operation as it is, so columns are unchanged.
$(B)/hemicube.o: CXXFLAGS += -ftree-vectorize -fvect-cost-model=dynamic

# The browser view's page, view/view.html and view/view.js, as C++ raw
# string literals that view.cpp includes (why there: view.cpp).
$(B)/view_page.inc: view/view.html view/view.js | $(B)
	@! grep -q ')radiosity_view"' view/view.html view/view.js || { echo "view/: the raw string delimiter is in the page" >&2; exit 1; }
	{ printf 'const char kViewHtml[] = R"radiosity_view('; cat view/view.html; printf ')radiosity_view";\n'; \
	  printf 'const char kViewJs[] = R"radiosity_view('; cat view/view.js; printf ')radiosity_view";\n'; } > $@
$(B)/view.o: $(B)/view_page.inc
$(B)/view.o: CPPFLAGS += -I$(B)

$(B)/%.o: %.cpp | $(B)
	$(CXX) $(CPPFLAGS) $(CXXFLAGS) -c -o $@ $<

# The unit tests' biggest header, gtest.h, is parsed once per tree into a
# precompiled header (it was a third of a test file's compile). gcc uses
# the .gch only when it was made with the same flags, else the header.
GTEST_CFLAGS := $(shell pkg-config --cflags gtest 2>/dev/null)
$(B)/tests/gtest.h: | $(B)/tests
	echo '#include <gtest/gtest.h>' >$@
$(B)/tests/gtest.h.gch: $(B)/tests/gtest.h
	$(CXX) $(CPPFLAGS) $(GTEST_CFLAGS) $(CXXFLAGS) $(TESTFLAGS) -x c++-header -o $@ $<

$(B)/tests/%.o: tests/%.cpp $(B)/tests/gtest.h.gch | $(B)/tests
	$(CXX) $(CPPFLAGS) -I. $(GTEST_CFLAGS) $(CXXFLAGS) $(TESTFLAGS) -include $(B)/tests/gtest.h -c -o $@ $<

# Each directory on its own: build/ may exist already (build/fuzz, build/asan).
$(B) $(B)/tests $(B)/bench:
	mkdir -p $@

# Installs the Debian packages the build and the tests need, only if some
# are missing (the check is dpkg's, so a machine that has them all is left
# alone and needs no network).
deps:
	@sh tests/deps.sh

check: deps
	@$(MAKE) --no-print-directory -j$(NPROC) check-build
	@sh tests/run.sh

# The three builds make check needs, side by side under one jobserver, so
# that no core idles while one build links or compiles its last file.
check-build: check-build-main check-build-asan check-build-fuzz
check-build-main:
	@$(MAKE) --no-print-directory radiosity $(B)/unit_tests $(B)/scenegen
check-build-asan:
	@$(MAKE) --no-print-directory asan
check-build-fuzz:
	@if sh fuzz/probe.sh >/dev/null; then $(MAKE) --no-print-directory fuzz-build; fi

# The test files themselves at -O0 (instrumented all the same): they
# compile in half the time -O1 takes them and spend the run in the
# library, which stays at -O1.
asan:
	@$(MAKE) --no-print-directory B=build/asan PROG=build/asan/radiosity OPTFLAGS="$(SAN)" \
	  TESTFLAGS=-O0 LDFLAGS="$(SAN)" build/asan/radiosity build/asan/unit_tests

demo: deps
	@$(MAKE) --no-print-directory radiosity
	./radiosity -o out/cornell scenes/cornell.obj
	@echo "pictures and results: $(CURDIR)/out/cornell (final.png, final.hdr, frame-NN.png per wave, error.svg, result.csv, log.csv, result.ply, result.gltf, view.html)"

bench: deps
	@$(MAKE) --no-print-directory radiosity $(B)/radiosity-bench $(B)/radiosity-parallel \
	  $(B)/radiosity-waves $(B)/radiosity-column $(B)/radiosity-master $(B)/radiosity-cluster $(B)/radiosity-startup $(B)/radiosity-feed $(B)/scenegen
	@sh bench/run.sh

# The paper's measurements with this machine's cores, written up as
# bench/results/report.md (half an hour or more, not yet timed with parts 5-8; run it on an idle machine).
report: deps
	@$(MAKE) --no-print-directory -j$(NPROC) radiosity $(B)/radiosity-bench $(B)/radiosity-parallel \
	  $(B)/radiosity-waves $(B)/radiosity-column $(B)/radiosity-master $(B)/radiosity-cluster $(B)/radiosity-startup $(B)/radiosity-feed \
	  $(B)/radiosity-ffbytes $(B)/radiosity-throttle $(B)/scenegen
	@sh bench/report

install: radiosity
	install -d $(DESTDIR)$(PREFIX)/bin $(DESTDIR)$(PREFIX)/share/man/man1
	install -m 755 radiosity $(DESTDIR)$(PREFIX)/bin/radiosity
	install -m 644 man/radiosity.1 $(DESTDIR)$(PREFIX)/share/man/man1/radiosity.1

clean:
	rm -rf $(B) radiosity out

# Fuzz targets (libFuzzer, clang): fuzz/*_fuzz.cpp against the loaders and
# the protocol decoder, built with their sources under ASan + UBSan into
# build/fuzz/. `make fuzz` runs each for FUZZ_SECONDS; `make check` for a
# few seconds (tests/run.sh), skipped when clang or libFuzzer is missing.
FUZZ_CXX     ?= clang++
FUZZ_SECONDS ?= 60
FUZZ_B       := build/fuzz
FUZZ_SAN     := -O1 -g1 -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=all
FUZZ_LIB     := $(addprefix $(FUZZ_B)/,scene.o surface.o mesh.o divide.o split.o groups.o coding.o ffcodec.o protocol.o version.o hosts.o files.o checkpoint.o crypto.o solver.o shooters.o subdivide.o memory.o)
FUZZ_BINS    := $(FUZZ_B)/scene_fuzz $(FUZZ_B)/hosts_fuzz $(FUZZ_B)/protocol_fuzz $(FUZZ_B)/checkpoint_fuzz

$(FUZZ_B)/%.o: %.cpp
	@mkdir -p $(FUZZ_B)
	$(FUZZ_CXX) $(CPPFLAGS) -std=c++17 $(FUZZ_SAN) -fsanitize=fuzzer-no-link -MMD -MP -c -o $@ $<

$(FUZZ_B)/%_fuzz: fuzz/%_fuzz.cpp $(FUZZ_LIB)
	$(FUZZ_CXX) $(CPPFLAGS) -I. -std=c++17 $(FUZZ_SAN) -fsanitize=fuzzer -o $@ $^ $(LDLIBS)

$(FUZZ_B)/protocol_seeds: fuzz/protocol_seeds.cpp $(FUZZ_LIB)
	$(FUZZ_CXX) $(CPPFLAGS) -I. -std=c++17 $(FUZZ_SAN) -o $@ $^ $(LDLIBS)

fuzz-build: $(FUZZ_BINS) $(FUZZ_B)/protocol_seeds
	@sh fuzz/seeds.sh

fuzz: deps
	@$(MAKE) --no-print-directory -j$(NPROC) fuzz-build
	@sh fuzz/run.sh $(FUZZ_SECONDS)

.PHONY: all deps check check-build check-build-main check-build-asan check-build-fuzz asan demo bench report install clean fuzz fuzz-build

-include $(wildcard $(B)/*.d $(B)/tests/*.d $(B)/bench/*.d $(FUZZ_B)/*.d)
