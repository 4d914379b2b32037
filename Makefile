# trajd - one non-recursive Makefile.
#
#   make            build everything into $(BUILD)
#   make run        install missing Debian packages, build, run the demo
#   make check      install missing Debian packages, build, run every test
#                   (unit, oracle, replay, daemon, CAN on a UML kernel, Modbus,
#                   then the C tests again under ASan+UBSan)
#   make lint       cppcheck (make check runs it: tests/e2e/test_cppcheck.sh)
#   make format     rewrite the C sources with clang-format (.clang-format);
#   make format-check  list the files that differ from it, fail if any
#   make bench      benchmarks, printing tables
#   make fuzz       libFuzzer targets to FUZZ_EXECS executions (or FUZZ_SECONDS)
#                   each, two at a time, then a table (tests/fuzz/run_fuzz.sh)
#   make install    PREFIX, DESTDIR respected
#
# Files are found by name, so adding a module or a test needs no edit here:
#   lib/<family>/*.c             -> $(BUILD)/libtrajd.a (pure: no I/O)
#   daemon/<family>/*.c          -> $(BUILD)/libtrajdaemon.a
#   daemon/<family>/*_transport.c: each `const transport_t NAME_transport = {`
#                                   -> transport_table[] ($(BUILD)/gen/transport_table.c)
#   daemon/<program>.c           -> $(BUILD)/bin/<program>
#   tests/unit/test_*.c          -> cmocka test binaries $(BUILD)/tests/test_*
#   tests/*/test_*.py, test_*.sh -> run by tests/run.sh
#   tests/bench/bench_*.c, .sh   -> make bench
#   tests/fuzz/fuzz_*.c          -> make fuzz
# Every folder holding headers is on the include path, so a header is named
# by its file name alone (#include "engine.h").

CC ?= cc
CFLAGS ?= -O2 -g
PREFIX ?= /usr/local
# Debian's multiarch would be LIBDIR=$(PREFIX)/lib/x86_64-linux-gnu.
LIBDIR ?= $(PREFIX)/lib
SYSCONFDIR ?= /etc
DESTDIR ?=
BUILD ?= build
FUZZ_SECONDS ?=
FUZZ_EXECS ?=
FUZZ_JOBS ?= 2
FUZZ_TARGETS ?=
COUNTS ?=
PYTHON ?= /usr/bin/python3

PROGRAMS := trajd trajctl trajreplay trajsurf

WARN := -Wall -Wextra -Wshadow -Wfloat-equal -Wstrict-prototypes \
        -Wmissing-prototypes -Wpointer-arith -Wformat=2 -Wvla -Wundef
# CI (which sets CI=true) builds with warnings as errors; .ci/run still just
# calls `make check`, and a local build with a newer compiler is not broken
# by a warning it introduces.
ifneq ($(filter true 1 yes,$(CI)),)
WARN += -Werror
endif
# pkg-config is expanded lazily (=), so it is read after 'make deps' installed it.
PKGS := libmodbus libsystemd inih expat
PKG_CFLAGS = $(shell pkg-config --cflags $(PKGS) 2>/dev/null)
PKG_LIBS = $(shell pkg-config --libs $(PKGS) 2>/dev/null)
INC_DIRS := lib $(sort $(dir $(wildcard lib/*/*.h daemon/*/*.h))) tests/helpers
TRAJD_CPPFLAGS = $(INC_DIRS:%=-I%) -D_GNU_SOURCE $(PKG_CFLAGS) $(CPPFLAGS)
TRAJD_CFLAGS = -std=c11 $(WARN) $(CFLAGS) -MMD -MP
LDLIBS_DAEMON = $(PKG_LIBS) -lm -lpthread
LDLIBS_TEST = -lcmocka -lgsl -lgslcblas $(LDLIBS_DAEMON)

