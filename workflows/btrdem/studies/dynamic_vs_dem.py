"""`dynamic-vs-dem`: dynamic BTR against DEM in the rotating drum and the tapped Brazil-nut box.

The same scene (grains, fill, seed) runs through dynamic BTR (`btr drum`, `btr shake`) and through a DEM engine
(`btr drum --engine`, `btr shake --engine`): the engine's drum turns at the Froude number of the case, its floor
taps at the case's Gamma. Both write the same per-snapshot table (NAME_steps.csv, NAME_cycles.csv: the measures
come from the one C++ function each), so the comparison reads columns, nothing engine-specific.

Drum cases: dimension x fill x Froude number; DEM with several seeds (its scatter is the unit of the error),
BTR with the same seeds. Per run: radial segregation and core index against revolutions, the dynamic angle
(mean over the last revolution), the revolutions to 90 % of the final core index, and processor seconds per
revolution. Brazil-nut cases: diameter ratio Phi; the intruder's height against cycles (BTR) and taps (DEM).
A cost row measures both sides' processor time per revolution on one larger drum.

Outputs (rewritten after every run, so a stopped study keeps what it did): runs/<case>/<side>/ (scenes,
snapshots, tables), drum_runs.csv, drum_vs_dem.csv, brazil_runs.csv, cost.csv, segregation_vs_dem.png,
intruder_vs_dem.png, report.md (dynamic_vs_dem_report.py), run.json. A failed run is a row with its reason."""
from __future__ import annotations

import copy
import json
from pathlib import Path

import numpy as np

from ..core.io import InputError, read_json, write_json, write_scene_toml
from ..core.runner import REPO, RunRecord, StepFailed, find_btr, run_command
from . import dynamic_vs_dem_report as out_report
from .brazil_nut import read_cycles, scene_dict as brazil_scene
from .drum import read_steps

G = 9.81

# Drum cases: dimension x fill (fraction of the drum) x Froude numbers, for `revolutions`, DEM with the first
# `dem_seeds` of the run's seeds (BTR with all of them). Brazil nut: 3D, Phi values, bed grains in a cell size_d
# bed diameters wide, taps (BTR cycles) at Gamma, DEM with `dem_seeds` seeds. Cost: one 3D drum of cost_grains,
# the DEM side over cost_revolutions.
def _drum(dims, fills, froude, revolutions, dem_seeds):
    return [{"dim": d, "fill_name": n, "fill": f, "froude": froude, "revolutions": revolutions, "dem_seeds": dem_seeds}
            for d in dims for n, f in fills.items()]


# The mapping part: dynamic BTR's steps per revolution and lift (a fraction of R) swept on the drum cases. The lift
# changes only last bits (a grain falls vertically from any start above the pile), two values show it.
MAPPING = {"steps": [10, 25, 50, 100, 200, 400], "lifts": [0.025, 0.1]}

PLANS = {
    # What the issue asks for: 2D and 3D, 2 fills, 2 speeds in the rolling regime, 3 seeds; 3 revolutions in 2D,
    # 2 in 3D (its core index reaches 90 % of its final value within 0.6 revolution: docs/dynamic_vs_dem).
    "full": {"drum": _drum([2], {"low": 0.3, "high": 0.45}, [3e-3, 1e-2], 3.0, 3)
             + _drum([3], {"low": 0.3, "high": 0.45}, [3e-3, 1e-2], 2.0, 3),
             "brazil": {"phis": [2.0, 3.0, 4.0, 6.0], "count": 1650, "size_d": 12.0, "taps": 10, "gamma": 2.0,
                        "dem_seeds": 3},
             "cost_grains": 10000, "cost_revolutions": 0.05, "mapping": MAPPING},
    # What fits in about half an hour of two cores (measured: a 2D revolution 86 s at Fr 1e-2, 3D 274 s).
    "reduced": {"drum": _drum([2], {"high": 0.45}, [3e-3, 1e-2], 2.0, 3) + _drum([3], {"high": 0.45}, [1e-2], 1.0, 1),
                "brazil": {"phis": [2.0, 3.0, 4.0, 6.0], "count": 1650, "size_d": 12.0, "taps": 5, "gamma": 2.0,
                           "dem_seeds": 2},
                "cost_grains": 10000, "cost_revolutions": 0.02, "mapping": MAPPING},
    # For the tests: one 2D drum for a tenth of a revolution, one Phi, one tap.
    "tiny": {"drum": _drum([2], {"low": 0.3}, [1e-2], 0.1, 1),
             "brazil": {"phis": [3.0], "count": 80, "size_d": 5.0, "taps": 1, "gamma": 2.0, "dem_seeds": 1},
             "cost_grains": 0, "cost_revolutions": 0.0, "mapping": {"steps": [20], "lifts": [0.1]}},
}


