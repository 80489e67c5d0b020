# ljgap -- boring on purpose: pkg-config, out-of-tree build/, -MMD -MP, warnings on.
#   make            build the libraries, the CLI build/ljgap, the daemon build/ljgapd (with the
#                   page compiled in) and the test and benchmark programs
#   make run        install what building and serving need, build, serve on $(PORT) with the
#                   jobs kept in $(BUILD)/state
#   make check      the quick loop after an edit (under 2 minutes on 2 cores): build, then the
#                   unit tests but the three long numerical ones, the HTTP, contract, CSV, CLI
#                   and layout suites (last line: tests: N passed, N failed)
#   make test       install that and the test tools, build, run every test but the memcheck
#                   suite, JOBS (default: the cores) at a time (last line as above);
#                   MEMCHECK=1 adds it (.ci/run does, in the plain build)
#   make bench      install that and the benchmark tools, run the benchmarks (bench/results/);
#                   BENCH="speed errtime" runs only those
#   make fuzz       install clang and its fuzzer runtime, fuzz (mk/fuzz.mk)
#   make deps       install every package any of them needs (apt-get, through sudo if not root)
#   make install    PREFIX=/usr/local DESTDIR=: the programs, the library (static and shared),
#                   its headers and pkg-config file, the manual pages, the systemd unit
#   make uninstall  remove what make install put there
#   SANITIZE=address,undefined   sanitizer build in build/san/
#   V=1             show commands

PORT ?= 8080
# What each goal needs, by goal. Every goal needs the first three (building and serving); the
# others add their own. Each feature adds to these in its own fragment mk/*.mk:
#   PKGS, DEBS, CMDS                 pkg-config modules, Debian packages, and commands on PATH
#                                    (name:package) that building and serving need
#   TEST_PKGS, TEST_DEBS, TEST_CMDS  what make test needs besides
#   BENCH_DEBS, BENCH_CMDS           what make bench needs besides
#   FUZZ_DEBS, FUZZ_CMDS             what make fuzz needs besides
#   ALL_EXTRA                        more things `make all` builds
#   TEST_PREP                        things built or fetched before the test suites run
#   RUN_PREP                         things `make run` needs built
#   EXTRA_LIBS                       libraries pkg-config does not name (linked before it)
PKGS := libmicrohttpd libcjson gsl fftw3 sqlite3
DEBS := pkg-config libmicrohttpd-dev libcjson-dev libgsl-dev libfftw3-dev libsqlite3-dev
CMDS :=
TEST_PKGS := cmocka
TEST_DEBS := libcmocka-dev
TEST_CMDS := curl:curl jq:jq
BENCH_DEBS :=
BENCH_CMDS := curl:curl
FUZZ_DEBS :=
FUZZ_CMDS :=
ALL_EXTRA :=
TEST_PREP :=
RUN_PREP :=
EXTRA_LIBS :=

ifdef SANITIZE
BUILD ?= build/san
SANFLAGS := -fsanitize=$(SANITIZE) -fno-omit-frame-pointer
else
BUILD ?= build
SANFLAGS :=
endif

ifeq ($(V),1)
Q :=
else
Q := @
endif

VERSION := $(shell sed -n 's/^\#define LJGAP_VERSION "\(.*\)"/\1/p' include/ljgap.h)
SOMAJOR := $(firstword $(subst ., ,$(VERSION)))

