"""`error-vs-runtime SCENE`: error against run time of BTR, BTR + relaxation and DEM pours
(docs/design.md section 6).

Reference: LIGGGHTS pours of the BTR packing's grains with `ref_seeds` seeds (the pour's lattice
jitter); their mean is the reference value of each structural measure and their seed-to-seed
standard deviation the error floor. Methods, each with its wall time measured in this run:
  BTR                      btr deposit alone
  BTR + relax T            deposit + `btr relax` capped at T simulated seconds (the scene's kinetic-
                           energy stop rule still applies, so a relaxation may end earlier)
  BTR + relax damped D      the same with quasi-static damping D (`btr relax --damping D`)
  BTR + target phi         `btr relax --target-phi X --damping D`, X the reference pours' mean (or a number): in
                           one run, the bed compacts with the friction scaled down (btr relax's friction scales and
                           compaction damping) until its bulk packing fraction reaches X, then the friction is
                           restored, the grains stopped, and the bed settles with damping D on the scene's rule
  BTR + target phi (unbalanced-force rule)  the same, settled until YADE's unbalanced-force ratio < 1e-3
                           (both with --compaction-timestep-fraction F when the study sets it: the compaction at a
                           larger fraction of the Rayleigh time than the settle)
  BTR + K shakes + relax   `btr shake` (K Jullien-Meakin cycles of BTR redeposition) then `btr relax`
  BTR + pre-loaded relax   `btr relax --preload` (a failed row with the reason where this build has none)
  BTR + pre-loaded damped  `btr relax --preload --damping D --max-overlap 0.1`
  btr settle (engine)      `btr settle SCENE --count N` (issue 20): deposit, a small calibration pour whose packing
                           fraction is the target, relaxation to it; its cost is settle.json's cpu_seconds (the
                           calibration included); it never sees the reference pours' numbers
  DEM pour (pace p, stop s)  a pour of another seed, released p times faster than the reference's
                           pace and stopped at kinetic ratio s: shorter pours; the last one is the
                           reference's own settings
With reuse_pours a pour already finished in its folder with the same settings and grains is reused with
its recorded wall time (pours dominate the study's cost; the rows say "reused").
Cost: every run's processor time (user + system of btr and the engine it starts, btrdem.core.runner.run_command),
which is what its wall time is on an otherwise idle core and, unlike the wall time, does not grow when other
jobs share the machine; wall times are recorded beside it. The verdict is on the three measures of the
structure, packing fraction, coordination and g(r) (CORE_MEASURES); the others (segregation index, heap angle)
are reported.
Error of a method in a measure: |value - reference mean| (g(r): RMS difference from the mean
reference g(r) for r > 0.5 d, in 0.1 d bins). The floor of a measure is the reference seeds' standard
deviation s; a method reaches the floor when its error is at most 2 s sqrt(1 + 1/n) (n reference
seeds): the error another seed of the reference pour itself stays below about 95 % of the time."""
from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np

from ..core import btr_cli, report

from ..analysis import measures
from ..core.io import atomic_write_text, read_json, read_packing, write_json
from .pipeline import default_outdir, scene_inputs
from ..dem.pour import PourSettings, finished_pour, pour
from ..core.runner import RunRecord, StepFailed, failure_reason, find_btr

METHODS = ("relax", "damped", "target-phi", "target-phi-unbalanced", "shake", "preload", "preload-damped", "settle")
# The measures the verdict requires (the others are reported beside them).
CORE_MEASURES = ("packing_fraction", "coordination", "rdf")
# The pre-load's fit leaves neighbours up to ~0.07 r beyond their intended overlap at 10 000 grains
# (docs/guide/relax.md, "Pre-loaded start"): the pre-loaded damped method allows that much.
PRELOAD_MAX_OVERLAP = 0.1

MEASURES = {"packing_fraction": "packing fraction", "coordination": "mean coordination", "rdf": "g(r) RMS",
            "angle_of_repose": "angle of repose [deg]", "segregation": "segregation index"}


def measures_of(packing_csv: str, margin: float | None = None) -> dict:
    s = measures.measure(packing_csv, margin)
    r_d, g = measures.rdf(s)
    return {"packing_fraction": measures.packing_fraction(s), "coordination": measures.coordination(s),
            "rdf": {"r_over_d": r_d, "g": g}, "angle_of_repose": measures.angle_of_repose(s),
            "segregation": measures.segregation(s), "bulk_grains": s["bulk"].get("grains_in_window"),
            "definitions": measures.definitions(s)}


