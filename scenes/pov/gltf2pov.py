#!/usr/bin/env python3
"""Translate a glTF file written by `quadray convert` into a POV-Ray 3.7 scene, so that POV-Ray
can check the reference images of scenes made of meshes, image textures and QUADRAY_quadrics
shapes (see scenes/README.md).

    python3 gltf2pov.py SCENE.gltf OUT.pov [WIDTH HEIGHT]

It reads only what quadray writes: one root node turning z-up into y-up, whose children hold
meshes in world coordinates, QUADRAY_quadrics shapes (node matrix = placement, quadray
coordinates), one camera and KHR_lights_punctual point lights; materials carry quadray's
parameters in extensions.QUADRAY_quadrics.whitted. Geometry, materials and lights are mapped
with toml2pov.py's functions (axes, the (1 - reflectivity) weighting, highlights, 1/d² falloff,
clip boxes, ramp ranges), so both translations agree by construction. Added here:
- Meshes become `mesh2` with their normals; a base colour texture becomes a `uv_mapping`
  `image_map` (bilinear, `interpolate 2`) with v flipped, since POV-Ray's images have v upwards
  and glTF's downwards. The PNG is written beside the .pov file.
- A reflection tint t (quadray's metals) with a constant colour c is a coloured reflection,
  `reflection { rgb r·(1 − t + t·c) }` (POV-Ray's `metallic` would fade the tint at grazing angles).
- glTF light intensities are divided by 683·π, as quadray's import does.
"""
import base64
import json
import math
import os
import struct
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import toml2pov as t2p  # noqa: E402


def column_major(m):
    """A 4x4 column-major list as a 3x3 rows matrix and a translation."""
    rows = [[m[c * 4 + r] for c in range(3)] for r in range(3)]
    return rows, [m[12], m[13], m[14]]


def pov_matrix(m):
    """A quadray-frame affine map (column-major 4x4) as a POV `matrix` in the swapped frame."""
    rows, tr = column_major(m)
    swap = [0, 2, 1]
    a = [[rows[swap[i]][swap[j]] for j in range(3)] for i in range(3)]
    vals = [a[j][i] for i in range(3) for j in range(3)] + [tr[0], tr[2], tr[1]]
    return "  matrix <" + ", ".join(f"{x:.17g}" for x in vals) + ">\n"


def node_matrix(n):
    if "matrix" in n:
        return n["matrix"]
    m = [1.0, 0, 0, 0, 0, 1.0, 0, 0, 0, 0, 1.0, 0, 0, 0, 0, 1.0]
    if "rotation" in n or "scale" in n:
        raise SystemExit("gltf2pov: quadray writes matrices or translations only")
    t = n.get("translation", [0, 0, 0])
    m[12], m[13], m[14] = t
    return m


