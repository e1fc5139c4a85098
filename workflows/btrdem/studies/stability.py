"""`stability`: stiff and extreme cases run to rest in each engine, and the largest stable time step
found by bisection, as a multiple of the coupling's rule (coupling/dem/timestep.h).

Every run starts pre-loaded (START: `btr relax --preload`, coupling/dem/preload.h: each contact starts with
the overlap that carries its static force, so a stiff bed starts near rest); if the pre-load is refused
(its packing overlaps beyond the intended overlaps above --max-overlap, e.g. soft 5 cm grains whose
law overlaps reach half a radius) the case runs from the touching start and its row says so.

For every material case and engine:
1. **Run to rest** at the rule's step: the run ends at its stop rule (REST_STOP_RULE, unbalanced force:
   with a pre-loaded start the kinetic rule arms after sqrt(2 delta_max / g), a few hundred steps of a
   stiff bed, and fires before the grains have moved; the unbalanced force asks for static equilibrium)
   or at a simulated-time cap of REST_FREE_FALL_TIMES free-fall times of the bed, sqrt(2 H / g) with H
   the packing's top (never at a step cap). Verdict, one of
     stable            bounded, no overlap above the bound (at rest, or "not at rest" at the cap)
     unstable          numerically unstable: the engine blew up (kinetic energy above twice the energy the
                       packing holds), NaN, lost grains, grains outside, kinetic-energy growth
     outside validity  bounded, but the static overlap is above OVERLAP_BOUND of the smaller radius: the
                       contact model (small-overlap Hertz/Hooke) is outside its range; the predicted static
                       overlap of the same law is shown beside it (predicted_overlap: `btr relax
                       --predict-overlap`, the coupling's contact law)
     refused           the coupling refused the case before any engine ran (with its reason)
     not at rest       the rest run used its wall-time budget first (a cost verdict, never unstable)
   Overlaps are btr relax's own (relaxed.json: final_largest_overlap, final_largest_floor_overlap); why a
   run failed is the kind of its relax_failure.json (classify), never its message text.
2. **Find the edge**: `btr relax --force-timestep` (hidden, study only) at multiples m of the rule's
   step over a window of WINDOW_STEPS rule steps from the same start as the rest run (pre-loaded or
   touching) and a stop rule that never fires (every probe runs its whole window): m = 2, 4, 8, ... up
   to MAX_MULTIPLE until a run is unbounded, then bisection (geometric midpoints) between the last
   bounded and the first unbounded multiple. Bounded: exit 0, kinetic energy not above GROWTH x the
   largest of the rule-step run, largest overlap not above OVERLAP_GROWTH x the rule-step run's plus
   0.01 radius. The margin of the rule is the largest bounded multiple."""
from __future__ import annotations

import copy
import json
import math
import os
import re
from pathlib import Path

import numpy as np

from ..core import btr_cli, report

from ..dem import dem_params
from ..core.io import atomic_write_text, read_packing, write_json, write_scene_toml
from ..core.runner import REPO, RunRecord, StepFailed, find_btr

OVERLAP_BOUND = 0.05   # static overlap / smaller radius above which the contact law is outside its validity
REST_FREE_FALL_TIMES = 5.0
GROWTH = 10.0          # forced run unbounded if its largest kinetic energy exceeds this x the rule run's
OVERLAP_GROWTH = 2.0
MAX_MULTIPLE = 64.0
START = "preload"      # every run starts pre-loaded (btr relax --preload); touching if the pre-load is refused
REST_STOP_RULE = "unbalanced-force"  # the rest run's stop rule (static equilibrium, see the module doc)
NEVER_STOP_RATIO = 1e-200  # the probes' kinetic stop ratio: their stop rule never fires