def reference_stats(refs: list) -> tuple[dict, dict, list]:
    """Mean and seed-to-seed standard deviation (the floor) of each measure that every reference has."""
    mean, floor = {}, {}
    names = []
    for key in MEASURES:
        if key == "rdf":
            gs = [r["rdf"]["g"] for r in refs]
            if any(g is None for g in gs):
                continue
            g = np.mean(np.array(gs), axis=0)
            mean["rdf"] = {"r_over_d": refs[0]["rdf"]["r_over_d"], "g": g.tolist()}
            dev = [measures.rdf_distance(gi, g, refs[0]["rdf"]["r_over_d"]) for gi in gs]
            floor["rdf"] = float(math.sqrt(np.sum(np.square(dev)) / (len(gs) - 1)))
        else:
            vals = [r[key] for r in refs]
            if any(v is None for v in vals):
                continue
            mean[key] = float(np.mean(vals))
            floor[key] = float(np.std(vals, ddof=1))
        names.append(key)
    return mean, floor, names


def errors_of(m: dict, mean: dict, names: list) -> dict:
    out = {}
    for key in names:
        if key == "rdf":
            out[key] = measures.rdf_distance(m["rdf"]["g"], mean["rdf"]["g"], mean["rdf"]["r_over_d"])
        else:
            out[key] = None if m[key] is None else abs(m[key] - mean[key])
    return out


