"""`settle-matrix`: `btr settle` (issue 20: BTR deposit -> calibration pour -> relaxation to its packing fraction)
against reference DEM pours over a matrix of scenes (settle_rows.py): periodic beds with friction 0.1-0.8, with
rolling friction, with size ratios 1, 2 and 4, a cylinder, and heaps (open floor, Hele-Shaw cells).

Each bed row: `ref_seeds` reference pours of the row's scene (`btr pour SCENE --seed s`, s = 1..n; a pour
already finished in its folder is reused with reuse_pours), their mean and floor (seed-to-seed std) in packing
fraction, coordination, g(r) and segregation index (error_runtime.measures_of / reference_stats), then
`btr settle SCENE --seed 1` and its error per measure in units of the floor (settle_report.judge) and its cost
ratio; with settle_seeds N, also seeds 2..N of each bed row's settle, each judged the same way, and their mean
and seed-to-seed spread beside the pours' (one settle's own scatter; a failed seed is an entry with its reason).
A heap row runs settle first: a refused scene (exit 2) is a failed row with btr's reason, and no pour is
run for it; a heap that settles is judged by the heap angle. settle never sees the pours' numbers.

Every row is a case of the run record: a failure is a row with its reason and the study goes on. report.md,
settle_matrix.json, settle_matrix.png and run.json are rewritten after every row. Engine runs go to OUT/runs/,
the row scenes to OUT/scenes/."""
from __future__ import annotations

import hashlib
from pathlib import Path

from ..core import btr_cli
from ..core.io import atomic_write_text, read_json, write_json
from ..core.runner import RunRecord, StepFailed, find_btr
from ..dem.pour import PourSettings, finished_scene_pour, pour_scene
from .error_runtime import errors_of, measures_of, reach_threshold, reference_stats
from . import settle_report
from .settle_rows import (BED_BASE, DEFAULT_COUNT, DEFAULT_DEPTH, DEFAULT_HEAP_COUNT, HEAP_BASES, matrix_rows,
                          write_row_scene)