STEEL = {"young": 2e11, "poisson": 0.3}
GLASS_BED = {  # the base: a small periodic bed of glass-density grains, radius 0.5-1 mm
    "scene": {"name": "stability", "dimension": 3, "seed": 1},
    "grains": {"count": 40, "density": 2500.0, "radius": {"distribution": "uniform", "min": 0.5e-3, "max": 1.0e-3}},
    "container": {"kind": "periodic", "size": [0.005, 0.005]},
    "source": {"kind": "rain"},
    "material": {"young": 5e6, "poisson": 0.3, "restitution": 0.5, "friction": 0.5},
    "relax": {"engine": "liggghts", "model": "hertz", "max_time": 1.0, "stop_kinetic_ratio": 1e-6,
              "timestep_fraction": 0.2},
}


def _case(name, what, count=None, density=None, radius=None, container=None, source=None, material=None,
          dimension=None):
    sc = copy.deepcopy(GLASS_BED)
    sc["scene"]["name"] = name
    if count is not None:
        sc["grains"]["count"] = count
    if density is not None:
        sc["grains"]["density"] = density
    if radius is not None:
        sc["grains"]["radius"] = radius
    if container is not None:
        sc["container"] = container
    if source is not None:
        sc["source"] = source
    if material:
        sc["material"].update(material)
    if dimension is not None:
        sc["scene"]["dimension"] = dimension
    return {"name": name, "what": what, "scene": sc}


def build_cases(tiny: bool = False, full: bool = False) -> list:
    """The material cases: one scene each. tiny: the fewest grains that still run; full: the 1e4-grain column."""
    n = 12 if tiny else 40
    # The tall steel column: 1000 grains in a 3 d x 3 d cell (about 100 d tall); --full: the 1e4
    # grains in a 6 d x 6 d cell (about 250 d tall: wider rather than 1000 d tall).
    column = 30 if tiny else (10000 if full else 1000)
    column_cell = 0.012 if full and not tiny else 0.006
    return [
        _case("base", "glass-density bed, E = 5e6 Pa, r 0.5-1 mm", count=n),
        _case("steel", "steel, E = 2e11 Pa, rho = 7800", count=n, density=7800.0, material=STEEL),
        _case("steel_ratio10", "steel, r_max / r_min = 10 (r 0.2-2 mm)", count=n, density=7800.0, material=STEEL,
              radius={"distribution": "uniform", "min": 0.2e-3, "max": 2.0e-3},
              container={"kind": "periodic", "size": [0.012, 0.012]}),
        _case("soft_large", "soft (E = 1e5 Pa) grains of 5 cm", count=n, material={"young": 1e5},
              radius={"distribution": "constant", "value": 0.025}, container={"kind": "periodic", "size": [0.2, 0.2]}),
        _case("e0.05_mu1", "restitution 0.05, friction 1", count=n, material={"restitution": 0.05, "friction": 1.0}),
        _case("e0.1_mu1", "restitution 0.1, friction 1", count=n, material={"restitution": 0.1, "friction": 1.0}),
        _case("steel_column", f"steel column of {column} grains (r = 1 mm, {column_cell / 2e-3:g} d x "
              f"{column_cell / 2e-3:g} d cell)", count=column, density=7800.0, material=STEEL,
              radius={"distribution": "constant", "value": 1.0e-3},
              container={"kind": "periodic", "size": [column_cell, column_cell]}),
        _case("hele_shaw_w1.1d", "Hele-Shaw cell, gap w = 1.1 d (r = 0.5 mm)", count=n,
              radius={"distribution": "constant", "value": 0.5e-3},
              container={"kind": "hele-shaw", "size": [0.02], "gap": 1.1e-3},
              source={"kind": "region", "x": [-0.009, 0.009], "y": [-0.04e-3, 0.04e-3]}),
        _case("2d", "2D disks, periodic 2 cm", count=n, dimension=2, container={"kind": "periodic", "size": [0.02]}),
    ]


# ---------------------------------------------------------------- predicted static overlap