def run_error_vs_runtime(scene_path: str, outdir=None, engine: str = "liggghts", ref_seeds: int = 3,
                         count: int | None = None, relax_times=None, pour_variants=None, ranks: int = 1,
                         margin: float | None = None, progress=print, methods=METHODS, damping: float = 0.5,
                         target_phi="pour", shakes: int = 10, reuse_pours: bool = False,
                         friction_scales=None, compaction_damping=None,
                         compaction_timestep_fraction: float | None = None) -> dict:
    if ref_seeds < 3:
        raise StepFailed(f"error-vs-runtime: --ref-seeds: expected at least 3 (the seed-to-seed spread is the "
                         f"error floor), got {ref_seeds}")
    btr = find_btr()
    outdir = (Path(outdir) if outdir else default_outdir(scene_path) / "error_vs_runtime").absolute()
    rec = RunRecord(outdir, "error-vs-runtime", inputs=scene_inputs(scene_path), btr=btr, progress=progress,
                    settings={"scene": os.path.abspath(scene_path), "engine": engine, "ref_seeds": ref_seeds,
                              "count": count, "relax_times": relax_times, "pour_variants": pour_variants, "np": ranks,
                              "margin": margin, "methods": list(methods), "damping": damping,
                              "target_phi": target_phi, "shakes": shakes, "reuse_pours": reuse_pours,
                              "friction_scales": friction_scales, "compaction_damping": compaction_damping,
                              "compaction_timestep_fraction": compaction_timestep_fraction})
    bad = [m for m in methods if m not in METHODS]
    if bad:
        raise StepFailed(f"error-vs-runtime: --methods: expected some of {', '.join(METHODS)}, got {', '.join(bad)}")

    def poured(outdir_, settings_):
        done = finished_pour(btr_packing, outdir_, settings_) if reuse_pours else None
        if done is not None:
            progress(f"  [{settings_.label}] reused the finished pour in {outdir_} ({done['wall_seconds']:.1f} s wall)")
            return done
        return pour(btr_packing, outdir_, settings_, progress)
    rows = []
    with rec.step("BTR deposit") as st:
        dep = btr_cli.deposit(btr, scene_path, outdir / "btr", "btr", None, count, progress)
        st.update(outputs=[dep["csv"]])
    btr_packing = read_packing(dep["csv"])
    scene = btr_packing.scene()
    base_max_time = float(scene["relax"]["max_time"])
    relax_times = [base_max_time * f for f in (0.05, 0.25, 1.0)] if relax_times is None else relax_times
    pour_variants = pour_variants if pour_variants is not None else [(0.25, 1e-3), (0.5, 1e-4), (1.0, float(scene["relax"]["stop_kinetic_ratio"]))]

    refs, ref_runs = [], []
    for seed in range(1, ref_seeds + 1):
        with rec.step(f"reference pour seed {seed}") as st:
            s = poured(outdir / f"reference_seed{seed}", PourSettings(seed=seed, np=ranks, label=f"reference-{seed}"))
            refs.append(measures_of(s["packing"], margin))
            ref_runs.append(s)
            st.update(outputs=[s["packing"]], wall_seconds_engine=s["wall_seconds"], stop_reason=s["stop_reason"])
    mean, floor, names = reference_stats(refs)
    if not names:
        raise StepFailed("error-vs-runtime: the reference pours have no structural measure in common (empty bulk "
                         "window?); use a larger scene (--count) or a smaller window margin (--margin)")

    ref_wall = float(np.mean([s["wall_seconds"] for s in ref_runs]))
    ref_cpu = (float(np.mean([s["cpu_seconds"] for s in ref_runs]))
               if all(s.get("cpu_seconds") is not None for s in ref_runs) else None)
    reference = {"seeds": list(range(1, ref_seeds + 1)), "mean": mean, "floor": floor,
                 "reach_threshold": reach_threshold(floor, ref_seeds), "values": refs,
                 "wall_seconds": [s["wall_seconds"] for s in ref_runs],
                 "cpu_seconds": [s.get("cpu_seconds") for s in ref_runs],
                 "reused": [bool(s.get("reused")) for s in ref_runs],
                 "stop_reasons": [s["stop_reason"] for s in ref_runs],
                 "removed": [int(s.get("removed", 0)) for s in ref_runs]}

    basis = "cpu" if ref_cpu is not None else "wall"
    ref_cost = ref_cpu if ref_cpu is not None else ref_wall
    reference["cost_basis"] = basis

    def write_tables(rows):
        """error_vs_runtime.json / .md / .png from the rows so far (rewritten after every method)."""
        done = [r for r in rows if r["status"] == "ok"]
        for r in done:
            r["cost_seconds"] = cost_of(r, basis)
        verdict = first_to_floor(done, floor, names, ref_cost, ref_seeds)
        verdict["cost_basis"] = basis
        verdict["reference_pour_wall_seconds"] = ref_wall
        result = {"scene": os.path.abspath(scene_path), "grains": len(btr_packing), "engine": engine,
                  "reference": reference, "measures": names, "rows": rows, "verdict": verdict}
        write_json(outdir / "error_vs_runtime.json", result)
        fig = plot(outdir / "error_vs_runtime.png", done, floor, reach_threshold(floor, ref_seeds), names)
        atomic_write_text(outdir / "error_vs_runtime.md", markdown(result, os.path.basename(fig)))
        return result

    def method(label, kind, **fields):
        return rec.case(label, rows, dict(method=label, kind=kind, values=None, errors=None, **fields),
                        on_row=write_tables)

    with method("BTR", "btr", wall_seconds=dep["wall_seconds"], cpu_seconds=dep["cpu_seconds"], path=dep["csv"]) as row:
        row["values"] = m = measures_of(dep["csv"], margin)
        row["errors"] = errors_of(m, mean, names)

    def relax_row(row, kind_dir, csv, extra, start):
        """btr relax of csv into outdir/kind_dir; the row's times add those of `start` (what made csv)."""
        r = btr_cli.relax(btr, csv, engine, outdir / kind_dir, np=ranks, progress=progress, label=kind_dir,
                          extra_args=extra)
        row["values"] = m = measures_of(r["csv"], margin)
        row.update(wall_seconds=start["wall_seconds"] + r["wall_seconds"], relax_wall_seconds=r["wall_seconds"],
                   cpu_seconds=_sum_or_none(start.get("cpu_seconds"), r.get("cpu_seconds")),
                   errors=errors_of(m, mean, names), path=r["csv"], stdout=r["stdout"][-600:],
                   removed=removed_by_relax(r["csv"]))
        return r

    # A heap (or a bed too thin for a bulk window) has no packing fraction to aim at: its target-phi rows fail.
    target = mean.get("packing_fraction") if target_phi == "pour" else float(target_phi)

    def target_methods(cd, name_by_damping):
        """The target-phi methods (kinetic and unbalanced-force rule) with compaction damping cd (None: btr's)."""
        scales = "" if friction_scales is None else ",".join(f"{x:g}" for x in friction_scales)
        target_args = (["--target-phi", repr(float(target or 0.0)), "--damping", repr(float(damping))] +
                       (["--friction-scales", scales] if scales else []) +
                       (["--compaction-damping", repr(float(cd))] if cd is not None else []) +
                       (["--compaction-timestep-fraction", repr(float(compaction_timestep_fraction))]
                        if compaction_timestep_fraction is not None else []) +
                       (["--target-margin", repr(float(margin))] if margin is not None else []))
        settings_label = (f" friction scales {scales}" if scales else "") + \
            (f" compaction damping {cd:g}" if cd is not None else "") + \
            (f" compaction step fraction {compaction_timestep_fraction:g}"
             if compaction_timestep_fraction is not None else "")
        for kind, rule in (("target-phi", None), ("target-phi-unbalanced", "unbalanced-force")):
            if kind not in methods:
                continue
            folder = "relax_" + kind.replace("-", "_") + (f"_cd{cd:g}" if name_by_damping else "")
            phi_label = f"{target:.4g}" if target is not None else "of the pours (none)"
            with method(f"BTR + {engine} target phi {phi_label} damped {damping:g}{settings_label}" +
                        (f" ({rule} rule)" if rule else ""), "target" if rule is None else "target-ub",
                        wall_seconds=None, target_phi=target, compaction_damping=cd) as row:
                if target is None:
                    raise StepFailed("no packing fraction to target: the reference pours have an empty bulk window "
                                     "(a heap, or a bed thinner than the window's margins); --target-phi PHI sets one")
                r = relax_row(row, folder, dep["csv"], target_args + (["--stop-rule", rule] if rule else []), dep)
                row["target_phi_record"] = read_json(Path(r["csv"]).with_suffix(".json")).get("target_phi")

    for t in (relax_times if "relax" in methods else []):
        with method(f"BTR + {engine} relax {t:.3g} s", "relax", wall_seconds=None) as row:
            d = outdir / f"relax_{t:.3g}s"
            csv = btr_cli.variant(dep["csv"], d / "input", "btr",
                                  lambda sc, t=t: sc["relax"].update(max_time=float(t)))
            relax_row(row, f"relax_{t:.3g}s", csv, [], dep)
    if "damped" in methods:
        with method(f"BTR + {engine} relax damped {damping:g}", "damped", wall_seconds=None) as row:
            relax_row(row, f"relax_damped{damping:g}", dep["csv"], ["--damping", repr(float(damping))], dep)
    dampings = ([None] if compaction_damping is None else
                list(compaction_damping) if isinstance(compaction_damping, (list, tuple)) else [compaction_damping])
    for cd in dampings:
        target_methods(cd, len(dampings) > 1)
    if "shake" in methods:
        with method(f"BTR + {shakes} shakes + {engine} relax", "shake", wall_seconds=None, shakes=shakes) as row:
            sh = btr_cli.shake(btr, scene_path, outdir / f"shake{shakes}", shakes, count, progress=progress)
            row["shaken_values"] = measures_of(sh["csv"], margin)
            relax_row(row, f"relax_shake{shakes}", sh["csv"], [], sh)
            row["shake_wall_seconds"] = sh["wall_seconds"]
    if "preload" in methods:
        with method(f"BTR + pre-loaded {engine} relax", "preload", wall_seconds=None) as row:
            if "--preload" not in btr_cli.help_text(btr, "relax"):
                raise StepFailed(f"{btr} relax has no --preload option: the pre-loaded start (issue 7 parts 1-2) is "
                                 "not in this build")
            relax_row(row, "relax_preload", dep["csv"], ["--preload"], dep)
    if "preload-damped" in methods:
        with method(f"BTR + pre-loaded {engine} relax damped {damping:g}", "preload-damped", wall_seconds=None) as row:
            relax_row(row, f"relax_preload_damped{damping:g}", dep["csv"],
                      ["--preload", "--damping", repr(float(damping)), "--max-overlap", repr(PRELOAD_MAX_OVERLAP)],
                      dep)
    if "settle" in methods:
        with method(f"btr settle ({engine})", "settle", wall_seconds=None) as row:
            settle_row(row, btr, scene_path, outdir / "settle", engine, count, ranks, margin, mean, names, progress)
    for k, (pace, stop) in enumerate(pour_variants):
        label = f"DEM pour pace {pace:g} stop {stop:.0e}"
        seed = ref_seeds + 1 + k
        with method(label, "pour", wall_seconds=None, seed=seed) as row:
            s = poured(outdir / f"pour_pace{pace:g}_stop{stop:.0e}",
                       PourSettings(seed=seed, np=ranks, pace=pace, stop_ratio=stop, label=f"pour-{pace:g}"))
            row["values"] = m = measures_of(s["packing"], margin)
            row.update(wall_seconds=s["wall_seconds"], cpu_seconds=s.get("cpu_seconds"),
                       errors=errors_of(m, mean, names), path=s["packing"],
                       stop_reason=s["stop_reason"], reused=bool(s.get("reused")), removed=int(s.get("removed", 0)))

    with rec.step("table and plot") as st:
        result = write_tables(rows)
        verdict = result["verdict"]
        st.update(outputs=[str(outdir / "error_vs_runtime.md"), str(outdir / "error_vs_runtime.png")])
        failed = [r["method"] for r in rows if r["status"] != "ok"]
        if failed:
            verdict["summary"] += f" Failed methods (rows with their reasons): {', '.join(failed)}."
            write_json(outdir / "error_vs_runtime.json", result)
            atomic_write_text(outdir / "error_vs_runtime.md", markdown(result, "error_vs_runtime.png"))
    rec.finish({"verdict": verdict["summary"]})
    progress(verdict["summary"])
    return result


