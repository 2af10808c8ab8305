#!/usr/bin/env python3
"""Translate a quadray scene file (TOML, right-handed, z up) into a POV-Ray 3.7 scene, so an
independent renderer can check quadray's reference images (see scenes/README.md).

    python3 toml2pov.py SCENE.toml OUT.pov

Every quadray feature the bundled scenes use has an exact POV-Ray counterpart:
- POV-Ray is left-handed with y up; swapping y and z mirrors the scene and flips the handedness
  convention, so the image is the same (not mirrored): pov(x, y, z) = world(x, z, y).
- quadray weights ambient and diffuse by (1 - reflectivity); POV-Ray adds reflection on top, so
  a quadray material maps to POV ambient ka(1-r), diffuse kd(1-r), reflection r.
- Phong highlights map to `phong ks phong_size n`, Blinn ones to `specular ks roughness 1/n`.
- A point light with distance falloff (irradiance I/d^2) maps to `fade_distance D fade_power 2`,
  whose attenuation 2/(1 + (d/D)^2) is 2 D^2/d^2 to a relative 1e-4/d^2 for D = 0.01, with the
  light's colour scaled by 1/(2 D^2); `falloff = false` lights are POV-Ray's plain lights.
- Directional lights are `parallel` lights 1e5 units away.
- Quadrics keep their object-frame coefficients and clip box and are placed with `matrix`, their
  pigment given before the transform so it stays in the object frame, like quadray's textures.
  Every quadric is bounded by its clip box (`clipped_by { bounded_by }`), which sidesteps POV-Ray
  3.7.0's FS#331 bounding bug for paraboloids.
- Glass (`transmission` t) is a filtering pigment `rgbf <colour, t>` with `interior { ior }`, and
  its mirror a Fresnel `reflection { (1 - t) r, (1 - t) r + t fresnel on } conserve_energy`; an
  attenuation is POV-Ray's exponential fade (`fade_power 1001`) matched to quadray's law.
  Thin-walled glass has no POV-Ray counterpart (rendered as a solid, with a warning).
- The height ramp and bands are `gradient` colour maps over the z range of the surface inside its
  clip box, which this script finds on its own (roots along a grid of vertical lines).
"""
import math
import sys
import tomllib

RAMP = [(0.05, 0.15, 0.9), (0.1, 0.75, 0.15), (0.95, 0.85, 0.05)]


def v(p):
    """A world point or vector as a POV vector (y and z swapped)."""
    x, y, z = p
    return f"<{x:.12g}, {z:.12g}, {y:.12g}>"


def rgb(c):
    return f"rgb <{c[0]:.9g}, {c[1]:.9g}, {c[2]:.9g}>"


def ramp(h):
    h = min(max(h, 0.0), 1.0)
    a, b, t = (RAMP[0], RAMP[1], h * 2) if h < 0.5 else (RAMP[1], RAMP[2], (h - 0.5) * 2)
    return [x + (y - x) * t for x, y in zip(a, b)]


def coefficients(q):
    kind = q["kind"]
    if kind == "general":
        return list(q["coefficients"])
    a, b, c = q.get("a", 1.0), q.get("b", 1.0), q.get("c", 1.0)
    ia, ib, ic = 1 / a**2, 1 / b**2, 1 / c**2
    z = [0.0] * 10
    table = {
        "ellipsoid": (ia, ib, ic, -1.0, 0.0),
        "hyperboloid1": (ia, ib, -ic, -1.0, 0.0),
        "hyperboloid2": (ia, ib, -ic, 1.0, 0.0),
        "cone": (ia, ib, -ic, 0.0, 0.0),
        "elliptic-cylinder": (ia, ib, 0.0, -1.0, 0.0),
        "hyperbolic-cylinder": (ia, -ib, 0.0, -1.0, 0.0),
        "parabolic-cylinder": (ia, 0.0, 0.0, 0.0, -1 / c),
        "elliptic-paraboloid": (ia, ib, 0.0, 0.0, -1 / c),
        "hyperbolic-paraboloid": (ia, -ib, 0.0, 0.0, -1 / c),
    }
    A, B, C, J, I = table[kind]
    z[0], z[1], z[2], z[9], z[8] = A, B, C, J, I
    return z