def run_settle_matrix(outdir, count: int = DEFAULT_COUNT, depth: float = DEFAULT_DEPTH,
                      heap_count: int = DEFAULT_HEAP_COUNT, yade_count: int = 0, engine: str = "liggghts",
                      ref_seeds: int = 3, ranks: int = 1, margin: float | None = None, reuse_pours: bool = False,
                      pours_only: bool = False, only=None, progress=print, reuse_settles: bool = False,
                      settle_seeds: int = 1) -> dict:
    if ref_seeds < 3:
        raise StepFailed(f"settle-matrix: --ref-seeds: expected at least 3 (the seed-to-seed spread is the floor), "
                         f"got {ref_seeds}")
    if settle_seeds < 1:
        raise StepFailed(f"settle-matrix: --settle-seeds: expected at least 1, got {settle_seeds}")
    btr = find_btr()
    outdir = Path(outdir).absolute()
    specs = matrix_rows(count, heap_count, yade_count, only)
    settings = {"count": count, "depth": depth, "heap_count": heap_count, "yade_count": yade_count, "engine": engine,
                "ref_seeds": ref_seeds, "np": ranks, "margin": margin, "reuse_pours": reuse_pours,
                "reuse_settles": reuse_settles, "pours_only": pours_only, "settle_seeds": settle_seeds,
                "rows": [s["name"] for s in specs]}
    rec = RunRecord(outdir, "settle-matrix", inputs=[BED_BASE, *HEAP_BASES.values()], btr=btr, progress=progress,
                    settings=settings)
    command = " ".join(["/usr/bin/python3"] + [str(a) for a in rec.data["command"][1:]])
    rows = []

    def write(rows_):
        result = {"command": command, "settings": settings, "rows": rows_}
        write_json(outdir / "settle_matrix.json", result)
        fig = settle_report.plot(outdir / "settle_matrix.png", result)
        atomic_write_text(outdir / "report.md", settle_report.markdown(result, Path(fig).name))
        return result

    for i, spec in enumerate(specs, 1):
        eng = spec.get("engine", engine)
        progress(f"settle-matrix: row {i}/{len(specs)}: {spec['name']} ({spec['label']}, {spec['count']} grains, {eng})")
        with rec.case(f"{spec['name']}: {spec['label']}", rows,
                      {"row": spec["name"], "label": spec["label"], "kind": spec["kind"], "engine": eng,
                       "count": spec["count"], "scene": None, "reference": None, "settle": None}, on_row=write) as row:
            scene = write_row_scene(outdir / "scenes", spec, spec["count"], depth)
            row["scene"] = str(Path(scene).relative_to(outdir))
            folder = outdir / "runs" / spec["name"]
            measures = settle_report.HEAP_MEASURES if spec["kind"] == "heap" else settle_report.BED_MEASURES
            settled = None
            if spec["kind"] == "heap":
                if pours_only:
                    row.update(status="skipped", reason="a heap row runs settle first; --pours-only runs no settle")
                    continue
                settled = settle_run(btr, scene, folder / "settle", eng, ranks, reuse_settles, progress)  # refused: fails
            refs, runs = [], []
            for seed in range(1, ref_seeds + 1):
                s = reference_pour(scene, folder / f"pour_seed{seed}", seed, eng, ranks, reuse_pours, progress)
                refs.append(measures_of(s["packing"], margin))
                runs.append(s)
            mean, floor, names = reference_stats(refs)
            names = [k for k in names if k in measures]
            if not names:
                raise StepFailed(f"the reference pours have none of {', '.join(measures)} in common (empty bulk "
                                 "window? a larger --count or a smaller --margin)")
            row["reference"] = {"seeds": list(range(1, ref_seeds + 1)), "measures": names,
                                "mean": {k: mean[k] for k in names}, "floor": {k: floor[k] for k in names},
                                "reach_threshold": reach_threshold({k: floor[k] for k in names}, ref_seeds),
                                "values": [{k: m[k] for k in names if k != "rdf"} for m in refs],
                                "cpu_seconds": [s["record_cpu_seconds"] for s in runs],
                                "wall_seconds": [s["wall_seconds"] for s in runs],
                                "reused": [bool(s.get("reused")) for s in runs],
                                "stop_reasons": [s["stop_reason"] for s in runs]}
            if pours_only:
                row["settle"] = {"note": "settle not run (--pours-only)"}
                continue
            if settled is None:
                settled = settle_run(btr, scene, folder / "settle", eng, ranks, reuse_settles, progress)
            row["settle"] = judged_settle(settled, row["reference"], margin, ref_seeds)
            if spec["kind"] != "heap" and settle_seeds > 1:
                row["settle_seeds"] = other_seeds(btr, scene, folder, eng, ranks, reuse_settles, progress, row,
                                                  margin, ref_seeds, settle_seeds)
    rec.finish({"rows": len(rows), "ok": sum(r["status"] == "ok" for r in rows)})
    return write(rows)


def reference_pour(scene: str, folder: Path, seed: int, engine: str, ranks: int, reuse: bool, progress) -> dict:
    """`btr pour SCENE --seed seed` into folder (or the pour finished there, with reuse); the summary plus
    record_cpu_seconds, pour.json's processor time of btr and the engine."""
    settings = PourSettings(seed=seed, np=ranks, engine=engine, label=f"pour-seed{seed}")
    done = finished_scene_pour(scene, folder, settings, progress=progress) if reuse else None
    if done is not None:
        progress(f"  [pour seed {seed}] reused the finished pour in {folder} ({done['wall_seconds']:.1f} s wall)")
    s = done or pour_scene(scene, folder, settings, progress)
    return dict(s, record_cpu_seconds=read_json(folder / "pour.json").get("cpu_seconds"))


def other_seeds(btr: str, scene: str, folder: Path, engine: str, ranks: int, reuse: bool, progress, row: dict,
                margin, ref_seeds: int, settle_seeds: int) -> dict:
    """Seeds 2..settle_seeds of the row's settle (folder/settle_seedS), each judged as seed 1 is, and
    settle_report.seed_summary of all of them (seed 1: the row's settle)."""
    def entry(seed: int, judged: dict) -> dict:
        return {"seed": seed, "status": "ok", "values": judged["values"], "judged": judged["judged"],
                "cpu_seconds": judged["cpu_seconds"], "target_phi": (judged.get("target_phi") or {}).get("value")}

    entries = [entry(1, row["settle"])]
    for seed in range(2, settle_seeds + 1):
        try:
            res = settle_run(btr, scene, folder / f"settle_seed{seed}", engine, ranks, reuse, progress, seed)
            entries.append(entry(seed, judged_settle(res, row["reference"], margin, ref_seeds)))
        except (StepFailed, OSError, ValueError) as e:  # the seed's reason; the other seeds and rows go on
            progress(f"  [settle seed {seed}] failed: {e}")
            entries.append({"seed": seed, "status": "fail", "reason": str(e)})
    return {"entries": entries, "summary": settle_report.seed_summary(entries, row["reference"])}