def settle_row(row, btr, scene_path, folder, engine, count, ranks, margin, mean, names, progress):
    """`btr settle` of the study's scene (its seed, the study's count and engine) into folder; its cost is
    settle.json's cpu_seconds (calibration pour included)."""
    res = btr_cli.settle(btr, scene_path, engine, folder, np=ranks, count=count, progress=progress)
    record = res["record"]
    row["values"] = m = measures_of(res["csv"], margin)
    row.update(wall_seconds=record.get("wall_seconds", res["wall_seconds"]), cpu_seconds=res["cpu_seconds"],
               errors=errors_of(m, mean, names), path=res["csv"], target_reached=res["target_reached"],
               chosen=record.get("chosen"), settle_steps=record.get("steps"))


def removed_by_relax(relaxed_csv) -> int:
    """Grains an open floor's relaxation removed (relaxed.json relax.removed.count; 0 elsewhere)."""
    meta = read_json(Path(relaxed_csv).with_suffix(".json"))
    return int(((meta.get("relax") or {}).get("removed") or {}).get("count", 0))


def _sum_or_none(*xs):
    return None if any(x is None for x in xs) else float(sum(xs))


def cost_of(row: dict, basis: str) -> float:
    """The row's cost in seconds: its processor time (basis "cpu"), or its wall time where a run (a pour
    reused from before the processor time was recorded) has none, or with basis "wall"."""
    if basis == "cpu" and row.get("cpu_seconds") is not None:
        return float(row["cpu_seconds"])
    return float(row["wall_seconds"])