def quadric_pov(k):
    """Coefficients A..J in the object frame, with y and z swapped (as json2pov.py does)."""
    A, B, C, D, E, F, G, H, I, J = k
    f = lambda x: f"{x:.15g}"
    return (f"<{f(A)}, {f(C)}, {f(B)}>, <{f(E)}, {f(D)}, {f(F)}>, "
            f"<{f(G)}, {f(I)}, {f(H)}>, {f(J)}")


def clip_box(q):
    c = q.get("clip", 1.0)
    if isinstance(c, dict):
        return c["min"], c["max"]
    return [-c] * 3, [c] * 3


def height_range(k, lo, hi, n=201):
    """The z range of the surface inside the clip box (the ramp's extent, as quadray computes it),
    found independently here: roots on a grid of vertical lines, plus the top and bottom faces
    where the equation changes sign over them."""
    A, B, C, D, E, F, G, H, I, J = k
    zs = []
    grid = lambda a, b: [a + (b - a) * i / (n - 1) for i in range(n)]
    f = lambda x, y, z: (A * x * x + B * y * y + C * z * z + D * x * y + E * x * z + F * y * z
                         + G * x + H * y + I * z + J)
    for x in grid(lo[0], hi[0]):
        for y in grid(lo[1], hi[1]):
            qa, qb = C, E * x + F * y + I
            qc = A * x * x + B * y * y + D * x * y + G * x + H * y + J
            if qa == 0:
                roots = [] if qb == 0 else [-qc / qb]
            else:
                disc = qb * qb - 4 * qa * qc
                roots = [] if disc < 0 else [(-qb + sg * math.sqrt(disc)) / (2 * qa) for sg in (1, -1)]
            zs += [z for z in roots if lo[2] <= z <= hi[2]]
    for z in (lo[2], hi[2]):
        vals = [f(x, y, z) for x in grid(lo[0], hi[0]) for y in grid(lo[1], hi[1])]
        if min(vals) <= 0 <= max(vals):
            zs.append(z)
    return (min(zs), max(zs)) if zs else (lo[2], hi[2])


def matmul(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(3)) for j in range(3)] for i in range(3)]


def rotation(deg):
    rx, ry, rz = (math.radians(d) for d in deg)
    cx, sx, cy, sy, cz, sz = math.cos(rx), math.sin(rx), math.cos(ry), math.sin(ry), math.cos(rz), math.sin(rz)
    Rx = [[1, 0, 0], [0, cx, -sx], [0, sx, cx]]
    Ry = [[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]]
    Rz = [[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]]
    return matmul(Rz, matmul(Ry, Rx))


def transform_pov(t):
    """quadray's scale, rotate x, y, z, translate as a POV `matrix` in the swapped frame."""
    if not t:
        return ""
    s = t.get("scale", 1.0)
    s = [s] * 3 if isinstance(s, (int, float)) else s
    r = rotation(t.get("rotate", [0, 0, 0]))
    m = [[r[i][j] * s[j] for j in range(3)] for i in range(3)]
    tr = t.get("translate", [0, 0, 0])
    swap = [0, 2, 1]
    # A = S M S in column-vector form; POV's matrix lists it row-vector style (transposed).
    a = [[m[swap[i]][swap[j]] for j in range(3)] for i in range(3)]
    vals = [a[j][i] for i in range(3) for j in range(3)] + [tr[0], tr[2], tr[1]]
    return "  matrix <" + ", ".join(f"{x:.15g}" for x in vals) + ">\n"