def settle_run(btr: str, scene: str, folder: Path, engine: str, ranks: int, reuse: bool, progress,
               seed: int = 1) -> dict:
    """`btr settle SCENE --seed seed` (btr_cli.settle); StepFailed with btr's reason (exit 2: a refused scene) unless
    it wrote its packing. With reuse, a settle that finished in folder from the same scene text and the same btr
    program (both kept beside it in settled_by.json) with the same engine and seed is taken as it is, with its
    recorded times."""
    stamp = folder / "settled_by.json"
    done = finished_settle(btr, scene, folder, engine, seed) if reuse else None
    if done is not None:
        progress(f"  [settle seed {seed}] reused the finished settle in {folder} ({done['cpu_seconds']:.1f} s CPU)")
        return done
    stamp.unlink(missing_ok=True)
    res = btr_cli.settle(btr, scene, engine, folder, np=ranks, seed=seed, progress=progress)
    write_json(stamp, settled_by(btr, scene))
    return res


def settled_by(btr: str, scene: str) -> dict:
    """What a settle's result depends on besides its options: the scene's text and the btr program (its SHA-256)."""
    return {"scene": Path(scene).read_text(), "btr_sha256": hashlib.sha256(Path(btr).read_bytes()).hexdigest()}


def finished_settle(btr: str, scene: str, folder: Path, engine: str, seed: int = 1) -> dict | None:
    stamp, record_path = folder / "settled_by.json", folder / "settle.json"
    if not (stamp.exists() and record_path.exists()) or read_json(stamp) != settled_by(btr, scene):
        return None
    record = read_json(record_path)
    csv = folder / f"{record.get('scene_name')}.csv"
    if record.get("engine") != engine or record.get("seed") != seed or not csv.exists():
        return None
    return {"target_reached": (record.get("target_phi") or {}).get("reached", True) is not False,
            "wall_seconds": record.get("wall_seconds"), "cpu_seconds": record.get("cpu_seconds"), "csv": str(csv),
            "record": record, "reused": True}


def judged_settle(res: dict, ref: dict, margin, ref_seeds: int) -> dict:
    """The settled packing's values, errors against the pours' mean, error / floor, and cost ratio."""
    names = ref["measures"]
    values = measures_of(res["csv"], margin)
    record = res["record"]
    cpu = record.get("cpu_seconds")
    judged = settle_report.judge(errors_of(values, ref["mean"], names), ref["floor"], ref_seeds)
    out = {"target_reached": res["target_reached"], "csv": res["csv"],
           "values": {k: values[k] for k in names if k != "rdf"}, "judged": judged,
           "all_within": all(j["within"] for j in judged.values()),
           "cpu_seconds": cpu, "reused": bool(res.get("reused")),
           "wall_seconds": record.get("wall_seconds", res["wall_seconds"]),
           "measured_cpu_seconds": res.get("run_cpu_seconds"),
           "cost_ratio": settle_report.cost_ratio(cpu, ref["cpu_seconds"]),
           "target_phi": (record.get("chosen") or {}).get("target_phi"), "chosen": record.get("chosen"),
           "target_phi_reached": record.get("target_phi"),
           "steps": [{k: s.get(k) for k in ("step", "cpu_seconds", "wall_seconds")} for s in record.get("steps", [])]}
    if cpu is None:
        out["note"] = "settle.json has no cpu_seconds: no cost ratio"
    if not res["target_reached"]:
        out["note"] = (out.get("note", "") + "; " if out.get("note") else "") + \
            "btr settle: target not reached (exit 6), the packing it wrote is judged"
    return out