def reach_threshold(floor: dict, n_seeds: int) -> dict:
    return {k: 2.0 * v * math.sqrt(1.0 + 1.0 / n_seeds) for k, v in floor.items()}


def first_to_floor(rows, floor, names, ref_cost, n_seeds) -> dict:
    """Per measure, and over the core measures (packing fraction, coordination, g(r): "all"): the cheapest method
    whose error is within the floor, with its cost (rows' cost_seconds) relative to the reference pour's."""
    limit = reach_threshold(floor, n_seeds)
    # A heap has no bulk window, hence none of the core measures: then "all" is every measure it has (the
    # angle of repose, the segregation index), never an empty set that every method would reach.
    core = [k for k in names if k in CORE_MEASURES] or list(names)

    def reaches(row, keys):
        return all(row["errors"][k] is not None and row["errors"][k] <= limit[k] for k in keys)

    by_cost = sorted(rows, key=lambda r: r["cost_seconds"])
    per = {}
    for key in names + ["all"]:
        keys = core if key == "all" else [key]
        hit = next((r for r in by_cost if reaches(r, keys)), None)
        pour_hit = next((r for r in by_cost if r["kind"] == "pour" and reaches(r, keys)), None)
        per[key] = None if hit is None else {
            "method": hit["method"], "cost_seconds": hit["cost_seconds"], "wall_seconds": hit["wall_seconds"],
            "cost_ratio_to_reference_pour": hit["cost_seconds"] / ref_cost,
            "cost_ratio_to_cheapest_pour_reaching": (hit["cost_seconds"] / pour_hit["cost_seconds"]) if pour_hit else None,
            "cheapest_pour_reaching": pour_hit["method"] if pour_hit else None}
    a = per["all"]
    others = [k for k in names if k not in core]
    if not rows:
        summary = "No method finished."
    elif a is None:
        closest = min(rows, key=lambda r: max((r["errors"][k] or math.inf) / max(limit[k], 1e-300) for k in core))
        worst = max((closest["errors"][k] or math.inf) / max(limit[k], 1e-300) for k in core)
        summary = (f"No method reaches the reference's error floor in {', '.join(MEASURES[k] for k in core)} together; "
                   f"the closest is {closest['method']} ({closest['cost_seconds']:.3g} s), whose worst error is "
                   f"{worst:.3g} x the floor's limit.")
    else:
        summary = (f"{a['method']} is the cheapest to reach the reference's error floor in "
                   f"{', '.join(MEASURES[k] for k in core)}: {a['cost_seconds']:.3g} s, "
                   f"{a['cost_ratio_to_reference_pour']:.3g} x a reference pour ({ref_cost:.3g} s)")
        if a["cost_ratio_to_cheapest_pour_reaching"] is not None and a["method"] != a["cheapest_pour_reaching"]:
            summary += (f" and {a['cost_ratio_to_cheapest_pour_reaching']:.3g} x the cheapest pour that also reaches "
                        f"it ({a['cheapest_pour_reaching']})")
        summary += "."
        hit = next(r for r in rows if r["method"] == a["method"])
        for k in others:
            if hit["errors"].get(k) is not None:
                summary += (f" Its {MEASURES[k]} error is {hit['errors'][k] / max(limit[k], 1e-300):.3g} x the "
                            "floor's limit.")
    return {"per_measure": per, "core_measures": core, "reference_pour_cost_seconds": ref_cost, "summary": summary}


