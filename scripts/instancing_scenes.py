#!/usr/bin/env python3
"""Writes the scene-graph benchmark scenes into OUT (see scripts/bench-instancing.sh).

- dag.gltf: a node DAG of DEPTH levels, each placing the next twice (translated along x, then
  y, alternately), over a 12-triangle box: 2^DEPTH box placements from a file of a few kB.
- dragons.toml: the dragon OBJ placed 1000 times (its definition and 999 instances, a 40x25 grid).
- bunnies-instanced.toml / bunnies-flat.toml: the bunny placed 64 times, as instances of one
  mesh, and as 64 [[mesh]] entries each baked into world space (the same pixels).
- many-N.toml: N world-level instances of one box, for the memory per extra instance.
"""
import base64, json, math, struct, sys

out, dragon, bunny = sys.argv[1], sys.argv[2], sys.argv[3]
DEPTH = int(sys.argv[4]) if len(sys.argv) > 4 else 18

# A unit box, 8 vertices and 12 triangles, as a glTF buffer.
v = [(x, y, z) for z in (0, 1) for y in (0, 1) for x in (0, 1)]
faces = [(0, 2, 1), (1, 2, 3), (4, 5, 6), (5, 7, 6), (0, 1, 4), (1, 5, 4),
         (2, 6, 3), (3, 6, 7), (0, 4, 2), (2, 4, 6), (1, 3, 5), (3, 7, 5)]
pos = b"".join(struct.pack("<3f", *[c * 0.8 for c in p]) for p in v)
idx = b"".join(struct.pack("<3H", *f) for f in faces)
buf = pos + idx + b"\0" * ((4 - len(idx) % 4) % 4)
nodes = [{"mesh": 0}]  # node 0: the box
below = 0
for level in range(DEPTH):
    step = float(2 ** (level // 2))
    axis = level % 2
    t = [0.0, 0.0, 0.0]
    t[axis] = step
    a = len(nodes)
    nodes.append({"children": [below]})
    nodes.append({"children": [below], "translation": t})
    nodes.append({"children": [a, a + 1]})
    below = a + 2
side = 2 ** (DEPTH // 2)
gltf = {
    "asset": {"version": "2.0"},
    "scene": 0,
    "scenes": [{"nodes": [below]}],
    "nodes": nodes,
    "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
    "buffers": [{"byteLength": len(buf),
                 "uri": "data:application/octet-stream;base64," + base64.b64encode(buf).decode()}],
    "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": len(pos)},
                    {"buffer": 0, "byteOffset": len(pos), "byteLength": len(idx)}],
    "accessors": [{"bufferView": 0, "componentType": 5126, "count": 8, "type": "VEC3",
                   "min": [0, 0, 0], "max": [0.8, 0.8, 0.8]},
                  {"bufferView": 1, "componentType": 5123, "count": 36, "type": "SCALAR"}],
}
json.dump(gltf, open(f"{out}/dag.gltf", "w"))

header = """version = 1
[camera]
from = {frm}
to = {to}
up = [0, 0, 1]
vfov = 40
[render]
resolution = [640, 360]
[[material]]
name = "grey"
color = [0.7, 0.7, 0.7]
specular = 0.3
shininess = 30
[[light]]
type = "directional"
direction = [-0.4, 0.5, -1.0]
"""
# The npm dragon lies along x, about 0.1 units across, y up: turned z up and scaled by 10.
s = [header.format(frm="[-4, -5, 4]", to="[8, 6, 0]")]
s.append(f'[[mesh]]\nname = "dragon"\npath = "{dragon}"\nup = "y"\nmaterial = "grey"\n'
         'transform = { scale = 5 }\n')
for i in range(1, 1000):
    x, y = i % 40, i // 40
    s.append(f'[[instance]]\nof = "dragon"\ntransform = {{ scale = 5, translate = [{x * 1.2}, {y * 1.2}, 0] }}\n')
open(f"{out}/dragons.toml", "w").write("\n".join(s))

for kind in ("instanced", "flat"):
    s = [header.format(frm="[4, -14, 9]", to="[4, 4, 0]")]
    for i in range(64):
        x, y = i % 8, i // 8
        t = f'{{ scale = 0.1, rotate = [0, 0, {i * 37 % 360}], translate = [{x * 1.2}, {y * 1.2}, 0] }}'
        if kind == "flat":
            s.append(f'[[mesh]]\npath = "{bunny}"\nup = "y"\nmaterial = "grey"\ntransform = {t}\n')
        elif i == 0:
            s.append(f'[[mesh]]\nname = "bunny"\npath = "{bunny}"\nup = "y"\nmaterial = "grey"\ntransform = {t}\n')
        else:
            s.append(f'[[instance]]\nof = "bunny"\ntransform = {t}\n')
    open(f"{out}/bunnies-{kind}.toml", "w").write("\n".join(s))

for n in (0, 100000):
    s = [header.format(frm="[-50, -50, 400]", to="[160, 160, 0]")]
    s.append('[[mesh]]\nname = "box"\nvertices = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]\n'
             'indices = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]\nmaterial = "grey"\n')
    for i in range(n):
        s.append(f'[[instance]]\nof = "box"\ntransform = {{ translate = [{i % 316 * 1.0}, {i // 316 * 1.0}, 0] }}\n')
    open(f"{out}/many-{n}.toml", "w").write("\n".join(s))
