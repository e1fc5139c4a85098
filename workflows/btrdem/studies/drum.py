"""`drum`: size segregation and the dynamic angle in a slowly rotating drum under dynamic BTR
(seed 000 section 6, Figs. 12-13; Baumann, Janosi & Wolf).

Cases (each `btr drum` with --check, so every snapshot passed the self-check):
  poly2d    inputs/drum2d.toml: 2D, constant-mass radii 0.1-1 mm (ratio 10, as the paper, scaled)
  bi2d      the same drum with a bidisperse fill: radii 0.3 and 1 mm, equal area fractions
  poly3d    inputs/drum3d.toml: 3D, flat end walls, constant-mass radii 0.4-1 mm
  wide3d    (not with --tiny) 3D, 6000 spheres, constant-mass radii 0.2-1 mm, R = 20 mm, length 8 mm
Each runs `revolutions` revolutions of 100 steps (rotate 3.6 degrees, lift by R/10, redeposit).
The radial segregation index is (mean distance from the axis of the large grains - that of the small
grains) / R, small and large split at the median radius: > 0 when the small grains gather inwards.
The dynamic angle is the slope of the free surface over |x| <= 0.6 R, averaged over the last revolution.

Outputs: cases/<case>/ (scene, snapshots, .pvd, NAME_steps.csv), drum.csv, segregation.png,
surface_angle.png, snapshots.png (2D cases: initial and final), report.md, run.json."""
from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from ..core import report
from ..core.io import atomic_write_text, read_packing, read_scene_toml, write_scene_toml
from ..core.runner import REPO, RunRecord, StepFailed, failure_reason, find_btr, run_command


def cases(tiny: bool) -> list:
    poly2d = read_scene_toml(REPO / "inputs" / "drum2d.toml")
    poly3d = read_scene_toml(REPO / "inputs" / "drum3d.toml")
    bi2d = read_scene_toml(REPO / "inputs" / "drum2d.toml")
    bi2d["scene"]["name"] = "bi2d"
    bi2d["grains"].pop("radius")
    bi2d["grains"]["fraction_by"] = "volume"
    bi2d["grains"]["component"] = [
        {"species": 1, "fraction": 0.5, "radius": {"distribution": "constant", "value": 0.3e-3}},
        {"species": 2, "fraction": 0.5, "radius": {"distribution": "constant", "value": 1.0e-3}}]
    bi2d["grains"]["count"] = 1000  # about half the drum (equal areas: ~8 % of the disks are large)
    out = [("poly2d", poly2d), ("bi2d", bi2d), ("poly3d", poly3d)]
    if not tiny:  # a wider size ratio in 3D: constant-mass radii 0.2-1 mm, 6000 spheres
        wide3d = read_scene_toml(REPO / "inputs" / "drum3d.toml")
        wide3d["scene"]["name"] = "wide3d"
        wide3d["grains"]["count"] = 6000
        wide3d["grains"]["radius"] = {"distribution": "constant-mass", "min": 0.2e-3, "max": 1.0e-3}
        wide3d["container"].update(radius=0.02, length=0.008)
        wide3d["drum"]["lift"] = 0.002
        out.append(("wide3d", wide3d))
    if tiny:
        for _, sc in out:
            sc["grains"]["count"] = min(sc["grains"]["count"], 300)
            sc["drum"]["steps_per_revolution"] = 20
            sc["drum"]["snapshot_every"] = 10
    return out


def read_steps(path) -> dict:
    with open(path) as f:
        rows = list(csv.DictReader(f))
    return {k: np.array([float(r[k]) for r in rows]) for k in rows[0]} if rows else {}


