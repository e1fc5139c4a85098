#!/usr/bin/python3
"""The mesh container against the analytic one: inputs/cylinder.toml's grains rained into the cylinder
container and into tests/data/mesh_cylinder.stl (the same cylinder as 96 flat panels of equal area, 288
facets), several seeds each; packing fraction and coordination in the same bulk window; and a figure of a
filled hopper (inputs/hopper.toml).

    /usr/bin/python3 scripts/validate_mesh.py [--btr build/app/btr] [--seeds 5] [--count 3000] [-o docs/mesh]

Writes OUT/mesh_validation.json and OUT/hopper.png. The window: centres within R - 2 d_max of the axis,
from 2 d_max above the floor up to the 90th percentile of centre heights less 2 d_max; a grain counts by
its centre (the same rule for both containers, so the comparison is fair; the absolute value is biased
low by the window's edges)."""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

import numpy as np
from scipy.spatial import cKDTree

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def deposit(btr, scene, seed, count, out):
    t0 = time.time()
    subprocess.run([btr, "deposit", scene, "-o", out, "--seed", str(seed), "--count", str(count), "-q", "--check"],
                   check=True)
    name = os.path.splitext(os.path.basename(scene))[0]
    data = np.loadtxt(os.path.join(out, name + ".csv"), delimiter=",", skiprows=1)
    return data, time.time() - t0


def measures(data, radius):
    x, r = data[:, 1:4], data[:, 4]
    d_max = 2.0 * r.max()
    rho = np.hypot(x[:, 0], x[:, 1])
    z_hi = np.percentile(x[:, 2], 90) - 2 * d_max
    inside = (rho < radius - 2 * d_max) & (x[:, 2] > 2 * d_max) & (x[:, 2] < z_hi)
    window = np.pi * (radius - 2 * d_max) ** 2 * (z_hi - 2 * d_max)
    phi = float(np.sum(4.0 / 3.0 * np.pi * r[inside] ** 3) / window)
    tree = cKDTree(x)
    pairs = tree.query_pairs(2 * r.max() * (1 + 1e-6), output_type="ndarray")
    dist = np.linalg.norm(x[pairs[:, 0]] - x[pairs[:, 1]], axis=1)
    touch = pairs[dist <= (r[pairs[:, 0]] + r[pairs[:, 1]]) * (1 + 1e-7)]
    z = np.bincount(touch.ravel(), minlength=len(r))
    return phi, float(z[inside].mean()), int(inside.sum())


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--btr", default=os.path.join(ROOT, "build", "app", "btr"))
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--count", type=int, default=3000)
    ap.add_argument("-o", "--out", default=os.path.join(ROOT, "docs", "mesh"))
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        with open(os.path.join(ROOT, "inputs", "cylinder.toml")) as f:
            text = f.read()
        mesh_scene = os.path.join(tmp, "mesh_cylinder.toml")
        stl = os.path.join(ROOT, "tests", "data", "mesh_cylinder.stl")
        with open(mesh_scene, "w") as f:
            f.write(text.replace('name = "cylinder"', 'name = "mesh_cylinder"')
                    .replace('kind = "cylinder"\nradius = 0.015\nheight = 0.06',
                             'kind = "mesh"\nfile = "%s"\nscale = 1e-3' % stl))
        result = {"count": a.count, "seeds": list(range(1, a.seeds + 1)), "window": "see the script's docstring"}
        for label, scene in (("cylinder", os.path.join(ROOT, "inputs", "cylinder.toml")), ("mesh", mesh_scene)):
            rows = []
            for seed in result["seeds"]:
                data, secs = deposit(a.btr, scene, seed, a.count, os.path.join(tmp, "%s_%d" % (label, seed)))
                phi, z, n = measures(data, 0.015)
                rows.append({"seed": seed, "phi": phi, "coordination": z, "grains_in_window": n, "seconds": secs})
                print(label, rows[-1], flush=True)
            phis = np.array([r["phi"] for r in rows])
            zs = np.array([r["coordination"] for r in rows])
            result[label] = {"runs": rows, "phi_mean": phis.mean(), "phi_std": phis.std(ddof=1),
                             "z_mean": zs.mean(), "z_std": zs.std(ddof=1)}
        c, m = result["cylinder"], result["mesh"]
        result["phi_difference"] = m["phi_mean"] - c["phi_mean"]
        result["z_difference"] = m["z_mean"] - c["z_mean"]
        # Within the scatter: the difference of the means within two standard errors of it.
        n = a.seeds
        result["phi_within_scatter"] = bool(abs(result["phi_difference"]) <= 2 * np.hypot(c["phi_std"], m["phi_std"]) / np.sqrt(n))
        result["z_within_scatter"] = bool(abs(result["z_difference"]) <= 2 * np.hypot(c["z_std"], m["z_std"]) / np.sqrt(n))
        with open(os.path.join(a.out, "mesh_validation.json.tmp"), "w") as f:
            json.dump(result, f, indent=1)
        os.replace(os.path.join(a.out, "mesh_validation.json.tmp"), os.path.join(a.out, "mesh_validation.json"))
        print(json.dumps({k: v for k, v in result.items() if k not in ("cylinder", "mesh")}, indent=1))

        hopper, _ = deposit(a.btr, os.path.join(ROOT, "inputs", "hopper.toml"), 1, 1500, os.path.join(tmp, "hopper"))
        figure(hopper, os.path.join(a.out, "hopper.png"))
    return 0


def figure(data, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    x, r = data[:, 1:4] * 1e3, data[:, 4] * 1e3
    fig = plt.figure(figsize=(9, 4.5))
    ax = fig.add_subplot(1, 2, 1, projection="3d")
    ax.scatter(x[:, 0], x[:, 1], x[:, 2], s=(r / r.max()) ** 2 * 6, c=x[:, 2], cmap="viridis", depthshade=True)
    t = np.linspace(0, 2 * np.pi, 97)
    for z, rad in ((0.0, 4.0), (25.0, 20.0)):
        ax.plot(rad * np.cos(t), rad * np.sin(t), z, color="0.3", lw=0.8)
    for k in range(0, 96, 12):
        ax.plot([4 * np.cos(t[k]), 20 * np.cos(t[k])], [4 * np.sin(t[k]), 20 * np.sin(t[k])], [0, 25], color="0.3", lw=0.6)
    ax.set_xlabel("x [mm]"); ax.set_ylabel("y [mm]"); ax.set_zlabel("z [mm]")
    ax.set_title("BTR fill of inputs/hopper.toml (%d grains)" % len(r))
    ax2 = fig.add_subplot(1, 2, 2)
    sl = np.abs(x[:, 1]) < r
    for (px, pz), pr in zip(x[sl][:, [0, 2]], np.sqrt(np.maximum(r[sl] ** 2 - x[sl][:, 1] ** 2, 0))):
        ax2.add_patch(plt.Circle((px, pz), pr, color="tab:orange", alpha=0.8))
    ax2.plot([-20, -4, 4, 20], [25, 0, 0, 25], color="k", lw=1)
    ax2.set_aspect("equal"); ax2.set_xlim(-22, 22); ax2.set_ylim(-1, 27)
    ax2.set_xlabel("x [mm]"); ax2.set_ylabel("z [mm]"); ax2.set_title("section |y| < r through the axis")
    fig.tight_layout()
    fig.savefig(path + ".tmp.png", dpi=110)
    os.replace(path + ".tmp.png", path)


if __name__ == "__main__":
    sys.exit(main())
