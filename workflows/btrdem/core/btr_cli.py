"""The `btr` program's deposit, relax and pour subcommands, run as subprocesses with progress lines."""
from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

from .io import InputError, read_json, read_packing, write_json, write_scene_toml
from .runner import StepFailed, run_command

ENGINES = ("liggghts", "yade")
# `btr relax` exit code: the run ended and wrote its packing, but a target it was given (--target-phi) was not
# reached; relaxed.json's target_phi record says by how much.
TARGET_NOT_REACHED = 6
# `btr relax` exit code: the engine failed; OUTDIR/relax_failure.json says how ("kind": engine_error, time_limit,
# blow_up, non_finite, lost_grains, outside_container, missed_contact, bad_output; docs/faults.md).
ENGINE_FAILED = 5
FAILURE_FILE = "relax_failure.json"
PREDICTED_OVERLAP_FILE = "predicted_overlap.json"


def deposit(btr: str, scene_path: str, outdir, name: str = "btr", seed: int | None = None, count: int | None = None,
            progress=print, label: str = "deposit") -> dict:
    """btr deposit SCENE -o OUTDIR --name NAME [--seed] [--count]; returns {csv, wall_seconds, ...}."""
    outdir = Path(outdir).absolute()  # the command runs in outdir: a relative -o would nest
    outdir.mkdir(parents=True, exist_ok=True)
    argv = [btr, "deposit", os.path.abspath(scene_path), "-o", str(outdir), "--name", name, "--quiet"]
    if seed is not None:
        argv += ["--seed", str(seed)]
    if count is not None:
        argv += ["--count", str(count)]
    res = run_command(argv, outdir, label, progress=progress)
    csv = outdir / f"{name}.csv"
    if res["returncode"] != 0:
        raise StepFailed(f"{label}: btr deposit exited with status {res['returncode']}:\n"
                         f"{Path(res['stderr']).read_text(errors='replace').strip()[-2000:]}")
    if not csv.exists():
        raise StepFailed(f"{label}: btr deposit succeeded but wrote no {csv}")
    return {"csv": str(csv), "wall_seconds": res["wall_seconds"], "cpu_seconds": res["cpu_seconds"],
            "argv": [str(a) for a in argv], "stdout": res["stdout"], "stderr": res["stderr"]}


def relax(btr: str, packing_csv: str, engine: str, outdir, np: int = 1, timestep: float | None = None,
          time_limit: float | None = None, progress=print, label: str | None = None, check: bool = True,
          extra_args=()) -> dict:
    """btr relax PACKING --engine E -o OUTDIR [extra options]; returns {returncode, wall_seconds, csv, error,
    failure, ...}: `failure` is the run's relax_failure.json (kind, engine, message, values) when the engine failed
    (exit 5), else None. With check=True a failed run raises StepFailed with the program's message."""
    if engine not in ENGINES:
        raise StepFailed(f"relax: engine: expected one of {', '.join(ENGINES)}, got {engine!r}")
    label = label or f"relax-{engine}"
    outdir = Path(outdir).absolute()  # the command runs in outdir: a relative -o would nest
    outdir.mkdir(parents=True, exist_ok=True)
    argv = [btr, "relax", os.path.abspath(packing_csv), "--engine", engine, "-o", str(outdir), "--np", str(np)]
    if timestep is not None:
        argv += ["--timestep", repr(float(timestep))]
    if time_limit is not None:
        argv += ["--time-limit", repr(float(time_limit))]
    argv += [str(a) for a in extra_args]
    log = _engine_log(outdir, engine)
    res = run_command(argv, outdir, label, progress=progress, watch=log, stdout_name=f"{label}.stdout")
    err = Path(res["stderr"]).read_text(errors="replace").strip()
    target_missed = res["returncode"] == TARGET_NOT_REACHED
    out = {"returncode": 0 if target_missed else res["returncode"], "target_reached": not target_missed,
           "wall_seconds": res["wall_seconds"], "cpu_seconds": res["cpu_seconds"],
           "argv": [str(a) for a in argv],
           "csv": str(outdir / "relaxed.csv"), "error": err if res["returncode"] not in (0, TARGET_NOT_REACHED) else None,
           "stdout": Path(res["stdout"]).read_text(errors="replace").strip(),
           "failure": failure_record(outdir) if res["returncode"] == ENGINE_FAILED else None}
    if out["returncode"] == 0 and not (outdir / "relaxed.csv").exists():
        out["returncode"] = -1
        out["error"] = f"btr relax succeeded but wrote no {outdir / 'relaxed.csv'}"
    if check and out["returncode"] != 0:
        kind = f" ({out['failure']['kind']})" if out["failure"] else ""
        raise StepFailed(f"{label}: btr relax exited with status {res['returncode']}{kind}:\n{out['error'][-3000:]}")
    return out


