#!/usr/bin/python3
"""Writes the OpenVDB files of the density tests into the folder given as the only argument, with
OpenVDB's own Python module (Debian's python3-openvdb). Each file is made at test time, never
stored in the repository:

  sphere.vdb     "density": a sphere of smoke (radius 1.3 around (0.4, 0.8, 0.3), voxels of
                 0.1 in a frame turned 30 degrees about y), rho = 4 (1 - (r/R)^2)^2 (1 + 0.4 sin(3x)
                 sin(2z)) at each voxel centre, background 0; and "temperature", a second grid
  constant.vdb   "density": background 1 and 4x4x4 active voxels of 1, voxels of 1 (rho = 1
                 everywhere)
  vec3.vdb       "density": a Vec3S grid
  bool.vdb       "density": a bool grid
  huge.vdb       "density": 8192^3 active voxels of 0.5, stored as tiles (a few kilobytes)
  negative.vdb   "density": the sphere with the voxel at index (2, 3, 4) set to -0.5
  nan.vdb        "density": the sphere with the voxel at index (2, 3, 4) set to NaN
  empty.vdb      "density": no active voxel
"""
import math
import os
import sys

import pyopenvdb as vdb

CENTRE = (0.4, 0.8, 0.3)
RADIUS = 1.3
VOXEL = 0.1
TURN = math.radians(30)


def sphere_transform():
    c, s = math.cos(TURN), math.sin(TURN)
    # OpenVDB's matrices act on row vectors: rows are the images of the index axes, then the
    # translation (the world position of index (0, 0, 0)).
    return vdb.createLinearTransform([[VOXEL * c, 0, -VOXEL * s, 0], [0, VOXEL, 0, 0],
                                      [VOXEL * s, 0, VOXEL * c, 0],
                                      [CENTRE[0], CENTRE[1], CENTRE[2], 1]])


def sphere_density(x, y, z):
    r2 = ((x - CENTRE[0])**2 + (y - CENTRE[1])**2 + (z - CENTRE[2])**2) / RADIUS**2
    if r2 >= 1:
        return 0.0
    return 4.0 * (1 - r2)**2 * (1 + 0.4 * math.sin(3 * x) * math.sin(2 * z))


def sphere_grid():
    grid = vdb.FloatGrid(0.0)
    grid.name = "density"
    grid.transform = sphere_transform()
    acc = grid.getAccessor()
    n = int(math.ceil(RADIUS / VOXEL)) + 1
    for i in range(-n, n + 1):
        for j in range(-n, n + 1):
            for k in range(-n, n + 1):
                x, y, z = grid.transform.indexToWorld((i, j, k))
                v = sphere_density(x, y, z)
                if v > 0:
                    acc.setValueOn((i, j, k), v)
    return grid


def main():
    out = sys.argv[1]
    os.makedirs(out, exist_ok=True)
    sphere = sphere_grid()
    temperature = vdb.FloatGrid(0.0)
    temperature.name = "temperature"
    temperature.getAccessor().setValueOn((0, 0, 0), 300.0)
    vdb.write(os.path.join(out, "sphere.vdb"), grids=[sphere, temperature])

    constant = vdb.FloatGrid(1.0)
    constant.name = "density"
    constant.transform = vdb.createLinearTransform(1.0)
    constant.fill((0, 0, 0), (3, 3, 3), 1.0, True)
    vdb.write(os.path.join(out, "constant.vdb"), grids=[constant])

    vec3 = vdb.Vec3SGrid()
    vec3.name = "density"
    vec3.getAccessor().setValueOn((0, 0, 0), (1, 2, 3))
    vdb.write(os.path.join(out, "vec3.vdb"), grids=[vec3])

    flags = vdb.BoolGrid(False)
    flags.name = "density"
    flags.getAccessor().setValueOn((0, 0, 0), True)
    vdb.write(os.path.join(out, "bool.vdb"), grids=[flags])

    huge = vdb.FloatGrid(0.0)
    huge.name = "density"
    huge.fill((0, 0, 0), (8191, 8191, 8191), 0.5, True)
    vdb.write(os.path.join(out, "huge.vdb"), grids=[huge])

    for name, value in (("negative", -0.5), ("nan", float("nan"))):
        bad = sphere_grid()
        bad.getAccessor().setValueOn((2, 3, 4), value)
        vdb.write(os.path.join(out, name + ".vdb"), grids=[bad])

    empty = vdb.FloatGrid(0.0)
    empty.name = "density"
    vdb.write(os.path.join(out, "empty.vdb"), grids=[empty])


if __name__ == "__main__":
    main()
