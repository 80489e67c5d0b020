# fuzz.mk -- hardening (issue 8): the libFuzzer target on ljgap__handle and its corpus replay;
# a second target on the instrument-file readers (tests/fuzz/fuzz_files.c, issue 28).
#   make fuzz FUZZ_SECONDS=N   build $(BUILD)/fuzz/fuzz_handler with clang
#                              -fsanitize=fuzzer,address,undefined and fuzz for N s (default 60),
#                              starting from tests/fuzz/corpus (new inputs go to
#                              $(BUILD)/fuzz/corpus, crashes to $(BUILD)/fuzz/artifacts/)
#   make test                  builds $(BUILD)/fuzz/replay with the normal compiler (no fuzzer
#                              runtime needed) and tests/fuzz/run.sh replays the corpus
# clang's libFuzzer runtime is Debian's libclang-rt-14-dev: make fuzz installs both; make test
# does not need them.
FUZZ_DEBS += clang libclang-rt-14-dev
FUZZ_CMDS += clang:clang

FUZZ_SECONDS ?= 60
FUZZ_CC ?= clang
FUZZ_DIR := $(BUILD)/fuzz
FUZZ_BIN := $(FUZZ_DIR)/fuzz_handler
FUZZ_REPLAY := $(FUZZ_DIR)/replay
FUZZ_SAN := -fsanitize=address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer
# The same sources as the libraries (the Makefile's lists are set after this file is read).
FUZZ_SRC := $(wildcard core/*.c core/sim/*.c core/topo/*.c server/api/*.c server/api/*/*.c server/uncert/*.c server/jobs/*.c server/files/*.c) \
            server/ljgapd/budget.c server/ljgapd/forwarded.c
FUZZ_OBJ := $(FUZZ_SRC:%.c=$(FUZZ_DIR)/obj/%.o)
# the instrument-file readers' target (issue 28) and its replay, seeded by tests/fuzz/files_corpus
FUZZ_FILES_BIN := $(FUZZ_DIR)/fuzz_files
FUZZ_FILES_REPLAY := $(FUZZ_DIR)/replay_files

TEST_PREP += $(FUZZ_REPLAY) $(FUZZ_FILES_REPLAY)

.PHONY: fuzz
fuzz: check-deps-fuzz
	@$(MAKE) --no-print-directory $(FUZZ_BIN) $(FUZZ_FILES_BIN)
	@mkdir -p $(FUZZ_DIR)/corpus $(FUZZ_DIR)/files_corpus $(FUZZ_DIR)/artifacts
	$(FUZZ_BIN) -max_total_time=$(FUZZ_SECONDS) -timeout=10 -max_len=4096 \
	  -dict=tests/fuzz/json.dict -artifact_prefix=$(FUZZ_DIR)/artifacts/ \
	  -print_final_stats=1 $(FUZZ_DIR)/corpus tests/fuzz/corpus
	$(FUZZ_FILES_BIN) -max_total_time=$(FUZZ_SECONDS) -timeout=10 -max_len=65536 \
	  -artifact_prefix=$(FUZZ_DIR)/artifacts/files- \
	  -print_final_stats=1 $(FUZZ_DIR)/files_corpus tests/fuzz/files_corpus

$(FUZZ_DIR)/obj/%.o: %.c
	@mkdir -p $(dir $@)
	@$(if $(Q),echo "  FUZZCC  $<")
	$(Q)$(FUZZ_CC) $(filter-out -fsanitize=% -fno-omit-frame-pointer,$(ALL_CFLAGS)) \
	  $(FUZZ_SAN) -fsanitize=fuzzer-no-link -c $< -o $@

$(FUZZ_BIN): $(FUZZ_DIR)/obj/tests/fuzz/fuzz_handler.o $(FUZZ_OBJ)
	@mkdir -p $(dir $@)
	@$(if $(Q),echo "  LD      $@")
	$(Q)$(FUZZ_CC) $(FUZZ_SAN) -fsanitize=fuzzer $^ $(LDLIBS) -o $@

$(FUZZ_FILES_BIN): $(FUZZ_DIR)/obj/tests/fuzz/fuzz_files.o $(FUZZ_OBJ)
	@mkdir -p $(dir $@)
	@$(if $(Q),echo "  LD      $@")
	$(Q)$(FUZZ_CC) $(FUZZ_SAN) -fsanitize=fuzzer $^ $(LDLIBS) -o $@

$(FUZZ_FILES_REPLAY): $(BUILD)/tests/fuzz/replay.o $(BUILD)/tests/fuzz/fuzz_files.o \
                      $(BUILD)/libljgap_server.a $(BUILD)/libljgap.a
	@mkdir -p $(dir $@)
	@$(if $(Q),echo "  LD      $@")
	$(Q)$(CC) $(ALL_LDFLAGS) $^ $(LDLIBS) -o $@

$(FUZZ_REPLAY): $(BUILD)/tests/fuzz/replay.o $(BUILD)/tests/fuzz/fuzz_handler.o \
                $(BUILD)/libljgapd.a $(BUILD)/libljgap_server.a $(BUILD)/libljgap.a
	@mkdir -p $(dir $@)
	@$(if $(Q),echo "  LD      $@")
	$(Q)$(CC) $(ALL_LDFLAGS) $^ $(LDLIBS) -o $@
