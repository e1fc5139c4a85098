"""`nano-powder`: coarsening of a cohesive nano-powder by redeposition of rigid clusters (seed 000
section 5, Fig. 11). Each case runs `btr redeposit --check` (every cycle's packing passed the cluster
check: no overlap, every cluster statically supported) for one or more seeds and fits the mean height
of the deposit, averaged over the seeds, over the cycles n >= 1 (the seed: the initial deposit of
clusters of 3 does not fit the law) with

    <h>(n) = a - b exp(-n / tau)

by scipy's curve_fit; the uncertainties are the square roots of the covariance's diagonal.
The seed found <h> = 9450 - 5000 exp(-n/6) for 6e6 disks in a box 8000 wide, blocks of 50 d.

Cases: 2d (inputs/nano_powder.toml, one seed) and 3d (the same grains in a square box, three seeds),
sizes that run in minutes. Outputs: cases/<case>/seed<s>/ (snapshots, NAME_cycles.csv, NAME_sizes.csv),
nano_powder.csv (one row per case with a, b, tau and their uncertainties), mean_height.png, report.md,
run.json."""
from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np

from ..core import report
from ..core.io import atomic_write_text, read_scene_toml, write_scene_toml
from ..core.runner import REPO, RunRecord, StepFailed, find_btr, run_command


def saturating(n, a, b, tau):
    return a - b * np.exp(-np.asarray(n, dtype=float) / tau)


def fit_saturation(n, h) -> dict:
    """Least-squares fit of h = a - b exp(-n/tau); returns a, b, tau and their standard errors
    (NaN errors when the fit is underdetermined: fewer than 4 points). Raises ValueError if it fails."""
    from scipy.optimize import curve_fit
    n = np.asarray(n, dtype=float)
    h = np.asarray(h, dtype=float)
    if len(n) < 3:
        raise ValueError(f"fit: expected at least 3 cycles, got {len(n)}")
    a0 = float(h.max())
    b0 = max(float(h.max() - h.min()), 1e-12 * max(abs(a0), 1.0))
    popt, pcov = curve_fit(saturating, n, h, p0=(a0, b0, max(1.0, float(n.max() - n.min()) / 3.0)),
                           bounds=([-np.inf, -np.inf, 1e-3], [np.inf, np.inf, 1e4]), maxfev=20000)
    err = np.sqrt(np.diag(pcov)) if len(n) > 3 and np.all(np.isfinite(pcov)) else np.full(3, np.nan)
    # tau shorter than half the cycle spacing (the exponential is gone by the first fitted cycle) or
    # less than its own error: the data show no approach to saturation, so b and tau mean nothing.
    spacing = float(np.min(np.diff(np.unique(n)))) if len(np.unique(n)) > 1 else 1.0
    determined = bool(popt[2] > 0.5 * spacing and np.isfinite(err[2]) and err[2] < popt[2])
    return {"a": float(popt[0]), "b": float(popt[1]), "tau": float(popt[2]),
            "a_err": float(err[0]), "b_err": float(err[1]), "tau_err": float(err[2]), "determined": determined}


def read_cycles(path) -> dict:
    with open(path) as f:
        rows = list(csv.DictReader(f))
    return {k: np.array([float(r[k]) for r in rows]) for k in rows[0]} if rows else {}


def cases(tiny: bool, cycles: int) -> list:
    """(name, scene, seeds). 3d: 16 000 spheres, blocks of 10 d in a box 40 d x 40 d, three seeds
    averaged (about a minute each). With blocks of 5 d the height saturates within the first cycle, so b
    and tau are not determined; with blocks of 10 d in a box 20 d wide (two blocks across) one seed gave
    tau = 5 +- 5."""
    two = read_scene_toml(REPO / "inputs" / "nano_powder.toml")
    three = read_scene_toml(REPO / "inputs" / "nano_powder.toml")
    three["scene"].update(name="nano_powder3d", dimension=3)
    three["grains"]["count"] = 1000 if tiny else 16000
    side = 40e-6 if tiny else 80e-6  # 20 or 40 mean diameters
    three["container"]["size"] = [side, side]
    three["clusters"]["block"] = 10.0
    if tiny:
        two["grains"]["count"] = 600
        two["container"]["size"] = [60e-6]
    for s in (two, three):
        s["clusters"]["cycles"] = cycles
    return [("2d", two, [two["scene"]["seed"]]), ("3d", three, [1, 2] if tiny else [1, 2, 3])]


