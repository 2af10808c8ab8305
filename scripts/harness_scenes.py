#!/usr/bin/env python3
"""Write quadray ports of the POV-Ray harness's `grid` and `mesh` scenes.

    python3 scripts/harness_scenes.py ../shared/peers/povray/scenes.json OUT_DIR

reads the harness's renderer-neutral scenes.json and writes OUT_DIR/grid.toml (ten clipped
quadrics) and OUT_DIR/mesh.toml (the kitchen mesh, which it expects at OUT_DIR/kitchen.obj).
Used by scripts/bench-render.sh and scripts/bench-error.sh.
"""
import json, sys
scenes = json.load(open(sys.argv[1]))["scenes"]
out = sys.argv[2]
def header(s):
    c = s["camera"]
    lines = ["version = 1", "", "[camera]",
             f"from = {c['position']}", f"to = {c['look_at']}", f"up = {c['up']}", f"vfov = {c['fov_y_deg']}", "",
             "[render]", f"resolution = [{c['width']}, {c['height']}]", "spp = 1",
             f"max_depth = {s['max_trace_level']}", f"background = {s['background']}", ""]
    for l in s["lights"]:
        assert l["type"] == "point"
        lines += ["[[light]]", 'type = "point"', f"position = {l['position']}", f"color = {l['color']}", "falloff = false", ""]
    return lines
def material(name, o):
    f, p = o["finish"], o["pigment"]
    # POV-Ray adds reflection on top; quadray blends it in (see scenes/reflective.toml).
    keep = 1.0 - f["reflection"]
    lines = ["[[material]]", f'name = "{name}"']
    if p["type"] == "height_ramp":
        lines.append('texture = "ramp"')
    elif p["type"] == "solid":
        lines.append(f"color = {p['color']}")
    else:
        raise SystemExit(f"unsupported pigment {p['type']}")
    lines += [f"ambient = {f['ambient'] / keep:.6f}", f"diffuse = {f['diffuse'] / keep:.6f}",
              f"specular = {f['phong']}", f"shininess = {f['phong_size']}", f"reflectivity = {f['reflection']}", ""]
    return lines
grid = scenes["grid"]
lines = header(grid)
for o in grid["objects"]:
    lines += material(o["name"], o)
for o in grid["objects"]:
    b = o["clip_box"]
    lines += ["[[quadric]]", 'kind = "general"', f"coefficients = {o['coeffs']}",
              f"clip = {{ min = {b['min']}, max = {b['max']} }}", f'material = "{o["name"]}"', ""]
open(f"{out}/grid.toml", "w").write("\n".join(lines))
mesh = scenes["mesh"]
lines = header(mesh) + material("kitchen", mesh["objects"][0])
lines += ["[[mesh]]", f'path = "{out}/kitchen.obj"', 'material = "kitchen"', ""]
open(f"{out}/mesh.toml", "w").write("\n".join(lines))
