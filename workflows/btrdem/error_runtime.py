"""`error-vs-runtime SCENE`: error against run time of BTR, BTR + relaxation and DEM pours
(DESIGN.md section 6).

Reference: LIGGGHTS pours of the BTR packing's grains with `ref_seeds` seeds (the pour's lattice
jitter); their mean is the reference value of each structural measure and their seed-to-seed
standard deviation the error floor. Methods, each with its wall time measured in this run:
  BTR                      btr deposit alone
  BTR + relax T            deposit + `btr relax` capped at T simulated seconds (the scene's kinetic-
                           energy stop rule still applies, so a relaxation may end earlier)
  DEM pour (pace p, stop s)  a pour of another seed, released p times faster than the reference's
                           pace and stopped at kinetic ratio s: shorter pours; the last one is the
                           reference's own settings
Error of a method in a measure: |value - reference mean| (g(r): RMS difference from the mean
reference g(r) for r > 0.5 d, in 0.1 d bins). The floor of a measure is the reference seeds' standard
deviation s; a method reaches the floor when its error is at most 2 s sqrt(1 + 1/n) (n reference
seeds): the error another seed of the reference pour itself stays below about 95 % of the time."""
from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np

from . import btr_cli, measures, report
from .io import atomic_write_text, read_packing, write_json
from .pipeline import default_outdir, scene_inputs
from .pour import PourSettings, pour
from .runner import RunRecord, StepFailed, find_btr

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
                         margin: float | None = None, progress=print) -> dict:
    if ref_seeds < 3:
        raise StepFailed(f"error-vs-runtime: --ref-seeds: expected at least 3 (the seed-to-seed spread is the "
                         f"error floor), got {ref_seeds}")
    btr = find_btr()
    outdir = Path(outdir) if outdir else default_outdir(scene_path) / "error_vs_runtime"
    rec = RunRecord(outdir, "error-vs-runtime", inputs=scene_inputs(scene_path), btr=btr, progress=progress,
                    settings={"scene": os.path.abspath(scene_path), "engine": engine, "ref_seeds": ref_seeds,
                              "count": count, "relax_times": relax_times, "pour_variants": pour_variants, "np": ranks,
                              "margin": margin})
    rows = []
    with rec.step("BTR deposit") as st:
        dep = btr_cli.deposit(btr, scene_path, outdir / "btr", "btr", None, count, progress)
        st.update(outputs=[dep["csv"]])
    btr_packing = read_packing(dep["csv"])
    scene = btr_packing.scene()
    base_max_time = float(scene["relax"]["max_time"])
    relax_times = relax_times or [base_max_time * f for f in (0.05, 0.25, 1.0)]
    pour_variants = pour_variants or [(0.25, 1e-3), (0.5, 1e-4), (1.0, float(scene["relax"]["stop_kinetic_ratio"]))]

    refs, ref_runs = [], []
    for seed in range(1, ref_seeds + 1):
        with rec.step(f"reference pour seed {seed}") as st:
            s = pour(btr_packing, outdir / f"reference_seed{seed}", PourSettings(seed=seed, np=ranks,
                                                                                 label=f"reference-{seed}"), progress)
            refs.append(measures_of(s["packing"], margin))
            ref_runs.append(s)
            st.update(outputs=[s["packing"]], wall_seconds_engine=s["wall_seconds"], stop_reason=s["stop_reason"])
    mean, floor, names = reference_stats(refs)
    if not names:
        raise StepFailed("error-vs-runtime: the reference pours have no structural measure in common (empty bulk "
                         "window?); use a larger scene (--count) or a smaller window margin (--margin)")

    ref_wall = float(np.mean([s["wall_seconds"] for s in ref_runs]))
    reference = {"seeds": list(range(1, ref_seeds + 1)), "mean": mean, "floor": floor,
                 "reach_threshold": reach_threshold(floor, ref_seeds), "values": refs,
                 "wall_seconds": [s["wall_seconds"] for s in ref_runs],
                 "stop_reasons": [s["stop_reason"] for s in ref_runs]}

    def write_tables(rows):
        """error_vs_runtime.json / .md / .png from the rows so far (rewritten after every method)."""
        done = [r for r in rows if r["status"] == "ok"]
        verdict = first_to_floor(done, floor, names, ref_wall, ref_seeds)
        result = {"scene": os.path.abspath(scene_path), "grains": len(btr_packing), "engine": engine,
                  "reference": reference, "measures": names, "rows": rows, "verdict": verdict}
        write_json(outdir / "error_vs_runtime.json", result)
        fig = plot(outdir / "error_vs_runtime.png", done, floor, reach_threshold(floor, ref_seeds), names)
        atomic_write_text(outdir / "error_vs_runtime.md", markdown(result, os.path.basename(fig)))
        return result

    def method(label, kind, **fields):
        return rec.case(label, rows, dict(method=label, kind=kind, values=None, errors=None, **fields),
                        on_row=write_tables)

    with method("BTR", "btr", wall_seconds=dep["wall_seconds"], path=dep["csv"]) as row:
        row["values"] = m = measures_of(dep["csv"], margin)
        row["errors"] = errors_of(m, mean, names)
    for t in relax_times:
        label = f"BTR + {engine} relax {t:.3g} s"
        with method(label, "relax", wall_seconds=None) as row:
            d = outdir / f"relax_{t:.3g}s"
            csv = btr_cli.variant(dep["csv"], d / "input", "btr",
                                  lambda sc, t=t: sc["relax"].update(max_time=float(t)))
            r = btr_cli.relax(btr, csv, engine, d, np=ranks, progress=progress, label=f"relax-{t:.3g}s")
            row["values"] = m = measures_of(r["csv"], margin)
            row.update(wall_seconds=dep["wall_seconds"] + r["wall_seconds"], relax_wall_seconds=r["wall_seconds"],
                       errors=errors_of(m, mean, names), path=r["csv"])
    for k, (pace, stop) in enumerate(pour_variants):
        label = f"DEM pour pace {pace:g} stop {stop:.0e}"
        seed = ref_seeds + 1 + k
        with method(label, "pour", wall_seconds=None, seed=seed) as row:
            s = pour(btr_packing, outdir / f"pour_pace{pace:g}_stop{stop:.0e}",
                     PourSettings(seed=seed, np=ranks, pace=pace, stop_ratio=stop, label=f"pour-{pace:g}"), progress)
            row["values"] = m = measures_of(s["packing"], margin)
            row.update(wall_seconds=s["wall_seconds"], errors=errors_of(m, mean, names), path=s["packing"],
                       stop_reason=s["stop_reason"])

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


