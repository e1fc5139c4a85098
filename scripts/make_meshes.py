#!/usr/bin/python3
"""Writes the small STL meshes of the mesh-container scenes (ASCII STL, millimetres).

    /usr/bin/python3 scripts/make_meshes.py            # writes inputs/hopper.stl, inputs/silo.stl,
                                                       # tests/data/mesh_cylinder.stl, tests/data/...

hopper.stl        a conical hopper: outlet radius 4 mm at z = 0, closed by a flat disk, widening to a
                  radius of 20 mm at z = 25 mm; open at the top. 48 segments.
silo.stl          a flat-bottomed silo: radius 15 mm, height 40 mm, open at the top. 48 segments.
mesh_cylinder.stl the cylinder of inputs/cylinder.toml (radius 15 mm) as a polygon of 96 sides whose area
                  equals the circle's (the polygon's circumradius is R sqrt(2 pi / (n sin(2 pi / n)))),
                  height 60 mm, flat bottom, open top: 288 facets.
open_hopper.stl   the hopper with its outlet left open (for the tests: grains over it are refused).
tall_hopper.stl   the hopper with a vertical wall of radius 20 mm on its rim up to z = 50 mm (docs/mesh's
                  1e5-grain benchmark: the hopper alone overflows its rim before that).
Every facet shares its vertices with its neighbours, so the mesh's edges are known by their ends.
"""
import math
import os
import sys


def ring(radius, z, n):
    return [(radius * math.cos(2 * math.pi * k / n), radius * math.sin(2 * math.pi * k / n), z) for k in range(n)]


def band(lower, upper):
    """Triangles joining two rings of the same number of points (the wall between them)."""
    n = len(lower)
    tris = []
    for k in range(n):
        a, b = lower[k], lower[(k + 1) % n]
        c, d = upper[k], upper[(k + 1) % n]
        tris.append((a, b, d))
        tris.append((a, d, c))
    return tris


def disk(rim, centre):
    n = len(rim)
    return [(centre, rim[(k + 1) % n], rim[k]) for k in range(n)]


def write_stl(path, name, tris):
    def normal(t):
        (ax, ay, az), (bx, by, bz), (cx, cy, cz) = t
        ux, uy, uz = bx - ax, by - ay, bz - az
        vx, vy, vz = cx - ax, cy - ay, cz - az
        nx, ny, nz = uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx
        s = math.sqrt(nx * nx + ny * ny + nz * nz)
        return nx / s, ny / s, nz / s

    lines = [f"solid {name}"]
    for t in tris:
        lines.append("  facet normal %.9e %.9e %.9e" % normal(t))
        lines.append("    outer loop")
        for v in t:
            lines.append("      vertex %.9e %.9e %.9e" % v)
        lines.append("    endloop")
        lines.append("  endfacet")
    lines.append(f"endsolid {name}")
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        f.write("\n".join(lines) + "\n")
    os.replace(tmp, path)
    print(f"{path}: {len(tris)} facets")


def hopper(n=48, closed=True):
    outlet, top = ring(4.0, 0.0, n), ring(20.0, 25.0, n)
    tris = band(outlet, top)
    if closed:
        tris += disk(outlet, (0.0, 0.0, 0.0))
    return tris


def tall_hopper(n=48, height=50.0):
    return hopper(n) + band(ring(20.0, 25.0, n), ring(20.0, height, n))


def silo(n=48, radius=15.0, height=40.0, levels=2):
    rings = [ring(radius, height * i / levels, n) for i in range(levels + 1)]
    tris = disk(rings[0], (0.0, 0.0, 0.0))
    for lo, hi in zip(rings, rings[1:]):
        tris += band(lo, hi)
    return tris


def main():
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    os.makedirs(os.path.join(root, "tests", "data"), exist_ok=True)
    write_stl(os.path.join(root, "inputs", "hopper.stl"), "hopper", hopper())
    write_stl(os.path.join(root, "inputs", "silo.stl"), "silo", silo())
    n = 96
    circumradius = 15.0 * math.sqrt(2 * math.pi / (n * math.sin(2 * math.pi / n)))
    write_stl(os.path.join(root, "tests", "data", "mesh_cylinder.stl"), "mesh_cylinder",
              silo(n=n, radius=circumradius, height=60.0, levels=1))
    write_stl(os.path.join(root, "tests", "data", "open_hopper.stl"), "open_hopper", hopper(closed=False))
    write_stl(os.path.join(root, "inputs", "tall_hopper.stl"), "tall_hopper", tall_hopper())
    return 0


if __name__ == "__main__":
    sys.exit(main())
