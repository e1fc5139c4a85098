"""`brazil-nut`: the Brazil-nut effect under dynamic BTR shaking (seed 001 section 6.6, Jullien-Meakin).

One intruder of diameter ratio Phi rests on the floor under a bed of equal grains (diameter d) in a
laterally periodic cell; `btr shake` lifts and redeposits the pile cycle after cycle. For each
dimension, noise amplitude a (in d) and Phi the study records the intruder's centre height (in d,
and relative to the bed's mean top) against cycles. An intruder "rises" when its centre climbs at
least RISE_D = 2 d during the run, and "reaches the top" when its top comes within one d of the bed's
mean surface; each measured threshold lies between the largest Phi that does not and the smallest that
does, to compare with Phi_c = (3 + sqrt 2)/(3 - sqrt 2) ~ 2.78 in 3D (Jullien-Meakin found ~2.8 with
this model) and 12.9 in 2D (Duran's arch model).
Beds without an intruder give the packing fraction against cycles: does shaking densify a BTR bed?

Outputs: cases/<case>/ (scene, snapshots, NAME_cycles.csv), brazil_nut.csv (one row per case),
densify.csv, height_vs_cycles.png, rise_vs_phi.png, packing_vs_cycles.png, report.md, run.json.
A failed case is a row with its reason; the others still run."""
from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np

from ..core import report
from ..core.io import atomic_write_text, write_scene_toml
from ..core.runner import REPO, RunRecord, StepFailed, failure_reason, find_btr, run_command

PHI_C = {3: (3 + math.sqrt(2)) / (3 - math.sqrt(2)), 2: 12.9}
D = 1.0e-3  # bed-grain diameter [m]

# Per dimension: cell footprint (in d), bed grains, cycles, Phi values. The cell is periodic and at least
# three intruder diameters wide for the largest Phi; the bed is ~25 d (3D) and ~38 d (2D) deep.
FULL = {
    3: {"size": 12.0, "count": 4000, "cycles": 80, "phis": [1.5, 2.0, 2.5, 3.0, 3.5, 4.0]},
    2: {"size": 64.0, "count": 3000, "cycles": 150, "phis": [2.0, 4.0, 8.0, 11.0, 13.0, 15.0, 18.0]},
}
TINY = {
    3: {"size": 8.0, "count": 400, "cycles": 6, "phis": [1.5, 4.0]},
    2: {"size": 24.0, "count": 300, "cycles": 6, "phis": [2.0, 8.0]},
}
NOISES = [0.0, 0.1, 0.3]  # amplitude a in d
RISE_D = 2.0  # climb (in d) over the run that counts as rising
TINY_NOISES = [0.0, 0.3]