def plot(path, rows, floor, limit, names) -> str:
    import matplotlib.pyplot as plt

    n = len(names)
    fig, axes = plt.subplots(1, n, figsize=(4.2 * n, 3.8), squeeze=False)
    markers = {"btr": ("s", "tab:green"), "relax": ("o", "tab:blue"), "damped": ("v", "tab:cyan"),
               "target": ("*", "tab:purple"), "target-ub": ("h", "tab:pink"), "shake": ("D", "tab:olive"),
               "preload": ("P", "tab:orange"),
               "preload-damped": ("X", "tab:brown"),
               "settle": ("p", "black"),
               "pour": ("^", "tab:red")}
    names_of = {"btr": "BTR", "relax": "BTR + relaxation", "damped": "BTR + damped relaxation",
                "target": "BTR + target phi", "target-ub": "BTR + target phi (unbalanced-force rule)",
                "shake": "BTR + shakes + relaxation", "preload": "BTR + pre-loaded",
                "preload-damped": "BTR + pre-loaded damped",
                "settle": "btr settle",
                "pour": "DEM pour"}
    for ax, key in zip(axes[0], names):
        for kind, (mk, col) in markers.items():
            sel = [r for r in rows if r["kind"] == kind and r["errors"][key] is not None]
            if not sel:
                continue
            x = [r["cost_seconds"] for r in sel]
            y = [max(r["errors"][key], floor[key] * 1e-3, 1e-12) for r in sel]
            ax.plot(x, y, marker=mk, color=col, ls="-" if kind in ("relax", "pour") else "none", label=names_of[kind])
        ax.axhline(max(floor[key], 1e-12), color="gray", ls="--", lw=1, label="floor: seed-to-seed std s")
        ax.axhline(max(limit[key], 1e-12), color="gray", ls=":", lw=1, label="reached below 2 s sqrt(1 + 1/n)")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("cost [s]: processor time (wall time where none was recorded)")
        ax.set_ylabel(f"error: {MEASURES[key]}")
        ax.legend(fontsize=7, loc="best")
    fig.suptitle("Error against the DEM pour reference vs cost")
    fig.tight_layout()
    return report.save_figure(fig, path)


def markdown(res: dict, fig_name: str) -> str:
    names = res["measures"]
    ref = res["reference"]
    core = res["verdict"].get("core_measures", names)
    ref_cost = res["verdict"]["reference_pour_cost_seconds"]
    cpu = [c for c in ref.get("cpu_seconds", []) if c is not None]
    headers = (["method", "wall time [s]", "CPU time [s]", "cost / pour"] + [f"error: {MEASURES[k]}" for k in names] +
               [f"reaches floor ({', '.join(MEASURES[k] for k in core)})"])
    rows = [["reference mean (" + ", ".join(f"seed {s}" for s in ref["seeds"]) + ")",
             f"{report.fmt(float(np.mean(ref['wall_seconds'])))} (mean)",
             f"{report.fmt(float(np.mean(cpu)))} (mean)" if cpu else "-", 1] +
            [("curve" if k == "rdf" else report.fmt(ref["mean"][k])) for k in names] + ["-"],
            ["floor (seed-to-seed std s)", "-", "-", "-"] + [report.fmt(ref["floor"][k]) for k in names] + ["-"],
            ["reached below 2 s sqrt(1 + 1/n)", "-", "-", "-"] +
            [report.fmt(ref["reach_threshold"][k]) for k in names] + ["-"]]
    failed = []
    for r in res["rows"]:
        if r["status"] != "ok":
            failed.append([r["method"], r["status"], r["reason"]])
            continue
        ok = all(r["errors"][k] is not None and r["errors"][k] <= ref["reach_threshold"][k] for k in core)
        rows.append([r["method"], r["wall_seconds"], r.get("cpu_seconds") if r.get("cpu_seconds") is not None else "-",
                     r["cost_seconds"] / ref_cost] + [r["errors"][k] for k in names] + ["yes" if ok else "no"])
    vals = [["method"] + [MEASURES[k] for k in names if k != "rdf"]]
    for r in res["rows"]:
        if r["status"] == "ok":
            vals.append([r["method"]] + [r["values"][k] for k in names if k != "rdf"])
    lines = [f"# Error against run time: {os.path.basename(res['scene'])}", "",
             f"{res['grains']} grains; engine {res['engine']}; reference: LIGGGHTS pours with seeds "
             f"{ref['seeds']} (stop: {', '.join(ref['stop_reasons'])}). Times were measured in this run, on this "
             f"machine; the cost is the {'processor' if res['verdict'].get('cost_basis') == 'cpu' else 'wall'} time "
             "(user + system of btr and the engine: the wall time on an otherwise idle core), relative to the mean "
             "reference pour's.", "", "## Verdict", "", res["verdict"]["summary"], ""]
    per = res["verdict"]["per_measure"]
    lines.append(report.md_table(["measure", "first to reach the floor", "cost [s]", "cost / reference pour"],
                                 [[MEASURES.get(k, "all of " + ", ".join(MEASURES[c] for c in core)),
                                   per[k]["method"] if per[k] else "none",
                                   per[k]["cost_seconds"] if per[k] else "-",
                                   per[k]["cost_ratio_to_reference_pour"] if per[k] else "-"]
                                  for k in names + ["all"]]))
    lines += ["## Errors", "", report.md_table(headers, rows)]
    if failed:
        lines += ["## Failed methods", "", report.md_table(["method", "status", "reason"], failed)]
    removed = [(f"reference pour seed {s}", n) for s, n in zip(ref["seeds"], ref.get("removed", [])) if n] + \
        [(r["method"], r["removed"]) for r in res["rows"] if r["status"] == "ok" and r.get("removed")]
    if removed:
        lines += ["## Grains removed on the open floor", "",
                  "Grains whose centre left the region (the footprint + relax.open_margin largest diameters) were "
                  f"removed from the run and counted; the measures are those of the rest (of {res['grains']}).", "",
                  report.md_table(["run", "grains removed"], removed)]
    defs = next((r["values"]["definitions"] for r in res["rows"] if r["status"] == "ok"), None)
    lines += ["## Values", "", report.md_table(vals[0], vals[1:])]
    if defs:
        lines += [f"Measured by `btr measure`: {defs}.", ""]
    lines += [f"![error vs run time]({fig_name})", ""]
    return "\n".join(lines)


