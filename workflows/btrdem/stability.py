"""`stability`: relax a small BTR packing in each engine over a one-at-a-time sweep of Young's
modulus, size ratio, grain size, restitution, friction and time-step fraction (DESIGN.md section 7).

Each case starts from the base scene and changes one thing:
  young          the scene's Young's modulus (Pa)
  size_ratio     r_max / r_min of a uniform radius distribution with the base r_max (a new deposit)
  grain_size     the whole packing scaled so that the largest diameter is this (m)
  restitution, friction   the scene's material
  timestep_fraction       the scene's relax.timestep_fraction (the coupling's rule allows (0, 1])
  timestep_x     an explicit --timestep of this multiple of the stable step (above 1: must be refused)
Every relaxation is capped at `max_steps` time steps (max_time = min(scene max_time, max_steps dt)).
Status: pass; fail with the reason (engine error, kinetic energy growth, overlap above bound, grains
lost); refused (the coupling refused the case before any engine ran: a time step above the stable one,
as its rule says it must, or a value the engine cannot run, e.g. LIGGGHTS' restitution <= 0.05).
The time-step rule is consistent when every case it allows passes."""
from __future__ import annotations

import copy
import math
import os
from pathlib import Path

import numpy as np

from . import btr_cli, dem_params, report
from .neighbours import touching_pairs
from .io import atomic_write_text, read_packing, read_scene_toml, write_json, write_scene_toml
from .runner import REPO, RunRecord, StepFailed, find_btr

OVERLAP_BOUND = 0.05  # largest overlap / smaller radius accepted in a relaxed packing

FULL_SWEEP = {
    "young": [1e5, 1e6, 1e8, 1e10, 2e11],
    "size_ratio": [1.0, 3.0, 6.46, 10.0],
    "grain_size": [50e-6, 5e-4, 5e-3, 5e-2],
    "restitution": [0.05, 0.5, 0.95],
    "friction": [0.0, 0.5, 1.0],
    "timestep_fraction": [0.05, 0.1, 0.5, 1.0],
    "timestep_x": [0.5, 2.0],
}
TINY_SWEEP = {
    "young": [1e5, 2e11],
    "size_ratio": [1.0, 10.0],
    "grain_size": [50e-6, 5e-2],
    "restitution": [0.05, 0.95],
    "friction": [0.0, 1.0],
    "timestep_fraction": [0.05, 1.0],
    "timestep_x": [2.0],
}

BASE_SCENE = {
    "scene": {"name": "stability", "dimension": 3, "seed": 1},
    "grains": {"count": 200, "density": 2500.0, "radius": {"distribution": "uniform", "min": 0.5e-3, "max": 1.0e-3}},
    "container": {"kind": "periodic", "size": [0.008, 0.008]},
    "source": {"kind": "rain"},
    "material": {"young": 5e6, "poisson": 0.3, "restitution": 0.5, "friction": 0.5},
    "relax": {"engine": "liggghts", "model": "hertz", "max_time": 0.1, "stop_kinetic_ratio": 1e-6,
              "timestep_fraction": 0.2},
}


def _set_material(sc: dict, **kw):
    for comp in sc["grains"]["components"]:
        comp["material"].update(kw)


def classify_failure(message: str) -> str:
    """The failure reason of a non-zero `btr relax` exit, from its message (which carries the
    engine log's tail): one of the sweep's categories, with the engine's own ERROR line if any."""
    reason = _classify(message)
    engine_error = next((line.strip() for line in message.splitlines() if line.strip().startswith("ERROR")), None)
    return f"{reason}: {engine_error}" if engine_error else reason


def _classify(message: str) -> str:
    m = message.lower()
    if "kinetic energy" in m or "blew up" in m or "blow-up" in m:
        return "kinetic energy growth"
    if "lost" in m or "outside the container" in m or "left the" in m:
        return "grains lost"
    if "overlap" in m:
        return "overlap above bound"
    if "nan" in m or "non-finite" in m:
        return "engine error (non-finite values)"
    return "engine error"