def main():
    src, out = sys.argv[1], sys.argv[2]
    g = json.load(open(src))
    base = os.path.dirname(os.path.abspath(src))
    buf = g["buffers"][0]
    if "uri" in buf:
        uri = buf["uri"]
        data = (base64.b64decode(uri.split(",", 1)[1]) if uri.startswith("data:")
                else open(os.path.join(base, uri), "rb").read())
    else:
        raise SystemExit("gltf2pov: GLB files are not read; convert to .gltf")

    def view_bytes(i):
        v = g["bufferViews"][i]
        o = v.get("byteOffset", 0)
        return data[o:o + v["byteLength"]]

    def accessor(i):
        a = g["accessors"][i]
        width = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}[a["type"]]
        fmt = {5126: "f", 5125: "I"}[a["componentType"]]
        raw = view_bytes(a["bufferView"])[a.get("byteOffset", 0):]
        vals = struct.unpack_from(f"<{a['count'] * width}{fmt}", raw)
        return [vals[k * width:(k + 1) * width] for k in range(a["count"])]

    hints = g["scenes"][g.get("scene", 0)].get("extras", {}).get("quadray", {})
    w, h = hints.get("resolution", [640, 480])
    if len(sys.argv) > 4:
        w, h = int(sys.argv[3]), int(sys.argv[4])
    ext = g["extensions"]["QUADRAY_quadrics"]

    # Materials as toml2pov material tables (plus a texture file and a tint).
    mats = []
    for i, m in enumerate(g["materials"]):
        wd = m["extensions"]["QUADRAY_quadrics"]["whitted"]
        t = {
            "ambient": wd["ambient"], "diffuse": wd["diffuse"], "specular": wd["specular"],
            "shininess": wd["shininess"], "specular_model": wd["specularModel"],
            "reflectivity": wd["reflectivity"], "tint": wd.get("reflectionTint", 0.0),
        }
        tex = wd.get("texture")
        pbr = m["pbrMetallicRoughness"]
        if tex is None:
            if "baseColorTexture" not in pbr:
                raise SystemExit(f"gltf2pov: material {i} has neither texture")
            if any(abs(c - 1.0) > 1e-6 for c in pbr["baseColorFactor"][:3]):
                raise SystemExit("gltf2pov: only image textures with factor 1 are mapped")
            image = g["images"][g["textures"][pbr["baseColorTexture"]["index"]]["source"]]
            name = f"{os.path.splitext(os.path.basename(out))[0]}-image{i}.png"
            open(os.path.join(os.path.dirname(os.path.abspath(out)), name), "wb").write(
                view_bytes(image["bufferView"]))
            t["image"] = name
        elif tex["type"] == "constant":
            t["texture"], t["color"] = "constant", tex["color"]
        elif tex["type"] == "ramp":
            t["texture"] = "ramp"
        elif tex["type"] == "bands":
            t["texture"], t["bands"] = "bands", tex["steps"]
        else:
            t["texture"], t["checker_size"] = "checker", tex["size"]
            t["color"], t["color2"] = tex["even"], tex["odd"]
        mats.append(t)

    def finish(m):
        f = t2p.finish(m)
        if m["tint"] > 0:
            # A coloured reflection: r·(1 − t + t·colour). (POV-Ray's `metallic` would also fade
            # the tint towards white at grazing angles, which quadray does not do.)
            if m.get("texture") != "constant":
                raise SystemExit("gltf2pov: tinted reflections need a constant colour")
            r, t = m["reflectivity"], m["tint"]
            tint = [r * (1 - t + t * c) for c in m["color"]]
            f = f.replace(f"reflection {{ {r:.9g} }}", f"reflection {{ {t2p.rgb(tint)} }}")
        return f

    def texture(m, **kw):
        if "image" in m:
            pig = f'pigment {{ uv_mapping image_map {{ png "{m["image"]}" interpolate 2 }} }}'
        else:
            pig = t2p.pigment(m, **kw)
        return f"  texture {{\n    {pig}\n    {finish(m)}\n  }}\n"

    o = [f"// {src}: generated by scenes/pov/gltf2pov.py", "#version 3.7;",
         "global_settings { assumed_gamma 1.0 max_trace_level "
         f"{hints.get('maxDepth', 8)} adc_bailout 0 ambient_light rgb <1, 1, 1> }}",
         f"background {{ color {t2p.rgb(hints.get('background', [0, 0, 0]))} }}"]
    root = g["nodes"][g["scenes"][g.get("scene", 0)]["nodes"][0]]
    ext_lights = g.get("extensions", {}).get("KHR_lights_punctual", {}).get("lights", [])
    for c in root["children"]:
        n = g["nodes"][c]
        m = node_matrix(n)
        rows, tr = column_major(m)
        if "camera" in n:
            cam = g["cameras"][n["camera"]]["perspective"]
            fwd = [-rows[r][2] for r in range(3)]
            up = [rows[r][1] for r in range(3)]
            o.append(t2p.camera({"from": tr, "to": [a + b for a, b in zip(tr, fwd)], "up": up,
                                 "vfov": math.degrees(cam["yfov"])}, w, h))
        elif "KHR_lights_punctual" in n.get("extensions", {}):
            l = ext_lights[n["extensions"]["KHR_lights_punctual"]["light"]]
            if l["type"] != "point":
                raise SystemExit("gltf2pov: only point lights are mapped")
            k = l["intensity"] / (683 * math.pi)
            o.append(t2p.light({"type": "point", "position": tr,
                                "color": [x * k for x in l["color"]]}))
        elif "QUADRAY_quadrics" in n.get("extensions", {}):
            s = ext["shapes"][n["extensions"]["QUADRAY_quadrics"]["shape"]]
            mat = mats[s["material"]]
            if s["type"] == "sphere":
                r = s["sphere"]["radius"]
                o.append(f"sphere {{ {t2p.v(tr)}, {r:.17g}\n{texture(mat, origin=tr)}}}\n")
            elif s["type"] == "plane":
                normal = [rows[r][2] for r in range(3)]
                d = sum(a * b for a, b in zip(normal, tr))
                o.append(f"plane {{ {t2p.v(normal)}, {d:.17g}\n"
                         f"{texture(mat, origin=tr, plane=True)}}}\n")
            else:
                q = dict(s["quadric"])
                lo, hi = s["clip"]["min"], s["clip"]["max"]
                k = t2p.coefficients(q)
                o.append(f"quadric {{ {t2p.quadric_pov(k)}\n"
                         f"  bounded_by {{ box {{ {t2p.v(lo)}, {t2p.v(hi)} }} }} clipped_by {{ bounded_by }}\n"
                         f"{texture(mat, height_range=t2p.height_range(k, lo, hi))}{pov_matrix(m)}}}\n")
        elif "mesh" in n:
            prim = g["meshes"][n["mesh"]]["primitives"][0]
            at = prim["attributes"]
            pos = accessor(at["POSITION"])
            nor = accessor(at["NORMAL"]) if "NORMAL" in at else None
            idx = accessor(prim["indices"])
            tris = [tuple(x[0] for x in idx[3 * t:3 * t + 3]) for t in range(len(idx) // 3)]
            mat = mats[prim["material"]]
            parts = ["mesh2 {", "  vertex_vectors { " + str(len(pos)) + ", "
                     + ", ".join(t2p.v(p) for p in pos) + " }"]
            if nor:
                parts.append("  normal_vectors { " + str(len(nor)) + ", "
                             + ", ".join(t2p.v(p) for p in nor) + " }")
            if "image" in mat:
                uv = accessor(at["TEXCOORD_0"])
                parts.append("  uv_vectors { " + str(len(uv)) + ", "
                             + ", ".join(f"<{u:.9g}, {1 - vv:.9g}>" for u, vv in uv) + " }")
            # POV's frame is mirrored (y and z swapped): keep the index order, as toml2pov does.
            parts.append("  face_indices { " + str(len(tris)) + ", "
                         + ", ".join(f"<{a}, {b}, {c}>" for a, b, c in tris) + " }")
            if nor:
                parts.append("  normal_indices { " + str(len(tris)) + ", "
                             + ", ".join(f"<{a}, {b}, {c}>" for a, b, c in tris) + " }")
            if "image" in mat:
                parts.append("  uv_indices { " + str(len(tris)) + ", "
                             + ", ".join(f"<{a}, {b}, {c}>" for a, b, c in tris) + " }")
            parts.append(texture(mat) + "}\n")
            o.append("\n".join(parts))
    open(out, "w").write("\n".join(o))


if __name__ == "__main__":
    main()
