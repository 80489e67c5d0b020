# files.mk -- instrument files in (issue 28): the readers of server/files/ go into the server
# library (the Makefile's SERVER_SRC); the tests' dump tool, and what the cross-check with
# Gwyddion needs (tests/files/run.sh: gwyddion converts the test files headless, numpy reads
# them back).
TEST_DEBS += gwyddion python3-numpy
# in a folder of its own: every program right in $(BUILD)/tests/ is run as a unit test
FILES_DUMP := $(BUILD)/tests/files/files_dump
ALL_EXTRA += $(FILES_DUMP)
TEST_PREP += $(FILES_DUMP)

$(FILES_DUMP): $(BUILD)/tests/files/files_dump.o $(BUILD)/libljgap_server.a
	@mkdir -p $(dir $@)
	@$(if $(Q),echo "  LD      $@")
	$(Q)$(CC) $(ALL_LDFLAGS) $^ $(LDLIBS) -o $@