def summarise(t: dict, steps_per_rev: int) -> dict:
    rev = t["step"] / steps_per_rev
    last = rev >= max(rev[-1] - 1.0, 0.0) + 1e-12 if rev[-1] > 1.0 else rev > 0
    angles = t["surface_angle_deg"][last]
    core = t["core_large_R"] - t["core_small_R"]
    k1 = min(steps_per_rev, len(rev) - 1)
    return {"revolutions": float(rev[-1]), "index_0": float(t["segregation_index"][0]),
            "core_index_0": float(core[0]), "core_index_one_rev": float(core[k1]),
            "core_index_end_mean": float(np.mean(core[last])),
            "index_end": float(t["segregation_index"][-1]),
            "index_one_rev": float(t["segregation_index"][k1]),
            "dynamic_angle_deg": float(np.nanmean(angles)) if np.any(np.isfinite(angles)) else float("nan"),
            "dynamic_angle_std": float(np.nanstd(angles)) if np.any(np.isfinite(angles)) else float("nan"),
            "seconds_per_step": float(np.mean(t["seconds"][1:])) if len(rev) > 1 else float("nan")}


class Study:
    def __init__(self, outdir, revolutions, tiny, progress):
        self.out, self.revolutions, self.tiny, self.progress = Path(outdir), revolutions, tiny, progress
        self.rows, self.series, self.snaps = [], {}, {}
        self.btr = find_btr()

    def run_case(self, rec, name, scene):
        d = self.out / "cases" / name
        d.mkdir(parents=True, exist_ok=True)
        scene["drum"]["revolutions"] = self.revolutions
        spr = int(scene["drum"]["steps_per_revolution"])
        row = {"case": name, "dimension": scene["scene"]["dimension"], "grains": scene["grains"]["count"],
               "status": "ok", "reason": ""}
        try:
            with rec.step(f"drum {name}"):
                path = d / "scene.toml"
                write_scene_toml(path, scene)
                res = run_command([self.btr, "drum", str(path), "-o", str(d), "--check", "--quiet"], d, "drum",
                                  progress=self.progress)
                if res["returncode"] != 0:
                    raise StepFailed(f"btr drum exited with status {res['returncode']}: "
                                     f"{Path(res['stderr']).read_text(errors='replace').strip()[-1500:]}")
                name_ = scene["scene"]["name"]
                t = read_steps(d / f"{name_}_steps.csv")
                row.update(summarise(t, spr))
                self.series[name] = (t, spr)
                snaps = sorted(d.glob(f"{name_}_s[0-9]*.csv"))
                self.snaps[name] = (snaps[0], snaps[-1], scene["container"]["radius"])
        except StepFailed as e:
            row.update(status="failed", reason=failure_reason(str(e)))
        self.rows.append(row)
        self.write_outputs()

    def write_outputs(self):
        keys = ["case", "dimension", "grains", "status", "reason", "revolutions", "index_0", "index_one_rev",
                "index_end", "core_index_0", "core_index_one_rev", "core_index_end_mean", "dynamic_angle_deg", "dynamic_angle_std", "seconds_per_step"]
        lines = [",".join(keys)] + [",".join("" if r.get(k) is None else str(r.get(k)).replace(",", ";")
                                             for k in keys) for r in self.rows]
        atomic_write_text(self.out / "drum.csv", "\n".join(lines) + "\n")
        seg = [(name, t["step"] / spr, t["segregation_index"]) for name, (t, spr) in self.series.items()]
        report.curves(self.out / "segregation.png", seg, "revolutions",
                      "segregation index (large - small) / R", "Radial segregation in the drum")
        ang = [(name, t["step"] / spr, t["surface_angle_deg"]) for name, (t, spr) in self.series.items()]
        report.curves(self.out / "surface_angle.png", ang, "revolutions", "free-surface angle [deg]",
                      "Dynamic angle of the free surface")
        self.snapshot_figure()
        atomic_write_text(self.out / "report.md", self.report_text())

    def snapshot_figure(self):
        import matplotlib.pyplot as plt
        from matplotlib.collections import PatchCollection
        from matplotlib.patches import Circle
        two_d = [(n, s) for n, s in self.snaps.items() if self.series[n][0] is not None and
                 next(r for r in self.rows if r["case"] == n)["dimension"] == 2]
        if not two_d:
            return
        fig, axes = plt.subplots(len(two_d), 2, figsize=(8, 4 * len(two_d)), squeeze=False)
        for (name, (first, last, R)), row in zip(two_d, axes):
            for ax, path, title in ((row[0], first, "initial fill"), (row[1], last, "last snapshot")):
                p = read_packing(path)
                big = p.radius > np.median(p.radius)
                patches = [Circle((x, z), r) for (x, _, z), r in zip(p.pos, p.radius)]
                pc = PatchCollection(patches, array=np.where(big, 1.0, 0.0), cmap="coolwarm", edgecolor="none")
                ax.add_collection(pc)
                ax.add_patch(Circle((0, R), R, fill=False, color="k", lw=1))
                ax.set_xlim(-1.05 * R, 1.05 * R)
                ax.set_ylim(-0.05 * R, 2.05 * R)
                ax.set_aspect("equal")
                ax.set_title(f"{name}: {title} (blue: small half by radius)", fontsize=9)
                ax.set_xticks([])
                ax.set_yticks([])
        fig.tight_layout()
        report.save_figure(fig, self.out / "snapshots.png")

    def report_text(self) -> str:
        out = ["# Rotating drum under dynamic BTR", "",
               "Each step rotates every grain with the drum by 360/steps_per_revolution degrees (the drum's lowest "
               "point moves towards +x, so the material climbs the +x side), lifts every grain by R/10 and "
               "redeposits all of them with the BTR engine, lowest first (`btr drum`, seed 000 section 6). Every "
               "snapshot passed the self-check.", "",
               "Segregation index: (mean distance from the axis of the large grains - that of the small grains) / "
               "R, with small and large split at the median radius; positive when the small grains gather "
               "towards the centre. Core index: the same with distances from the centre of mass of the fill "
               "(the last column: its mean over the last revolution, as the axis index swings while the pile "
               "rotates). Dynamic angle: slope of the free surface over |x| <= 0.6 R, mean (and "
               "standard deviation) over the last revolution.", ""]
        rows = [[r["case"], f"{r['dimension']}D", r["grains"], r["status"], report.fmt(r.get("index_0")),
                 report.fmt(r.get("index_one_rev")), report.fmt(r.get("index_end")),
                 report.fmt(r.get("core_index_0")), report.fmt(r.get("core_index_one_rev")),
                 report.fmt(r.get("core_index_end_mean")), report.fmt(r.get("dynamic_angle_deg")), report.fmt(r.get("dynamic_angle_std")),
                 report.fmt(r.get("seconds_per_step")), r["reason"] or ""] for r in self.rows]
        out.append(report.md_table(["case", "dim", "grains", "status", "index at fill", "index after 1 rev",
                                    f"index after {self.revolutions:g} rev", "core index at fill",
                                    "core index after 1 rev", "core index, last rev (mean)", "dynamic angle [deg]",
                                    "std [deg]",
                                    "s per step", "reason"], rows))
        out += ["![segregation](segregation.png)", "", "![angle](surface_angle.png)", "",
                "![snapshots](snapshots.png)", ""]
        return "\n".join(out)


def run_drum(outdir=None, revolutions: float = 3.0, tiny: bool = False, progress=print) -> dict:
    outdir = Path(outdir) if outdir else REPO / "out" / "drum"
    if tiny:
        revolutions = min(revolutions, 1.0)
    rec = RunRecord(outdir, "drum", progress=progress, btr=find_btr(),
                    inputs=[str(REPO / "inputs" / "drum2d.toml"), str(REPO / "inputs" / "drum3d.toml")],
                    settings={"revolutions": revolutions, "tiny": tiny})
    study = Study(outdir, revolutions, tiny, progress)
    for name, scene in cases(tiny):
        study.run_case(rec, name, scene)
    failed = [r["case"] for r in study.rows if r["status"] != "ok"]
    rec.finish({"rows": study.rows, "failed_cases": failed, "report": str(outdir / "report.md")})
    progress(f"drum: {len(study.rows)} cases ({len(failed)} failed); report {outdir / 'report.md'}")
    return {"rows": study.rows}
