# Run inside Blender (tests/export/blender_import_test.sh does):
#   blender -b --factory-startup --python-exit-code 1 --python blender_import.py -- \
#       A.glb A_light.json A.report.json [B.glb B_light.json B.report.json ...]
# Imports each GLB into an empty scene with Blender's own glTF importer (io_scene_gltf2) and
# asserts, against values computed here from the light file (closed forms, not the GLB) and from
# `lightvol build`'s report:
#
# The light (KHR_lights_punctual on the node `light`):
#   - type: spot -> SPOT, directional -> SUN, omni -> POINT (glTF `point`); no parent.
#   - pose. glTF is Y-up, Blender Z-up: the importer maps a glTF point (x, y, z) to Blender's
#     (x, -z, y) (a rotation by +90 degrees about X, so handedness and volumes are kept), and
#     rotates light and camera nodes so that Blender's light shines along its local -Z as glTF's
#     does. So the object's location is C(position), its world -Z axis C(direction normalized)
#     and its world +Y axis C(up made orthogonal to the direction) (spot, directional), with
#     C(x, y, z) = (x, -z, y).
#   - spot_size = 2 x outerConeAngle and spot_blend = 1 - innerConeAngle / outerConeAngle (the
#     importer's own formulas), where for a centred frustum with t_y = tan(fov_y / 2) and
#     t_x = aspect * t_y the outer cone circumscribes it, atan(hypot(t_x, t_y)) (its corner), and
#     the inner cone is inscribed, atan(min(t_x, t_y)) (its nearest edge). Blender stores both as
#     32-bit floats: 1e-6.
#
# The mesh:
#   - vertices = build's `vertices`: per primitive, the importer keeps exactly the vertices its
#     indices reference (numpy.unique of the index accessor) and merges none (its
#     merge_vertices option is off by default); our GLB has no normals or UVs to split vertices
#     by, and every vertex of a closed volume belongs to a triangle.
#   - faces = build's `triangles`, each with 3 vertices: the importer's mesh.validate() removes
#     only degenerate and duplicate faces, which a checked volume has none of.
#   - edges = 3 x triangles / 2: a closed 2-manifold shares each edge between two triangles.
#   - bounds = C(report bounds) (its min and max swap on the negated axis), and the signed
#     volume (bmesh, outward-wound positive) = the report's volume: the axis change is a
#     rotation, so the winding stays outward and the volume positive.
#
# Import option: import_shading='FLAT'. Debian bookworm's blender 3.4.1 with its numpy 1.24
# fails in the importer's default shading mode ('NORMALS' calls numpy.bool, removed in numpy
# 1.24) on every glTF file; 'FLAT' is also the right shading for a volume without normals.
import json
import math
import sys
import time

import bmesh
import bpy
from mathutils import Vector

args = sys.argv[sys.argv.index("--") + 1:]
if not args or len(args) % 3 != 0:
    raise SystemExit("usage: blender ... --python blender_import.py -- (GLB LIGHT REPORT)...")


def to_blender(v):
    return Vector((v[0], -v[2], v[1]))


def normalized(v):
    n = math.sqrt(sum(c * c for c in v))
    return [c / n for c in v]


failures = []


def expect(cond, what):
    if not cond:
        failures.append(what)


def close(a, b, tol):
    return all(abs(x - y) <= tol for x, y in zip(a, b))


