# files.mk -- instrument files in (issue 28): the readers of server/files/ go into the server
# library (the Makefile's SERVER_SRC); X3P's zip members and compressed .sur data are inflated by
# zlib. The tests' dump tool, and what the independent cross-checks need (tests/files/run.sh,
# check_b.sh, check_c.sh: gwyddion converts the test files headless, numpy reads them back,
# python3-netcdf4 writes and reads the netCDF files).
PKGS += zlib
DEBS += zlib1g-dev
TEST_DEBS += gwyddion python3-netcdf4 python3-numpy
TEST_CMDS += gwyddion:gwyddion python3:python3
# in a folder of its own: every program right in $(BUILD)/tests/ is run as a unit test
FILES_DUMP := $(BUILD)/tests/files/files_dump
ALL_EXTRA += $(FILES_DUMP)
TEST_PREP += $(FILES_DUMP)

$(FILES_DUMP): $(BUILD)/tests/files/files_dump.o $(BUILD)/libljgap_server.a
	@mkdir -p $(dir $@)
	@$(if $(Q),echo "  LD      $@")
	$(Q)$(CC) $(ALL_LDFLAGS) $^ $(LDLIBS) -o $@