def predicted_overlap(btr: str, csv, outdir) -> dict:
    """Static overlap / radius of the contact law for a grain on the floor: alone (weight m g) and under its
    column (the packing's weight shared by the grains on the floor), from `btr relax --predict-overlap` (the
    coupling's law and materials, coupling/dem/preload.h; written to OUTDIR/predicted_overlap.json)."""
    pred = btr_cli.predict_overlap(btr, csv, outdir)
    return {"law": pred["law"], "single": float(pred["single_grain"]["mean_relative"]),
            "column": float(pred["under_column"]["mean_relative"]), "floor_grains": int(pred["floor_grains"])}


def relaxed_overlap(relax: dict) -> dict:
    """Largest overlap / smaller radius of the relaxed packing (grain pairs and every wall) and the
    largest grain-floor overlap / that grain's radius, as `btr relax` measured them (relaxed.json,
    coupling/dem/overlap.h): one definition, in C++."""
    return {"largest": float(relax["final_largest_overlap"]), "floor": float(relax["final_largest_floor_overlap"])}


# ---------------------------------------------------------------- one engine run

def _stable_step(stdout: str) -> float | None:
    m = re.search(r"^stable time step (\S+) s", stdout, re.M)
    return float(m.group(1)) if m else None


# The report's reason for each kind of relax_failure.json (coupling/dem/relax.h, FailureKind).
FAILURE_REASONS = {
    "time_limit": "engine hung (wall-time limit)",
    "blow_up": "blow-up (kinetic energy above twice the energy the packing holds)",
    "non_finite": "NaN",
    "lost_grains": "lost grains",
    "outside_container": "grains outside the container",
    "missed_contact": "grains went into each other (a contact the engine missed)",
    "bad_output": "engine error (bad output)",
    "engine_error": "engine error",
}


def classify(failure: dict | None) -> str:
    """The reason of a failed `btr relax` (exit 5), from its relax_failure.json record (btr_cli.failure_record):
    the kind decides; an engine error names the log line the engine failed on, when it had one."""
    if not failure:
        return "engine error"
    kind = failure.get("kind")
    reason = FAILURE_REASONS.get(kind, "engine error")
    line = (failure.get("values") or {}).get("log_line")
    if kind == "engine_error" and line:
        return f"engine error: {line.strip()}"
    return reason


def kinetic_history(outdir) -> np.ndarray:
    path = Path(outdir) / "kinetic.csv"
    if not path.exists():
        return np.zeros((0, 2))
    a = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    return a.reshape(-1, 2)


def relax_once(btr, csv, engine, outdir, max_time, forced=None, time_limit=None, label=None, progress=print,
               preload=False, stop_rule=None) -> dict:
    """One `btr relax`; returns rc, stdout, error, stable step, relax record (on success), kinetic history."""
    extra = ["--max-time", repr(float(max_time))]
    if forced is not None:
        extra += ["--force-timestep", repr(float(forced))]
    if preload:
        extra += ["--preload"]
    if stop_rule:
        extra += ["--stop-rule", stop_rule]
    r = btr_cli.relax(btr, csv, engine, outdir, time_limit=time_limit, progress=progress, label=label or engine,
                      check=False, extra_args=extra)
    out = {"rc": r["returncode"], "wall_seconds": r["wall_seconds"], "error": r["error"] or "",
           "failure": r["failure"], "stable_step": _stable_step(r["stdout"]), "relax": None,
           "kinetic": np.zeros((0, 2))}
    if r["returncode"] == 0:
        out["relax"] = json.loads((Path(outdir) / "relaxed.json").read_text())["relax"]
        out["kinetic"] = kinetic_history(outdir)
    return out


