#!/usr/bin/env python3
"""gen_nc.py -- writes netCDF test files the way SurfaceTopography's to_netcdf does (variables
heights(x, y), x and y with the attributes length, unit and periodic, an optional byte variable
mask, the global attribute json), with python3-netcdf4, and reads each back with it into
NAME.json (the heights in metres, row j along y holding x = 0 .. nx-1, null where missing), for
tests/files/check_b.sh.

Cases: a 2-D map in NETCDF3_64BIT_OFFSET (periodic, nm), a map in NETCDF3_CLASSIC with a
_FillValue hole and a NaN (µm), a map with a mask variable, a profile heights(x), a CDF-5 file
(NETCDF3_64BIT_DATA) with float heights stored (y, x), and a netCDF-4 (HDF5) file that the
reader must refuse.

usage: gen_nc.py OUTDIR
"""
import json
import os
import sys

import netCDF4
import numpy as np

UNIT = {"m": 1.0, "mm": 1e-3, "um": 1e-6, "nm": 1e-9}


def write(path, fmt, h, unit, sx, sy, periodic, dims=("x", "y"), fill=None, mask=None,
          info=None, dtype="f8"):
    """h[i, j]: x index i, y index j (SurfaceTopography's order)."""
    with netCDF4.Dataset(path, "w", format=fmt) as nc:
        if info is not None:
            nc.json = json.dumps(info)
        nx = h.shape[0]
        nc.createDimension("x", nx)
        if h.ndim == 2:
            nc.createDimension("y", h.shape[1])
        shape = dims if h.ndim == 2 else ("x",)
        kw = {"fill_value": fill} if fill is not None else {}
        v = nc.createVariable("heights", dtype, shape, **kw)
        v.set_auto_mask(False)
        v[...] = h.T if shape == ("y", "x") else h
        v.unit = unit
        if mask is not None:
            m = nc.createVariable("mask", "b", shape)
            m[...] = mask.astype("i1")
        x = nc.createVariable("x", "f8", ("x",))
        x.length, x.periodic, x.unit = sx, 1 if periodic else 0, unit
        x[...] = np.arange(nx) / nx * sx
        if h.ndim == 2:
            y = nc.createVariable("y", "f8", ("y",))
            y.length, y.periodic, y.unit = sy, 1 if periodic else 0, unit
            y[...] = np.arange(h.shape[1]) / h.shape[1] * sy


def readback(path, out, unit, extra):
    """netCDF4's own reading: masked points (fill value, mask variable) and NaN are missing."""
    with netCDF4.Dataset(path) as nc:
        hv = nc.variables["heights"]
        h = np.ma.masked_invalid(np.ma.asarray(hv[...]).astype("f8"))
        if hv.dimensions == ("y", "x"):
            h = h.T
        if "mask" in nc.variables:
            h = np.ma.masked_where(np.asarray(nc.variables["mask"][...], bool), h)
        if h.ndim == 1:
            h = h[:, None]
        nx, ny = h.shape
        x = nc.variables["x"]
        f = UNIT[x.unit]
        sx = float(x.length) * f
        sy = float(nc.variables["y"].length) * f if ny > 1 else sx / nx
        z = []
        for j in range(ny):
            for i in range(nx):
                z.append(None if h.mask is not np.ma.nomask and np.ma.getmaskarray(h)[i, j]
                         else float(h[i, j]) * UNIT[unit])
        d = {"nx": nx, "ny": ny, "size_x": sx, "size_y": sy, "z_unit": unit,
             "missing": sum(v is None for v in z), "z": z,
             "periodic": int(getattr(x, "periodic", 0) != 0)}
        d.update(extra)
    with open(out, "w") as fo:
        json.dump(d, fo)


def main():
    out = sys.argv[1]
    os.makedirs(out, exist_ok=True)
    rng = np.random.default_rng(7)
    info = {"acquisition_time": "2022-02-03T04:05:06", "instrument": {
        "name": "Bruker Dimension", "parameters": {"tip_radius": {"value": 25, "unit": "nm"}}}}
    j = lambda n: os.path.join(out, n)

    h = rng.normal(0, 5, (24, 18))
    write(j("nc_map.nc"), "NETCDF3_64BIT_OFFSET", h, "nm", 3.0e3, 2.0e3, True, info=info)
    readback(j("nc_map.nc"), j("nc_map.json"), "nm",
             {"instrument": "Bruker Dimension", "acquired": "2022-02-03T04:05:06",
              "tip_radius": 25e-9})

    h = rng.normal(0, 0.2, (16, 20))
    h[3, 4] = -9999.0
    h[10, 0] = np.nan
    write(j("nc_fill.nc"), "NETCDF3_CLASSIC", h, "um", 40.0, 50.0, False, fill=-9999.0)
    readback(j("nc_fill.nc"), j("nc_fill.json"), "um", {})

    h = rng.normal(0, 1, (12, 12))
    mask = np.zeros(h.shape, bool)
    mask[0, 0] = mask[5, 7] = mask[11, 11] = True
    write(j("nc_mask.nc"), "NETCDF3_64BIT_OFFSET", h, "nm", 100.0, 100.0, False, mask=mask)
    readback(j("nc_mask.nc"), j("nc_mask.json"), "nm", {})

    h = rng.normal(0, 3, 50)
    write(j("nc_profile.nc"), "NETCDF3_64BIT_OFFSET", h, "um", 500.0, None, False)
    readback(j("nc_profile.nc"), j("nc_profile.json"), "um", {})

    h = rng.normal(0, 3, (9, 7)).astype("f4")
    write(j("nc_cdf5_yx.nc"), "NETCDF3_64BIT_DATA", h, "mm", 0.9, 0.7, True, dims=("y", "x"),
          dtype="f4")
    readback(j("nc_cdf5_yx.nc"), j("nc_cdf5_yx.json"), "mm", {})

    write(j("nc4.nc"), "NETCDF4", rng.normal(0, 1, (4, 4)), "m", 1.0, 1.0, False)


if __name__ == "__main__":
    main()