# core/: the numerical library; core/sim/ the discrete numerical model and the hybrid; core/topo/
# measured topographies' PSDs
CORE_SRC := $(wildcard core/*.c core/sim/*.c core/topo/*.c)
# server/: the request layer (api/: the handler, validation, answers, CSV, problems), the
# instrument-file readers (files/) and the job
# store (jobs/), in one archive; the CLI (cli/) and the daemon (ljgapd/) link it.
SERVER_SRC := $(wildcard server/api/*.c server/api/*/*.c server/uncert/*.c server/jobs/*.c server/files/*.c)
# The daemon's own files (server/ljgapd/): all but main.c also go into an archive that the unit
# tests link (the scheduler and the connection records are tested without HTTP).
DAEMON_SRC := $(filter-out server/ljgapd/main.c,$(wildcard server/ljgapd/*.c))
CORE_OBJ := $(CORE_SRC:%.c=$(BUILD)/%.o)
SERVER_OBJ := $(SERVER_SRC:%.c=$(BUILD)/%.o)
DAEMON_OBJ := $(DAEMON_SRC:%.c=$(BUILD)/%.o)
LIBCORE := $(BUILD)/libljgap.a
LIBSERVER := $(BUILD)/libljgap_server.a
LIBDAEMON := $(BUILD)/libljgapd.a
# The core as a shared library, from objects compiled with -fPIC (the static library and the
# programs keep the plain objects).
SHLIB := $(BUILD)/libljgap.so.$(VERSION)
SONAME := libljgap.so.$(SOMAJOR)
PROGS := $(BUILD)/ljgap $(BUILD)/ljgapd

.DEFAULT_GOAL := all
# keep the objects of chained rules (test and bench objects): no rebuild on the next make
.SECONDARY:
include $(sort $(wildcard mk/*.mk))

PKG_CFLAGS := $(shell pkg-config --cflags $(PKGS) 2>/dev/null)
PKG_LIBS := $(shell pkg-config --libs $(PKGS) 2>/dev/null)
TEST_PKG_CFLAGS := $(shell pkg-config --cflags $(TEST_PKGS) 2>/dev/null)
TEST_PKG_LIBS := $(shell pkg-config --libs $(TEST_PKGS) 2>/dev/null)

CC ?= cc
OPT ?= -O2
CFLAGS ?= $(OPT) -g
WARN := -Wall -Wextra -Wshadow -Wpointer-arith -Wstrict-prototypes -Wmissing-prototypes \
        -Wno-unused-parameter
ALL_CFLAGS := -std=c11 -D_GNU_SOURCE $(WARN) $(CFLAGS) $(SANFLAGS) -Iinclude -Icore -Icore/sim -Icore/topo \
              -Iserver/api -Iserver/uncert -Iserver/jobs -Iserver/files -Iserver/ljgapd \
              $(PKG_CFLAGS) -MMD -MP
LDLIBS := $(EXTRA_LIBS) $(PKG_LIBS) -lpthread -lm
ALL_LDFLAGS := $(LDFLAGS) $(SANFLAGS)

UNIT_SRC := $(wildcard tests/unit/*.c)
UNIT_BIN := $(UNIT_SRC:tests/unit/%.c=$(BUILD)/tests/%)
BENCH_SRC := $(wildcard bench/*.c)
BENCH_BIN := $(BENCH_SRC:bench/%.c=$(BUILD)/bench/%)

.PHONY: all programs test check run deps bench clean format install uninstall
all: $(PROGS) $(UNIT_BIN) $(BENCH_BIN) $(ALL_EXTRA)
programs: $(PROGS)

$(BUILD)/%.o: %.c
	@mkdir -p $(dir $@)
	@$(if $(Q),echo "  CC      $<")
	$(Q)$(CC) $(ALL_CFLAGS) -c $< -o $@

$(BUILD)/pic/%.o: %.c
	@mkdir -p $(dir $@)
	@$(if $(Q),echo "  CC -fPIC $<")
	$(Q)$(CC) $(ALL_CFLAGS) -fPIC -c $< -o $@

$(LIBCORE): $(CORE_OBJ)
	$(Q)$(AR) rcs $@ $^

$(LIBSERVER): $(SERVER_OBJ)
	$(Q)$(AR) rcs $@ $^

$(LIBDAEMON): $(DAEMON_OBJ)
	$(Q)$(AR) rcs $@ $^

$(SHLIB): $(CORE_SRC:%.c=$(BUILD)/pic/%.o)
	@$(if $(Q),echo "  LD      $@")
	$(Q)$(CC) $(ALL_LDFLAGS) -shared -Wl,-soname,$(SONAME) $^ \
	  $(EXTRA_LIBS) $(shell pkg-config --libs gsl fftw3 2>/dev/null) -lpthread -lm -o $@

$(BUILD)/ljgap: $(BUILD)/server/cli/main.o $(LIBSERVER) $(LIBCORE)
	@$(if $(Q),echo "  LD      $@")
	$(Q)$(CC) $(ALL_LDFLAGS) $^ $(LDLIBS) -o $@

$(BUILD)/ljgapd: $(BUILD)/server/ljgapd/main.o $(BUILD)/gen/openapi.o $(BUILD)/gen/web.o \
                 $(LIBDAEMON) $(LIBSERVER) $(LIBCORE)
	@$(if $(Q),echo "  LD      $@")
	$(Q)$(CC) $(ALL_LDFLAGS) $^ $(LDLIBS) -o $@

# server/openapi.json embedded in the daemon as the C string ljgapd_openapi (no xxd needed): sed
# escapes backslashes, quotes and question marks (no trigraphs), one string literal per line.
$(BUILD)/gen/openapi.c: server/openapi.json
	@mkdir -p $(dir $@)
	@$(if $(Q),echo "  GEN     $@")
	$(Q){ echo '#include <stddef.h>'; echo 'const char ljgapd_openapi[] ='; \
	  sed -e 's/\\/\\\\/g' -e 's/"/\\"/g' -e 's/?/\\?/g' -e 's/^/    "/' -e 's/$$/\\n"/' $<; \
	  echo '    "";'; echo 'const size_t ljgapd_openapi_len = sizeof ljgapd_openapi - 1;'; } > $@

# The page (web/: every file it loads, uPlot from npm included, and the icons) embedded in the
# daemon as the table ljgapd_web_files (server/ljgapd/webfiles.h), written by tools/embed.c.
WEB_EMBED := $(sort $(wildcard web/*.html web/*.js web/*.css web/*.svg web/*.ico web/*.png)) \
             $(WEB_VENDOR)
$(BUILD)/gen/web.c: $(BUILD)/tools/embed $(WEB_EMBED)
	@mkdir -p $(dir $@)
	@$(if $(Q),echo "  GEN     $@")
	$(Q)$(BUILD)/tools/embed $@ web $(WEB_EMBED:web/%=%)

$(BUILD)/tools/embed: $(BUILD)/tools/embed.o $(LIBDAEMON) $(LIBSERVER)
	@$(if $(Q),echo "  LD      $@")
	$(Q)$(CC) $(ALL_LDFLAGS) $^ $(LDLIBS) -o $@

$(BUILD)/gen/%.o: $(BUILD)/gen/%.c
	$(Q)$(CC) $(ALL_CFLAGS) -c $< -o $@

$(BUILD)/tests/unit/%.o: tests/unit/%.c
	@mkdir -p $(dir $@)
	@$(if $(Q),echo "  CC      $<")
	$(Q)$(CC) $(ALL_CFLAGS) $(TEST_PKG_CFLAGS) -c $< -o $@

$(BUILD)/tests/%: $(BUILD)/tests/unit/%.o $(LIBDAEMON) $(LIBSERVER) $(LIBCORE)
	@mkdir -p $(dir $@)
	@$(if $(Q),echo "  LD      $@")
	$(Q)$(CC) $(ALL_LDFLAGS) $^ $(TEST_PKG_LIBS) $(LDLIBS) -o $@

# tests of what only the daemon links: the embedded openapi.json and page
$(BUILD)/tests/test_problems: $(BUILD)/gen/openapi.o
$(BUILD)/tests/test_webfiles: $(BUILD)/gen/web.o

$(BUILD)/bench/%: $(BUILD)/bench/%.o $(LIBSERVER) $(LIBCORE)
	@mkdir -p $(dir $@)
	@$(if $(Q),echo "  LD      $@")
	$(Q)$(CC) $(ALL_LDFLAGS) $^ $(LDLIBS) -o $@

# ---- dependencies, by goal ----
# For goal G (run, test, bench, fuzz, all): the packages building and serving need, and G's own.
GOAL_PKGS.run = $(PKGS)
GOAL_DEBS.run = $(DEBS)
GOAL_CMDS.run = $(CMDS)
GOAL_PKGS.test = $(PKGS) $(TEST_PKGS)
GOAL_DEBS.test = $(DEBS) $(TEST_DEBS)
GOAL_CMDS.test = $(CMDS) $(TEST_CMDS)
GOAL_PKGS.bench = $(PKGS)
GOAL_DEBS.bench = $(DEBS) $(BENCH_DEBS)
GOAL_CMDS.bench = $(CMDS) $(BENCH_CMDS)
GOAL_PKGS.fuzz = $(PKGS)
GOAL_DEBS.fuzz = $(DEBS) $(FUZZ_DEBS)
GOAL_CMDS.fuzz = $(CMDS) $(FUZZ_CMDS)
GOAL_PKGS.all = $(PKGS) $(TEST_PKGS)
GOAL_DEBS.all = $(sort $(DEBS) $(TEST_DEBS) $(BENCH_DEBS) $(FUZZ_DEBS))
GOAL_CMDS.all = $(sort $(CMDS) $(TEST_CMDS) $(BENCH_CMDS) $(FUZZ_CMDS))

# (check-deps-G and deps-G are pattern rules, so they cannot be .PHONY.)
# Install what goal G lacks, only when something is missing.
check-deps-%:
	@ok=1; pkg-config --exists $(GOAL_PKGS.$*) 2>/dev/null || ok=0; \
	for p in $(GOAL_DEBS.$*); do dpkg -s $$p >/dev/null 2>&1 || ok=0; done; \
	for c in $(GOAL_CMDS.$*); do command -v $${c%%:*} >/dev/null || ok=0; done; \
	[ $$ok = 1 ] || $(MAKE) --no-print-directory deps-$*

deps-%:
	@missing=""; for p in $(GOAL_DEBS.$*); do dpkg -s $$p >/dev/null 2>&1 || missing="$$missing $$p"; done; \
	for c in $(GOAL_CMDS.$*); do command -v $${c%%:*} >/dev/null || missing="$$missing $${c#*:}"; done; \
	if [ -n "$$missing" ]; then \
	  echo "installing for make $*:$$missing"; \
	  SUDO=""; [ "$$(id -u)" = 0 ] || SUDO=sudo; \
	  $$SUDO apt-get update -qq && DEBIAN_FRONTEND=noninteractive $$SUDO apt-get install -y -qq $$missing >/dev/null; \
	else echo "deps ($*): all present"; fi

deps: deps-all

# The recursive make re-reads pkg-config after check-deps may have installed libraries. The
# test preparations go first: one of them reinstalls web/node_modules, which the page is built
# from.
MEMCHECK ?= 0
test: check-deps-test
	@$(MAKE) --no-print-directory $(TEST_PREP)
	@$(MAKE) --no-print-directory all
	@BUILD=$(BUILD) MEMCHECK=$(MEMCHECK) tests/run.sh

# What an edit usually breaks, quickly: test_mc, test_cross and test_paper (the Monte Carlo and
# the paper's figures, minutes between them) wait for make test.
CHECK_SUITES := unit -test_mc -test_cross -test_paper http contract csv cli layout
check: check-deps-test
	@$(MAKE) --no-print-directory $(CONTRACT_NPM_STAMP)
	@$(MAKE) --no-print-directory $(PROGS) $(UNIT_BIN)
	@BUILD=$(BUILD) tests/run.sh $(CHECK_SUITES)

run: check-deps-run
	@$(MAKE) --no-print-directory $(PROGS) $(RUN_PREP)
	$(BUILD)/ljgapd --port $(PORT) --state-dir $(BUILD)/state

bench: check-deps-bench
	@$(MAKE) --no-print-directory $(PROGS) $(BENCH_BIN)
	@BUILD=$(BUILD) bench/run.sh $(BENCH)

format:
	clang-format -i include/*.h core/*.[ch] server/*.[ch] server/*/*.[ch] \
	  tests/unit/*.c bench/*.c tools/*.c

clean:
	rm -rf build

-include $(shell find $(BUILD) -name '*.d' 2>/dev/null)