def run_size_study(scene_path: str, counts, outdir=None, progress=print, **kwargs) -> dict:
    """error-vs-runtime at each grain count into OUTDIR/n<N>/, then size_study.{json,md,png}: each method's
    wall time as a fraction of the reference pour's against N, and the cheapest method at the floor.
    A count whose study fails is a row with its reason; the summary is rewritten after every count."""
    outdir = (Path(outdir) if outdir else default_outdir(scene_path) / "error_vs_runtime_sizes").absolute()
    outdir.mkdir(parents=True, exist_ok=True)
    sizes = []
    for n in counts:
        entry = {"count": int(n), "status": "running", "reason": "", "folder": str(outdir / f"n{n}")}
        sizes.append(entry)
        try:
            res = finished_study(outdir / f"n{n}", scene_path, int(n), kwargs) if kwargs.get("reuse_pours") else None
            if res is not None:
                progress(f"size study: {n} grains: reused the finished study in {outdir / f'n{n}'}")
            else:
                res = run_error_vs_runtime(scene_path, outdir / f"n{n}", count=int(n), progress=progress, **kwargs)
            entry.update(status="ok", **size_entry(res))
        except StepFailed as e:
            entry.update(status="fail", reason=failure_reason(str(e)))
            progress(f"size study: {n} grains FAILED ({entry['reason']}); the study goes on")
        write_size_study(outdir, scene_path, sizes)
    return {"sizes": sizes}


def finished_study(folder: Path, scene_path: str, count: int, kwargs: dict) -> dict | None:
    """The result of an error-vs-runtime study that finished in folder with the same scene, count and
    settings (run.json), or None."""
    if not (folder / "run.json").exists() or not (folder / "error_vs_runtime.json").exists():
        return None
    run = read_json(folder / "run.json")
    st = run.get("settings", {})
    want = {"scene": os.path.abspath(scene_path), "count": count, "engine": kwargs.get("engine", "liggghts"),
            "ref_seeds": kwargs.get("ref_seeds", 3), "margin": kwargs.get("margin"),
            "methods": list(kwargs.get("methods", METHODS)), "damping": kwargs.get("damping", 0.5),
            "target_phi": kwargs.get("target_phi", "pour"), "shakes": kwargs.get("shakes", 10),
            "friction_scales": kwargs.get("friction_scales"), "compaction_damping": kwargs.get("compaction_damping"),
            "compaction_timestep_fraction": kwargs.get("compaction_timestep_fraction"),
            "relax_times": kwargs.get("relax_times"),
            "pour_variants": None if kwargs.get("pour_variants") is None else [list(v) for v in kwargs["pour_variants"]]}
    if run.get("status") != "ok" or any(st.get(k) != v for k, v in want.items()):
        return None
    return read_json(folder / "error_vs_runtime.json")


def size_entry(res: dict) -> dict:
    ref_cost = res["verdict"]["reference_pour_cost_seconds"]
    core = res["verdict"].get("core_measures", list(CORE_MEASURES))
    methods = []
    for r in res["rows"]:
        row = {"method": r["method"], "kind": r["kind"], "status": r["status"], "reason": r.get("reason", "")}
        if r["status"] == "ok":
            reach = {k: r["errors"][k] is not None and r["errors"][k] <= res["reference"]["reach_threshold"][k]
                     for k in res["measures"]}
            row.update(wall_seconds=r["wall_seconds"], cpu_seconds=r.get("cpu_seconds"),
                       cost_seconds=r["cost_seconds"], cost_ratio=r["cost_seconds"] / ref_cost, reaches=reach,
                       reaches_core=all(reach[k] for k in core),
                       values={k: r["values"][k] for k in res["measures"] if k != "rdf"},
                       error_over_limit={k: (r["errors"][k] / res["reference"]["reach_threshold"][k]
                                             if r["errors"][k] is not None and res["reference"]["reach_threshold"][k] > 0
                                             else None) for k in res["measures"]})
        methods.append(row)
    per = res["verdict"]["per_measure"]
    return {"grains": res["grains"], "reference_pour_cost_seconds": ref_cost,
            "reference_pour_wall_seconds": res["verdict"].get("reference_pour_wall_seconds"),
            "cost_basis": res["verdict"].get("cost_basis", "wall"), "core_measures": core, "measures": res["measures"],
            "reference_mean": {k: v for k, v in res["reference"]["mean"].items() if k != "rdf"},
            "methods": methods, "cheapest_at_floor": {k: (per[k]["method"], per[k]["cost_ratio_to_reference_pour"])
                                                      if per[k] else None for k in per},
            "verdict": res["verdict"]["summary"]}


