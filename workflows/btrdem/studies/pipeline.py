"""The README's main chain: `btr settle` (BTR deposit -> calibration pour -> DEM relaxation to its packing
fraction) -> comparison of the settled packing against the BTR packing -> report, into out/<scene>/.

OUTDIR/
  run.json            command, inputs, versions, each step's status, wall time and error
  inputs/             the scene file (and its drop list) as run
  settle/             NAME.csv/.json/.vtp (the settled packing), settle.json (steps, costs, chosen values),
                      dem_input/ (the engine's ready-to-run input of it), btr/ (the BTR packing),
                      calibration/ (the calibration pour), relax/ (the engine run)
  compare/            compare.json, compare.md, per_grain.csv, figures/, *_displacement.vtp
  report.md           the summary
"""
from __future__ import annotations

import os
from pathlib import Path

from ..core import btr_cli, report

from ..analysis import measures
from ..analysis.compare import compare
from ..core.io import atomic_write_text, read_scene_toml
from ..core.runner import REPO, RunRecord, find_btr


def default_outdir(scene_path: str) -> Path:
    scene = read_scene_toml(scene_path)
    name = (scene.get("scene") or {}).get("name") or Path(scene_path).stem
    return REPO / "out" / name


def scene_inputs(scene_path: str) -> list:
    """The scene file and any file it refers to (a list source's drops)."""
    files = [scene_path]
    src = read_scene_toml(scene_path).get("source") or {}
    if src.get("kind") == "list" and src.get("file"):
        f = Path(src["file"])
        files.append(str(f if f.is_absolute() else Path(scene_path).parent / f))
    return files


def run_pipeline(scene_path: str, outdir=None, engine: str = "liggghts", np: int = 1, seed: int | None = None,
                 count: int | None = None, progress=print, calibration_grains: int | None = None) -> dict:
    btr = find_btr()
    outdir = (Path(outdir) if outdir else default_outdir(scene_path)).absolute()
    rec = RunRecord(outdir, "pipeline", inputs=scene_inputs(scene_path), btr=btr, progress=progress,
                    settings={"scene": os.path.abspath(scene_path), "engine": engine, "np": np, "seed": seed,
                              "count": count, "calibration_grains": calibration_grains})
    progress(f"pipeline: {scene_path} -> {outdir}")
    with rec.step(f"settle ({engine})") as st:
        sett = btr_cli.settle(btr, scene_path, engine, outdir / "settle", np=np, seed=seed, count=count,
                              progress=progress, extra_args=["--calibration-grains", calibration_grains]
                              if calibration_grains else ())
        st.update(outputs=[sett["csv"], sett["btr_csv"]], command=sett["argv"], engine_output=sett["stdout"])
    with rec.step("compare") as st:
        res = compare(sett["btr_csv"], sett["csv"], str(outdir / "compare"), progress=progress)
        st.update(outputs=[res["files"]["compare_md"]])
    with rec.step("report") as st:
        text = pipeline_report(outdir, scene_path, engine, sett, res)
        atomic_write_text(outdir / "report.md", text)
        st.update(outputs=[str(outdir / "report.md")])
    summary = summary_numbers(sett, res)
    rec.finish(summary)
    progress(f"pipeline: done; report {outdir / 'report.md'}")
    return summary


def step_seconds(sett: dict, step: str, key: str) -> float:
    return sum(s[key] for s in sett["record"]["steps"] if s["step"] == step)


