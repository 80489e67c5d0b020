# ljgap -- boring on purpose: pkg-config, out-of-tree build/, -MMD -MP, warnings on.
#   make            build the library, the CLI build/ljgap and the daemon build/ljgapd
#   make test       install what is missing, build, run every test (last line: tests: N passed, N failed)
#   make run        install what is missing, build, serve on $(PORT) with the page from web/
#   make bench      build and run the benchmarks (writes bench/results/)
#   make deps       install missing Debian packages (apt-get)
#   SANITIZE=address,undefined   sanitizer build in build/san/
#   V=1             show commands

PORT ?= 8080
PKGS := libmicrohttpd libcjson gsl cmocka fftw3
DEBS := pkg-config libmicrohttpd-dev libcjson-dev libgsl-dev libcmocka-dev libfftw3-dev curl jq
# Commands that must be on PATH; a missing one is installed from the Debian package after the colon.
CMDS := curl:curl jq:jq
# Each feature adds to these in its own fragment mk/*.mk:
#   PKGS, DEBS, CMDS   what check-deps makes sure of
#   ALL_EXTRA          more things `make all` builds
#   TEST_PREP          things built or fetched before the test suites run
#   RUN_PREP           things `make run` needs (the page's vendored files, say)
ALL_EXTRA :=
TEST_PREP :=
RUN_PREP :=

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

