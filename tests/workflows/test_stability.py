"""The stability sweep at tiny size, with the real engines: every verdict (stable, unstable, outside
validity, refused, not at rest), a forced step that blows up in each engine, the hidden --force-timestep,
the pre-loaded start and its fallback, the bisection and the predicted static overlap against closed forms."""
import json
import math
import subprocess
import sys

import numpy as np
import pytest

from btrdem.core import btr_cli
from btrdem.studies import stability as st
from btrdem.core.io import read_packing, write_scene_toml


def tiny_case(tmp_path, btr_binary, name, **kw):
    """A tiny case's BTR packing (the sweep's own scene builder, 12 grains)."""
    case = next(c for c in st.build_cases(tiny=True) if c["name"] == name)
    sc = case["scene"]
    for k, v in kw.items():
        sc["material"][k] = v
    path = tmp_path / f"{name}.toml"
    write_scene_toml(path, sc)
    out = tmp_path / name
    subprocess.run([btr_binary, "deposit", str(path), "-o", str(out), "--name", "btr", "-q"], check=True)
    return str(out / "btr.csv")


def rest(btr_binary, csv, engine, out, max_time=0.05, preload=True, time_limit=120):
    """A rest run as the sweep makes it: pre-loaded start, its stop rule."""
    run = st.relax_once(btr_binary, csv, engine, out, max_time, time_limit=time_limit, progress=lambda m: None,
                        preload=preload, stop_rule=st.REST_STOP_RULE)
    return run, st.rest_verdict(run, 1e-12)


def test_force_timestep_is_hidden_forced_and_recorded(tmp_path, btr_binary, liggghts):
    help_text = subprocess.run([btr_binary, "relax", "--help"], capture_output=True, text=True).stdout
    assert "--timestep" in help_text and "--force-timestep" not in help_text
    csv = tiny_case(tmp_path, btr_binary, "base")
    run, (verdict, reason, _) = rest(btr_binary, csv, "liggghts", tmp_path / "rule", max_time=0.02, preload=False)
    assert verdict == "stable", reason
    dt = run["stable_step"]
    assert run["relax"]["timestep_forced"] is False and run["relax"]["timestep"] == pytest.approx(dt, rel=1e-5)
    # a requested step above the stable one is refused ...
    p = subprocess.run([btr_binary, "relax", csv, "-o", str(tmp_path / "req"), "--engine", "liggghts",
                        "--timestep", repr(1.5 * dt)], capture_output=True, text=True)
    assert p.returncode == 2 and "above the stable step" in p.stderr
    # ... the same step forced runs, and the run says it was forced
    forced = st.relax_once(btr_binary, csv, "liggghts", tmp_path / "forced", 0.02, forced=1.5 * dt,
                           progress=lambda m: None)
    assert forced["rc"] == 0, forced["error"]
    assert forced["relax"]["timestep_forced"] is True
    assert forced["relax"]["timestep"] == pytest.approx(1.5 * dt, rel=1e-12)
    assert forced["relax"]["stable_timestep"] == pytest.approx(dt, rel=1e-5)
    assert "FORCED" in forced["relax"]["timestep_rule"]
    # and both flags at once are a usage error
    p = subprocess.run([btr_binary, "relax", csv, "-o", str(tmp_path / "both"), "--timestep", repr(dt),
                        "--force-timestep", repr(dt)], capture_output=True, text=True)
    assert p.returncode != 0 and not (tmp_path / "both" / "relaxed.csv").exists()