def check_result(relaxed_csv: str, n_expected: int, kinetic_threshold: float) -> tuple[str, str, dict]:
    """(status, reason, numbers) of a relaxation that exited normally."""
    p = read_packing(relaxed_csv)
    c = p.container()
    info = {}
    if len(p) != n_expected:
        return "fail", f"grains lost: {len(p)} of {n_expected} came back", info
    if not np.all(np.isfinite(p.pos)):
        return "fail", "engine error (non-finite positions)", info
    outside = (p.pos[:, 2] < -0.5 * p.radius) | (c.wall_distance(p.pos) < -0.5 * p.radius)
    if np.any(outside):
        return "fail", f"grains lost: grain {int(p.ids[np.argmax(outside)])} left the container", info
    pairs, dist = touching_pairs(p.pos, p.radius, c, tol=0.0)
    worst = 0.0
    if len(pairs):
        ri, rj = p.radius[pairs[:, 0]], p.radius[pairs[:, 1]]
        worst = float(np.max((ri + rj - dist) / np.minimum(ri, rj)))
    floor_overlap = float(np.max(np.maximum(p.radius - p.pos[:, 2], 0.0) / p.radius))
    info["max_overlap"] = max(worst, floor_overlap)
    if info["max_overlap"] > OVERLAP_BOUND:
        return "fail", f"overlap above bound: {info['max_overlap']:.3g} of the smaller radius > {OVERLAP_BOUND:g}", info
    kin = Path(relaxed_csv).parent / "kinetic.csv"
    rows = kin.read_text().split("\n")[1:] if kin.exists() else []
    if any(line.strip() for line in rows):
        a = np.array([[float(v) for v in line.split(",")[:2]] for line in rows if line.strip()])
        if a.size:
            e = a[:, 1]
            info["final_kinetic_energy"] = float(e[-1])
            info["max_kinetic_energy"] = float(np.max(e))
            q = max(1, len(e) // 4)
            late, before = float(np.mean(e[-q:])), float(np.mean(e[-2 * q:-q])) if len(e) >= 2 * q else float(e[0])
            if not np.all(np.isfinite(e)):
                return "fail", "kinetic energy growth (non-finite)", info
            if late > kinetic_threshold and before > 0 and late > 10.0 * before:
                return "fail", f"kinetic energy growth: {late:.3g} J in the last quarter vs {before:.3g} J before", info
    return "pass", "", info


def build_cases(sweep: dict) -> list:
    cases = [("base", None)]
    for param, values in sweep.items():
        for v in values:
            cases.append((param, v))
    return cases


def run_stability(outdir=None, engines=("liggghts", "yade"), base_scene: str | None = None, tiny: bool = False,
                  max_steps: int | None = None, ranks: int = 1, progress=print) -> dict:
    btr = find_btr()
    outdir = Path(outdir) if outdir else REPO / "out" / "stability"
    sweep = TINY_SWEEP if tiny else FULL_SWEEP
    max_steps = max_steps or (3000 if tiny else 20000)
    base = read_scene_toml(base_scene) if base_scene else copy.deepcopy(BASE_SCENE)
    if tiny and not base_scene:
        base["grains"]["count"] = 60
        base["container"]["size"] = [0.006, 0.006]
    outdir.mkdir(parents=True, exist_ok=True)
    base_path = outdir / "inputs" / "base_scene.toml"
    write_scene_toml(base_path, base)
    rec = RunRecord(outdir, "stability", inputs=[base_scene] if base_scene else [], btr=btr, progress=progress,
                    settings={"engines": list(engines), "sweep": sweep, "max_steps": max_steps, "tiny": tiny,
                              "overlap_bound": OVERLAP_BOUND, "base_scene": str(base_path)})
    with rec.step("base deposit") as st:
        dep = btr_cli.deposit(btr, str(base_path), outdir / "base", "btr", progress=progress)
        st.update(outputs=[dep["csv"]])
    base_packing = read_packing(dep["csv"])
    r_max = float(np.max(base_packing.radius))
    results = []

    def write_tables(rows):
        """stability.json / .md / .png from the rows so far (rewritten after every case)."""
        rule = timestep_rule_verdict(rows)
        res = {"engines": list(engines), "max_steps": max_steps, "overlap_bound": OVERLAP_BOUND, "cases": rows,
               "timestep_rule": rule, "base_scene": str(base_path)}
        write_json(outdir / "stability.json", res)
        fig = heatmap(outdir / "stability.png", rows, engines)
        atomic_write_text(outdir / "stability.md", markdown(res, os.path.basename(fig)))
        return res

    for param, value in build_cases(sweep):
        case = "base" if param == "base" else f"{param}={value:g}"
        cdir = outdir / "cases" / case.replace("=", "_")
        built = {}

        def case_input(param=param, value=value, cdir=cdir, built=built):
            """The case's packing and settings, built once for all engines; a case whose input cannot be
            built fails in every engine with the reason "input: ..."."""
            if "error" not in built and "csv" not in built:
                try:
                    built["csv"], built["timestep_x"] = _case_input(btr, param, value, base, dep["csv"], cdir, r_max,
                                                                    max_steps, progress)
                except StepFailed as e:
                    built["error"] = f"input: {str(e).splitlines()[0]}"
                else:
                    p = read_packing(built["csv"])
                    sc = p.scene()
                    built["grains"] = len(p)
                    built["max_time"] = float(sc["relax"]["max_time"])
                    built["dt"], _ = dem_params.stable_timestep(p.radius, p.species, sc,
                                                                float(sc["relax"]["timestep_fraction"]))
                    built["threshold"] = dem_params.kinetic_threshold(p.radius, p.species, sc,
                                                                      float(sc["relax"]["stop_kinetic_ratio"]))
            if "error" in built:
                raise StepFailed(built["error"])
            return built

        for engine in engines:
            row = {"case": case, "parameter": param, "value": value, "engine": engine, "wall_seconds": 0.0}
            with rec.case(f"case {case} / {engine}", results, row, on_row=write_tables):
                c = case_input()
                ts = c["dt"] * c["timestep_x"] if c["timestep_x"] is not None else None
                r = btr_cli.relax(btr, c["csv"], engine, cdir / engine, np=ranks, timestep=ts, progress=progress,
                                  label=f"{case}-{engine}", check=False)
                row.update(wall_seconds=r["wall_seconds"], timestep=ts or c["dt"],
                           steps=int(round(c["max_time"] / (ts or c["dt"]))), grains=c["grains"])
                if r["returncode"] == 0:
                    status, reason, info = check_result(r["csv"], c["grains"], c["threshold"])
                    row.update(info)
                elif r["returncode"] == 2:
                    # refused by the coupling before any engine ran: a step above the stable one,
                    # or a value the engine cannot run (LIGGGHTS: restitution <= 0.05)
                    status, reason = "refused", (r["error"] or "refused").splitlines()[0].replace("btr relax: ", "")
                else:
                    status, reason = "fail", classify_failure(r["error"] or "")
                    row["error"] = (r["error"] or "")[:2000]
                row.update(status=status, reason=reason)
    with rec.step("table and heat map") as st:
        res = write_tables(results)
        rule = res["timestep_rule"]
        st.update(outputs=[str(outdir / "stability.md"), str(outdir / "stability.png")])
    rec.finish({"timestep_rule": rule["summary"]})
    progress(rule["summary"])
    return res


def _case_input(btr, param, value, base, base_csv, cdir: Path, r_max, max_steps, progress):
    """The packing to relax for one case (its JSON scene edited), and the time-step multiple."""
    timestep_x = None

    def cap(sc, radius, species):
        dt, _ = dem_params.stable_timestep(radius, species, sc, float(sc["relax"]["timestep_fraction"]))
        sc["relax"]["max_time"] = float(min(float(sc["relax"]["max_time"]), max_steps * dt))

    def edit(fn):
        def apply(sc):
            fn(sc)
            p = read_packing(base_csv)
            cap(sc, p.radius, p.species)
        return apply

    if param in ("base", "young", "restitution", "friction", "timestep_fraction", "timestep_x"):
        if param == "young":
            f = edit(lambda sc: _set_material(sc, young=float(value)))
        elif param == "restitution":
            f = edit(lambda sc: _set_material(sc, restitution=float(value)))
        elif param == "friction":
            f = edit(lambda sc: _set_material(sc, friction=float(value)))
        elif param == "timestep_fraction":
            f = edit(lambda sc: sc["relax"].update(timestep_fraction=float(value)))
        else:
            f = edit(lambda sc: None)
            if param == "timestep_x":
                timestep_x = float(value)
        return btr_cli.variant(base_csv, cdir / "input", "btr", f), timestep_x
    if param == "grain_size":
        factor = float(value) / (2.0 * r_max)
        csv = btr_cli.scaled_variant(base_csv, cdir / "input", "scaled", factor)
        p = read_packing(csv)
        return btr_cli.variant(csv, cdir / "input", "btr", lambda sc: cap(sc, p.radius, p.species)), None
    if param == "size_ratio":
        scene = copy.deepcopy(base)
        rmax = float(scene["grains"]["radius"]["max"])
        if value == 1.0:
            scene["grains"]["radius"] = {"distribution": "constant", "value": rmax}
        else:
            scene["grains"]["radius"] = {"distribution": "uniform", "min": rmax / float(value), "max": rmax}
        scene["scene"]["name"] = f"stability_size_ratio_{value:g}"
        path = cdir / "input" / "scene.toml"
        write_scene_toml(path, scene)
        dep = btr_cli.deposit(btr, str(path), cdir / "input", "deposited", progress=progress, label="deposit")
        p = read_packing(dep["csv"])
        return btr_cli.variant(dep["csv"], cdir / "input", "btr", lambda sc: cap(sc, p.radius, p.species)), None
    raise StepFailed(f"stability: unknown parameter {param!r}")


def timestep_rule_verdict(results) -> dict:
    allowed = [r for r in results if r["status"] != "refused"]
    failed = [r for r in allowed if r["status"] == "fail"]
    refused = [r for r in results if r["status"] == "refused"]
    wrongly_allowed = [r for r in results if r["parameter"] == "timestep_x" and r["value"] > 1.0 and r["status"] != "refused"]
    if failed:
        summary = (f"Time-step rule: {len(failed)} of {len(allowed)} allowed cases FAILED: " +
                   "; ".join(f"{r['case']} / {r['engine']} ({r['reason']})" for r in failed))
    else:
        summary = f"Time-step rule: all {len(allowed)} allowed cases passed"
    above = sum(1 for r in refused if "above the stable" in r["reason"])
    summary += (f"; {len(refused)} refused before any engine ran ({above} for a step above the stable one, "
                f"{len(refused) - above} for values the engine cannot run).")
    if wrongly_allowed:
        summary += " Steps above the stable one were NOT refused: " + ", ".join(
            f"{r['case']} / {r['engine']}" for r in wrongly_allowed) + "."
    return {"allowed": len(allowed), "failed_allowed": [f"{r['case']} / {r['engine']}" for r in failed],
            "refused": len(refused), "above_stable_not_refused": [f"{r['case']} / {r['engine']}" for r in wrongly_allowed],
            "consistent": not failed and not wrongly_allowed, "summary": summary}


def heatmap(path, results, engines) -> str:
    import matplotlib.pyplot as plt
    from matplotlib.colors import ListedColormap

    cases = []
    for r in results:
        if r["case"] not in cases:
            cases.append(r["case"])
    code = {"pass": 0, "refused": 1, "fail": 2}
    grid = np.full((len(cases), len(engines)), np.nan)
    text = [["" for _ in engines] for _ in cases]
    for r in results:
        i, j = cases.index(r["case"]), list(engines).index(r["engine"])
        grid[i, j] = code[r["status"]]
        text[i][j] = f"{r['status']} {r['wall_seconds']:.1f}s"
    fig, ax = plt.subplots(figsize=(2.2 + 2.2 * len(engines), 0.8 + 0.32 * len(cases)))
    ax.imshow(grid, cmap=ListedColormap(["#4caf50", "#bdbdbd", "#e53935"]), vmin=0, vmax=2, aspect="auto")
    for i in range(len(cases)):
        for j in range(len(engines)):
            ax.text(j, i, text[i][j], ha="center", va="center", fontsize=7)
    ax.set_xticks(range(len(engines)))
    ax.set_xticklabels(engines)
    ax.set_yticks(range(len(cases)))
    ax.set_yticklabels(cases, fontsize=7)
    ax.set_title("Relaxation stability: pass (green), refused (grey), fail (red); wall time")
    return report.save_figure(fig, path)


def markdown(res: dict, fig_name: str) -> str:
    headers = ["case", "engine", "status", "reason", "wall time [s]", "time step [s]", "steps (cap)", "max overlap / r"]
    rows = []
    for r in res["cases"]:
        rows.append([r["case"], r["engine"], r["status"], r["reason"] or "-", r["wall_seconds"], r.get("timestep"),
                     r.get("steps"), r.get("max_overlap", "-") if r["status"] == "pass" else "-"])
    return "\n".join([
        "# Stability sweep", "",
        f"One parameter at a time from the base scene ({res['base_scene']}); each relaxation capped at "
        f"{res['max_steps']} time steps; a relaxed packing fails above an overlap of {res['overlap_bound']:g} of the "
        "smaller radius.", "", "## Time-step rule", "", res["timestep_rule"]["summary"], "", "## Cases", "",
        report.md_table(headers, rows), f"![stability heat map]({fig_name})", ""])
