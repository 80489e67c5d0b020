# files_b.mk -- instrument files in (issue 28), the X3P, netCDF, Digital Surf and MetroPro
# readers (server/files/): X3P's zip members and compressed .sur data are inflated by zlib.
# tests/files/check_b.sh cross-checks them against Gwyddion and python3-netcdf4.
PKGS += zlib
DEBS += zlib1g-dev
TEST_DEBS += gwyddion python3-netcdf4 python3-numpy
TEST_CMDS += gwyddion:gwyddion python3:python3
