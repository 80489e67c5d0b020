# standalone.mk -- the project on its own (issue 14): what its tests need besides the others'.
#   tests/csv/compare.py and the README's Python examples (tests/docs/run.sh) run on Debian's
#   python3, the latter with its requests and pandas; tests/install/run.sh checks the manual
#   pages with groff and the systemd unit with systemd-analyze where systemd is installed (it is
#   not installed for that alone). make install itself needs nothing beyond building.
TEST_DEBS += python3-requests python3-pandas
TEST_CMDS += python3:python3 groff:groff-base