def energy_growth(kinetic: np.ndarray, threshold: float) -> str | None:
    """Kinetic-energy growth in a run that ended normally: the last quarter's mean above 10x the
    quarter before, and above the stop threshold."""
    e = kinetic[:, 1] if len(kinetic) else np.zeros(0)
    if len(e) and not np.all(np.isfinite(e)):
        return "NaN in the kinetic energy"
    if len(e) < 8:
        return None
    q = len(e) // 4
    late, before = float(np.mean(e[-q:])), float(np.mean(e[-2 * q:-q]))
    if late > threshold and before > 0 and late > 10.0 * before:
        return f"kinetic-energy growth: {late:.3g} J in the last quarter vs {before:.3g} J before"
    return None


def _first_line(message: str | None) -> str:
    text = (message or "").strip()
    return text.splitlines()[0].replace("btr relax: ", "") if text else "refused"


def rest_verdict(run: dict, threshold: float) -> tuple[str, str, dict]:
    """(verdict, reason, numbers) of the run at the rule's step."""
    if run["rc"] == 2:
        return "refused", _first_line(run["error"]), {}
    if run["rc"] != 0:
        why = classify(run.get("failure"))
        if (run.get("failure") or {}).get("kind") == "time_limit":  # the wall-time budget, not a blow-up
            return "not at rest", "wall-time limit reached before the stop rule or the time cap", {}
        return "unstable", why, {}
    rx = run["relax"]
    info = {"stop_reason": rx["stop_reason"], "simulated_time": rx["simulated_time"],
            "final_kinetic_ratio": float(rx["final_kinetic_energy"]) / threshold,
            "final_unbalanced_force": rx.get("final_unbalanced_force")}
    grow = energy_growth(run["kinetic"], threshold)
    if grow:
        return "unstable", grow, info
    ov = relaxed_overlap(run["relax"])
    info["overlap"] = ov
    if ov["largest"] > OVERLAP_BOUND:
        return "outside validity", (f"static overlap {ov['largest']:.3g} of the smaller radius > {OVERLAP_BOUND:g}"), info
    return "stable", "", info


def forced_bounded(run: dict, ref_max_kinetic: float, ref_overlap: float) -> tuple[bool, str]:
    """ref_max_kinetic: the larger of the rule-step run's largest kinetic energy and the stop threshold
    (a bed that hardly moves at the rule's step must not make round-off energies count as growth)."""
    if run["rc"] == 2:
        return False, "refused: " + run["error"].splitlines()[0]
    if run["rc"] != 0:
        return False, classify(run.get("failure"))
    e = run["kinetic"][:, 1] if len(run["kinetic"]) else np.zeros(0)
    if len(e) and not np.all(np.isfinite(e)):
        return False, "NaN"
    if len(e) and float(np.max(e)) > GROWTH * max(ref_max_kinetic, 1e-300):
        return False, f"kinetic energy {float(np.max(e)):.3g} J > {GROWTH:g} x the rule-step run's {ref_max_kinetic:.3g} J"
    ov = relaxed_overlap(run["relax"])["largest"]
    if ov > OVERLAP_GROWTH * ref_overlap + 0.01:
        return False, f"overlap {ov:.3g} of the radius > {OVERLAP_GROWTH:g} x the rule-step run's {ref_overlap:.3g} + 0.01"
    return True, ""


# ---------------------------------------------------------------- bisection

def find_edge(probe, iterations: int, max_multiple: float = MAX_MULTIPLE) -> dict:
    """probe(m) -> (bounded, reason). Doubles from 2 up to max_multiple until unbounded, then bisects
    (geometric midpoint) `iterations` times. Returns the largest bounded multiple (lo), the smallest
    unbounded one (hi, None if none up to max_multiple), its reason, and every probe."""
    probes = []

    def run(m):
        ok, why = probe(m)
        probes.append({"multiple": m, "bounded": ok, "reason": why})
        return ok, why

    lo, hi, hi_reason = 1.0, None, ""
    m = 2.0
    while m <= max_multiple:
        ok, why = run(m)
        if not ok:
            hi, hi_reason = m, why
            break
        lo = m
        m *= 2.0
    if hi is not None:
        for _ in range(iterations):
            mid = math.sqrt(lo * hi)
            ok, why = run(mid)
            if ok:
                lo = mid
            else:
                hi, hi_reason = mid, why
    return {"largest_bounded": lo, "smallest_unbounded": hi, "unbounded_reason": hi_reason, "probes": probes}


