#!/usr/bin/python3
"""Time per rotating-drum step against N (dynamic BTR, `btr drum`), printed as a table.

A 3D drum with flat end walls (length = radius), monodisperse-ish spheres (constant-mass radii
0.8-1 mm), filled to ~40 % of its volume; the radius grows with N so the fill stays the same. Each N
runs `btr drum --steps S` in a fresh process; the table gives the fill time, the mean wall and CPU
(process time, std::clock) time per step (every grain redeposited), grains placed per wall second,
and the projected wall and CPU time of one revolution of 100 steps. Then the least-squares exponent
b of CPU time per step ~ N^b.
    scripts/bench_drum.py [--sizes 1000,10000,100000] [--steps 3] [--dimension 3]"""
import argparse
import csv
import math
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


def scene_text(n: int, dim: int) -> str:
    a, b = 0.8e-3, 1.0e-3
    if dim == 3:
        mean_v = 4.0 / 3.0 * math.pi * a * b * (a + b) / 2.0  # constant-mass law: <R^3> = ab(a+b)/2
        # 0.4 pi R^2 L with L = R, grains at a packing fraction of ~0.58
        R = (n * mean_v / 0.58 / (0.4 * math.pi)) ** (1.0 / 3.0)
        cont = f'kind = "drum"\nradius = {R!r}\nlength = {R!r}'
    else:
        mean_a = math.pi * a * b
        R = math.sqrt(n * mean_a / 0.8 / (0.4 * math.pi))
        cont = f'kind = "drum"\nradius = {R!r}'
    return (f'[scene]\nname = "bench"\ndimension = {dim}\nseed = 1\n[grains]\ncount = {n}\n'
            f'radius = {{ distribution = "constant-mass", min = {a!r}, max = {b!r} }}\n'
            f'[container]\n{cont}\n[source]\nkind = "rain"\n'
            f'[drum]\nsteps_per_revolution = 100\nrevolutions = 1\nlift = {R / 10!r}\nsnapshot_every = 100000\n')


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sizes", default="1000,10000,100000")
    ap.add_argument("--steps", type=int, default=3)
    ap.add_argument("--dimension", type=int, choices=[2, 3], default=3)
    ap.add_argument("--btr", default=os.environ.get("BTR_BINARY", str(REPO / "build" / "app" / "btr")))
    args = ap.parse_args()
    sizes = [int(float(s)) for s in args.sizes.split(",") if s]
    print(f"{'N':>9} {'fill s':>8} {'s/step':>9} {'cpu s/step':>10} {'grains/s':>10} {'1 rev wall s':>12} "
          f"{'1 rev cpu s':>11}")
    xs, ys = [], []
    with tempfile.TemporaryDirectory() as tmp:
        for n in sizes:
            scene = Path(tmp) / f"bench_{n}.toml"
            scene.write_text(scene_text(n, args.dimension))
            out = Path(tmp) / f"out_{n}"
            t0 = time.monotonic()
            p = subprocess.run([args.btr, "drum", str(scene), "-o", str(out), "--steps", str(args.steps), "-q"],
                               capture_output=True, text=True)
            if p.returncode != 0:
                print(f"{n:>9} FAILED: {p.stderr.strip()[-300:]}")
                continue
            rows = list(csv.DictReader(open(out / "bench_steps.csv")))
            fill = float(rows[0]["seconds"])
            per_step = sum(float(r["seconds"]) for r in rows[1:]) / (len(rows) - 1)
            cpu_step = sum(float(r["cpu_seconds"]) for r in rows[1:]) / (len(rows) - 1)
            print(f"{n:>9} {fill:>8.3f} {per_step:>9.4f} {cpu_step:>10.4f} {n / per_step:>10.0f} "
                  f"{100 * per_step:>12.1f} {100 * cpu_step:>11.1f}", flush=True)
            xs.append(math.log(n))
            ys.append(math.log(cpu_step))
    if len(xs) >= 2:
        mx, my = sum(xs) / len(xs), sum(ys) / len(ys)
        b = sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sum((x - mx) ** 2 for x in xs)
        print(f"\nleast-squares exponent b of CPU time per step ~ N^b: {b:.2f}")


if __name__ == "__main__":
    sys.exit(main())