def summary_numbers(sett, res) -> dict:
    sp, sq = res["structure"]["pre"], res["structure"]["post"]
    chosen = sett["record"]["chosen"]
    return {"grains": sp["n_grains"], "settle_cpu_seconds": sett["cpu_seconds"],
            "settle_wall_seconds": sett["wall_seconds"],
            "btr_wall_seconds": step_seconds(sett, "deposit", "wall_seconds"),
            "target_phi": chosen["target_phi"]["value"], "target_reached": sett["target_reached"],
            "moved_above_0.1d": res["displacement_d"]["fraction_above_0.1"],
            "moved_above_0.5d": res["displacement_d"]["fraction_above_0.5"],
            "packing_fraction_btr": measures.packing_fraction(sp),
            "packing_fraction_settled": measures.packing_fraction(sq),
            "coordination_btr": measures.coordination(sp), "coordination_settled": measures.coordination(sq),
            "definitions": measures.definitions(sp),
            "change_packing_fraction": res["changes"]["packing_fraction"],
            "change_coordination": res["changes"]["coordination_mean"]}


def pipeline_report(outdir: Path, scene_path, engine, sett, res) -> str:
    s = summary_numbers(sett, res)
    st = res["displacement_d"]
    rec = sett["record"]
    name = rec["scene_name"]
    outputs = {"deposit": f"settle/btr/{name}.csv", "calibration": "settle/calibration/poured.csv",
               "relax": "settle/relax/relaxed.csv", "engine input": "settle/dem_input/"}
    rows = [[x["step"], x["cpu_seconds"], x["wall_seconds"], outputs.get(x["step"], "")] for x in rec["steps"]]
    rows.append(["total", rec["cpu_seconds"], rec["wall_seconds"], f"settle/{name}.csv, settle/settle.json"])
    chosen = rec["chosen"]
    frm = chosen["target_phi"]["from"]
    relax_step = next((x for x in rec["steps"] if x["step"] == "relax"), {})
    lines = [f"# {Path(scene_path).stem}: btr settle ({engine})", "",
             f"Scene `{scene_path}`, {s['grains']} grains: the BTR packing, settled in {engine} to the packing "
             "fraction of a small periodic pour of the same grains (no pour of the scene itself). Every number below "
             "comes from this run's folder; run.json records the command, inputs, versions and timings.", "",
             report.md_table(["step", "processor time [s]", "wall time [s]", "output"], rows),
             f"Target bulk packing fraction {report.fmt(chosen['target_phi']['value'])}, from the calibration pour "
             f"of {frm.get('grains')} grains in a periodic cell {report.fmt(frm.get('cell', {}).get('width', 0) * 1e3)} "
             f"mm wide; {'reached' if sett['target_reached'] else 'NOT reached'}. Compaction damping "
             f"{report.fmt(chosen['compaction_damping']['value'])}, settle damping {report.fmt(chosen['damping']['value'])}, "
             f"stop rule {chosen['stop_rule']['value']} (stopped by {relax_step.get('stop_reason', '?')}); where each "
             "value came from: settle/settle.json, \"chosen\".", "",
             "## What settling changed", "", f"Measures by `btr measure` ({s['definitions']}).", "",
             report.md_table(["measure", "BTR", "settled", "change"],
                             [["packing fraction (bulk)", s["packing_fraction_btr"], s["packing_fraction_settled"],
                               s["change_packing_fraction"]],
                              ["mean coordination (bulk)", s["coordination_btr"], s["coordination_settled"],
                               s["change_coordination"]],
                              ["grains moved > 0.1 d", "", "", st["fraction_above_0.1"]],
                              ["grains moved > 0.5 d", "", "", st["fraction_above_0.5"]],
                              ["displacement mean / 95th pct / max [d]", "", "",
                               f"{report.fmt(st['mean'])} / {report.fmt(st['p95'])} / {report.fmt(st['max'])}"]]),
             "Full comparison, the nonphysical BTR configurations and the figures: "
             "[compare/compare.md](compare/compare.md). How close settle comes to real pours, scene by scene: "
             "docs/settle/.", ""]
    for k, v in res["files"].items():
        if v.endswith(".png"):
            lines.append(f"![{k}](compare/figures/{os.path.basename(v)})")
    lines += ["", "ParaView: compare/pre_displacement.vtp and compare/post_displacement.vtp (colour by 'displacement').",
              f"Your own {engine} run can start from settle/dem_input/."]
    return "\n".join(lines) + "\n"