def drum_scene(dim: int, fill: float, seed: int, steps_per_rev: int = 100) -> dict:
    """A drum (2D: radius 20 mm; 3D: radius 10 mm, 6 mm long, flat end walls: the DEM drum has no periodic
    ends) with a bidisperse fill (radii 0.5 and 1 mm, equal solid fractions) filling `fill` of its
    area (volume) at a packing fraction of 0.8 (2D) / 0.6 (3D)."""
    R, length = (0.02 if dim == 2 else 0.01), 0.006
    r_small, r_large = 0.5e-3, 1.0e-3
    phi_bulk = 0.8 if dim == 2 else 0.6
    solid = fill * np.pi * R * R * phi_bulk * (1.0 if dim == 2 else length)
    # Equal solid fractions: the number fraction of small grains is w / (1 + w), w = (r_large / r_small)^dim.
    w = (r_large / r_small) ** dim
    f_small = w / (1.0 + w)
    unit = np.pi if dim == 2 else 4.0 / 3.0 * np.pi
    count = int(round(solid / (unit * (f_small * r_small ** dim + (1 - f_small) * r_large ** dim))))
    container = {"kind": "drum", "radius": R}
    if dim == 3:
        container.update(length=length, ends="walls")
    return {
        "scene": {"name": "drum", "dimension": dim, "seed": seed},
        "grains": {"count": count, "density": 2500.0, "fraction_by": "volume",
                   "component": [{"species": 1, "fraction": 0.5, "radius": {"distribution": "constant", "value": r_small}},
                                 {"species": 2, "fraction": 0.5, "radius": {"distribution": "constant", "value": r_large}}]},
        "container": container,
        "source": {"kind": "rain"},
        "drum": {"steps_per_revolution": steps_per_rev, "revolutions": 1.0, "lift": R / 10.0,
                 "snapshot_every": max(1, steps_per_rev // 20)},
    }


def t90(rev: np.ndarray, index: np.ndarray) -> float | None:
    """Revolutions until the index first reaches 90 % of its final value (the mean over the last fifth of the
    run), counted from its value at the fill; None if it never rises."""
    if len(index) < 3:
        return None
    q = max(1, len(index) // 5)
    final, start = float(np.mean(index[-q:])), float(index[0])
    if not final > start:
        return None
    hit = np.nonzero(index >= start + 0.9 * (final - start))[0]
    return float(rev[hit[0]]) if len(hit) else None


def drum_summary(t: dict, steps_per_rev: int) -> dict:
    rev = t["step"] / steps_per_rev
    core = t["core_large_R"] - t["core_small_R"]
    last = rev >= rev[-1] - 1.0 if rev[-1] >= 1.0 else rev > 0.5 * rev[-1]
    ang = t["surface_angle_deg"][last]
    cpu = t["cpu_seconds"]  # BTR: of each step (row 0: the fill); DEM rows are replaced by drum_dem.json's figure
    span = rev[-1] - rev[0]
    return {"revolutions": float(rev[-1]), "segregation_end": float(np.mean(t["segregation_index"][last])),
            "core_end": float(np.mean(core[last])), "core_t90_rev": t90(rev, core),
            "dynamic_angle_deg": float(np.nanmean(ang)) if np.any(np.isfinite(ang)) else None,
            "cpu_per_rev": float(np.sum(cpu[1:]) / span) if span > 0 else None}


FINISHED = "finished_run.json"


def _arguments(d: Path, argv: list) -> list:
    """The run's arguments without the program, its own folder written "." (a run folder can be moved)."""
    return [str(a).replace(str(d), ".") for a in argv[1:]]


def mark_finished(d: Path, scene: dict, argv: list, cpu_seconds: float):
    """Written after a run exited 0: what ran (scene and arguments) and its processor time, for --reuse-runs."""
    write_json(d / FINISHED, {"scene": scene, "argv": _arguments(d, argv), "cpu_seconds": cpu_seconds})


def finished_run(d: Path, scene: dict, argv: list) -> dict | None:
    """The record of a run that finished in d from the same scene and arguments (the btr program may differ),
    or None."""
    p = d / FINISHED
    if not p.exists():
        return None
    done = read_json(p)
    same = done.get("scene") == json.loads(json.dumps(scene)) and done.get("argv") == _arguments(d, argv)
    return done if same else None


def dem_cpu_per_rev(d: Path) -> float:
    """The DEM rotation's engine processor seconds per revolution (drum_dem.json, written by btr drum --engine)."""
    return float(read_json(d / "drum_dem.json")["engine_cpu_seconds_per_revolution"])


class Study:
    def __init__(self, outdir, engine, plan, seeds, np_, progress, reuse=False, report_only=False):
        self.out, self.engine, self.plan, self.seeds, self.np = Path(outdir), engine, plan, seeds, np_
        self.progress, self.reuse, self.report_only = progress, reuse or report_only, report_only
        self.btr = find_btr()
        self.drum_rows, self.brazil_rows, self.cost_rows, self.mapping_rows = [], [], [], []
        self.series = {}  # run tag -> (x, y) for the figures

    def _run(self, argv, d: Path, label: str) -> dict:
        res = run_command(argv, d, label, progress=self.progress)
        if res["returncode"] != 0:
            raise StepFailed(f"{label} exited with status {res['returncode']}: "
                             f"{Path(res['stderr']).read_text(errors='replace').strip()[-600:]}")
        return res

    def _run_fresh(self, argv, d: Path, scene: dict, label: str) -> dict:
        """Runs argv on d/scene.toml (written from `scene`) and marks the run finished; a stale mark goes first, so a
        run stopped half-way is never reused."""
        (d / FINISHED).unlink(missing_ok=True)
        write_scene_toml(d / "scene.toml", scene)
        res = self._run(argv, d, label)
        mark_finished(d, scene, argv, res["cpu_seconds"])
        return res

    def write(self):
        out_report.write_outputs(self)

    # ---- drum
    def drum_run(self, rec, case: str, side: str, scene: dict, froude: float | None, seed: int, revolutions: float):
        tag = f"{case}_{side}" + (f"_fr{froude:g}" if froude is not None else "") + f"_s{seed}"
        d = self.out / "runs" / case / tag
        row = {"case": case, "side": side, "froude": froude, "seed": seed, "dimension": scene["scene"]["dimension"],
               "grains": scene["grains"]["count"]}
        with rec.case(f"drum {tag}", self.drum_rows, row, on_row=lambda _: self.write()):
            sc = copy.deepcopy(scene)
            sc["scene"]["seed"] = seed
            sc["drum"]["revolutions"] = revolutions
            if froude is not None:
                sc["drum"]["froude"] = froude
            d.mkdir(parents=True, exist_ok=True)
            path = d / "scene.toml"
            argv = [self.btr, "drum", str(path), "-o", str(d), "--quiet"]
            if side != "btr":
                argv += ["--engine", side, "--np", str(self.np), "--revolutions", f"{revolutions:g}"]
            done = finished_run(d, sc, argv) if self.reuse else None
            if done is not None:
                self.progress(f"  [drum {tag}] reused the run finished in {d}")
                res = {"cpu_seconds": done["cpu_seconds"]}
            elif self.report_only:
                row.update(status="not run", reason=f"no finished run in runs/{case}/{tag} (--report-only)")
                return
            else:
                res = self._run_fresh(argv, d, sc, f"btr drum {side}")
            t = read_steps(d / "drum_steps.csv")
            row.update(drum_summary(t, int(sc["drum"]["steps_per_revolution"])))
            if side != "btr":  # the engine's processor time of the rotation alone (not the fill, not the settle)
                row["cpu_per_rev"] = dem_cpu_per_rev(d)
            row["cpu_seconds"] = res["cpu_seconds"]
            rev = t["step"] / int(sc["drum"]["steps_per_revolution"])
            self.series[tag] = (rev, t["core_large_R"] - t["core_small_R"], t["surface_angle_deg"])

    def drum_cases(self, rec):
        """Dimension by dimension: the (cheap) BTR runs, then DEM seed by seed over the fills and speeds, so a
        study stopped early has every case at the same number of seeds."""
        plans = [(f"drum{p['dim']}d_{p['fill_name']}", p, drum_scene(p["dim"], p["fill"], 1)) for p in self.plan["drum"]]
        for dim in sorted({p["dim"] for p in self.plan["drum"]}):
            same = [x for x in plans if x[1]["dim"] == dim]
            for case, p, scene in same:
                for seed in self.seeds:
                    self.drum_run(rec, case, "btr", scene, None, seed, p["revolutions"])
            for seed in self.seeds:
                for case, p, scene in same:
                    if seed in self.seeds[:p["dem_seeds"]]:
                        for fr in p["froude"]:
                            self.drum_run(rec, case, self.engine, scene, fr, seed, p["revolutions"])

    def cost_case(self, rec):
        """Processor time per revolution, both sides, on one 3D drum of plan['cost_grains'] grains: BTR over a
        whole revolution, DEM over plan['cost_revolutions'] of one (a rotating drum's cost per unit time is steady once the
        flow has formed; the fill and the still relaxation are not counted: the table's first row is after them)."""
        n = self.plan["cost_grains"]
        if not n:
            return
        scene = drum_scene(3, 0.45, 1)
        scale = (n / scene["grains"]["count"]) ** (1.0 / 3.0)
        scene["container"]["radius"] *= scale
        scene["container"]["length"] *= scale
        scene["drum"]["lift"] *= scale
        scene["grains"]["count"] = n
        fr = self.plan["drum"][0]["froude"][-1]
        for side, revs in (("btr", 1.0), (self.engine, self.plan["cost_revolutions"])):
            row = {"case": f"cost_{n}", "side": side, "grains": n, "froude": fr if side != "btr" else None,
                   "revolutions_run": revs}
            d = self.out / "runs" / "cost" / side
            with rec.case(f"cost {side} {n} grains", self.cost_rows, row, on_row=lambda _: self.write()):
                sc = copy.deepcopy(scene)
                sc["drum"]["revolutions"] = revs
                sc["drum"]["snapshot_every"] = 5
                if side != "btr":
                    sc["drum"]["froude"] = fr
                d.mkdir(parents=True, exist_ok=True)
                write_scene_toml(d / "scene.toml", sc)
                argv = [self.btr, "drum", str(d / "scene.toml"), "-o", str(d), "--quiet"]
                if side != "btr":
                    argv += ["--engine", side, "--np", "1", "--revolutions", f"{revs:g}"]
                self._run(argv, d, f"cost {side}")
                t = read_steps(d / "drum_steps.csv")
                row["cpu_per_rev"] = (drum_summary(t, int(sc["drum"]["steps_per_revolution"]))["cpu_per_rev"]
                                      if side == "btr" else dem_cpu_per_rev(d))

    def mapping_cases(self, rec):
        """BTR alone over its own steps per revolution and lift, on every drum case, all seeds (dynamic_vs_dem_mapping);
        with --reuse-runs (or --report-only) a run finished in its folder is read again."""
        m = self.plan["mapping"]
        for p in self.plan["drum"]:
            case = f"drum{p['dim']}d_{p['fill_name']}"
            scene = drum_scene(p["dim"], p["fill"], 1)
            for spr in m["steps"]:
                for lift in m["lifts"]:
                    for seed in self.seeds:
                        row = {"case": case, "steps_per_revolution": spr, "lift_R": lift, "seed": seed}
                        d = self.out / "runs" / "mapping" / case / f"n{spr}_lift{lift:g}_s{seed}"
                        with rec.case(f"mapping {case} {spr} steps/rev lift {lift:g} R seed {seed}", self.mapping_rows,
                                      row, on_row=lambda _: self.write()):
                            sc = copy.deepcopy(scene)
                            sc["scene"]["seed"] = seed
                            sc["drum"].update(steps_per_revolution=spr, lift=lift * sc["container"]["radius"],
                                              revolutions=p["revolutions"], snapshot_every=max(1, spr // 20))
                            d.mkdir(parents=True, exist_ok=True)
                            argv = [self.btr, "drum", str(d / "scene.toml"), "-o", str(d), "--quiet"]
                            if self.reuse and finished_run(d, sc, argv) is not None:
                                self.progress(f"  [mapping] reused the run finished in {d}")
                            else:
                                self._run_fresh(argv, d, sc, "btr drum (mapping)")
                            row.update(drum_summary(read_steps(d / "drum_steps.csv"), spr))

    # ---- Brazil nut
    def brazil_cases(self, rec):
        p = self.plan["brazil"]
        for phi in p["phis"]:
            for side in ("btr", self.engine):
                for seed in self.seeds[:p["dem_seeds"] if side != "btr" else 1]:
                    self.brazil_run(rec, phi, side, seed, p)

    def brazil_run(self, rec, phi, side, seed, p):
        tag = f"phi{phi:g}_{side}_s{seed}"
        d = self.out / "runs" / "brazil" / tag
        row = {"case": f"phi{phi:g}", "phi": phi, "side": side, "seed": seed}
        with rec.case(f"brazil {tag}", self.brazil_rows, row, on_row=lambda _: self.write()):
            sc = brazil_scene(3, p["size_d"], p["count"], p["taps"], 0.1, phi, seed, "shake")
            if side != "btr":
                sc["shaking"]["gamma"] = p["gamma"]
            d.mkdir(parents=True, exist_ok=True)
            write_scene_toml(d / "scene.toml", sc)
            argv = [self.btr, "shake", str(d / "scene.toml"), "-o", str(d), "--quiet"]
            if side != "btr":
                argv += ["--engine", side, "--np", str(self.np), "--taps", str(p["taps"])]
            res = self._run(argv, d, f"btr shake {side}")
            t = read_cycles(d / "shake_cycles.csv")
            z = t["intruder_z_d"]
            n = t["cycle"][-1]
            row.update(cycles=int(n), z0_d=float(z[0]), z_end_d=float(z[-1]),
                       rise_d_per_cycle=float((z[-1] - z[0]) / n) if n > 0 else None,
                       cpu_per_cycle=float(res["cpu_seconds"] / n) if n > 0 else None)  # the fill included
            self.series[tag] = (t["cycle"], z, None)


def run_dynamic_vs_dem(outdir=None, engine: str = "liggghts", plan_name: str = "full", seeds=(1, 2, 3), np_: int = 1,
                       parts=("drum", "brazil", "cost"), progress=print, reuse_runs: bool = False,
                       dims=(2, 3), report_only: bool = False) -> dict:
    """report_only: the drum cases' tables from the runs finished in outdir/runs (as --reuse-runs finds them),
    the others rows "not run": no drum run is started (the mapping's BTR runs, seconds each, still run)."""
    if report_only and not set(parts) <= {"drum", "mapping"}:
        raise InputError(f"--report-only: only with --parts drum and mapping (got {','.join(parts)})")
    outdir = Path(outdir) if outdir else REPO / "out" / "dynamic_vs_dem"
    plan = copy.deepcopy(PLANS[plan_name])
    plan["drum"] = [p for p in plan["drum"] if p["dim"] in dims]
    seeds = list(seeds)
    rec = RunRecord(outdir, "dynamic-vs-dem", progress=progress, btr=find_btr(),
                    settings={"engine": engine, "plan_name": plan_name, "seeds": seeds, "np": np_, "parts": list(parts),
                              "plan": plan, "reuse_runs": reuse_runs, "dims": list(dims), "report_only": report_only})
    study = Study(outdir, engine, plan, seeds, np_, progress, reuse_runs, report_only)
    study.write()
    if "drum" in parts:
        study.drum_cases(rec)
    if "brazil" in parts:
        study.brazil_cases(rec)
    if "cost" in parts:
        study.cost_case(rec)
    if "mapping" in parts:
        study.mapping_cases(rec)
    study.write()
    rows = study.drum_rows + study.brazil_rows + study.cost_rows + study.mapping_rows
    failed = [r for r in rows if r["status"] != "ok"]
    rec.finish({"runs": len(rows), "failed": len(failed), "report": str(outdir / "report.md")})
    progress(f"dynamic-vs-dem: {len(rows)} runs ({len(failed)} failed); report {outdir / 'report.md'}")
    return {"drum": study.drum_rows, "brazil": study.brazil_rows, "cost": study.cost_rows,
            "mapping": study.mapping_rows}