# ---------------------------------------------------------------- the study

def run_stability(outdir=None, engines=("liggghts", "yade"), tiny: bool = False, full: bool = False, ranks: int = 1,
                  progress=print, cases: list | None = None) -> dict:
    btr = find_btr()
    outdir = (Path(outdir) if outdir else REPO / "out" / "stability").resolve()
    iterations = 1 if tiny else (4 if full else 2)
    window = 1500 if tiny else (8000 if full else 3000)
    time_limit = 60.0 if tiny else 240.0
    rest_limit = 120.0 if tiny else (1800.0 if full else 600.0)
    selected = build_cases(tiny, full) if cases is None else cases
    outdir.mkdir(parents=True, exist_ok=True)
    rec = RunRecord(outdir, "stability", btr=btr, progress=progress,
                    settings={"engines": list(engines), "tiny": tiny, "full": full, "cases": [c["name"] for c in selected],
                              "overlap_bound": OVERLAP_BOUND, "rest_free_fall_times": REST_FREE_FALL_TIMES,
                              "window_rule_steps": window, "bisection_iterations": iterations,
                              "max_multiple": MAX_MULTIPLE, "growth": GROWTH, "start": START,
                              "rest_stop_rule": REST_STOP_RULE})
    rows = []
    # Rows of an earlier run of the same settings into this folder are kept (a restarted sweep goes on).
    earlier = {}
    previous = outdir / "stability.json"
    if previous.exists():
        old = json.loads(previous.read_text())
        if old.get("window_rule_steps") == window and old.get("start") == START and \
                old.get("rest_stop_rule") == REST_STOP_RULE:
            earlier = {(r["case"], r["engine"]): r for r in old.get("rows", [])
                       if r.get("edge") or r.get("verdict") == "refused"}

    def write_tables(rows_so_far):
        res = {"engines": list(engines), "overlap_bound": OVERLAP_BOUND, "window_rule_steps": window,
               "start": START, "rest_stop_rule": REST_STOP_RULE,
               "rest_free_fall_times": REST_FREE_FALL_TIMES, "max_multiple": MAX_MULTIPLE, "rows": rows_so_far,
               "summary": summary(rows_so_far)}
        write_json(outdir / "stability.json", res)
        fig = margin_figure(outdir / "stability.png", rows_so_far, engines)
        atomic_write_text(outdir / "stability.md", markdown(res, os.path.basename(fig)))
        return res

    for case in selected:
        cdir = outdir / "cases" / case["name"]
        built = {}

        def case_input(case=case, cdir=cdir, built=built):
            if not built:
                scene_path = cdir / "scene.toml"
                write_scene_toml(scene_path, case["scene"])
                dep = btr_cli.deposit(btr, str(scene_path), cdir, "btr", progress=progress)
                p = read_packing(dep["csv"])
                sc = p.scene()
                top = float(np.max(p.pos[:, 2] + p.radius))
                # The probes' copy: the same packing whose stop rule never fires (kinetic-energy with a
                # vanishing threshold), so that every probe runs its whole window.
                probe_csv = btr_cli.variant(dep["csv"], cdir / "probe_input", "btr_probe",
                                            lambda sc: sc["relax"].update(stop_rule="kinetic-energy",
                                                                          stop_kinetic_ratio=NEVER_STOP_RATIO))
                built.update(csv=dep["csv"], probe_csv=probe_csv, grains=len(p), top=top,
                             rest_time=REST_FREE_FALL_TIMES * math.sqrt(2.0 * top / dem_params.G),
                             threshold=dem_params.kinetic_threshold(p.radius, p.species, sc,
                                                                    float(sc["relax"]["stop_kinetic_ratio"])),
                             predicted=predicted_overlap(btr, dep["csv"], cdir))
            return built

        for engine in engines:
            if (case["name"], engine) in earlier and earlier[(case["name"], engine)].get("grains") == \
                    case["scene"]["grains"]["count"]:
                rows.append(_reclassified(earlier[(case["name"], engine)], outdir))
                progress(f"   {case['name']} / {engine}: kept from the earlier run in {outdir}")
                continue
            row = {"case": case["name"], "what": case["what"], "engine": engine, "wall_seconds": 0.0}
            with rec.case(f"{case['name']} / {engine}", rows, row, on_row=write_tables):
                c = case_input()
                row.update(grains=c["grains"], rest_time_cap=c["rest_time"], predicted_overlap=c["predicted"])
                edir = cdir / engine
                rest = relax_once(btr, c["csv"], engine, edir / "rest", c["rest_time"], time_limit=rest_limit,
                                  label="rest", progress=progress, preload=START == "preload", stop_rule=REST_STOP_RULE)
                start, preload_refused, wall = START, None, rest["wall_seconds"]
                if START == "preload" and rest["rc"] == 2:
                    # Refused: by the pre-load (e.g. overlaps beyond the intended ones), or by the case itself.
                    # The touching start tells which; if only the pre-load was refused the case runs from it.
                    touching = relax_once(btr, c["csv"], engine, edir / "rest_touching", c["rest_time"],
                                          time_limit=rest_limit, label="rest", progress=progress,
                                          stop_rule=REST_STOP_RULE)
                    wall += touching["wall_seconds"]
                    if touching["rc"] != 2:
                        start, preload_refused = "touching (pre-load refused)", _first_line(rest["error"])
                    rest = touching
                verdict, reason, info = rest_verdict(rest, c["threshold"])
                row.update(verdict=verdict, reason=reason, stable_step=rest["stable_step"], start=start,
                           preload_refused=preload_refused, wall_seconds=wall, **info)
                preload = start == "preload"
                row["status"] = verdict
                if verdict in ("refused",) or rest["stable_step"] is None:
                    continue
                if verdict == "unstable":
                    ref_ke, ref_ov = c["threshold"], 0.0
                elif verdict == "not at rest":  # the reference is the rule's step over the probes' window
                    ref = relax_once(btr, c["probe_csv"], engine, edir / "window_x1", window * rest["stable_step"],
                                     time_limit=time_limit, label="x1", progress=progress, preload=preload)
                    if ref["rc"] != 0:
                        row["reason"] += f"; the rule's step over the window failed too: {classify(ref.get('failure'))}"
                        continue
                    ref_ke = max(float(np.max(ref["kinetic"][:, 1])) if len(ref["kinetic"]) else 0.0, c["threshold"])
                    ref_ov = relaxed_overlap(ref["relax"])["largest"]
                else:
                    ref_ke = max(float(np.max(rest["kinetic"][:, 1])) if len(rest["kinetic"]) else 0.0, c["threshold"])
                    ref_ov = info["overlap"]["largest"]
                dt = rest["stable_step"]

                first_wall = []

                def probe(m, edir=edir, c=c, dt=dt, ref_ke=ref_ke, ref_ov=ref_ov, engine=engine, first_wall=first_wall,
                          preload=preload):
                    # A probe has at most as many steps as the first one; YADE can hang after a blow-up (its
                    # collider), so a probe is killed at 4x the first probe's wall time (at least 20 s).
                    limit = max(20.0, 4.0 * first_wall[0]) if first_wall else time_limit
                    d = edir / f"forced_x{m:.4g}"
                    r = relax_once(btr, c["probe_csv"], engine, d, window * dt, forced=m * dt, time_limit=limit,
                                   label=f"x{m:.4g}", progress=progress, preload=preload)
                    if not first_wall:
                        first_wall.append(r["wall_seconds"])
                    row["wall_seconds"] += r["wall_seconds"]
                    return forced_bounded(r, ref_ke, ref_ov)

                if verdict == "unstable":  # the rule's own step is not bounded: look below it
                    edge = {"largest_bounded": None, "smallest_unbounded": 1.0, "unbounded_reason": reason,
                            "probes": []}
                    m = 0.5
                    while m >= 0.125:
                        ok, why = probe(m)
                        edge["probes"].append({"multiple": m, "bounded": ok, "reason": why})
                        if ok:
                            edge["largest_bounded"] = m
                            break
                        edge["smallest_unbounded"], edge["unbounded_reason"] = m, why
                        m /= 2.0
                else:
                    edge = find_edge(probe, iterations)
                row["edge"] = edge
                row["margin"] = edge["largest_bounded"]
    with rec.step("table and figure") as st:
        res = write_tables(rows)
        st.update(outputs=[str(outdir / "stability.md"), str(outdir / "stability.png")])
    rec.finish({"summary": res["summary"]})
    progress(res["summary"])
    return res