def pigment(m, height_range=None, origin=None, plane=False):
    tex = m.get("texture", "constant")
    t = m.get("transmission", 0.0)
    if tex == "constant" and t > 0:
        # Glass: the filter share passes, tinted by the colour.
        r, g, b = m.get("color", [0.8] * 3)
        return f"pigment {{ color rgbf <{r:.9g}, {g:.9g}, {b:.9g}, {t:.9g}> }}"
    if tex == "constant":
        return f"pigment {{ color {rgb(m.get('color', [0.8] * 3))} }}"
    if tex == "checker":
        even = m.get("color", [0.4] * 3)
        odd = m.get("color2", [(c + 1) / 2 for c in even])
        size = m.get("checker_size", 1.0)
        shift = ""
        if origin is not None:
            # Spheres and planes keep their checker in a frame at their centre or point.
            px, py, pz = origin
            if plane:
                # A plane lies at height 0 of its frame: put it mid-cell along the normal, so
                # rounding cannot flip the parity.
                pz -= 0.5 * size
            shift = f" translate <{px:.12g}, {pz:.12g}, {py:.12g}>"
        return (f"pigment {{ checker color {rgb(even)} color {rgb(odd)} scale {size:.12g}{shift} }}")
    lo, hi = height_range
    span = hi - lo
    # gradient y repeats with period 1: map [lo, hi] to [0.25, 0.75] so values just outside clamp.
    entries = [(0.0, ramp(0.0))]
    if tex == "ramp":
        entries += [(0.25 + 0.5 * s, ramp(s)) for s in (0.0, 0.5, 1.0)]
    else:
        n = m.get("bands", 8)
        for k in range(n):
            c = ramp(0.5 if n == 1 else k / (n - 1))
            entries += [(0.25 + 0.5 * k / n, c), (0.25 + 0.5 * (k + 1) / n, c)]
    entries.append((1.0, ramp(1.0)))
    cm = " ".join(f"[{p:.9g} color {rgb(c)}]" for p, c in entries)
    return (f"pigment {{ gradient y color_map {{ {cm} }}\n"
            f"      scale <1, {2 * span:.12g}, 1> translate <0, {lo - 0.5 * span:.12g}, 0> }}")


def finish(m):
    r = m.get("reflectivity", 0.0)
    ka, kd = m.get("ambient", 0.1) * (1 - r), m.get("diffuse", 0.9) * (1 - r)
    ks, n = m.get("specular", 0.0), m.get("shininess", 32.0)
    # GGX (glTF's highlight) has no POV-Ray counterpart: Blinn-Phong of the same lobe width.
    if m.get("specular_model", "phong") in ("blinn", "ggx"):
        hl = f"phong 0 specular {ks:.9g} roughness {1 / n:.9g}"
    else:
        hl = f"phong {ks:.9g} phong_size {n:.9g} specular 0"
    t = m.get("transmission", 0.0)
    if t > 0:
        # quadray's mirror (1 - t) r + t F: POV-Ray's Fresnel reflection from its min to its max,
        # with the transmitted light reduced by what is reflected (conserve_energy).
        lo = (1 - t) * r
        refl = f"reflection {{ {lo:.9g}, {lo + t:.9g} fresnel on }} conserve_energy"
    else:
        refl = f"reflection {{ {r:.9g} }}"
    return f"finish {{ ambient {ka:.9g} diffuse {kd:.9g} {hl} {refl} }}"


def interior(m):
    """Glass's interior: its ior and, for an attenuation, POV-Ray 3.7's exponential fade
    (fade_power 1001 multiplies by exp(-(1 - fade_color) d / fade_distance), measured), matched
    to quadray's color^(d / distance) channel by channel."""
    if m.get("transmission", 0.0) <= 0:
        return ""
    if m.get("thin_walled", False):
        print("warning: POV-Ray has no thin-walled glass: rendered as a solid", file=sys.stderr)
    out = f"  interior {{ ior {m.get('ior', 1.5):.9g}"
    if "attenuation_color" in m:
        d = m["attenuation_distance"]
        sigma = [-math.log(c) for c in m["attenuation_color"]]
        scale = max(1.0, max(sigma))
        fade = d / scale
        colour = [1 - s * fade / d for s in sigma]
        out += f" fade_distance {fade:.9g} fade_power 1001 fade_color {rgb(colour)}"
    return out + " }\n"


def texture(m, **kw):
    return f"  texture {{\n    {pigment(m, **kw)}\n    {finish(m)}\n  }}\n{interior(m)}"


def camera(c, w, h):
    proj = c.get("projection", "perspective")
    up = c.get("up", [0, 0, 1])
    if "orbit" in c:
        o = c["orbit"]
        yaw, pitch = math.radians(o["yaw"]), math.radians(o["pitch"])
        tgt = o.get("target", [0, 0, 0])
        off = [math.cos(pitch) * math.cos(yaw), math.cos(pitch) * math.sin(yaw), math.sin(pitch)]
        frm = [t + x * o["distance"] for t, x in zip(tgt, off)]
        to = tgt
        up = [-math.sin(pitch) * math.cos(yaw), -math.sin(pitch) * math.sin(yaw), math.cos(pitch)]
    else:
        frm, to = c["from"], c["to"]
    if proj == "orthographic":
        hh = c["height"]
        return (f"camera {{ orthographic\n  location {v(frm)}\n  sky {v(up)}\n"
                f"  right x*{hh * w / h:.12g} up y*{hh:.12g}\n  look_at {v(to)}\n}}\n")
    vfov = c.get("vfov", 40.0)
    fovx = 2 * math.degrees(math.atan(math.tan(math.radians(vfov) / 2) * w / h))
    return (f"camera {{ perspective\n  location {v(frm)}\n  sky {v(up)}\n"
            f"  right x*{w}/{h} up y\n  angle {fovx:.12g}\n  look_at {v(to)}\n}}\n")