LIB_SRC := $(wildcard lib/*.c lib/*/*.c)
DAEMON_MAINS := $(wildcard $(PROGRAMS:%=daemon/%.c))
DAEMON_SRC := $(wildcard daemon/*/*.c)
# The daemon's C++ files: each only wraps a header-only Debian C++ library in a
# C function (daemon/csv/csv_dragonbox.cc: libdragonbox-dev), built without
# exceptions or RTTI, so nothing links libstdc++.
DAEMON_CXX_SRC := $(wildcard daemon/*/*.cc)
TEST_SRC := $(wildcard tests/unit/test_*.c)
# Test scaffolding in C (tests/helpers/*.c, not in the product): linked into the
# C tests; a *_main.c there is a build-time tool $(BUILD)/tests/<name>.
HELPER_SRC := $(filter-out %_main.c,$(wildcard tests/helpers/*.c))
HELPER_OBJ := $(HELPER_SRC:%.c=$(BUILD)/%.o)
TOOLS := $(patsubst tests/helpers/%_main.c,$(BUILD)/tests/%,$(wildcard tests/helpers/*_main.c))
BENCH_SRC := $(wildcard tests/bench/bench_*.c)
FUZZ_SRC := $(wildcard tests/fuzz/fuzz_*.c)

LIB_OBJ := $(LIB_SRC:%.c=$(BUILD)/%.o)
PIC_OBJ := $(LIB_SRC:%.c=$(BUILD)/pic/%.o)
# The transport table is generated (see daemon/core/transport.h): sorted by path.
TRANSPORT_SRC := $(sort $(wildcard daemon/*/*_transport.c))
GEN_TABLE := $(BUILD)/gen/transport_table.c
DAEMON_OBJ := $(DAEMON_SRC:%.c=$(BUILD)/%.o) $(DAEMON_CXX_SRC:%.cc=$(BUILD)/%.o) $(GEN_TABLE:%.c=%.o)
BINS := $(DAEMON_MAINS:daemon/%.c=$(BUILD)/bin/%)
TEST_BINS := $(TEST_SRC:tests/unit/%.c=$(BUILD)/tests/%)
BENCHES := $(BENCH_SRC:tests/bench/%.c=$(BUILD)/tests/%)
# Each fuzz target with a plain main (tests/fuzz/replay.c): a C test that replays
# tests/fuzz/regress/<target>/ and tests/fuzz/corpus/<target>/.
REPLAY_BINS := $(FUZZ_SRC:tests/fuzz/%.c=$(BUILD)/tests/test_%)
UML_HELPERS := $(BUILD)/tests/uml/xstate_preload.so $(BUILD)/tests/uml/xstate_check