def _reclassified(row: dict, outdir: Path) -> dict:
    """A kept row whose failed probes' reasons are read again from their relax_failure.json with today's
    classify(); a probe without one (run by an older btr) keeps its reason."""
    edge = row.get("edge") or {}
    for pr in edge.get("probes", []):
        if pr["bounded"]:
            continue
        record = btr_cli.failure_record(outdir / "cases" / row["case"] / row["engine"] / f"forced_x{pr['multiple']:.4g}")
        if record is not None:
            pr["reason"] = classify(record)
            if pr["multiple"] == edge.get("smallest_unbounded"):
                edge["unbounded_reason"] = pr["reason"]
    return row


def summary(rows) -> str:
    done = [r for r in rows if r.get("edge")]
    edges = [r for r in done if r["edge"]["smallest_unbounded"] is not None]
    below = [r for r in done if r["margin"] is None or r["margin"] < 1.0]
    text = (f"{len(edges)} of {len(done)} case/engine pairs reached an unbounded step by bisection; "
            f"verdicts at the rule's step: " +
            ", ".join(f"{v} {sum(1 for r in rows if r.get('verdict') == v)}"
                      for v in ("stable", "unstable", "outside validity", "not at rest", "refused")) + ".")
    if done:
        finite = [r["margin"] for r in done if r["margin"] is not None]
        if finite:
            text += f" Smallest margin of the rule: {min(finite):.3g} x its step."
    if below:
        text += " The rule's step is NOT stable for: " + ", ".join(f"{r['case']} / {r['engine']}" for r in below) + "."
    return text