def light(l):
    c = [x * l.get("intensity", 1.0) for x in l.get("color", [1, 1, 1])]
    if l["type"] == "directional":
        d = l["direction"]
        n = math.sqrt(sum(x * x for x in d))
        far = [-x / n * 1e5 for x in d]
        return f"light_source {{ {v(far)} color {rgb(c)} parallel point_at <0, 0, 0> }}\n"
    if l.get("falloff", True):
        dist = 0.01
        c = [x / (2 * dist * dist) for x in c]
        return (f"light_source {{ {v(l['position'])} color {rgb(c)} "
                f"fade_distance {dist} fade_power 2 }}\n")
    return f"light_source {{ {v(l['position'])} color {rgb(c)} }}\n"


def main():
    src, out = sys.argv[1], sys.argv[2]
    s = tomllib.load(open(src, "rb"))
    r = s.get("render", {})
    w, h = r.get("resolution", [640, 480])
    if len(sys.argv) > 4:
        w, h = int(sys.argv[3]), int(sys.argv[4])
    mats = {m["name"]: m for m in s.get("material", [])}
    o = [f"// {src}: generated by scenes/pov/toml2pov.py", "#version 3.7;",
         "global_settings { assumed_gamma 1.0 max_trace_level "
         f"{r.get('max_depth', 8)} adc_bailout 0 ambient_light rgb <1, 1, 1> }}",
         f"background {{ color {rgb(r.get('background', [0, 0, 0]))} }}",
         camera(s["camera"], w, h)]
    o += [light(l) for l in s.get("light", [])]
    for sp in s.get("sphere", []):
        t = texture(mats[sp["material"]], origin=sp["center"])
        o.append(f"sphere {{ {v(sp['center'])}, {sp['radius']:.12g}\n{t}}}\n")
    for p in s.get("plane", []):
        n = p["normal"]
        ln = math.sqrt(sum(x * x for x in n))
        n = [x / ln for x in n]
        d = sum(a * b for a, b in zip(n, p["point"]))
        m = mats[p["material"]]
        off = p["point"] if abs(abs(n[2]) - 1) < 1e-12 else None
        if m.get("texture") == "checker" and off is None:
            raise SystemExit("toml2pov: checker planes must be horizontal")
        o.append(f"plane {{ {v(n)}, {d:.12g}\n{texture(m, origin=off, plane=True)}}}\n")
    for q in s.get("quadric", []):
        lo, hi = clip_box(q)
        m = mats[q["material"]]
        o.append(f"quadric {{ {quadric_pov(coefficients(q))}\n"
                 f"  bounded_by {{ box {{ {v(lo)}, {v(hi)} }} }} clipped_by {{ bounded_by }}\n"
                 f"{texture(m, height_range=height_range(coefficients(q), lo, hi))}{transform_pov(q.get('transform'))}}}\n")
    for me in s.get("mesh", []):
        vs, normals = me["vertices"], me.get("normals")
        tris = []
        for i, j, k in me["indices"]:
            if normals:
                tris.append(f"  smooth_triangle {{ {v(vs[i])}, {v(normals[i])}, {v(vs[j])}, "
                            f"{v(normals[j])}, {v(vs[k])}, {v(normals[k])} }}")
            else:
                tris.append(f"  triangle {{ {v(vs[i])}, {v(vs[j])}, {v(vs[k])} }}")
        m = mats[me["material"]]
        o.append("mesh {\n" + "\n".join(tris) + "\n" + texture(m)
                 + transform_pov(me.get("transform")) + "}\n")
    open(out, "w").write("\n".join(o))


if __name__ == "__main__":
    main()