.DEFAULT_GOAL := all
# keep the objects of chained rules (test and bench objects): no rebuild on the next make
.SECONDARY:
include $(sort $(wildcard mk/*.mk))

PKG_CFLAGS := $(shell pkg-config --cflags $(PKGS) 2>/dev/null)
PKG_LIBS := $(shell pkg-config --libs $(PKGS) 2>/dev/null)

CC ?= cc
OPT ?= -O2
CFLAGS ?= $(OPT) -g
WARN := -Wall -Wextra -Wshadow -Wpointer-arith -Wstrict-prototypes -Wmissing-prototypes \
        -Wno-unused-parameter
ALL_CFLAGS := -std=c11 -D_GNU_SOURCE $(WARN) $(CFLAGS) $(SANFLAGS) -Iinclude -Iserver -Icore \
              -Iserver/ljgapd \
              $(PKG_CFLAGS) -MMD -MP
LDLIBS := $(PKG_LIBS) -lpthread -lm
ALL_LDFLAGS := $(LDFLAGS) $(SANFLAGS)

CORE_SRC := $(wildcard core/*.c)
SERVER_SRC := $(filter-out server/cli.c,$(wildcard server/*.c))
# The daemon's own files (server/ljgapd/): all but main.c also go into an archive that the unit
# tests link (the scheduler and the connection records are tested without HTTP).
DAEMON_SRC := $(filter-out server/ljgapd/main.c,$(wildcard server/ljgapd/*.c))
CORE_OBJ := $(CORE_SRC:%.c=$(BUILD)/%.o)
SERVER_OBJ := $(SERVER_SRC:%.c=$(BUILD)/%.o)
DAEMON_OBJ := $(DAEMON_SRC:%.c=$(BUILD)/%.o)
LIBCORE := $(BUILD)/libljgap.a
LIBSERVER := $(BUILD)/libljgap_server.a
LIBDAEMON := $(BUILD)/libljgapd.a

UNIT_SRC := $(wildcard tests/unit/*.c)
UNIT_BIN := $(UNIT_SRC:tests/unit/%.c=$(BUILD)/tests/%)
BENCH_SRC := $(wildcard bench/*.c)
BENCH_BIN := $(BENCH_SRC:bench/%.c=$(BUILD)/bench/%)

PROGS := $(BUILD)/ljgap $(BUILD)/ljgapd

.PHONY: all test run deps check-deps bench clean format
all: $(PROGS) $(UNIT_BIN) $(BENCH_BIN) $(ALL_EXTRA)

$(BUILD)/%.o: %.c
	@mkdir -p $(dir $@)
	@$(if $(Q),echo "  CC      $<")
	$(Q)$(CC) $(ALL_CFLAGS) -c $< -o $@

$(LIBCORE): $(CORE_OBJ)
	$(Q)$(AR) rcs $@ $^

$(LIBSERVER): $(SERVER_OBJ)
	$(Q)$(AR) rcs $@ $^

$(LIBDAEMON): $(DAEMON_OBJ)
	$(Q)$(AR) rcs $@ $^

$(BUILD)/ljgap: $(BUILD)/server/cli.o $(LIBSERVER) $(LIBCORE)
	@$(if $(Q),echo "  LD      $@")
	$(Q)$(CC) $(ALL_LDFLAGS) $^ $(LDLIBS) -o $@

$(BUILD)/ljgapd: $(BUILD)/server/ljgapd/main.o $(BUILD)/gen/openapi.o $(LIBDAEMON) $(LIBSERVER) \
                 $(LIBCORE)
	@$(if $(Q),echo "  LD      $@")
	$(Q)$(CC) $(ALL_LDFLAGS) $^ $(LDLIBS) -o $@

# server/openapi.json embedded in the daemon as the C string ljgapd_openapi (no xxd needed).
$(BUILD)/gen/openapi.c: server/openapi.json
	@mkdir -p $(dir $@)
	@$(if $(Q),echo "  GEN     $@")
	$(Q)awk 'BEGIN { print "#include <stddef.h>"; print "const char ljgapd_openapi[] =" } \
	  { gsub(/\\/, "\\\\"); gsub(/"/, "\\\""); print "    \"" $$0 "\\n\"" } \
	  END { print "    \"\";"; \
	        print "const size_t ljgapd_openapi_len = sizeof ljgapd_openapi - 1;" }' $< > $@

$(BUILD)/gen/openapi.o: $(BUILD)/gen/openapi.c
	$(Q)$(CC) $(ALL_CFLAGS) -c $< -o $@

$(BUILD)/tests/%: $(BUILD)/tests/unit/%.o $(LIBDAEMON) $(LIBSERVER) $(LIBCORE)
	@mkdir -p $(dir $@)
	@$(if $(Q),echo "  LD      $@")
	$(Q)$(CC) $(ALL_LDFLAGS) $^ $(LDLIBS) -o $@

# tests of what only the daemon links: the embedded openapi.json
$(BUILD)/tests/test_problems: $(BUILD)/gen/openapi.o

$(BUILD)/bench/%: $(BUILD)/bench/%.o $(LIBSERVER) $(LIBCORE)
	@mkdir -p $(dir $@)
	@$(if $(Q),echo "  LD      $@")
	$(Q)$(CC) $(ALL_LDFLAGS) $^ $(LDLIBS) -o $@

# Install what a fresh Debian machine lacks, only when something is missing.
check-deps:
	@ok=1; pkg-config --exists $(PKGS) 2>/dev/null || ok=0; \
	for p in $(DEBS); do dpkg -s $$p >/dev/null 2>&1 || ok=0; done; \
	for c in $(CMDS); do command -v $${c%%:*} >/dev/null || ok=0; done; \
	[ $$ok = 1 ] || $(MAKE) --no-print-directory deps

deps:
	@missing=""; for p in $(DEBS); do dpkg -s $$p >/dev/null 2>&1 || missing="$$missing $$p"; done; \
	for c in $(CMDS); do command -v $${c%%:*} >/dev/null || missing="$$missing $${c#*:}"; done; \
	if [ -n "$$missing" ]; then \
	  echo "installing:$$missing"; \
	  SUDO=""; [ "$$(id -u)" = 0 ] || SUDO=sudo; \
	  $$SUDO apt-get update -qq && DEBIAN_FRONTEND=noninteractive $$SUDO apt-get install -y -qq $$missing >/dev/null; \
	else echo "deps: all present"; fi

# The recursive make re-reads pkg-config after check-deps may have installed libraries.
test: check-deps
	@$(MAKE) --no-print-directory all $(TEST_PREP)
	@BUILD=$(BUILD) tests/run.sh

run: check-deps
	@$(MAKE) --no-print-directory all $(RUN_PREP)
	$(BUILD)/ljgapd --port $(PORT) --web web

bench: check-deps
	@$(MAKE) --no-print-directory all
	@BUILD=$(BUILD) bench/run.sh

format:
	clang-format -i include/*.h core/*.c server/*.c server/*.h server/ljgapd/*.[ch] \
	  tests/unit/*.c bench/*.c

clean:
	rm -rf build

-include $(shell find $(BUILD) -name '*.d' 2>/dev/null)