# Manual pages (daemon/doc/): hand-written troff with @VERSION@/@DATADIR@/@PREFIX@, and
# trajd.conf(5) generated from config/trajd.conf's comments (one source each).
VERSION := $(shell sed -n 's/^\#define TRAJD_VERSION "\(.*\)"$$/\1/p' daemon/core/version.h)
MAN_SRC := $(wildcard daemon/doc/*.[1-8])
MANS := $(MAN_SRC:daemon/doc/%=$(BUILD)/man/%) $(BUILD)/man/trajd.conf.5

.PHONY: FORCE all run check check-long uninstall check-build test test-asan bench fuzz fuzz-merge install deps deps-run clean
.DELETE_ON_ERROR:
.SECONDARY:

all: $(MANS) $(BUILD)/libtrajd.a $(BUILD)/libtrajd.so $(BUILD)/libtrajdaemon.a $(BINS) $(TEST_BINS) $(BENCHES) \
     $(REPLAY_BINS) $(UML_HELPERS) $(TOOLS) $(BUILD)/libtrajd_test.so

$(BUILD)/%.o: %.c
	@mkdir -p $(@D)
	$(CC) $(TRAJD_CPPFLAGS) $(TRAJD_CFLAGS) -c -o $@ $<

# Debian installs Dragonbox's headers under a versioned folder.
DRAGONBOX_INC = $(firstword $(wildcard /usr/include/dragonbox-*))
TRAJD_CXXFLAGS = -std=c++17 -fno-exceptions -fno-rtti -Wall -Wextra $(CFLAGS) -MMD -MP \
                 $(if $(DRAGONBOX_INC),-I$(DRAGONBOX_INC))
$(BUILD)/%.o: %.cc
	@mkdir -p $(@D)
	$(CXX) $(TRAJD_CXXFLAGS) -c -o $@ $<

# Regenerated at every make (cheap), replaced only when its text changes, so a
# transport file added, removed or renamed is picked up and nothing else rebuilds.
$(GEN_TABLE): FORCE
	@mkdir -p $(@D)
	@sh daemon/core/transport_table.sh $(TRANSPORT_SRC) > $@.tmp
	@if cmp -s $@.tmp $@; then rm -f $@.tmp; else mv $@.tmp $@; echo "generated $@"; fi
FORCE:

$(BUILD)/gen/%.o: $(BUILD)/gen/%.c
	$(CC) $(TRAJD_CPPFLAGS) $(TRAJD_CFLAGS) -c -o $@ $<

$(BUILD)/pic/%.o: %.c
	@mkdir -p $(@D)
	$(CC) $(TRAJD_CPPFLAGS) $(TRAJD_CFLAGS) -fPIC -c -o $@ $<

$(BUILD)/libtrajd.a: $(LIB_OBJ)
	@rm -f $@
	$(AR) rcs $@ $^

# The shared library (also for the Python oracle tests, ctypes), with the
# soname libtrajd.so.$(SOVERSION): bump SOVERSION when lib/'s ABI breaks.
SOVERSION := 0
$(BUILD)/libtrajd.so: $(PIC_OBJ) Makefile
	$(CC) -shared -Wl,-soname,libtrajd.so.$(SOVERSION) -o $@ $(filter %.o,$^) -lm

# For the Python oracle tests only (never installed): libtrajd, the ctypes
# shims of tests/helpers/ctypes_shims.c (the engine with flat arguments) and
# the global solves of tests/helpers/global_curve.c.
$(BUILD)/libtrajd_test.so: $(PIC_OBJ) $(BUILD)/pic/tests/helpers/ctypes_shims.o \
		$(BUILD)/pic/tests/helpers/global_curve.o Makefile
	$(CC) -shared -o $@ $(filter %.o,$^) -lm

# Written again whenever PREFIX or LIBDIR differ from the last make's (make all,
# then make install PREFIX=/usr): each run writes it aside, and replaces it if changed.
$(BUILD)/trajd.pc: Makefile daemon/core/version.h FORCE
	@mkdir -p $(@D)
	@printf '%s\n' 'prefix=$(PREFIX)' 'libdir=$(LIBDIR)' 'includedir=$${prefix}/include' '' \
		'Name: trajd' 'Description: trajd engine: streaming spline interpolation of timed waypoints (pure, no I/O)' \
		'Version: $(VERSION)' 'Cflags: -I$${includedir}/trajd' 'Libs: -L$${libdir} -ltrajd' \
		'Libs.private: -lm' > $@.new
	@if cmp -s $@.new $@; then rm -f $@.new; else mv $@.new $@; echo "wrote $@ (prefix $(PREFIX))"; fi

FORCE:

$(BUILD)/libtrajdaemon.a: $(DAEMON_OBJ)
	@rm -f $@
	$(AR) rcs $@ $^

$(BUILD)/bin/%: $(BUILD)/daemon/%.o $(BUILD)/libtrajdaemon.a $(BUILD)/libtrajd.a
	@mkdir -p $(@D)
	$(CC) $(CFLAGS) $(LDFLAGS) -o $@ $^ $(LDLIBS_DAEMON)

$(BUILD)/libtrajdtest.a: $(HELPER_OBJ)
	@rm -f $@
	$(AR) rcs $@ $^

$(TEST_BINS): $(BUILD)/tests/%: $(BUILD)/tests/unit/%.o $(BUILD)/libtrajdtest.a $(BUILD)/libtrajdaemon.a \
		$(BUILD)/libtrajd.a
	@mkdir -p $(@D)
	$(CC) $(CFLAGS) $(LDFLAGS) -o $@ $^ $(LDLIBS_TEST)

# config/trajd.dbc: $(BUILD)/tests/canproto_dbc prints it (tests/oracle/test_canproto.py).
$(TOOLS): $(BUILD)/tests/%: $(BUILD)/tests/helpers/%_main.o $(BUILD)/libtrajdtest.a $(BUILD)/libtrajd.a
	@mkdir -p $(@D)
	$(CC) $(CFLAGS) $(LDFLAGS) -o $@ $^ -lm

$(BUILD)/tests/fuzz/replay-%.o: tests/fuzz/replay.c
	@mkdir -p $(@D)
	$(CC) $(TRAJD_CPPFLAGS) $(TRAJD_CFLAGS) -DFUZZ_NAME='"$*"' -c -o $@ $<

$(REPLAY_BINS): $(BUILD)/tests/test_%: $(BUILD)/tests/fuzz/%.o $(BUILD)/tests/fuzz/replay-%.o \
		$(BUILD)/libtrajdaemon.a $(BUILD)/libtrajd.a
	@mkdir -p $(@D)
	$(CC) $(CFLAGS) $(LDFLAGS) -o $@ $^ $(LDLIBS_DAEMON)

$(BENCHES): $(BUILD)/tests/%: $(BUILD)/tests/bench/%.o $(BUILD)/libtrajdtest.a $(BUILD)/libtrajdaemon.a \
		$(BUILD)/libtrajd.a
	@mkdir -p $(@D)
	$(CC) $(CFLAGS) $(LDFLAGS) -o $@ $^ $(LDLIBS_TEST)

# user-mode-linux on hosts with a large XSAVE area (AVX-512, AMX): the ptrace()
# wrapper tests/uml/host.sh preloads, and the check of it (test_uml_xstate.sh).
$(BUILD)/tests/uml/xstate_preload.so: tests/uml/xstate_preload.c
	@mkdir -p $(@D)
	$(CC) -std=c11 -D_GNU_SOURCE $(WARN) $(CFLAGS) -shared -fPIC -o $@ $< -ldl
$(BUILD)/tests/uml/xstate_check: tests/uml/xstate_check.c
	@mkdir -p $(@D)
	$(CC) -std=c11 -D_GNU_SOURCE $(WARN) $(CFLAGS) -o $@ $<

$(BUILD)/man/%: daemon/doc/% daemon/core/version.h
	@mkdir -p $(@D)
	sed -e 's|@VERSION@|$(VERSION)|g' -e 's|@DATADIR@|$(PREFIX)/share|g' -e 's|@PREFIX@|$(PREFIX)|g' $< > $@

# trajreplay(1)'s ENGINE SETTINGS: the options of its --help, one source.
$(BUILD)/man/trajreplay.1: daemon/doc/trajreplay.1 daemon/doc/help2man.awk daemon/core/version.h \
		$(BUILD)/bin/trajreplay
	@mkdir -p $(@D)
	$(BUILD)/bin/trajreplay --help | awk -f daemon/doc/help2man.awk > $@.opts
	sed -e 's|@VERSION@|$(VERSION)|g' -e 's|@DATADIR@|$(PREFIX)/share|g' -e 's|@PREFIX@|$(PREFIX)|g' \
		-e '/@ENGINE_SETTINGS@/{r $@.opts' -e 'd;}' $< > $@
	rm -f $@.opts

# the page describes /etc/trajd/trajd.conf as `make install` writes it (INSTALLED_CONF)
$(BUILD)/man/trajd.conf.5: config/trajd.conf daemon/doc/conf2man.awk daemon/core/version.h Makefile
	@mkdir -p $(@D)
	$(INSTALLED_CONF) | awk -v version=$(VERSION) -f daemon/doc/conf2man.awk > $@

# ---- Debian packages ---------------------------------------------------
# Everything beyond a minimal Debian 12 (debootstrap --variant=minbase, which has
# neither make nor procps): procps gives /bin/kill, which the units' ExecReload
# names and `systemd-analyze verify` (tests/e2e/test_systemd.sh) requires to exist.
DEPS_BUILD := gcc g++ make pkg-config libc6-dev libmodbus-dev libsystemd-dev libinih-dev libexpat1-dev \
              libdragonbox-dev
DEPS_TEST := libcmocka-dev libgsl-dev python3 python3-scipy python3-numpy mbpoll \
             python3-pymodbus python3-serial python3-serial-asyncio can-utils python3-can python3-canmatrix \
             user-mode-linux busybox-static socat iproute2 clang libclang-rt-14-dev \
             systemd procps valgrind python3-pyproj cppcheck clang-format gpsbabel \
             groff-base man-db tshark linuxcnc-uspace strace gdb

# make bench only: cyclictest (rt-tests), the wakeup-latency reference
# tests/bench/bench_lateness.sh measures beside trajd's tick lateness.
DEPS_BENCH := rt-tests

deps-run:
	@sh tests/deps.sh $(DEPS_BUILD)

deps:
	@sh tests/deps.sh $(DEPS_BUILD) $(DEPS_TEST)

# ---- the two commands ----------------------------------------------------
run: deps-run
	@$(MAKE) --no-print-directory $(BUILD)/bin/trajd
	$(BUILD)/bin/trajd -f -c config/demo.conf

# The plain pass and the sanitizer pass both run, whatever the first gives; the
# last line adds them up (tests/run.sh appends each pass's counts to COUNTS).
# The sanitizer pass (its build and its C unit tests: CPU alone, no clock, no
# daemon) runs beside the plain pass under SCHED_IDLE (chrt --idle 0), so that
# it takes only CPU time nothing else wants: the plain pass's parallel section
# keeps both CPUs full, but its serial section (tests/serial.txt: one program at
# a time, most of it waiting on a guest kernel or a paced sender) leaves one
# mostly idle, and the kernel preempts an idle-class task at once for any other.
# Its output is printed after the plain pass's.  Before, the two passes ran one
# after the other: about 100 s more (47 s of build, 49 s of tests).
CHECK_COUNTS = $(abspath $(BUILD))/check-counts
# the builds of `make check` use every CPU, whatever -j the caller gave
NPROC := $(shell nproc 2>/dev/null || echo 1)
check: deps
	@$(MAKE) --no-print-directory -j$(NPROC) check-build
	@$(MAKE) --no-print-directory format-check
	@rm -f $(CHECK_COUNTS) $(CHECK_COUNTS).asan; \
	chrt --idle 0 $(MAKE) --no-print-directory test-asan COUNTS=$(CHECK_COUNTS).asan \
		> $(abspath $(BUILD))/check-asan.log 2>&1 & asan=$$!; \
	BUILD=$(abspath $(BUILD)) PYTHON=$(PYTHON) COUNTS=$(CHECK_COUNTS) sh tests/run.sh; \
	wait $$asan; echo "sanitizer pass (ASan + UBSan, beside the plain pass):"; \
	cat $(abspath $(BUILD))/check-asan.log; cat $(CHECK_COUNTS).asan >> $(CHECK_COUNTS) 2>/dev/null; \
	awk '{p += $$1; f += $$2; s += $$3; n++} END { if (n < 2) f++; \
		printf "check: %d passed, %d failed, %d skipped\n", p, f, s; exit f > 0 }' $(CHECK_COUNTS)

check-build: all

# Long scenarios, beside `make check`: the drive events at 20 and 100 Hz (issue 23).
check-long: all
	@BUILD=$(abspath $(BUILD)) PYTHON=$(PYTHON) RATES="20 100" STALL=1 DRIVE_STALLS=fail \
		TESTS="test_drive_events_uml.sh" \
		sh tests/run.sh

test: all
	@BUILD=$(abspath $(BUILD)) PYTHON=$(PYTHON) sh tests/run.sh

# The C unit tests again under AddressSanitizer + UndefinedBehaviorSanitizer.
SAN := -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=all
test-asan:
	@$(MAKE) --no-print-directory -j$(NPROC) BUILD=$(BUILD)/asan CFLAGS="-O1 -g $(SAN)" \
		LDFLAGS="$(SAN)" $(TEST_BINS:$(BUILD)/%=$(BUILD)/asan/%) $(BINS:$(BUILD)/%=$(BUILD)/asan/%) \
		$(REPLAY_BINS:$(BUILD)/%=$(BUILD)/asan/%)
	@BUILD=$(abspath $(BUILD)/asan) ONLY=c COUNTS=$(COUNTS) sh tests/run.sh

# ---- static analysis and formatting -----------------------------------------
# cppcheck (Debian 12: 2.10) on every C file, in the one configuration we build
# (-D given: no #ifdef combinations).  Checks: warning (undefined behaviour,
# bad API use, uninitialised or null reads), portability, performance.  Not
# "style": its findings here are taste (variableScope against our
# declarations at the top of a block) or defensive checks it calls
# redundant.  Run by tests/run.sh as tests/e2e/test_cppcheck.sh.  A false
# positive is suppressed on its line with a reason:
#   /* cppcheck-suppress <id> ; why it cannot happen */
CPPCHECK_SRC := lib daemon tests/unit tests/helpers tests/bench tests/fuzz
lint: $(GEN_TABLE)
	@echo "cppcheck: $(CPPCHECK_SRC) $(GEN_TABLE)"
	@cppcheck -q --std=c11 -D_GNU_SOURCE -DFUZZ_NAME='"fuzz"' --enable=warning,portability,performance \
		--inline-suppr --error-exitcode=1 -j2 $(INC_DIRS:%=-I%) \
		--template='{file}:{line}: {severity}: {message} [{id}]' $(CPPCHECK_SRC) $(GEN_TABLE)

# clang-format (Debian 12: 14) with .clang-format, which follows the tree's
# style as closely as clang-format 14 can.  `make format` rewrites the files,
# `make format-check` lists those that differ and fails.
FORMAT_SRC := $(wildcard lib/*.h lib/*/*.[ch] daemon/*.c daemon/*/*.[ch] tests/*/*.[ch])
format:
	@clang-format -i --style=file $(FORMAT_SRC)
format-check:
	@bad=$$(clang-format --dry-run --style=file $(FORMAT_SRC) 2>&1 | \
		sed -n 's/^\([^:]*\):[0-9]*:[0-9]*: warning: code should be clang-formatted.*/\1/p' | sort -u); \
	if [ -n "$$bad" ]; then echo "format-check: not as clang-format would write them (make format):"; \
		for f in $$bad; do echo "  $$f"; done; exit 1; fi; echo "format-check: $(words $(FORMAT_SRC)) files clean"

bench: deps
	@sh tests/deps.sh $(DEPS_BENCH)
	@$(MAKE) --no-print-directory all
	@for b in $(BENCHES); do echo "== $$b"; $$b || exit 1; done
	@for b in $(wildcard tests/bench/bench_*.sh); do echo "== $$b"; BUILD=$(abspath $(BUILD)) sh $$b || exit 1; done

# ---- libFuzzer (clang) ------------------------------------------------------
# Two builds of every target.  Depth (the default, $(BUILD)/fuzz/): -O2 with
# UndefinedBehaviorSanitizer only, so a target runs at the speed of the code it
# checks: AddressSanitizer cost the engine target 17 x in CPU time (its shadow
# memory and allocator, not the engine), which kept it from depth.  Memory
# errors are still looked for: run_fuzz.sh replays every input a run kept
# (the grown corpus) through the AddressSanitizer + UBSan build of the plain
# replay driver ($(BUILD)/asan/tests/test_fuzz_*, as `make check` does for the
# checked-in corpora).  FUZZ_ASAN=1 fuzzes with ASan itself ($(BUILD)/fuzz-asan/).
FUZZ_CC := clang
FUZZ_CXX := clang++
FUZZ_ASAN ?= 0
ifeq ($(FUZZ_ASAN),1)
FUZZ_SAN := address,undefined
FUZZ_OPT := -O1
FUZZ_DIR := $(BUILD)/fuzz-asan
FUZZ_OBJ := $(FUZZ_DIR)/obj-abort
else
FUZZ_SAN := undefined
FUZZ_OPT := -O2
FUZZ_DIR := $(BUILD)/fuzz
FUZZ_OBJ := $(FUZZ_DIR)/obj-O2-ubsan-abort
endif
# -fno-sanitize-recover=undefined: a UBSan report ends the run, as it already
# did (run_fuzz.sh: UBSAN_OPTIONS=halt_on_error=1), and each check's error path
# ends in a noreturn call.  With recoverable checks every check split its block
# in two and coverage counted both halves: 5 520 edges of fuzz_engine where 1 546
# remain, twice the counters libFuzzer collects after every input, for no more
# information (the second half runs exactly when the first does).  fuzz_engine:
# about 6 700 -> 11 600 exec/CPU-s (tests/fuzz/RESULTS.md "Speed").
FUZZ_FLAGS := -g $(FUZZ_OPT) -fsanitize=fuzzer-no-link,$(FUZZ_SAN) -fno-sanitize-recover=undefined
FUZZ_BINS := $(FUZZ_SRC:tests/fuzz/%.c=$(FUZZ_DIR)/%)
$(FUZZ_OBJ)/%.o: %.c
	@mkdir -p $(@D)
	$(FUZZ_CC) $(TRAJD_CPPFLAGS) -std=c11 $(FUZZ_FLAGS) -MMD -MP -c -o $@ $<
$(FUZZ_OBJ)/gen/%.o: $(BUILD)/gen/%.c
	@mkdir -p $(@D)
	$(FUZZ_CC) $(TRAJD_CPPFLAGS) -std=c11 $(FUZZ_FLAGS) -MMD -MP -c -o $@ $<
$(FUZZ_OBJ)/%.o: %.cc
	@mkdir -p $(@D)
	$(FUZZ_CXX) $(TRAJD_CXXFLAGS) $(FUZZ_FLAGS) -c -o $@ $<
# Makefile too: a target built with other flags (FUZZ_FLAGS) is rebuilt, not kept
# because it is newer than the sources (its objects are secondary files).
$(FUZZ_DIR)/%: $(FUZZ_OBJ)/tests/fuzz/%.o $(LIB_SRC:%.c=$(FUZZ_OBJ)/%.o) $(DAEMON_SRC:%.c=$(FUZZ_OBJ)/%.o) \
		$(DAEMON_CXX_SRC:%.cc=$(FUZZ_OBJ)/%.o) $(FUZZ_OBJ)/gen/transport_table.o Makefile
	$(FUZZ_CC) -fsanitize=fuzzer,$(FUZZ_SAN) -o $@ $(filter %.o,$^) $(LDLIBS_DAEMON)
# Numeric code (engine, splines) without comparison tracing: it finds nothing
# there (no magic values) and took 40 % of the engine target's time.
FUZZ_NUMERIC := $(filter-out lib/spline/path.c,$(wildcard lib/engine/*.c lib/spline/*.c))
$(FUZZ_NUMERIC:%.c=$(FUZZ_OBJ)/%.o): FUZZ_FLAGS += -fno-sanitize-coverage=trace-cmp
# The AddressSanitizer replay drivers run_fuzz.sh passes every kept input through.
FUZZ_ASAN_REPLAY := $(REPLAY_BINS:$(BUILD)/%=$(BUILD)/asan/%)
# make fuzz [FUZZ_EXECS=N | FUZZ_SECONDS=S] [FUZZ_JOBS=2] [FUZZ_TARGETS="fuzz_x ..."] [FUZZ_ASAN=1]
fuzz: deps
	@$(MAKE) --no-print-directory $(FUZZ_BINS)
	@$(MAKE) --no-print-directory BUILD=$(BUILD)/asan CFLAGS="-O1 -g $(SAN)" LDFLAGS="$(SAN)" \
		$(FUZZ_ASAN_REPLAY)
	@BUILD=$(abspath $(BUILD)) FUZZ_DIR=$(abspath $(FUZZ_DIR)) FUZZ_EXECS="$(FUZZ_EXECS)" \
		FUZZ_SECONDS="$(FUZZ_SECONDS)" FUZZ_JOBS="$(FUZZ_JOBS)" FUZZ_TARGETS="$(FUZZ_TARGETS)" \
		bash tests/fuzz/run_fuzz.sh

# The corpora a run grew, minimized (-merge=1) back into tests/fuzz/corpus/<target>/.
fuzz-merge:
	@$(MAKE) --no-print-directory $(FUZZ_BINS)
	@for f in $(FUZZ_BINS); do n=$$(basename $$f); new=$(FUZZ_DIR)/merged/$$n; \
		rm -rf $$new; mkdir -p $$new tests/fuzz/corpus/$$n; \
		$$f -merge=1 $$new tests/fuzz/corpus/$$n $(FUZZ_DIR)/corpus/$$n > $(FUZZ_DIR)/$$n.merge.log 2>&1 \
			|| { echo "$$n: merge failed, see $(FUZZ_DIR)/$$n.merge.log"; exit 1; }; \
		rm -f tests/fuzz/corpus/$$n/*; cp $$new/* tests/fuzz/corpus/$$n/ 2>/dev/null; \
		echo "$$n: $$(ls tests/fuzz/corpus/$$n | wc -l) files, $$(du -sk tests/fuzz/corpus/$$n | cut -f1) KB"; done

# ---- install ----------------------------------------------------------------
# FHS under PREFIX (/usr/local; a package: PREFIX=/usr), DESTDIR for staging.
# Headers go to include/trajd/ and are included by bare name (Cflags of
# trajd.pc), as inside the tree.  make uninstall removes exactly these files,
# and /etc/trajd/trajd.conf only if it is still as installed (a changed
# config is kept, as dpkg keeps a changed conffile).
# Only the client API is installed: the headers that say so ("trajd public API"
# below their include guard; tests/e2e/test_install.sh builds each alone
# against the installed set): the engine, the seeds' spline toolkit, the
# protocol codecs and file formats, geodesy.  The engine's parts (acceptance,
# time scaling, fragments ...) stay inside.
LIB_HEADERS := $(shell grep -l '^/\* trajd public API: ' lib/motion.h lib/*/*.h)
DOCDIR := $(PREFIX)/share/doc/trajd
TRACKDIR := $(PREFIX)/share/trajd/tracks
# Configs as installed: track paths that resolve there (the demo track is
# installed beside them), and /etc/trajd/trajd.conf kept running as a service:
# once the demo track has played, the object rests at its end and the Modbus
# server goes on serving (exit_when_done = no), until it is stopped.
INSTALLED_TRACK = sed 's|^replay.track = .*/\([^/]*\)$$|replay.track = $(TRACKDIR)/\1|'
INSTALLED_CONF = $(INSTALLED_TRACK) config/trajd.conf | \
	sed 's|^exit_when_done = yes$$|exit_when_done = no|; s|^\# This example replays one track once, so it is on here.$$|\# As installed (a service): off, so trajd keeps serving once the demo track has played.|'
install: $(BINS) $(MANS) $(BUILD)/libtrajd.a $(BUILD)/libtrajd.so $(BUILD)/trajd.pc
	install -d $(DESTDIR)$(PREFIX)/share/man/man1 $(DESTDIR)$(PREFIX)/share/man/man5 \
		$(DESTDIR)$(PREFIX)/share/man/man8
	for m in $(MANS); do install -m 644 $$m $(DESTDIR)$(PREFIX)/share/man/man$${m##*.}/ || exit 1; done
	install -d $(DESTDIR)$(PREFIX)/bin $(DESTDIR)$(SYSCONFDIR)/trajd $(DESTDIR)$(PREFIX)/lib/systemd/system \
		$(DESTDIR)$(PREFIX)/share/trajd/tracks $(DESTDIR)$(LIBDIR)/pkgconfig \
		$(DESTDIR)$(PREFIX)/include/trajd $(DESTDIR)$(DOCDIR)/examples
	install -m 755 $(BINS) $(DESTDIR)$(PREFIX)/bin/
	install -m 644 $(BUILD)/libtrajd.a $(DESTDIR)$(LIBDIR)/
	install -m 755 $(BUILD)/libtrajd.so $(DESTDIR)$(LIBDIR)/libtrajd.so.$(VERSION)
	ln -sf libtrajd.so.$(VERSION) $(DESTDIR)$(LIBDIR)/libtrajd.so.$(SOVERSION)
	ln -sf libtrajd.so.$(SOVERSION) $(DESTDIR)$(LIBDIR)/libtrajd.so
	install -m 644 $(BUILD)/trajd.pc $(DESTDIR)$(LIBDIR)/pkgconfig/
	install -m 644 $(LIB_HEADERS) $(DESTDIR)$(PREFIX)/include/trajd/
	install -m 644 config/trajd.dbc config/trajd.lua $(DESTDIR)$(PREFIX)/share/trajd/
	install -m 644 daemon/doc/examples/trajd_client.c \
		daemon/doc/examples/trajd_can_sender.py daemon/doc/examples/trajd_modbus_hmi.py \
		$(DESTDIR)$(DOCDIR)/examples/
	$(INSTALLED_CONF) > $(DESTDIR)$(DOCDIR)/examples/trajd.conf
	$(INSTALLED_TRACK) config/demo.conf > $(DESTDIR)$(DOCDIR)/examples/demo.conf
	chmod 644 $(DESTDIR)$(DOCDIR)/examples/trajd.conf $(DESTDIR)$(DOCDIR)/examples/demo.conf
	install -m 644 README.md config/PROTOCOL.md lib/engine/CLOCK.md lib/engine/TIMESCALE.md $(DESTDIR)$(DOCDIR)/
	install -m 644 daemon/REFERENCE.md $(DESTDIR)$(DOCDIR)/REFERENCE.md
	install -m 644 tests/data/n2k_furuno_figure8_src52.csv tests/data/ATTRIBUTION.md \
		$(DESTDIR)$(PREFIX)/share/trajd/tracks/
	test -e $(DESTDIR)$(SYSCONFDIR)/trajd/trajd.conf || { \
		$(INSTALLED_CONF) > $(DESTDIR)$(SYSCONFDIR)/trajd/trajd.conf && chmod 644 $(DESTDIR)$(SYSCONFDIR)/trajd/trajd.conf; }
	for u in $(wildcard systemd/*.service systemd/*.socket); do \
		sed 's|@BINDIR@|$(PREFIX)/bin|g' $$u > $(DESTDIR)$(PREFIX)/lib/systemd/system/$$(basename $$u) && \
		chmod 644 $(DESTDIR)$(PREFIX)/lib/systemd/system/$$(basename $$u) || exit 1; done

uninstall:
	rm -f $(BINS:$(BUILD)/bin/%=$(DESTDIR)$(PREFIX)/bin/%)
	for m in $(MANS); do rm -f $(DESTDIR)$(PREFIX)/share/man/man$${m##*.}/$${m##*/}; done
	rm -f $(DESTDIR)$(LIBDIR)/libtrajd.a $(DESTDIR)$(LIBDIR)/libtrajd.so \
		$(DESTDIR)$(LIBDIR)/libtrajd.so.$(SOVERSION) $(DESTDIR)$(LIBDIR)/libtrajd.so.$(VERSION) \
		$(DESTDIR)$(LIBDIR)/pkgconfig/trajd.pc
	rm -rf $(DESTDIR)$(PREFIX)/include/trajd $(DESTDIR)$(PREFIX)/share/trajd $(DESTDIR)$(DOCDIR)
	for u in $(notdir $(wildcard systemd/*.service systemd/*.socket)); do \
		rm -f $(DESTDIR)$(PREFIX)/lib/systemd/system/$$u; done
	@if [ -f $(DESTDIR)$(SYSCONFDIR)/trajd/trajd.conf ]; then \
		if $(INSTALLED_CONF) | cmp -s - $(DESTDIR)$(SYSCONFDIR)/trajd/trajd.conf; then \
			rm -f $(DESTDIR)$(SYSCONFDIR)/trajd/trajd.conf; rmdir $(DESTDIR)$(SYSCONFDIR)/trajd 2>/dev/null || true; \
		else echo "kept $(DESTDIR)$(SYSCONFDIR)/trajd/trajd.conf (changed since it was installed)"; fi; fi

clean:
	rm -rf $(BUILD)

-include $(shell find $(BUILD) -name '*.d' 2>/dev/null)