def write_size_study(outdir: Path, scene_path: str, sizes: list):
    write_json(outdir / "size_study.json", {"scene": os.path.abspath(scene_path), "sizes": sizes})
    done = [s for s in sizes if s["status"] == "ok"]
    lines = [f"# Error against run time, size study: {os.path.basename(scene_path)}", "",
             "Cost ratio = method cost / mean cost of the reference pours at the same N, the cost being the "
             "processor time (user + system of btr and the engine; wall time where a reused run recorded none), "
             "measured in the same study (pours marked reused ran earlier in the same folder). Reaches: error "
             "within 2 s sqrt(1 + 1/n) of the reference mean (error / limit in brackets); the verdict needs packing "
             "fraction (phi), coordination (Z) and g(r).", ""]
    for s in sizes:
        if s["status"] != "ok":
            lines += [f"## {s['count']} grains: {s['status']}", "", s["reason"] or "(running)", ""]
            continue
        ref_cost = s.get("reference_pour_cost_seconds", s.get("reference_pour_wall_seconds"))
        lines += [f"## {s['grains']} grains (reference pour {ref_cost:.4g} s {s.get('cost_basis', 'wall')})", "",
                  s["verdict"], ""]
        rows = []
        for m in s["methods"]:
            if m["status"] != "ok":
                rows.append([m["method"], "-", "-", "-"] + ["-"] * len(s["measures"]) + [f"{m['status']}: {m['reason']}"])
                continue
            rows.append([m["method"], m["wall_seconds"], m.get("cost_seconds", m["wall_seconds"]), m["cost_ratio"]] +
                        [("yes" if m["reaches"][k] else "no") + (f" ({m['error_over_limit'][k]:.2g}x)"
                                                                  if m["error_over_limit"][k] is not None else "")
                         for k in s["measures"]] + [""])
        lines.append(report.md_table(["method", "wall [s]", "cost [s]", "cost / pour"] +
                                     [f"reaches {MEASURES[k]} (error / limit)" for k in s["measures"]] + ["note"],
                                     rows))
    fig = plot_sizes(outdir / "size_study.png", done)
    if fig:
        lines += [f"![cost ratio against N]({os.path.basename(fig)})", ""]
    atomic_write_text(outdir / "size_study.md", "\n".join(lines))


def plot_sizes(path: Path, done: list) -> str | None:
    if not done:
        return None
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(10, 4.8))
    labels = []
    for s in done:
        for m in s["methods"]:
            key = _size_label(m["method"])
            if m["status"] == "ok" and m["kind"] != "pour" and key not in labels:
                labels.append(key)
    for key in labels:
        pts = [(s["grains"], m["cost_ratio"], m.get("reaches_core", all(m["reaches"].values())))
               for s in done for m in s["methods"]
               if m["status"] == "ok" and _size_label(m["method"]) == key]
        if not pts:
            continue
        line, = ax.plot([p[0] for p in pts], [p[1] for p in pts], marker="o", label=_legend_label(key))
        for n, c, ok in pts:
            if ok:
                ax.plot([n], [c], marker="o", ms=11, mfc="none", color=line.get_color())
    ax.axhline(0.1, color="gray", ls=":", lw=1, label="target 0.1 x pour")
    ax.set_xscale("log")
    ax.set_yscale("log")
    counts = sorted({s["grains"] for s in done})
    ax.set_xticks(counts)
    ax.set_xticklabels([str(n) for n in counts])
    ax.minorticks_off()
    ax.set_xlabel("grains N")
    ax.set_ylabel("cost / reference pour's (processor time)")
    ax.set_title("Cost against N (ringed: at the floor in phi, Z and g(r))")
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1.0))
    fig.tight_layout()
    return report.save_figure(fig, path)


def _legend_label(key: str) -> str:
    """A method's line label without the engine and the settings every target-phi line shares."""
    for long, short in ((" compaction step fraction ", " step "), (" compaction damping ", ", compaction damping "),
                        (" (unbalanced-force rule)", ", unbalanced-force rule")):
        key = key.replace(long, short)
    return key.replace(" liggghts", "").replace(" yade", " YADE")


def _size_label(method: str) -> str:
    # "target phi 0.6271" differs with N: one line per kind of method
    if " target phi " not in method:
        return method
    head, tail = method.split(" target phi ", 1)
    return head + " target phi" + (" " + tail.split(" ", 1)[1] if " " in tail else "")