def reach_threshold(floor: dict, n_seeds: int) -> dict:
    return {k: 2.0 * v * math.sqrt(1.0 + 1.0 / n_seeds) for k, v in floor.items()}


def first_to_floor(rows, floor, names, ref_wall, n_seeds) -> dict:
    """Per measure and over all measures: the cheapest method whose error is within the floor."""
    limit = reach_threshold(floor, n_seeds)

    def reaches(row, keys):
        return all(row["errors"][k] is not None and row["errors"][k] <= limit[k] for k in keys)

    by_time = sorted(rows, key=lambda r: r["wall_seconds"])
    per = {}
    for key in names + ["all"]:
        keys = names if key == "all" else [key]
        hit = next((r for r in by_time if reaches(r, keys)), None)
        pour_hit = next((r for r in by_time if r["kind"] == "pour" and reaches(r, keys)), None)
        per[key] = None if hit is None else {
            "method": hit["method"], "wall_seconds": hit["wall_seconds"],
            "cost_ratio_to_reference_pour": hit["wall_seconds"] / ref_wall,
            "cost_ratio_to_cheapest_pour_reaching": (hit["wall_seconds"] / pour_hit["wall_seconds"]) if pour_hit else None,
            "cheapest_pour_reaching": pour_hit["method"] if pour_hit else None}
    a = per["all"]
    if not rows:
        summary = "No method finished."
    elif a is None:
        closest = min(rows, key=lambda r: max((r["errors"][k] or math.inf) / max(limit[k], 1e-300) for k in names))
        worst = max((closest["errors"][k] or math.inf) / max(limit[k], 1e-300) for k in names)
        summary = (f"No method reaches the reference's error floor in every measure; the closest is "
                   f"{closest['method']} ({closest['wall_seconds']:.3g} s), whose worst error is {worst:.3g} x the "
                   "floor's limit.")
    else:
        summary = (f"{a['method']} reaches the reference's error floor in every measure first, after "
                   f"{a['wall_seconds']:.3g} s: {a['cost_ratio_to_reference_pour']:.3g} x the wall time of a reference "
                   f"pour ({ref_wall:.3g} s)")
        if a["cost_ratio_to_cheapest_pour_reaching"] is not None and a["method"] != a["cheapest_pour_reaching"]:
            summary += (f" and {a['cost_ratio_to_cheapest_pour_reaching']:.3g} x the cheapest pour that also reaches "
                        f"it ({a['cheapest_pour_reaching']})")
        summary += "."
    return {"per_measure": per, "reference_pour_wall_seconds": ref_wall, "summary": summary}


