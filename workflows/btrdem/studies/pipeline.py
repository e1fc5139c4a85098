"""The README's main chain: BTR deposit -> DEM relaxation -> comparison -> report, into out/<scene>/.

OUTDIR/
  run.json            command, inputs, versions, each step's status, wall time and error
  inputs/             the scene file (and its drop list) as run
  btr/                btr.csv, btr.json, btr.vtp            (btr deposit)
  relax/              relaxed.csv/.json/.vtp, kinetic.csv, contacts.csv, engine inputs and log
  compare/            compare.json, compare.md, per_grain.csv, figures/, *_displacement.vtp
  report.md           the summary
"""
from __future__ import annotations

import os
from pathlib import Path

from ..core import btr_cli, report

from ..analysis import measures
from ..analysis.compare import compare
from ..core.io import atomic_write_text, read_json, read_scene_toml
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
                 count: int | None = None, progress=print) -> dict:
    btr = find_btr()
    outdir = (Path(outdir) if outdir else default_outdir(scene_path)).absolute()
    rec = RunRecord(outdir, "pipeline", inputs=scene_inputs(scene_path), btr=btr, progress=progress,
                    settings={"scene": os.path.abspath(scene_path), "engine": engine, "np": np, "seed": seed,
                              "count": count})
    progress(f"pipeline: {scene_path} -> {outdir}")
    with rec.step("deposit") as st:
        dep = btr_cli.deposit(btr, scene_path, outdir / "btr", "btr", seed, count, progress)
        st.update(outputs=[dep["csv"]], command=dep["argv"])
    with rec.step(f"relax ({engine})") as st:
        rel = btr_cli.relax(btr, dep["csv"], engine, outdir / "relax", np=np, progress=progress)
        st.update(outputs=[rel["csv"]], command=rel["argv"], engine_output=rel["stdout"])
    with rec.step("compare") as st:
        res = compare(dep["csv"], rel["csv"], str(outdir / "compare"), progress=progress)
        st.update(outputs=[res["files"]["compare_md"]])
    with rec.step("report") as st:
        text = pipeline_report(outdir, scene_path, engine, dep, rel, res)
        atomic_write_text(outdir / "report.md", text)
        st.update(outputs=[str(outdir / "report.md")])
    summary = summary_numbers(dep, rel, res)
    rec.finish(summary)
    progress(f"pipeline: done; report {outdir / 'report.md'}")
    return summary


def summary_numbers(dep, rel, res) -> dict:
    sp, sq = res["structure"]["pre"], res["structure"]["post"]
    return {"grains": sp["n_grains"], "btr_wall_seconds": dep["wall_seconds"], "relax_wall_seconds": rel["wall_seconds"],
            "moved_above_0.1d": res["displacement_d"]["fraction_above_0.1"],
            "moved_above_0.5d": res["displacement_d"]["fraction_above_0.5"],
            "packing_fraction_btr": measures.packing_fraction(sp),
            "packing_fraction_relaxed": measures.packing_fraction(sq),
            "coordination_btr": measures.coordination(sp), "coordination_relaxed": measures.coordination(sq),
            "definitions": measures.definitions(sp),
            "change_packing_fraction": res["changes"]["packing_fraction"],
            "change_coordination": res["changes"]["coordination_mean"]}


def pipeline_report(outdir: Path, scene_path, engine, dep, rel, res) -> str:
    relaxed_meta = {}
    try:
        relaxed_meta = read_json(Path(rel["csv"]).with_suffix(".json"))
    except Exception:  # the report still lists what there is
        pass
    s = summary_numbers(dep, rel, res)
    st = res["displacement_d"]
    stop = relaxed_meta.get("stop_reason") or (relaxed_meta.get("relax") or {}).get("stop_reason")
    lines = [f"# {Path(scene_path).stem}: BTR -> {engine} relaxation", "",
             f"Scene `{scene_path}`, {s['grains']} grains. Every number below comes from this run's folder; "
             "run.json records the command, inputs, versions and timings.", "",
             report.md_table(["step", "wall time [s]", "output"],
                             [["BTR deposit", dep["wall_seconds"], "btr/btr.csv"],
                              [f"{engine} relaxation", rel["wall_seconds"], "relax/relaxed.csv"]]),
             f"Relaxation stopped by: {stop or 'see relax/relaxed.json'}. {rel['stdout']}", "",
             "## What DEM changed", "", f"Measures by `btr measure` ({s['definitions']}).", "",
             report.md_table(["measure", "BTR", "relaxed", "change"],
                             [["packing fraction (bulk)", s["packing_fraction_btr"], s["packing_fraction_relaxed"],
                               s["change_packing_fraction"]],
                              ["mean coordination (bulk)", s["coordination_btr"], s["coordination_relaxed"],
                               s["change_coordination"]],
                              ["grains moved > 0.1 d", "", "", st["fraction_above_0.1"]],
                              ["grains moved > 0.5 d", "", "", st["fraction_above_0.5"]],
                              ["displacement mean / 95th pct / max [d]", "", "",
                               f"{report.fmt(st['mean'])} / {report.fmt(st['p95'])} / {report.fmt(st['max'])}"]]),
             f"Wall-time ratio (BTR + relaxation) / BTR: "
             f"{report.fmt((dep['wall_seconds'] + rel['wall_seconds']) / max(dep['wall_seconds'], 1e-9))}.", "",
             "Full comparison, the nonphysical BTR configurations and the figures: "
             "[compare/compare.md](compare/compare.md).", ""]
    for k, v in res["files"].items():
        if v.endswith(".png"):
            lines.append(f"![{k}](compare/figures/{os.path.basename(v)})")
    lines += ["", "ParaView: compare/pre_displacement.vtp and compare/post_displacement.vtp (colour by 'displacement')."]
    return "\n".join(lines) + "\n"