def check(glb, light_path, report_path):
    with open(light_path) as f:
        light = json.load(f)
    with open(report_path) as f:
        report = json.load(f)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    started = time.monotonic()
    bpy.ops.import_scene.gltf(filepath=glb, import_shading="FLAT")
    seconds = time.monotonic() - started
    objects = list(bpy.data.objects)
    lights = [o for o in objects if o.type == "LIGHT"]
    meshes = [o for o in objects if o.type == "MESH"]
    expect(len(lights) == 1 and len(meshes) == 1 and len(objects) == 2,
           f"{glb}: objects {[(o.name, o.type) for o in objects]}, want one light and one mesh")
    if len(lights) != 1 or len(meshes) != 1:
        return

    ob = lights[0]
    kind = light["type"]
    want_type = {"spot": "SPOT", "directional": "SUN", "omni": "POINT"}[kind]
    expect(ob.data.type == want_type, f"{glb}: light type {ob.data.type}, want {want_type}")
    expect(ob.parent is None, f"{glb}: the light has a parent {ob.parent}")
    world = ob.matrix_world
    location = world.to_translation()
    want_location = to_blender(light["position"])
    expect(close(location, want_location, 1e-5),
           f"{glb}: light at {tuple(location)}, want {tuple(want_location)}")
    line = f"blender_import: {glb}: {ob.data.type} at {tuple(round(c, 6) for c in location)}"
    if kind != "omni":
        rotation = world.to_3x3().normalized()
        direction = rotation @ Vector((0, 0, -1))
        d = normalized(light["direction"])
        want_direction = to_blender(d)
        expect(close(direction, want_direction, 1e-6),
               f"{glb}: light shines along {tuple(direction)}, want {tuple(want_direction)}")
        up = light["up"]
        k = sum(a * b for a, b in zip(up, d))
        want_up = to_blender(normalized([a - k * b for a, b in zip(up, d)]))
        got_up = rotation @ Vector((0, 1, 0))
        expect(close(got_up, want_up, 1e-6),
               f"{glb}: light's up {tuple(got_up)}, want {tuple(want_up)}")
        line += f" along {tuple(round(c, 6) for c in direction)}"
    if kind == "spot":
        ty = math.tan(math.radians(light["fov_y_deg"]) / 2)
        tx = light["aspect"] * ty
        outer = math.atan(math.hypot(tx, ty))
        inner = math.atan(min(tx, ty))
        expect(abs(ob.data.spot_size - 2 * outer) <= 1e-6,
               f"{glb}: spot_size {ob.data.spot_size}, want 2 x outer cone = {2 * outer}")
        expect(abs(ob.data.spot_blend - (1 - inner / outer)) <= 1e-6,
               f"{glb}: spot_blend {ob.data.spot_blend}, want 1 - inner/outer = {1 - inner / outer}")
        line += f", spot_size {ob.data.spot_size:.6f} blend {ob.data.spot_blend:.6f}"

    mesh_ob = meshes[0]
    mesh = mesh_ob.data
    v, t = report["vertices"], report["triangles"]
    expect(len(mesh.vertices) == v, f"{glb}: {len(mesh.vertices)} vertices, build wrote {v}")
    expect(len(mesh.polygons) == t, f"{glb}: {len(mesh.polygons)} faces, build wrote {t}")
    expect(all(len(p.vertices) == 3 for p in mesh.polygons), f"{glb}: a face is not a triangle")
    expect(2 * len(mesh.edges) == 3 * t, f"{glb}: {len(mesh.edges)} edges, want 3 x {t} / 2")
    points = [mesh_ob.matrix_world @ p.co for p in mesh.vertices]
    lo = [min(p[i] for p in points) for i in range(3)]
    hi = [max(p[i] for p in points) for i in range(3)]
    bmin, bmax = report["bounds"]["min"], report["bounds"]["max"]
    want_lo = (bmin[0], -bmax[2], bmin[1])
    want_hi = (bmax[0], -bmin[2], bmax[1])
    expect(close(lo, want_lo, 1e-4) and close(hi, want_hi, 1e-4),
           f"{glb}: bounds {lo} {hi}, want {want_lo} {want_hi}")
    bm = bmesh.new()
    bm.from_mesh(mesh)
    bm.transform(mesh_ob.matrix_world)
    volume = bm.calc_volume(signed=True)
    bm.free()
    expect(abs(volume - report["volume"]) <= 1e-4 * abs(report["volume"]),
           f"{glb}: signed volume {volume}, build's report says {report['volume']}")
    print(f"{line}; {len(mesh.vertices)} vertices, {len(mesh.polygons)} faces,"
          f" {len(mesh.edges)} edges, volume {volume:.6g} (build: {report['volume']:.6g});"
          f" import {seconds:.2f} s")


for i in range(0, len(args), 3):
    check(*args[i:i + 3])
if failures:
    for f in failures:
        print("blender_import: FAILED:", f)
    raise SystemExit(1)
print(f"blender_import: {len(args) // 3} volumes passed")