def mean_over_seeds(runs: list) -> dict:
    """The per-cycle series of several seeds averaged (seconds summed); mean_height_err is the standard
    error of the mean height over the seeds (NaN for one seed). Raises ValueError if the cycles differ."""
    cycles = runs[0]["cycle"]
    if any(len(t["cycle"]) != len(cycles) or np.any(t["cycle"] != cycles) for t in runs):
        raise ValueError("the seeds' runs have different cycles")
    out = {k: np.mean([t[k] for t in runs], axis=0) for k in runs[0]}
    out["seconds"] = np.sum([t["seconds"] for t in runs], axis=0)
    h = np.array([t["mean_height_d"] for t in runs])
    out["mean_height_err"] = (h.std(axis=0, ddof=1) / math.sqrt(len(runs)) if len(runs) > 1
                              else np.full(len(cycles), np.nan))
    return out


def fit_or_none(t) -> dict | None:
    later = t["cycle"] >= 1
    try:
        return fit_saturation(t["cycle"][later], t["mean_height_d"][later])
    except (ValueError, RuntimeError):  # RuntimeError: curve_fit found no minimum
        return None


class Study:
    def __init__(self, outdir, progress):
        self.out, self.progress = Path(outdir), progress
        self.rows, self.series, self.seed_series = [], {}, {}
        self.btr = find_btr()

    def run_case(self, rec, name, scene, seeds):
        d = self.out / "cases" / name
        d.mkdir(parents=True, exist_ok=True)
        row = {"case": name, "dimension": scene["scene"]["dimension"], "grains": scene["grains"]["count"],
               "block_d": scene["clusters"]["block"], "cycles": scene["clusters"]["cycles"],
               "seeds": " ".join(str(s) for s in seeds)}
        with rec.case(f"redeposit {name}", self.rows, row, on_row=lambda rows: self.write_outputs()):
            path = d / "scene.toml"
            write_scene_toml(path, scene)
            runs, failed = [], []
            for seed in seeds:
                sd = d / f"seed{seed}"
                res = run_command([self.btr, "redeposit", str(path), "-o", str(sd), "--seed", str(seed), "--check",
                                   "--quiet"], sd, "redeposit", progress=self.progress)
                stderr = Path(res["stderr"]).read_text(errors="replace").strip()
                if res["returncode"] == 4:  # files written, but some cycle's packing failed the cluster check
                    failed.append(f"seed {seed}: " + " ".join(stderr.splitlines()[:2]))
                elif res["returncode"] != 0:
                    raise StepFailed(f"btr redeposit (seed {seed}) exited with status {res['returncode']}: "
                                     f"{stderr[-1500:]}")
                runs.append(read_cycles(sd / f"{scene['scene']['name']}_cycles.csv"))
            if failed:
                row.update(status="check-failed", reason="; ".join(failed)[:300])
            t = mean_over_seeds(runs)
            self.series[name], self.seed_series[name] = t, runs
            later = t["cycle"] >= 1
            row.update(h0_d=float(t["mean_height_d"][0]), h_last_d=float(t["mean_height_d"][-1]),
                       phi_last=float(t["packing_fraction"][-1]),
                       mean_cluster_last=float(t["mean_cluster_size"][-1]),
                       seconds=float(t["seconds"].sum()))
            row.update(fit_saturation(t["cycle"][later], t["mean_height_d"][later]))

    def write_outputs(self):
        keys = ["case", "dimension", "grains", "block_d", "cycles", "seeds", "status", "reason", "h0_d", "h_last_d",
                "phi_last", "mean_cluster_last", "a", "a_err", "b", "b_err", "tau", "tau_err", "determined", "seconds"]
        lines = [",".join(keys)] + [",".join("" if r.get(k) is None else str(r.get(k)).replace(",", ";")
                                             for k in keys) for r in self.rows]
        atomic_write_text(self.out / "nano_powder.csv", "\n".join(lines) + "\n")
        self.figure()
        atomic_write_text(self.out / "report.md", self.report_text())

    def figure(self):
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(figsize=(6, 4))
        for name, t in self.series.items():
            runs = self.seed_series[name]
            label = f"{name}: measured" + (f", mean of {len(runs)} seeds" if len(runs) > 1 else "")
            line = ax.errorbar(t["cycle"], t["mean_height_d"],
                               yerr=None if len(runs) == 1 else t["mean_height_err"], fmt="D", ms=4,
                               capsize=2, label=label)[0]
            if len(runs) > 1:
                for r in runs:
                    ax.plot(r["cycle"], r["mean_height_d"], ".", color=line.get_color(), alpha=0.35, ms=3)
            row = next(r for r in self.rows if r["case"] == name)
            if row.get("determined"):
                n = np.linspace(1, t["cycle"].max(), 200)
                ax.plot(n, saturating(n, row["a"], row["b"], row["tau"]), "-", color=line.get_color(),
                        label=f"{name}: {row['a']:.3g} - {row['b']:.3g} exp(-n/{row['tau']:.3g})")
        ax.set_xlabel("redeposition cycle n")
        ax.set_ylabel("<h> [mean diameters]")
        ax.set_title("Mean height of the deposit vs redeposition cycle")
        ax.legend(fontsize=8)
        report.save_figure(fig, self.out / "mean_height.png")

    def report_text(self) -> str:
        out = ["# Nano-powder coarsening by redeposition of rigid clusters", "",
               "Per case and seed: `btr redeposit --check` (status check-failed: some cycle had clusters the "
               "independent check found unsupported or overlapping; the reason column quotes it) (initial "
               "clusters of 3, then per cycle blocks of `block_d` mean diameters split into clusters of "
               "touching grains and dropped again). <h>: strips one mean diameter wide, top of the highest "
               "grain of each, averaged (in mean diameters), then averaged over the seeds (error bars: "
               "standard error over the seeds; small dots: the seeds). Fit of <h> = a - b exp(-n/tau) over "
               "cycles n >= 1, errors one standard deviation from curve_fit's covariance. The seed (6e6 disks, "
               "blocks of 50 d): 9450 - 5000 exp(-n/6).", "",
               "![mean height](mean_height.png)", ""]

        def fitted(r, key):
            if key not in r:
                return ""
            if key != "a" and not r.get("determined"):
                return "not determined"
            return f"{report.fmt(r.get(key))} ± {report.fmt(r.get(key + '_err'))}"

        rows = [[r["case"], f"{r['dimension']}D", r["grains"], r["block_d"], r["cycles"], r["seeds"], r["status"],
                 report.fmt(r.get("h0_d")), report.fmt(r.get("h_last_d")), report.fmt(r.get("phi_last")),
                 report.fmt(r.get("mean_cluster_last")), fitted(r, "a"), fitted(r, "b"), fitted(r, "tau"),
                 report.fmt(r.get("seconds")), r.get("reason") or ""] for r in self.rows]
        out.append(report.md_table(["case", "dim", "grains", "block [d]", "cycles", "seeds", "status",
                                    "<h> at n=0", "<h> last", "phi last", "mean cluster last", "a", "b", "tau",
                                    "seconds", "reason"], rows))
        per_seed = [[name, seed] + ([fitted(f, "a"), fitted(f, "b"), fitted(f, "tau")] if f else ["fit failed"] * 3)
                    for name, runs in self.seed_series.items() if len(runs) > 1
                    for seed, f in zip(next(r for r in self.rows if r["case"] == name)["seeds"].split(),
                                       (fit_or_none(t) for t in runs))]
        if per_seed:
            out += ["", "The same fit for each seed alone (the scatter the mean removes):", "",
                    report.md_table(["case", "seed", "a", "b", "tau"], per_seed)]
        return "\n".join(out) + "\n"


def run_nano_powder(outdir=None, cycles: int = 12, tiny: bool = False, progress=print) -> dict:
    outdir = Path(outdir or REPO / "out" / "nano_powder").absolute()  # btr runs in it: a relative -o would nest
    study = Study(outdir, progress)
    rec = RunRecord(outdir, "nano-powder", progress=progress, btr=study.btr,
                    inputs=[str(REPO / "inputs" / "nano_powder.toml")], settings={"cycles": cycles, "tiny": tiny})
    for name, scene, seeds in cases(tiny, cycles):
        study.run_case(rec, name, scene, seeds)
    failed = [r["case"] for r in study.rows if r["status"] != "ok"]
    rec.finish({"rows": study.rows, "failed_cases": failed, "report": str(outdir / "report.md")})
    progress(f"nano-powder: {len(study.rows)} cases ({len(failed)} failed); report {outdir / 'report.md'}")
    return {"rows": study.rows, "outdir": str(outdir)}