def scene_dict(dim: int, size_d: float, count: int, cycles: int, noise_d: float, phi: float | None, seed: int,
               name: str) -> dict:
    size = [size_d * D] * (dim - 1)
    lift = max(2.0, phi or 1.0) * D  # above the fall of any grain: the lift then does not matter
    sc = {
        "scene": {"name": name, "dimension": dim, "seed": seed},
        "grains": {"count": count, "density": 2500.0, "radius": {"distribution": "constant", "value": 0.5 * D}},
        "container": {"kind": "periodic", "size": size},
        "source": {"kind": "rain"},
    }
    if phi is not None:
        sc["intruder"] = {"diameter_ratio": phi, "position": [0.0] * (dim - 1)}
    sc["shaking"] = {"cycles": cycles, "lift": lift, "noise": noise_d * D, "snapshot_every": max(1, cycles // 4)}
    return sc


def read_cycles(path) -> dict:
    with open(path) as f:
        rows = list(csv.DictReader(f))
    return {k: np.array([float(r[k]) for r in rows]) for k in rows[0]} if rows else {}


def summarise(t: dict, phi: float | None) -> dict:
    """Numbers of one case from its per-cycle table."""
    out = {"cycles": int(t["cycle"][-1]), "seconds_per_cycle": float(np.mean(t["seconds"][1:]))
           if len(t["seconds"]) > 1 else float("nan")}
    phi_fr = t["packing_fraction"]
    out["packing_fraction_0"] = float(phi_fr[0])
    q = max(1, len(phi_fr) // 5)
    out["packing_fraction_end"] = float(np.nanmean(phi_fr[-q:]))
    if phi is None:
        return out
    z, below = t["intruder_z_d"], t["intruder_below_top_d"]
    reached = np.nonzero(below <= 0.5 * phi + 1.0)[0]
    out.update(z0_d=float(z[0]), z_end_d=float(z[-1]), bed_top_d=float(t["bed_top_d"][-1]),
               rel_end=float(t["intruder_z_over_bed_top"][-1]), rose=bool(np.max(z) - z[0] >= RISE_D),
               reached_top=bool(len(reached)), cycles_to_top=int(t["cycle"][reached[0]]) if len(reached) else None)
    # Rise speed: up to the first arrival at the top (or over the whole run).
    k = reached[0] if len(reached) else len(z) - 1
    out["rise_d_per_cycle"] = float((z[k] - z[0]) / t["cycle"][k]) if k > 0 else 0.0
    return out


def threshold(rows: list, dim: int, noise: float, key: str = "rose"):
    """(largest Phi without `key`, smallest Phi with it, not monotonic) among the successful cases;
    key: "rose" (climbed RISE_D) or "reached_top"."""
    ok = [r for r in rows if r["dimension"] == dim and r["noise_d"] == noise and r["status"] == "ok"
          and r.get("phi") is not None]
    below = [r["phi"] for r in ok if not r[key]]
    above = [r["phi"] for r in ok if r[key]]
    return (max(below) if below else None, min(above) if above else None,
            bool(below and above and max(below) > min(above)))


class Study:
    def __init__(self, outdir, dims, noises, plan, seed, progress):
        self.out = Path(outdir)
        self.dims, self.noises, self.plan, self.seed, self.progress = dims, noises, plan, seed, progress
        self.rows, self.series = [], {}
        self.btr = find_btr()

    def run_case(self, rec: RunRecord, dim: int, noise: float, phi: float | None):
        p = self.plan[dim]
        tag = f"{dim}d_a{noise:g}_" + (f"phi{phi:g}" if phi is not None else "bed")
        case_dir = self.out / "cases" / tag
        case_dir.mkdir(parents=True, exist_ok=True)
        row = {"case": tag, "dimension": dim, "noise_d": noise, "phi": phi, "status": "ok", "reason": ""}
        try:
            with rec.step(f"shake {tag}"):
                scene = case_dir / "scene.toml"
                write_scene_toml(scene, scene_dict(dim, p["size"], p["count"], p["cycles"], noise, phi, self.seed,
                                                   "shake"))
                res = run_command([self.btr, "shake", str(scene), "-o", str(case_dir), "--check", "--quiet"],
                                  case_dir, "shake", progress=self.progress)
                if res["returncode"] != 0:
                    raise StepFailed(f"btr shake exited with status {res['returncode']}: "
                                     f"{Path(res['stderr']).read_text(errors='replace').strip()[-1500:]}")
                t = read_cycles(case_dir / "shake_cycles.csv")
                row.update(summarise(t, phi))
                self.series[tag] = t
        except StepFailed as e:
            row.update(status="failed", reason=failure_reason(str(e)))
        self.rows.append(row)
        self.write_outputs()

    def run(self, rec: RunRecord):
        for dim in self.dims:
            for noise in self.noises:
                self.run_case(rec, dim, noise, None)
                for phi in self.plan[dim]["phis"]:
                    self.run_case(rec, dim, noise, phi)

    # ---- outputs, rewritten after every case
    def write_outputs(self):
        keys = ["case", "dimension", "noise_d", "phi", "status", "reason", "cycles", "z0_d", "z_end_d", "bed_top_d",
                "rel_end", "rose", "reached_top", "cycles_to_top", "rise_d_per_cycle", "packing_fraction_0",
                "packing_fraction_end", "seconds_per_cycle"]
        lines = [",".join(keys)]
        for r in self.rows:
            lines.append(",".join("" if r.get(k) is None else str(r.get(k)).replace(",", ";") for k in keys))
        atomic_write_text(self.out / "brazil_nut.csv", "\n".join(lines) + "\n")
        self.figures()
        atomic_write_text(self.out / "report.md", self.report_text())

    def figures(self):
        import matplotlib.pyplot as plt
        combos = [(d, a) for d in self.dims for a in self.noises]
        fig, axes = plt.subplots(len(self.dims), len(self.noises), figsize=(4.2 * len(self.noises),
                                                                            3.4 * len(self.dims)), squeeze=False)
        for (dim, noise), ax in zip(combos, axes.flat):
            for r in self.rows:
                if r["dimension"] != dim or r["noise_d"] != noise or r["phi"] is None or r["case"] not in self.series:
                    continue
                t = self.series[r["case"]]
                ax.plot(t["cycle"], t["intruder_z_over_bed_top"], label=f"Phi = {r['phi']:g}")
            ax.set_title(f"{dim}D, noise a = {noise:g} d (Phi_c = {PHI_C[dim]:.3g})", fontsize=9)
            ax.set_xlabel("cycle")
            ax.set_ylabel("intruder height / bed top")
            ax.set_ylim(bottom=0)
            if ax.get_legend_handles_labels()[0]:
                ax.legend(fontsize=7, loc="lower right")
        fig.tight_layout()
        report.save_figure(fig, self.out / "height_vs_cycles.png")

        fig, axes = plt.subplots(1, len(self.dims), figsize=(5 * len(self.dims), 3.6), squeeze=False)
        for dim, ax in zip(self.dims, axes.flat):
            for noise in self.noises:
                pts = sorted((r["phi"], r["rise_d_per_cycle"]) for r in self.rows if r["dimension"] == dim
                             and r["noise_d"] == noise and r["phi"] is not None and r["status"] == "ok")
                if pts:
                    ax.plot(*zip(*pts), "o-", label=f"a = {noise:g} d")
            ax.axvline(PHI_C[dim], color="k", ls="--", lw=1, label=f"Phi_c = {PHI_C[dim]:.3g}")
            ax.set_xlabel("diameter ratio Phi")
            ax.set_ylabel("rise speed [d per cycle]")
            ax.set_title(f"{dim}D")
            ax.legend(fontsize=7)
        fig.tight_layout()
        report.save_figure(fig, self.out / "rise_vs_phi.png")

        series = []
        for r in self.rows:
            if r["phi"] is None and r["case"] in self.series:
                t = self.series[r["case"]]
                series.append((f"{r['dimension']}D, a = {r['noise_d']:g} d", t["cycle"], t["packing_fraction"]))
        report.curves(self.out / "packing_vs_cycles.png", series, "cycle", "bulk packing fraction",
                      "Beds without intruder under shaking")

    def report_text(self) -> str:
        out = ["# Brazil nut under dynamic BTR shaking", "",
               "One intruder of diameter ratio Phi starts on the floor under a bed of equal grains (diameter d) in a "
               "laterally periodic cell. One cycle: number the grains by height, lift the pile, redeposit them "
               "lowest first with the BTR engine (`btr shake`), each grain displaced horizontally by a uniform "
               "random amount in [-a, a] per axis (noise a; a = 0 is the deterministic model). Every snapshot "
               "passed the self-check (`--check`).", ""]
        for dim in self.dims:
            p = self.plan[dim]
            out.append(f"- {dim}D: cell {p['size']:g} d wide (periodic), {p['count']} bed grains, {p['cycles']} "
                       f"cycles per case.")
        out += ["", f"An intruder *rises* when its centre climbs at least {RISE_D:g} d during the run, and *reaches "
                "the top* when its top comes within 1 d of the bed's mean surface (`intruder_below_top_d <= Phi/2 + "
                "1`). Rise speed: centre height gained per cycle up to the top (or over the run).", "",
                "## Measured threshold", ""]

        def where(lo, hi, mixed):
            if mixed:
                return "not monotonic in Phi"
            if lo is not None and hi is not None:
                return "between " + report.fmt(lo) + " and " + report.fmt(hi)
            if lo is not None:
                return f"> {report.fmt(lo)} (no Phi did)"
            return f"< {report.fmt(hi)} (every Phi did)" if hi is not None else "n/a"

        trows = []
        for dim in self.dims:
            for noise in self.noises:
                trows.append([f"{dim}D", report.fmt(noise), where(*threshold(self.rows, dim, noise, "rose")),
                              where(*threshold(self.rows, dim, noise, "reached_top")), report.fmt(PHI_C[dim])])
        out.append(report.md_table(["dimension", "noise a [d]", f"threshold: rises >= {RISE_D:g} d",
                                    "threshold: reaches the top", "Phi_c (seed 001)"], trows))
        out += ["## Cases", ""]
        crow = []
        for r in self.rows:
            if r["phi"] is None:
                continue
            crow.append([r["case"], f"{r['dimension']}D", report.fmt(r["noise_d"]), report.fmt(r["phi"]), r["status"],
                         report.fmt(r.get("z0_d")), report.fmt(r.get("z_end_d")), report.fmt(r.get("bed_top_d")),
                         report.fmt(r.get("rel_end")), report.fmt(r.get("cycles_to_top")),
                         report.fmt(r.get("rise_d_per_cycle")), report.fmt(r.get("seconds_per_cycle")),
                         r["reason"] or ""])
        out.append(report.md_table(["case", "dim", "a [d]", "Phi", "status", "z start [d]", "z end [d]",
                                    "bed top [d]", "z end / top", "cycles to top", "rise [d/cycle]", "s/cycle",
                                    "reason"], crow))
        out += ["![intruder height](height_vs_cycles.png)", "", "![rise speed](rise_vs_phi.png)", "",
                "## Does shaking densify a BTR bed?", ""]
        drow = []
        for r in self.rows:
            if r["phi"] is not None:
                continue
            p0, p1 = r.get("packing_fraction_0"), r.get("packing_fraction_end")
            drow.append([f"{r['dimension']}D", report.fmt(r["noise_d"]), r["status"], report.fmt(p0), report.fmt(p1),
                         report.fmt(p1 - p0 if p0 is not None and p1 is not None else None), r["reason"] or ""])
        out.append(report.md_table(["dimension", "noise a [d]", "status", "packing fraction, cycle 0",
                                    "mean of the last 20 % of cycles", "change", "reason"], drow))
        out += ["![packing fraction](packing_vs_cycles.png)", ""]
        return "\n".join(out)


def run_brazil_nut(outdir=None, dims=(3, 2), tiny: bool = False, seed: int = 1, progress=print) -> dict:
    outdir = Path(outdir) if outdir else REPO / "out" / "brazil_nut"
    plan = TINY if tiny else FULL
    noises = TINY_NOISES if tiny else NOISES
    rec = RunRecord(outdir, "brazil-nut", progress=progress, btr=find_btr(),
                    settings={"dimensions": list(dims), "noises_d": noises, "plan": {str(k): plan[k] for k in dims},
                              "seed": seed, "tiny": tiny, "phi_c": {str(k): v for k, v in PHI_C.items()}})
    study = Study(outdir, list(dims), noises, plan, seed, progress)
    study.run(rec)
    thresholds = {f"{d}D a={a:g}": {"rises": threshold(study.rows, d, a, "rose")[:2],
                                    "reaches_top": threshold(study.rows, d, a, "reached_top")[:2]}
                  for d in dims for a in noises}
    failed = [r["case"] for r in study.rows if r["status"] != "ok"]
    rec.finish({"thresholds": thresholds, "failed_cases": failed, "report": str(outdir / "report.md")})
    progress(f"brazil-nut: {len(study.rows)} cases ({len(failed)} failed); report {outdir / 'report.md'}")
    return {"rows": study.rows, "thresholds": thresholds}