def pour(btr: str, input_path: str, engine: str, outdir, np: int = 1, time_limit: float | None = None,
         progress=print, label: str = "pour", extra_args=()) -> dict:
    """btr pour SCENE.toml|PACKING.csv --engine E -o OUTDIR [extra options]; returns {returncode, wall_seconds,
    cpu_seconds, csv, error, stdout}. Never raises on a failed run (the caller decides); a stop signal stops it."""
    if engine not in ENGINES:
        raise StepFailed(f"pour: engine: expected one of {', '.join(ENGINES)}, got {engine!r}")
    outdir = Path(outdir).absolute()  # the command runs in outdir: a relative -o would nest
    outdir.mkdir(parents=True, exist_ok=True)
    argv = [btr, "pour", os.path.abspath(input_path), "--engine", engine, "-o", str(outdir), "--np", str(np)]
    if time_limit is not None:
        argv += ["--time-limit", repr(float(time_limit))]
    argv += [str(a) for a in extra_args]
    res = run_command(argv, outdir, label, progress=progress, watch=_engine_log(outdir, engine),
                      stdout_name=f"{label.replace(' ', '_').replace('/', '_')}.stdout")
    err = Path(res["stderr"]).read_text(errors="replace").strip()
    out = {"returncode": res["returncode"], "wall_seconds": res["wall_seconds"], "cpu_seconds": res["cpu_seconds"],
           "argv": [str(a) for a in argv], "csv": str(outdir / "poured.csv"),
           "error": err if res["returncode"] != 0 else None,
           "stdout": Path(res["stdout"]).read_text(errors="replace").strip()}
    if out["returncode"] == 0 and not (outdir / "poured.csv").exists():
        out["returncode"] = -1
        out["error"] = f"btr pour succeeded but wrote no {outdir / 'poured.csv'}"
    return out


def settle(btr: str, scene_path: str, engine: str, outdir, np: int = 1, seed: int | None = None,
           count: int | None = None, progress=print, label: str = "settle", extra_args=()) -> dict:
    """btr settle SCENE --engine E -o OUTDIR; returns {returncode, wall_seconds, cpu_seconds (settle.json's: the
    calibration included), csv (the settled packing), btr_csv (its BTR packing), record (settle.json), error,
    stdout}. A refused scene or a failed run raises StepFailed with the program's message; a missed target
    (exit 6) does not (target_reached False)."""
    if engine not in ENGINES:
        raise StepFailed(f"settle: engine: expected one of {', '.join(ENGINES)}, got {engine!r}")
    outdir = Path(outdir).absolute()
    outdir.mkdir(parents=True, exist_ok=True)
    argv = [btr, "settle", os.path.abspath(scene_path), "--engine", engine, "-o", str(outdir), "--np", str(np),
            "--quiet"]
    if seed is not None:
        argv += ["--seed", str(seed)]
    if count is not None:
        argv += ["--count", str(count)]
    argv += [str(a) for a in extra_args]
    res = run_command(argv, outdir, label, progress=progress, stdout_name=f"{label}.stdout")
    err = Path(res["stderr"]).read_text(errors="replace").strip()
    if res["returncode"] not in (0, TARGET_NOT_REACHED):
        raise StepFailed(f"{label}: btr settle exited with status {res['returncode']}:\n{err[-3000:]}")
    record = read_json(outdir / "settle.json")
    name = record["scene_name"]
    return {"returncode": 0, "target_reached": res["returncode"] == 0, "wall_seconds": res["wall_seconds"],
            "cpu_seconds": record["cpu_seconds"], "run_cpu_seconds": res["cpu_seconds"],
            "argv": [str(a) for a in argv], "csv": str(outdir / f"{name}.csv"),
            "btr_csv": str(outdir / "btr" / f"{name}.csv"), "record": record, "error": None,
            "stdout": Path(res["stdout"]).read_text(errors="replace").strip()}


def failure_record(outdir) -> dict | None:
    """OUTDIR/relax_failure.json of the last `btr relax` into OUTDIR, or None if that run did not fail (btr removes
    the file when a run starts and writes it when the engine fails)."""
    path = Path(outdir) / FAILURE_FILE
    if not path.exists():
        return None
    try:
        record = read_json(path)
    except InputError:
        return None
    return record if isinstance(record, dict) and "kind" in record else None