def _margin_text(r) -> str:
    e = r.get("edge")
    if not e:
        return "-"
    lo = "<" + f"{e['smallest_unbounded']:.3g}" if e["largest_bounded"] is None else f"{e['largest_bounded']:.3g}"
    hi = f"{e['smallest_unbounded']:.3g}" if e["smallest_unbounded"] is not None else f"none up to {MAX_MULTIPLE:g}"
    return f"{lo} (unbounded at {hi})"


def margin_figure(path, rows, engines) -> str:
    import matplotlib.pyplot as plt

    cases = []
    for r in rows:
        if r["case"] not in cases:
            cases.append(r["case"])
    fig, ax = plt.subplots(figsize=(max(6.0, 1.1 * len(cases) + 2), 4.2))
    width = 0.8 / max(1, len(engines))
    colours = {"liggghts": "#1f77b4", "yade": "#ff7f0e"}
    for j, engine in enumerate(engines):
        for i, case in enumerate(cases):
            r = next((x for x in rows if x["case"] == case and x["engine"] == engine), None)
            x = i + (j - (len(engines) - 1) / 2) * width
            if r is None or not r.get("edge"):
                label = (r or {}).get("verdict", "")
                ax.text(x, 1.05, label or "-", rotation=90, ha="center", va="bottom", fontsize=7)
                continue
            e = r["edge"]
            lo = e["largest_bounded"] or 0.0
            ax.bar(x, max(lo, 1e-3), width, color=colours.get(engine, "grey"), label=engine if i == 0 else None)
            top = e["smallest_unbounded"]
            if top is not None:
                ax.plot([x - width / 2, x + width / 2], [top, top], color="red", lw=1.5)
            else:
                ax.text(x, lo * 1.05, ">", ha="center", va="bottom", fontsize=8)
    ax.axhline(1.0, color="black", lw=1, ls="--")
    ax.set_yscale("log")
    ax.set_ylim(0.1, MAX_MULTIPLE * 2)
    ax.set_xticks(range(len(cases)))
    ax.set_xticklabels(cases, rotation=30, ha="right", fontsize=8)
    ax.set_ylabel("largest bounded step / rule's step")
    ax.set_title("Stable-step margin (bar: largest bounded; red: first unbounded; dashed: the rule)", fontsize=9)
    handles, labels = ax.get_legend_handles_labels()
    if handles:
        ax.legend(fontsize=8)
    fig.tight_layout()
    return report.save_figure(fig, path)