@pytest.mark.parametrize("engine", ["liggghts", "yade"])
def test_forced_step_blows_up_and_rule_step_is_stable(tmp_path, btr_binary, liggghts, yade, engine):
    csv = tiny_case(tmp_path, btr_binary, "base")
    run, (verdict, reason, info) = rest(btr_binary, csv, engine, tmp_path / "rule")
    assert verdict == "stable", reason
    assert info["overlap"]["largest"] < st.OVERLAP_BOUND
    # the pre-loaded start was used, and the overlaps are relaxed.json's, which agree with the packing
    assert (tmp_path / "rule" / "preloaded.csv").exists()
    p = read_packing(str(tmp_path / "rule" / "relaxed.csv"))
    floor = float(np.max((p.radius - p.pos[:, 2]) / p.radius))
    assert floor > 0 and info["overlap"]["floor"] == pytest.approx(floor, rel=1e-6)
    assert info["overlap"]["floor"] <= info["overlap"]["largest"]
    dt = run["stable_step"]
    out = tmp_path / "x20"
    forced = st.relax_once(btr_binary, csv, engine, out, 1500 * dt, forced=20 * dt, time_limit=120,
                           progress=lambda m: None)
    assert forced["rc"] == 5, forced
    # the failure's kind comes from relax_failure.json, written by btr relax where the failure was detected
    assert forced["failure"] is not None and forced["failure"]["engine"] == engine, forced
    assert forced["failure"]["kind"] in ("blow_up", "lost_grains", "non_finite", "outside_container",
                                         "missed_contact"), forced["failure"]
    why = st.classify(forced["failure"])
    assert why == st.FAILURE_REASONS[forced["failure"]["kind"]]
    ok, why2 = st.forced_bounded(forced, 1e-9, 0.01)
    assert not ok and why2 == why
    # the verdict of a run that blew up at its own step is "unstable"
    assert st.rest_verdict(forced, 1e-12)[0] == "unstable"


def test_soft_large_grains_are_outside_validity_with_the_hertz_overlap(tmp_path, btr_binary, liggghts):
    csv = tiny_case(tmp_path, btr_binary, "soft_large")
    pred = st.predicted_overlap(btr_binary, csv, tmp_path / "predicted")
    assert pred["law"] == "hertz" and pred["floor_grains"] >= 1
    # hand value: one 5 cm grain (rho 2500, E 1e5, nu 0.3) on a wall of the same material
    r, e_star = 0.025, 1e5 / (2 * (1 - 0.3 ** 2))
    m = 2500 * 4 / 3 * math.pi * r ** 3
    assert pred["single"] == pytest.approx((3 * m * 9.81 / (4 * e_star * math.sqrt(r))) ** (2 / 3) / r, rel=1e-9)
    assert pred["column"] >= pred["single"]
    # the pre-load is refused: at a quarter of a radius the law's overlaps push grains into their neighbours
    pre, (verdict, reason, _) = rest(btr_binary, csv, "liggghts", tmp_path / "pre", max_time=1.0)
    assert verdict == "refused" and "pre-loaded packing" in reason, reason
    run, (verdict, reason, info) = rest(btr_binary, csv, "liggghts", tmp_path / "rule", max_time=1.0, preload=False)
    assert verdict == "outside validity", reason
    measured = info["overlap"]["largest"]
    assert measured > st.OVERLAP_BOUND
    # the engine's static overlap is the law's, between one grain's weight and the column load
    assert 0.8 * pred["single"] < measured < 1.2 * pred["column"]


def test_predicted_overlap_of_one_grain_on_the_floor_is_hertz_by_hand(tmp_path, btr_binary):
    # one grain of the base case (rho 2500, E = 5e6 Pa, nu = 0.3) rained onto the floor; no engine runs
    case = next(c for c in st.build_cases(tiny=True) if c["name"] == "base")
    case["scene"]["grains"]["count"] = 1
    write_scene_toml(tmp_path / "one.toml", case["scene"])
    subprocess.run([btr_binary, "deposit", str(tmp_path / "one.toml"), "-o", str(tmp_path / "one"), "--name", "btr",
                    "-q"], check=True)
    p = read_packing(str(tmp_path / "one" / "btr.csv"))
    r = float(p.radius[0])
    assert p.pos[0, 2] == pytest.approx(r, rel=1e-12)
    e_star = 1.0 / (2.0 * (1.0 - 0.3 ** 2) / 5e6)  # grain and floor of the same material
    m = 2500.0 * 4.0 / 3.0 * math.pi * r ** 3
    delta = (3.0 * m * 9.81 / (4.0 * e_star * math.sqrt(r))) ** (2.0 / 3.0)
    pred = st.predicted_overlap(btr_binary, tmp_path / "one" / "btr.csv", tmp_path / "pred")
    assert pred == {"law": "hertz", "single": pytest.approx(delta / r, rel=1e-12),
                    "column": pytest.approx(delta / r, rel=1e-12), "floor_grains": 1}
    record = json.loads((tmp_path / "pred" / btr_cli.PREDICTED_OVERLAP_FILE).read_text())
    assert record["single_grain"]["mean_overlap"] == pytest.approx(delta, rel=1e-12)
    assert record["wall_material"] == {"species": 1, "young": 5e6, "poisson": 0.3}
    assert not any(f.name.startswith(("in.", "relax_yade", "log.")) for f in (tmp_path / "pred").iterdir())


