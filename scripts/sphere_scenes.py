#!/usr/bin/env python3
"""Writes the sphere benchmark scenes for quadray and POV-Ray 3.7 side by side.

    scripts/sphere_scenes.py OUTDIR

For each scene, OUTDIR/NAME.toml (the spheres read from NAME/lattice.ply, written by
scripts/sphere-lattice.py) and OUTDIR/NAME.pov (the same spheres as POV-Ray `sphere` objects):
the same camera, one point light with shadows, a ground plane, and a material with a Phong
highlight, reflective in `spheres10k-reflective` (max trace level 8 in both). The two files do
equal work per pixel (rays cast: camera, one shadow ray per lit hit, reflections), which is
what the benchmark compares; their looks differ in detail (POV-Ray's ambient and highlight
models are not quadray's).
"""

import math
import os
import struct
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
WIDTH, HEIGHT, VFOV = 1280, 720, 40.0

# name: (n, flat, reflectivity)
SCENES = {
    "spheres10k-reflective": (100, True, 0.5),
    "spheres100k-flat": (316, True, 0.0),
    "spheres100k-lattice": (47, False, 0.0),
    "spheres1m-flat": (1000, True, 0.0),
    "spheres1m-lattice": (100, False, 0.0),
}


def camera(n, flat):
    """A camera above one corner, the lattice filling most of the frame (spacing 1)."""
    half = (n - 1) / 2
    top = 0 if flat else n - 1
    distance = 1.1 * max(half, 1.0) + 0.6 * top
    eye = (distance, -1.3 * distance, 0.9 * distance + top / 2)
    return eye, (0.0, 0.0, top / 2)


def toml(name, n, flat, reflect):
    eye, at = camera(n, flat)
    light = (eye[0] * 0.5, eye[1] * 1.5, eye[2] * 2.0)
    return f"""# {name}: written by scripts/sphere_scenes.py
version = 1

[camera]
from = [{eye[0]:.3f}, {eye[1]:.3f}, {eye[2]:.3f}]
to = [{at[0]:.3f}, {at[1]:.3f}, {at[2]:.3f}]
up = [0, 0, 1]
vfov = {VFOV}

[render]
resolution = [{WIDTH}, {HEIGHT}]
spp = 1
max_depth = 8
background = [0.05, 0.06, 0.08]

[[material]]
name = "atom"
color = [0.7, 0.72, 0.75]
ambient = 0.1
diffuse = 0.8
specular = 0.4
shininess = 40
reflectivity = {reflect}

[[material]]
name = "ground"
color = [0.5, 0.5, 0.5]
ambient = 0.1
diffuse = 0.8

[[light]]
type = "point"
position = [{light[0]:.3f}, {light[1]:.3f}, {light[2]:.3f}]
color = [1, 1, 1]
falloff = false

[[plane]]
point = [0, 0, -0.5]
normal = [0, 0, 1]
material = "ground"

[[spheres]]
path = "{name}/lattice.ply"
radius = 0.4
material = "atom"
"""


def pov(name, n, flat, reflect, out):
    """The same scene in POV-Ray's left-handed, y-up frame (world y and z swapped)."""
    eye, at = camera(n, flat)
    light = (eye[0] * 0.5, eye[1] * 1.5, eye[2] * 2.0)
    hfov = math.degrees(2 * math.atan(math.tan(math.radians(VFOV) / 2) * WIDTH / HEIGHT))
    v = lambda p: f"<{p[0]:.4f}, {p[2]:.4f}, {p[1]:.4f}>"
    out.write(f"""// {name}: written by scripts/sphere_scenes.py
#version 3.7;
global_settings {{ assumed_gamma 1.0 max_trace_level 8 adc_bailout 0 ambient_light rgb <1, 1, 1> }}
background {{ color rgb <0.05, 0.06, 0.08> }}
camera {{ perspective location {v(eye)} right x*{WIDTH}/{HEIGHT} up y sky <0, 1, 0>
  angle {hfov:.6f} look_at {v(at)} }}
light_source {{ {v(light)} color rgb <1, 1, 1> }}
plane {{ <0, 1, 0>, -0.5 texture {{ pigment {{ color rgb <0.5, 0.5, 0.5> }}
  finish {{ ambient 0.1 diffuse 0.8 }} }} }}
#declare Atom = texture {{ pigment {{ color rgb <0.7, 0.72, 0.75> }}
  finish {{ ambient 0.1 diffuse 0.8 phong 0.4 phong_size 40 reflection {{ {reflect} }} }} }}
union {{
""")
    half = (n - 1) / 2
    for k in range(1 if flat else n):
        out.write("".join(
            f"sphere {{ <{i - half:g}, {k:g}, {j - half:g}>, 0.4 }}\n"
            for j in range(n) for i in range(n)))
    out.write("texture { Atom } }\n")


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    outdir = sys.argv[1]
    for name, (n, flat, reflect) in SCENES.items():
        args = [sys.executable, os.path.join(HERE, "sphere-lattice.py"), str(n), "1.0", "0.4",
                os.path.join(outdir, name)] + (["--flat"] if flat else [])
        subprocess.run(args, check=True, stdout=subprocess.DEVNULL)
        with open(os.path.join(outdir, name + ".toml"), "w") as f:
            f.write(toml(name, n, flat, reflect))
        with open(os.path.join(outdir, name + ".pov"), "w") as f:
            pov(name, n, flat, reflect, f)
        print(f"{name}: {n * n * (1 if flat else n)} spheres")


if __name__ == "__main__":
    main()