def markdown(res: dict, fig_name: str) -> str:
    headers = ["case", "engine", "grains", "start", "verdict at the rule's step", "reason", "stop (t [s]; final E / threshold; "
               "unbalanced force)", "largest overlap / r (floor)",
               "predicted static overlap / r (1 grain; column)", "rule step [s]", "margin (largest bounded multiple)",
               "unbounded because", "wall [s]"]
    table, notes = [], []
    for r in res["rows"]:
        start = r.get("start", "-")
        if r.get("preload_refused"):  # the reason goes under the table
            notes.append(f"- {r['case']} / {r['engine']}: pre-load refused: {r['preload_refused']}")
        pred = r.get("predicted_overlap")
        ov = r.get("overlap") or {}
        e = r.get("edge") or {}
        stop = "-"
        if r.get("stop_reason"):
            uf = r.get("final_unbalanced_force")
            stop = (f"{r['stop_reason']} ({r['simulated_time']:.3g}; {r['final_kinetic_ratio']:.3g}; "
                    + (f"{uf:.2g})" if uf is not None else "-)"))
        table.append([r["case"], r["engine"], r.get("grains", "-"), start, r.get("verdict", r["status"]),
                      r["reason"] or "-", stop,
                      f"{ov['largest']:.3g} ({ov['floor']:.3g})" if ov else "-",
                      f"{pred['single']:.3g}; {pred['column']:.3g} ({pred['law']})" if pred else "-",
                      f"{r['stable_step']:.3g}" if r.get("stable_step") else "-", _margin_text(r),
                      e.get("unbounded_reason") or "-", f"{r['wall_seconds']:.1f}"])
    return "\n".join([
        "# Stability sweep: run to rest, and the edge of the time step", "",
        f"Each case runs at the rule's step from a {res.get('start', START)} start to its stop rule "
        f"({res.get('rest_stop_rule', REST_STOP_RULE)}) or {res['rest_free_fall_times']:g} free-fall times of the "
        f"bed. Verdicts: stable; unstable (blow-up, NaN, lost grains, grains outside, energy growth); outside validity "
        f"(static overlap above {res['overlap_bound']:g} of the smaller radius, with the contact law's predicted "
        "static overlap beside it); refused (with the coupling's reason). The edge: forced steps of m x the rule's "
        f"step over {res['window_rule_steps']} rule steps, doubled then bisected; bounded = exit 0, kinetic energy "
        f"at most {GROWTH:g} x the rule-step run's, overlap bounded.", "", "## Summary", "", res["summary"], "",
        "## Cases", "", report.md_table(headers, table), *(["", "Started touching:", *notes, ""] if notes else []),
        f"![stable-step margin]({fig_name})", ""])
