#!/usr/bin/python3
"""Effect of quasi-static damping on a relaxation: the same BTR bed relaxed without and with damping, in the
engines given; prints, per run, the stop reason, simulated time to the stop, wall time, and the bulk packing
fraction and mean coordination of the relaxed bed (workflows' compare, the same measures as every study).

  /usr/bin/python3 scripts/bench_damping.py [--count 3000] [--damping 0.3] [--engines liggghts,yade]
                                            [--stop-rule kinetic-energy] [--max-time 1.0] [-o /tmp/bench_damping]
"""
import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def run(cmd):
    res = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    if res.returncode != 0:
        raise RuntimeError("%s failed:\n%s" % (" ".join(map(str, cmd)), res.stdout[-2000:]))
    return res.stdout


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scene", default=str(ROOT / "inputs" / "bed3d.toml"))
    ap.add_argument("--count", type=int, default=3000)
    ap.add_argument("--damping", type=float, default=0.3)
    ap.add_argument("--engines", default="liggghts,yade")
    ap.add_argument("--stop-rule", default="kinetic-energy")
    ap.add_argument("--max-time", type=float, default=1.0)
    ap.add_argument("--btr", default=str(ROOT / "build" / "app" / "btr"))
    ap.add_argument("-o", "--out", default="/tmp/bench_damping")
    a = ap.parse_args()
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    run([a.btr, "deposit", a.scene, "--count", str(a.count), "-o", str(out / "bed"), "-q", "--name", "bed"])
    packing = out / "bed" / "bed.csv"
    print("bed: %s, %d grains; stop rule %s, max_time %g s; load average %s" % (
        a.scene, a.count, a.stop_rule, a.max_time, open("/proc/loadavg").read().split()[:3]))
    print("| engine | damping | stop | simulated time [s] | wall [s] | packing fraction | coordination |")
    print("|---|---|---|---|---|---|---|")
    for engine in a.engines.split(","):
        for damping in (0.0, a.damping):
            d = out / ("%s_%g" % (engine, damping))
            run([a.btr, "relax", str(packing), "--engine", engine, "--damping", str(damping), "--stop-rule",
                 a.stop_rule, "--max-time", str(a.max_time), "-o", str(d)])
            relax = json.loads((d / "relaxed.json").read_text())["relax"]
            run([sys.executable, str(ROOT / "workflows" / "btr_workflow.py"), "compare", str(packing),
                 str(d / "relaxed.csv"), "-o", str(d / "compare")])
            post = json.loads((d / "compare" / "compare.json").read_text())["structure"]["post"]
            phi = post["packing_fraction"]
            phi = phi["value"] if isinstance(phi, dict) else phi
            print("| %s | %g | %s | %.4g | %.3g | %s | %s |" % (
                engine, damping, relax["stop_reason"], relax["simulated_time"], relax["wall_seconds"],
                "%.4f" % phi if phi is not None else "n/a",
                "%.3f" % post["coordination"]["mean"] if post["coordination"]["mean"] is not None else "n/a"),
                flush=True)
    pre = json.loads((out / ("%s_0" % a.engines.split(",")[0]) / "compare" / "compare.json").read_text())
    phi = pre["structure"]["pre"]["packing_fraction"]
    print("BTR bed before relaxation: packing fraction %s, coordination %s" % (
        phi["value"] if isinstance(phi, dict) else phi, pre["structure"]["pre"]["coordination"]["mean"]))


if __name__ == "__main__":
    main()
