"""Reference DEM pour of a BTR packing's grains (same radii, species, order, container and source): `btr pour`
(docs/guide/pour.md) run as a subprocess, with the summary the studies read.

The pour itself (lattice over the source's footprint, batches released as a stream, the relaxation's time step,
materials, walls and stop rule, an open floor bounded and its runaway grains removed and counted) is the C++
command's; this module only runs it (btrdem.core.btr_cli.pour, which stops it on a stop signal) and reads its
record, DIR/poured.json's "pour" object."""
from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..core import btr_cli
from ..core.io import Packing, read_json, read_packing, write_json
from ..core.runner import StepFailed, find_btr


@dataclass
class PourSettings:
    seed: int = 1
    np: int = 1                        # LIGGGHTS: MPI ranks; YADE: threads
    pace: float = 1.0                  # batch interval / batch free-fall time (smaller: faster pour)
    drop_gap_d: float = 1.0            # drop height above the highest released grain [mean diameters]
    max_batches: int = 40
    stop_ratio: float | None = None    # default: the scene's relax.stop_kinetic_ratio
    settle_max_time: float | None = None  # simulated seconds after the last batch; default scene relax.max_time
    timestep_fraction: float | None = None  # default: the scene's relax.timestep_fraction
    check_every: float = 0.005         # simulated seconds between kinetic-energy checks (at least 1000 steps)
    wall_time_limit: float = 7200.0
    engine: str = "liggghts"
    label: str = "pour"
    extra: dict = field(default_factory=dict)


class PourFailure(StepFailed):
    pass


def _arguments(settings: PourSettings) -> list:
    args = ["--seed", str(int(settings.seed)), "--pace", repr(float(settings.pace)),
            "--drop-gap", repr(float(settings.drop_gap_d)), "--max-batches", str(int(settings.max_batches)),
            "--check-interval", repr(float(settings.check_every))]
    for option, value in (("--stop-ratio", settings.stop_ratio), ("--settle-max-time", settings.settle_max_time),
                          ("--timestep-fraction", settings.timestep_fraction)):
        if value is not None:
            args += [option, repr(float(value))]
    return args


def _summary(out: Path, record: dict, wall: float, cpu: float | None, seed: int) -> dict:
    removed = record.get("removed") or {}
    return {"wall_seconds": wall, "cpu_seconds": cpu, "stop_reason": record["stop_reason"],
            "simulated_time": record["simulated_time"], "timestep": record["timestep"],
            "timestep_rule": record["timestep_rule"], "batches": record["batches"], "engine": record["engine"],
            "packing": str(out / "poured.csv"), "seed": seed, "removed": int(removed.get("count", 0))}


def pour(btr: Packing, outdir: str | os.PathLike, settings: PourSettings = PourSettings(), progress=print) -> dict:
    """`btr pour BTR.csv -o OUTDIR` with the settings: writes OUTDIR/poured.{csv,json,vtp}, pour.json, the engine's
    inputs and log, kinetic.csv, and pour_summary.json, the returned summary (wall and processor time of btr and
    the engine, stop reason, simulated time, time step, batches, removed grains, the poured packing's path)."""
    if not btr.path:
        raise PourFailure("pour: the packing has no file; btr pour reads PACKING.csv and its JSON")
    return _pour_file(btr.path, outdir, settings, progress)


def pour_scene(scene_path: str, outdir: str | os.PathLike, settings: PourSettings = PourSettings(), progress=print,
               count: int | None = None) -> dict:
    """`btr pour SCENE.toml -o OUTDIR --seed S [--count N]`: the scene's own drops with the settings' seed (the
    grains `btr deposit` would place with that seed), poured as pour() pours a packing; the same summary."""
    return _pour_file(scene_path, outdir, settings, progress, [] if count is None else ["--count", str(int(count))])


def _pour_file(input_path: str, outdir, settings: PourSettings, progress, extra=()) -> dict:
    out = Path(outdir).absolute()
    res = btr_cli.pour(find_btr(), input_path, settings.engine, out, np=settings.np, time_limit=settings.wall_time_limit,
                       progress=progress, label=settings.label, extra_args=_arguments(settings) + list(extra))
    if res["returncode"] != 0:
        raise PourFailure(f"{settings.label}: btr pour exited with status {res['returncode']}:\n"
                          f"{(res['error'] or '')[-3000:]}")
    record = read_json(out / "poured.json")["pour"]
    summary = _summary(out, record, res["wall_seconds"], res["cpu_seconds"], settings.seed)
    write_json(out / "pour_summary.json", summary)
    progress(f"  [{settings.label}] done in {summary['wall_seconds']:.1f} s wall ({summary['cpu_seconds']:.1f} s CPU), "
             f"{summary['simulated_time']:.3g} s simulated, step {summary['timestep']:.3g} s, stop: "
             f"{summary['stop_reason']}" + (f"; {summary['removed']} grain(s) left the open floor's region, removed"
                                            if summary["removed"] else ""))
    return summary


# PourSettings field -> the key of poured.json's pour.settings it must equal for a pour to be reused
_REUSE_KEYS = {"seed": "seed", "pace": "pace", "stop_ratio": "stop_ratio", "drop_gap_d": "drop_gap",
               "max_batches": "max_batches", "settle_max_time": "settle_max_time",
               "timestep_fraction": "timestep_fraction"}


def finished_pour(btr: Packing, outdir: str | os.PathLike, settings: PourSettings) -> dict | None:
    """The summary of a pour already finished in outdir by `btr pour` with the same engine, settings and grains
    (radii equal to btr's, in order), or None. Its times are the ones recorded when it ran ("reused": true)."""
    out = Path(outdir)
    summary_path, meta_path, csv = out / "pour_summary.json", out / "poured.json", out / "poured.csv"
    if not (summary_path.exists() and meta_path.exists() and csv.exists()):
        return None
    summary, ran = read_json(summary_path), read_json(meta_path).get("pour") or {}
    if ran.get("engine") != settings.engine:
        return None
    done = ran.get("settings") or {}
    # None in settings means "the scene's value", which the record holds resolved: compare only what was set.
    if any(getattr(settings, k) is not None and done.get(key) != getattr(settings, k) for k, key in _REUSE_KEYS.items()):
        return None
    poured = read_packing(str(csv))
    removed = np.asarray((ran.get("removed") or {}).get("ids", []), dtype=np.int64)
    kept = np.setdiff1d(np.arange(1, len(btr) + 1), removed) - 1
    if len(poured) != len(kept) or not np.allclose(poured.radius, btr.radius[kept], rtol=1e-12, atol=0.0):
        return None
    return dict(summary, reused=True)


def finished_scene_pour(scene_path: str, outdir: str | os.PathLike, settings: PourSettings,
                        count: int | None = None, progress=print) -> dict | None:
    """finished_pour for a pour of a scene (pour_scene): the grains it must have are those `btr deposit` places with
    the same scene, seed and count (docs/guide/pour.md, "Which grains"), deposited into OUTDIR/grains; the poured
    scene (materials, container, source, relax settings) must also be that deposit's (a changed friction keeps the
    radii)."""
    out = Path(outdir)
    if not (out / "poured.json").exists():
        return None
    dep = btr_cli.deposit(find_btr(), scene_path, out / "grains", "grains", settings.seed, count, progress,
                          label="deposit-for-reuse")
    grains = read_packing(dep["csv"])
    poured_scene = read_json(out / "poured.json").get("scene") or {}
    want = grains.scene()
    if any(poured_scene.get(k) != want.get(k) for k in (set(poured_scene) | set(want)) - {"file"}):
        return None
    return finished_pour(grains, outdir, settings)
