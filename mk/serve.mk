# serve.mk -- the lab-server suite (tests/serve/run.sh) drives misbehaving clients (idle,
# dripping and probing connections from chosen loopback addresses) with tests/serve/clients.py,
# and bench/load.sh's lab clients are bench/lab_clients.py: python3 for make test and make bench.
TEST_CMDS += python3:python3
BENCH_CMDS += python3:python3