def predict_overlap(btr: str, packing_csv: str, outdir) -> dict:
    """`btr relax PACKING --predict-overlap -o OUTDIR` (no engine run): the contact law's static overlap of the
    grains on the floor, alone and under their column, as OUTDIR/predicted_overlap.json holds it."""
    outdir = Path(outdir).absolute()
    outdir.mkdir(parents=True, exist_ok=True)
    p = subprocess.run([btr, "relax", os.path.abspath(packing_csv), "-o", str(outdir), "--predict-overlap"],
                       capture_output=True, text=True, timeout=120)
    if p.returncode != 0:
        raise StepFailed(f"btr relax --predict-overlap exited with status {p.returncode}: {p.stderr.strip()[-1500:]}")
    return read_json(outdir / PREDICTED_OVERLAP_FILE)


def _engine_log(outdir: Path, engine: str) -> str:
    return str(outdir / ("log.liggghts" if engine == "liggghts" else "yade.log"))


def variant(packing_csv: str, outdir, name: str, scene_edit) -> str:
    """A copy of PACKING.csv/.json into outdir/NAME.csv whose JSON scene was changed by
    scene_edit(scene) (in place). Returns the new CSV path. `btr relax` reads its settings from it."""
    outdir = Path(outdir).absolute()  # the command runs in outdir: a relative -o would nest
    outdir.mkdir(parents=True, exist_ok=True)
    src_json = Path(packing_csv).with_suffix(".json")
    meta = read_json(src_json)
    if "scene" not in meta:
        raise StepFailed(f"{src_json}: no 'scene' to edit")
    scene_edit(meta["scene"])
    dst = outdir / f"{name}.csv"
    shutil.copyfile(packing_csv, dst)
    write_json(outdir / f"{name}.json", meta)
    return str(dst)


def scaled_variant(packing_csv: str, outdir, name: str, factor: float, scene_edit=None) -> str:
    """A copy scaled by `factor` (positions, radii and the scene's lengths), for grain-size sweeps."""
    p = read_packing(packing_csv)
    meta = p.meta
    sc = meta["scene"]
    c = sc["container"]
    for k in ("size_x", "size_y", "gap", "radius", "height"):
        c[k] = c.get(k, 0.0) * factor
    meta["container"] = c
    for comp in sc["grains"]["components"]:
        rs = comp["radius"]
        for k in ("value", "min", "max"):
            rs[k] = rs.get(k, 0.0) * factor
        rs["list"] = [v * factor for v in rs.get("list", [])]
    src = sc["source"]
    for k in ("x", "y", "scatter", "x_min", "x_max", "y_min", "y_max"):
        src[k] = src.get(k, 0.0) * factor
    if scene_edit:
        scene_edit(sc)
    p.pos = p.pos * factor
    p.radius = p.radius * factor
    from .io import write_packing

    write_packing(outdir, name, p, vtp=False)
    return str(Path(outdir) / f"{name}.csv")


def help_text(btr: str, command: str) -> str:
    """`btr COMMAND --help` (to check that this build has an option)."""
    p = subprocess.run([btr, command, "--help"], capture_output=True, text=True, timeout=60)
    return p.stdout + p.stderr


def shake(btr: str, scene_path: str, outdir, cycles: int, count: int | None = None, lift_d: float = 1.0,
          noise_d: float = 0.1, progress=print) -> dict:
    """`btr shake` of the scene (its grains or `count`) for `cycles` Jullien-Meakin cycles, lifting the pile by
    lift_d and moving each grain by up to noise_d largest diameters; returns {csv (last cycle), wall_seconds}."""
    import tomllib

    with open(scene_path, "rb") as f:
        scene = tomllib.load(f)
    if count is not None:
        scene["grains"]["count"] = int(count)
    rad = scene["grains"].get("radius", {})
    r_max = max(float(rad.get(k, 0.0)) for k in ("value", "max")) or max(rad.get("values", [0.0]))
    if not r_max > 0.0:
        raise StepFailed(f"{scene_path}: shake: no largest radius in [grains].radius")
    scene["shaking"] = {"cycles": int(cycles), "lift": 2.0 * r_max * lift_d, "noise": 2.0 * r_max * noise_d,
                        "snapshot_every": int(cycles)}
    outdir = Path(outdir).absolute()  # the command runs in outdir: a relative -o would nest
    outdir.mkdir(parents=True, exist_ok=True)
    toml = outdir / "shake_scene.toml"
    write_scene_toml(toml, scene)
    res = run_command([btr, "shake", str(toml), "-o", str(outdir), "--name", "shaken", "--quiet"], outdir, "shake",
                      progress=progress)
    csv = outdir / f"shaken_c{int(cycles):06d}.csv"
    if res["returncode"] != 0 or not csv.exists():
        raise StepFailed(f"btr shake exited with status {res['returncode']} (no {csv}): "
                         f"{Path(res['stderr']).read_text(errors='replace').strip()[-1500:]}")
    return {"csv": str(csv), "wall_seconds": res["wall_seconds"], "cpu_seconds": res["cpu_seconds"]}