def test_liggghts_refuses_restitution_near_zero(tmp_path, btr_binary, liggghts):
    csv = tiny_case(tmp_path, btr_binary, "e0.05_mu1")
    run, (verdict, reason, _) = rest(btr_binary, csv, "liggghts", tmp_path / "rule")
    assert verdict == "refused" and "restitution" in reason, reason


def test_rest_run_out_of_its_wall_time_is_not_at_rest(tmp_path, btr_binary, liggghts):
    # a steel bed whose stop rule cannot fire (the probes' copy), 1 s simulated at ~1e-7 s per step, and a
    # wall-time budget of 1 s: the engine is killed before the cap, a cost verdict, not "unstable"
    csv = tiny_case(tmp_path, btr_binary, "steel")
    never = btr_cli.variant(csv, tmp_path / "never", "btr", lambda sc: sc["relax"].update(
        stop_rule="kinetic-energy", stop_kinetic_ratio=st.NEVER_STOP_RATIO))
    run, (verdict, reason, _) = rest(btr_binary, never, "liggghts", tmp_path / "rule", max_time=1.0, time_limit=1.0)
    assert run["rc"] == 5 and run["failure"]["kind"] == "time_limit", run["error"]
    assert run["failure"]["values"]["time_limit"] == 1.0
    assert verdict == "not at rest", reason


def test_find_edge_brackets_a_known_edge():
    calls = []

    def probe(m):
        calls.append(m)
        return (m < 5.3, "" if m < 5.3 else "blow-up")

    e = st.find_edge(probe, iterations=3)
    assert e["largest_bounded"] < 5.3 <= e["smallest_unbounded"]
    assert e["smallest_unbounded"] / e["largest_bounded"] == pytest.approx(2 ** (1 / 8), rel=1e-9)
    assert calls[:3] == [2.0, 4.0, 8.0] and len(calls) == 6 and e["unbounded_reason"] == "blow-up"
    never = st.find_edge(lambda m: (True, ""), iterations=3)
    assert never["smallest_unbounded"] is None and never["largest_bounded"] == st.MAX_MULTIPLE


def test_energy_growth_is_detected():
    t = np.arange(40.0)
    assert st.energy_growth(np.c_[t, np.exp(-t / 5)], 1e-12) is None
    assert "growth" in st.energy_growth(np.c_[t, 1e-9 * np.exp(t / 3)], 1e-12)
    assert "NaN" in st.energy_growth(np.c_[t, np.where(t > 30, np.nan, 1.0)], 1e-12)


