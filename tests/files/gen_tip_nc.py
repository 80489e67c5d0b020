#!/usr/bin/env python3
"""gen_tip_nc.py OUT.nc R_NM -- a periodic 64 x 64 netCDF map (1 um a side, heights in nm with a
power-law spectrum) whose contact.engineering json attribute stores the tip radius R_NM (nm):
tests/files/run.sh checks that a stored tip radius feeds the reliable band (python3-netcdf4)."""
import json
import sys

import netCDF4
import numpy as np

out, r_nm = sys.argv[1], float(sys.argv[2])
n = 64
rng = np.random.default_rng(3)
f = np.fft.fftfreq(n)
k = np.hypot(f[:, None], f[None, :])
k[0, 0] = 1
amp = k ** -1.8
amp[0, 0] = 0
h = np.real(np.fft.ifft2(amp * np.exp(2j * np.pi * rng.random((n, n)))))
h *= 2.0 / h.std()
nc = netCDF4.Dataset(out, "w", format="NETCDF3_64BIT_OFFSET")
nc.createDimension("x", n)
nc.createDimension("y", n)
for name in ("x", "y"):
    v = nc.createVariable(name, "f8", (name,))
    v.length, v.unit, v.periodic = 1000.0, "nm", 1
z = nc.createVariable("heights", "f8", ("x", "y"))
z[:] = h
z.unit = "nm"
nc.json = json.dumps({"instrument": {"name": "Test AFM",
                                     "parameters": {"tip_radius": {"value": r_nm, "unit": "nm"}}}})
nc.close()
