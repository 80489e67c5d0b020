# scaleout.mk -- several ljgapd behind nginx sharing one PostgreSQL job store (issue 17).
#   building and serving: libpq (ljgapd --jobs-db postgresql://..., server/jobs/jobstore_pg.c)
#   make test: a private PostgreSQL cluster (initdb, pg_ctl, psql from Debian's postgresql) and
#              nginx in front of two ljgapd (tests/scaleout/run.sh); make run installs neither
#   make bench: nginx again (bench/scaleout.sh: /v1/adhesion through nginx, 1 and 2 ljgapd)
PKGS += libpq
DEBS += libpq-dev
TEST_DEBS += postgresql nginx
TEST_CMDS += nginx:nginx psql:postgresql-client
BENCH_DEBS += nginx
BENCH_CMDS += nginx:nginx

# The PostgreSQL backend's unit tests need a cluster, which tests/scaleout/run.sh starts: the
# program is built beside the unit tests, not among them (tests/run.sh runs those directly).
SCALEOUT_UNIT := $(BUILD)/tests/scaleout/test_jobstore_pg
ALL_EXTRA += $(SCALEOUT_UNIT)

$(BUILD)/tests/scaleout/%.o: tests/scaleout/%.c
	@mkdir -p $(dir $@)
	@$(if $(Q),echo "  CC      $<")
	$(Q)$(CC) $(ALL_CFLAGS) $(TEST_PKG_CFLAGS) -Itests/unit -c $< -o $@

$(SCALEOUT_UNIT): $(BUILD)/tests/scaleout/test_jobstore_pg.o $(LIBSERVER) $(LIBCORE)
	@mkdir -p $(dir $@)
	@$(if $(Q),echo "  LD      $@")
	$(Q)$(CC) $(ALL_LDFLAGS) $^ $(TEST_PKG_LIBS) $(LDLIBS) -o $@