def test_stability_workflow_tiny(tmp_path, source_dir, btr_binary, liggghts, yade):
    out = tmp_path / "stab"
    p = subprocess.run([sys.executable, str(source_dir / "workflows" / "btr_workflow.py"), "stability", "--tiny",
                        "--cases", "base,e0.05_mu1", "-o", str(out)], capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stdout + p.stderr
    res = json.loads((out / "stability.json").read_text())
    rows = {(r["case"], r["engine"]): r for r in res["rows"]}
    assert set(rows) == {(c, e) for c in ("base", "e0.05_mu1") for e in ("liggghts", "yade")}
    assert rows[("e0.05_mu1", "liggghts")]["verdict"] == "refused"
    for key in [("base", "liggghts"), ("base", "yade")]:
        r = rows[key]
        assert r["verdict"] == "stable", r
        e = r["edge"]  # the bisection found a real edge above the rule's step
        assert e["smallest_unbounded"] is not None and 1.0 <= e["largest_bounded"] < e["smallest_unbounded"]
        assert all(pr["bounded"] == (pr["multiple"] <= e["largest_bounded"]) for pr in e["probes"])
    md = (out / "stability.md").read_text()
    assert md.count("\n| base |") == 2 and "restitution" in md
    assert (out / "stability.png").read_bytes()[:4] == b"\x89PNG"
    assert {rows[("base", e)]["start"] for e in ("liggghts", "yade")} == {"preload"}
    run_json = json.loads((out / "run.json").read_text())
    assert run_json["status"] == "ok"


def test_stability_workflow_falls_back_to_the_touching_start(tmp_path, source_dir, btr_binary, liggghts):
    out = tmp_path / "soft"
    p = subprocess.run([sys.executable, str(source_dir / "workflows" / "btr_workflow.py"), "stability", "--tiny",
                        "--cases", "soft_large", "--engines", "liggghts", "-o", str(out)],
                       capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stdout + p.stderr
    (row,) = json.loads((out / "stability.json").read_text())["rows"]
    assert row["start"] == "touching (pre-load refused)" and "pre-loaded packing" in row["preload_refused"], row
    assert row["verdict"] == "outside validity" and row["edge"]["probes"], row
    # the probes started from the touching packing too (no pre-loaded copy beside them)
    probe_dirs = list((out / "cases" / "soft_large" / "liggghts").glob("forced_x*"))
    assert probe_dirs and not any((d / "preloaded.csv").exists() for d in probe_dirs)


def _failed_run(tmp_path, name, kind, message, values=None):
    """A failed run's folder with a relax_failure.json made by hand, and the run as relax_once returns it."""
    out = tmp_path / name
    out.mkdir()
    (out / btr_cli.FAILURE_FILE).write_text(json.dumps(
        {"kind": kind, "engine": "liggghts", "message": message, "values": values or {}, "log": "log.liggghts"}))
    return out, {"rc": 5, "error": "btr relax: " + message, "failure": btr_cli.failure_record(out)}


def test_classification_follows_the_failure_file_not_the_message(tmp_path):
    # messages that the old text matching would have misread: the kind in the file decides
    out, hung = _failed_run(tmp_path, "hung", "time_limit", "the kinetic energy blew up and grains were lost",
                            {"time_limit": 240.0, "wall_seconds": 240.02})
    assert btr_cli.failure_record(out)["values"]["time_limit"] == 240.0
    assert st.rest_verdict(hung, 1e-12)[0] == "not at rest"
    _, blown = _failed_run(tmp_path, "blown", "blow_up", "lost: killed after NaN",
                           {"kinetic_energy": 3.0, "bound": 1e-3, "time": 0.01})
    assert st.rest_verdict(blown, 1e-12) == ("unstable", st.FAILURE_REASONS["blow_up"], {})
    assert st.classify(blown["failure"]).startswith("blow-up")
    assert st.forced_bounded(blown, 1.0, 0.01) == (False, st.FAILURE_REASONS["blow_up"])
    for kind in ("lost_grains", "non_finite", "outside_container", "missed_contact", "bad_output"):
        _, run = _failed_run(tmp_path, kind, kind, "engine error: ERROR: nothing to see")
        assert st.classify(run["failure"]) == st.FAILURE_REASONS[kind]
    _, err = _failed_run(tmp_path, "err", "engine_error", "exit status 1", {"log_line": "ERROR: Unknown pair style"})
    assert st.classify(err["failure"]) == "engine error: ERROR: Unknown pair style"
    # no file (a run that did not fail, or an older btr): nothing to read, the reason is the generic one
    assert btr_cli.failure_record(tmp_path / "nowhere") is None
    assert st.classify(None) == "engine error"


def test_kept_rows_are_reclassified_from_their_failure_files(tmp_path):
    probes = tmp_path / "cases" / "base" / "liggghts"
    probes.mkdir(parents=True)
    (probes / "forced_x4").mkdir()
    (probes / "forced_x4" / btr_cli.FAILURE_FILE).write_text(json.dumps(
        {"kind": "lost_grains", "engine": "liggghts", "message": "blew up", "values": {}}))
    row = {"case": "base", "engine": "liggghts",
           "edge": {"largest_bounded": 2.0, "smallest_unbounded": 4.0, "unbounded_reason": "engine error",
                    "probes": [{"multiple": 2.0, "bounded": True, "reason": ""},
                               {"multiple": 4.0, "bounded": False, "reason": "engine error"},
                               {"multiple": 8.0, "bounded": False, "reason": "kinetic energy 3 J > 10 x ..."}]}}
    st._reclassified(row, tmp_path)
    e = row["edge"]
    assert e["probes"][1]["reason"] == "lost grains" and e["unbounded_reason"] == "lost grains"
    # a probe without a failure file (bounded by energy, or an older btr) keeps its reason
    assert e["probes"][0]["reason"] == "" and e["probes"][2]["reason"] == "kinetic energy 3 J > 10 x ..."