def plot(path, rows, floor, limit, names) -> str:
    import matplotlib.pyplot as plt

    n = len(names)
    fig, axes = plt.subplots(1, n, figsize=(4.2 * n, 3.8), squeeze=False)
    markers = {"btr": ("s", "tab:green"), "relax": ("o", "tab:blue"), "pour": ("^", "tab:red")}
    for ax, key in zip(axes[0], names):
        for kind, (mk, col) in markers.items():
            sel = [r for r in rows if r["kind"] == kind and r["errors"][key] is not None]
            if not sel:
                continue
            x = [r["wall_seconds"] for r in sel]
            y = [max(r["errors"][key], floor[key] * 1e-3, 1e-12) for r in sel]
            ax.plot(x, y, marker=mk, color=col, ls="-" if kind != "btr" else "none",
                    label={"btr": "BTR", "relax": "BTR + relaxation", "pour": "DEM pour"}[kind])
        ax.axhline(max(floor[key], 1e-12), color="gray", ls="--", lw=1, label="floor: seed-to-seed std s")
        ax.axhline(max(limit[key], 1e-12), color="gray", ls=":", lw=1, label="reached below 2 s sqrt(1 + 1/n)")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("wall time [s]")
        ax.set_ylabel(f"error: {MEASURES[key]}")
        ax.legend(fontsize=7, loc="best")
    fig.suptitle("Error against the DEM pour reference vs wall time")
    fig.tight_layout()
    return report.save_figure(fig, path)


def markdown(res: dict, fig_name: str) -> str:
    names = res["measures"]
    ref = res["reference"]
    headers = ["method", "wall time [s]"] + [f"error: {MEASURES[k]}" for k in names] + ["reaches floor (all)"]
    rows = [["reference mean (" + ", ".join(f"seed {s}" for s in ref["seeds"]) + ")",
             f"{report.fmt(float(np.mean(ref['wall_seconds'])))} (mean)"] +
            [("curve" if k == "rdf" else report.fmt(ref["mean"][k])) for k in names] + ["-"],
            ["floor (seed-to-seed std s)", "-"] + [report.fmt(ref["floor"][k]) for k in names] + ["-"],
            ["reached below 2 s sqrt(1 + 1/n)", "-"] + [report.fmt(ref["reach_threshold"][k]) for k in names] + ["-"]]
    failed = []
    for r in res["rows"]:
        if r["status"] != "ok":
            failed.append([r["method"], r["status"], r["reason"]])
            continue
        ok = all(r["errors"][k] is not None and r["errors"][k] <= ref["reach_threshold"][k] for k in names)
        rows.append([r["method"], r["wall_seconds"]] + [r["errors"][k] for k in names] + ["yes" if ok else "no"])
    vals = [["method"] + [MEASURES[k] for k in names if k != "rdf"]]
    for r in res["rows"]:
        if r["status"] == "ok":
            vals.append([r["method"]] + [r["values"][k] for k in names if k != "rdf"])
    lines = [f"# Error against run time: {os.path.basename(res['scene'])}", "",
             f"{res['grains']} grains; engine {res['engine']}; reference: LIGGGHTS pours with seeds "
             f"{ref['seeds']} (stop: {', '.join(ref['stop_reasons'])}). Wall times were measured in this run, "
             "on this machine.", "", "## Verdict", "", res["verdict"]["summary"], ""]
    per = res["verdict"]["per_measure"]
    lines.append(report.md_table(["measure", "first to reach the floor", "wall time [s]", "cost / reference pour"],
                                 [[MEASURES[k], per[k]["method"] if per[k] else "none",
                                   per[k]["wall_seconds"] if per[k] else "-",
                                   per[k]["cost_ratio_to_reference_pour"] if per[k] else "-"] for k in names]))
    lines += ["## Errors", "", report.md_table(headers, rows)]
    if failed:
        lines += ["## Failed methods", "", report.md_table(["method", "status", "reason"], failed)]
    defs = next((r["values"]["definitions"] for r in res["rows"] if r["status"] == "ok"), None)
    lines += ["## Values", "", report.md_table(vals[0], vals[1:])]
    if defs:
        lines += [f"Measured by `btr measure`: {defs}.", ""]
    lines += [f"![error vs run time]({fig_name})", ""]
    return "\n".join(lines)
