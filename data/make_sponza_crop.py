#!/usr/bin/env python3
"""Makes data/sponza_crop.ply, the demo's scene: the middle of the Dabrovic Sponza atrium.

Usage: python3 data/make_sponza_crop.py sponza.obj data/sponza_crop.ply

sponza.obj is the whole atrium (66,454 triangles); where it comes from is in data/README.md.

Keeps every triangle of sponza.obj that reaches into the slab |x| <= 6 (its x extent overlaps
[-6, 6]): the atrium's middle with both arcades, their columns and arches, the upper gallery,
and whole the large triangles of floor, walls and roof that cross the slab. Drops unused vertices, and writes binary little-endian PLY (float x y z; uchar/int faces). No welding,
no repair, no other change: the triangles are the original ones, positions as stored in the OBJ.
"""
import struct
import sys

X_HALF = 6.0


def main(src, dst):
    vertices, faces = [], []
    for line in open(src):
        if line.startswith("v "):
            vertices.append(tuple(float(t) for t in line.split()[1:4]))
        elif line.startswith("f "):
            idx = [int(t.split("/")[0]) for t in line.split()[1:]]
            idx = [i - 1 if i > 0 else len(vertices) + i for i in idx]
            for k in range(1, len(idx) - 1):
                faces.append((idx[0], idx[k], idx[k + 1]))
    kept = [f for f in faces
            if min(vertices[i][0] for i in f) <= X_HALF and max(vertices[i][0] for i in f) >= -X_HALF]
    remap = {}
    for f in kept:
        for i in f:
            remap.setdefault(i, len(remap))
    order = sorted(remap, key=remap.get)
    with open(dst, "wb") as out:
        header = (
            "ply\nformat binary_little_endian 1.0\n"
            "comment Sponza atrium by Marko Dabrovic: the triangles of sponza.obj reaching into |x| <= %g\n"
            "element vertex %d\nproperty float x\nproperty float y\nproperty float z\n"
            "element face %d\nproperty list uchar int vertex_indices\nend_header\n"
            % (X_HALF, len(order), len(kept))
        )
        out.write(header.encode("ascii"))
        for i in order:
            out.write(struct.pack("<3f", *vertices[i]))
        for f in kept:
            out.write(struct.pack("<B3i", 3, *(remap[i] for i in f)))
    print("%s: %d vertices, %d triangles" % (dst, len(order), len(kept)))


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
