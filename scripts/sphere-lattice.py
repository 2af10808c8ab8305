#!/usr/bin/env python3
"""Writes a lattice of spheres as a binary little-endian PLY file and a scene that reads it.

    scripts/sphere-lattice.py N SPACING RADIUS OUTDIR [--flat] [--colours K] [--radii]

writes OUTDIR/lattice.ply (N x N x N vertices, or N x N x 1 with --flat, each `float x, y, z`)
and OUTDIR/lattice.toml (camera, a light, a material and `[[spheres]] path = "lattice.ply"`).
--colours K adds `uchar red, green, blue` properties cycling through K colours (sRGB codes);
--radii adds a `float radius` property (RADIUS, times 0.5 to 1 along x) instead of the scene's
`radius`. Python standard library only. Example, a million spheres:

    scripts/sphere-lattice.py 100 1.0 0.4 /tmp/lattice
    target/release/quadray check /tmp/lattice/lattice.toml
"""

import argparse
import os
import struct

PALETTE = [
    (230, 57, 70), (241, 250, 238), (168, 218, 220), (69, 123, 157),
    (29, 53, 87), (255, 183, 3), (251, 133, 0), (33, 158, 188),
]


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("n", type=int, help="spheres along each axis")
    p.add_argument("spacing", type=float, help="distance between neighbouring centres")
    p.add_argument("radius", type=float, help="sphere radius")
    p.add_argument("outdir", help="folder for lattice.ply and lattice.toml")
    p.add_argument("--flat", action="store_true", help="one layer: N x N x 1")
    p.add_argument("--colours", type=int, default=0, metavar="K",
                   help="per-sphere colours cycling through K (1-8) palette entries")
    p.add_argument("--radii", action="store_true", help="per-sphere radius property")
    a = p.parse_args()
    if a.n < 1 or a.spacing <= 0 or a.radius <= 0 or not 0 <= a.colours <= len(PALETTE):
        p.error("need n >= 1, spacing > 0, radius > 0, 0 <= colours <= 8")
    nz = 1 if a.flat else a.n
    count = a.n * a.n * nz
    os.makedirs(a.outdir, exist_ok=True)

    props = ["float x", "float y", "float z"]
    fmt = "<3f"
    if a.radii:
        props.append("float radius")
        fmt += "f"
    if a.colours:
        props += ["uchar red", "uchar green", "uchar blue"]
        fmt += "3B"
    row = struct.Struct(fmt)
    header = "ply\nformat binary_little_endian 1.0\ncomment scripts/sphere-lattice.py\n"
    header += f"element vertex {count}\n"
    header += "".join(f"property {q}\n" for q in props) + "end_header\n"

    half = (a.n - 1) * a.spacing / 2
    with open(os.path.join(a.outdir, "lattice.ply"), "wb") as f:
        f.write(header.encode("ascii"))
        buf = bytearray()
        for k in range(nz):
            for j in range(a.n):
                for i in range(a.n):
                    values = [i * a.spacing - half, j * a.spacing - half, k * a.spacing]
                    if a.radii:
                        values.append(a.radius * (0.5 + 0.5 * i / max(a.n - 1, 1)))
                    if a.colours:
                        values += PALETTE[(i + j + k) % a.colours]
                    buf += row.pack(*values)
            f.write(buf)
            buf.clear()

    extent = max(half, 1.0)
    top = (nz - 1) * a.spacing
    distance = 2.0 * extent + 0.6 * top
    radius_line = "" if a.radii else f"radius = {a.radius}\n"
    scene = f"""# Written by scripts/sphere-lattice.py: {a.n} x {a.n} x {nz} spheres from lattice.ply.
version = 1

[camera]
from = [{distance:.3f}, {-1.3 * distance:.3f}, {0.9 * distance + top / 2:.3f}]
to = [0, 0, {top / 2:.3f}]
vfov = 40

[render]
resolution = [640, 480]
background = [0.05, 0.06, 0.08]

[[material]]
name = "atom"
color = [0.7, 0.72, 0.75]
specular = 0.4
shininess = 40

[[light]]
type = "directional"
direction = [-1, 0.6, -1.5]
intensity = 1.0

[[spheres]]
path = "lattice.ply"
{radius_line}material = "atom"
"""
    with open(os.path.join(a.outdir, "lattice.toml"), "w") as f:
        f.write(scene)
    print(f"wrote {count} spheres to {os.path.join(a.outdir, 'lattice.ply')} and lattice.toml")


if __name__ == "__main__":
    main()
