# harden.mk -- hardening (issue 8) besides the fuzzer (mk/fuzz.mk):
#   make memcheck   the curl suite and the bad-input catalogue with the daemon under valgrind
#                   memcheck (tests/memcheck/run.sh; make test MEMCHECK=1 and .ci/run run it too)
#   make bench      runs bench/load.sh with the other benchmarks: wrk against the daemon
TEST_CMDS += valgrind:valgrind
BENCH_CMDS += wrk:wrk

.PHONY: memcheck
memcheck: check-deps-test
	@$(MAKE) --no-print-directory all
	@BUILD=$(BUILD) tests/memcheck/run.sh
