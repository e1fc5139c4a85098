"""hele-shaw on tiny settings (one 3 d cell, 120 grains; LIGGGHTS runs for real, all four methods), a failed
method is a row with its reason, the seed-003 material in SI checked by hand, the Eq. 9 fit on data of known
parameters, and the report's comparison tables on rows of known values."""
import csv
import json
import math
import re
import subprocess
import sys

import numpy as np

from btrdem.studies import hele_shaw
from btrdem.core.runner import StepFailed


def _matrix(script: str, name: str) -> list:
    line = next(x for x in script.splitlines() if re.search(rf"property/global {name} peratomtypepair", x))
    vals = line.split("peratomtypepair")[1].split()
    return [float(v) for v in vals[1:]]


def test_hele_shaw_tiny(tmp_path, source_dir, btr_binary):
    out = tmp_path / "hs"
    p = subprocess.run([sys.executable, str(source_dir / "workflows" / "btr_workflow.py"), "hele-shaw", "--tiny",
                        "-o", str(out)], capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stdout + p.stderr
    rows = list(csv.DictReader(open(out / "hele_shaw.csv")))
    assert [r["method"] for r in rows] == ["dem", "btr", "btr+relax", "btr+ub-relax"]
    for r in rows:
        assert r["status"] == "ok", r
        assert 0 <= float(r["theta_deg"]) < 90 and 0 < float(r["z_mean"]) < 12, r
    theta = {r["method"]: float(r["theta_deg"]) for r in rows}
    assert theta["btr"] > theta["dem"]  # BTR has no inertia: its heap is the steeper one
    assert theta["btr+ub-relax"] < theta["btr"] - 10  # the relaxation lets the 40-degree BTR heap collapse
    # The new method ran with the unbalanced-force rule and reached rest by it (not by the 4 x 0.3 s cap);
    # the stop column is relaxed.json's reason and simulated time.
    stop = {r["method"]: r["stop"] for r in rows}
    for method, folder in (("btr+relax", "relax"), ("btr+ub-relax", "relax_ub")):
        rl = json.loads((out / "cases" / "d1mm_w3" / folder / "relaxed.json").read_text())["relax"]
        assert stop[method] == f"{rl['stop_reason']} at {rl['simulated_time']:.3g} s", (method, stop, rl)
        if method == "btr+ub-relax":
            assert rl["stop_rule"] == "unbalanced-force" and rl["stop_reason"] == "unbalanced-force", rl
            assert rl["stop_value"] < 1e-3 and rl["max_time"] == 4 * 0.3 and rl["simulated_time"] < 1.2, rl
            assert rl["damping"] == 0.0, rl
        else:
            assert rl["stop_rule"] == "kinetic-energy" and rl["max_time"] == 0.3, rl
    assert stop["dem"] in ("kinetic-energy", "max-time") and stop["btr"] == ""
    ub_script = (out / "cases" / "d1mm_w3" / "relax_ub" / "in.btr").read_text()
    assert 'Stop rule "unbalanced-force"' in ub_script
    # Seed 003 Table I for d = 1 mm, rho = 2400, worked out by hand:
    # m = 2400 pi/6 1e-9 = 1.2566371e-6 kg, kn = 2e3 m g / d = 24.65522 N/m, t0 = sqrt(1e-3/9.81) = 0.01009638 s
    kn, t0 = 24.65522, 0.01009638
    case = out / "cases" / "d1mm_w3"
    pour = (case / "dem" / "in.btr").read_text()
    relax = (case / "relax" / "in.btr").read_text()
    for script in (pour, relax, ub_script):
        assert "model hooke/stiffness tangential history" in script
        # types: 1 = grains, 2 = walls
        assert np.allclose(_matrix(script, "kn"), [kn] * 4, rtol=1e-5)
        assert np.allclose(_matrix(script, "kt"), [kn * 2 / 7] * 4, rtol=1e-5)
        assert np.allclose(_matrix(script, "gamman"), [50 / t0] * 4, rtol=1e-5)
        assert np.allclose(_matrix(script, "gammat"), [0, 50 / t0, 50 / t0, 50 / t0], rtol=1e-5)
    step = float(re.search(r"^timestep\s+(\S+)", pour, re.M).group(1))
    assert math.isclose(step, 2e-3 * t0, rel_tol=1e-5)
    run = json.loads((out / "run.json").read_text())
    assert run["status"] == "ok"
    md = (out / "report.md").read_text()
    assert "theta_vs_w.png" in md
    against = [x for x in md.splitlines() if x.startswith("| 1 | 3 | btr")]
    assert [x.split("|")[3].strip() for x in against] == ["btr", "btr+relax", "btr+ub-relax"], against
    d_theta = float(against[2].split("|")[4])
    assert abs(d_theta - (theta["btr+ub-relax"] - theta["dem"])) < 0.051, (against[2], theta)


def test_a_failed_method_is_a_row_with_its_reason(tmp_path, btr_binary, liggghts, monkeypatch):
    """The unbalanced-force relaxation is stopped by a 0.01 s wall-time limit: its row says fail with the
    engine's reason, the rows before it are ok, the report lists it, and the study finishes. Run with seed 2:
    the seed reaches the DEM pour too (it used to pour with seed 1 whatever --seed said)."""
    from btrdem.core import btr_cli

    real_relax = btr_cli.relax

    def relax(*args, **kw):
        if kw.get("label") == "relax-ub":
            kw["time_limit"] = 0.01
        return real_relax(*args, **kw)

    monkeypatch.setattr(btr_cli, "relax", relax)
    monkeypatch.setenv("BTR_BINARY", btr_binary)
    out = tmp_path / "hs"
    res = hele_shaw.run_hele_shaw(out, tiny=True, seed=2, progress=lambda m: None)
    rows = {r["method"]: r for r in res["rows"]}
    assert list(rows) == ["dem", "btr", "btr+relax", "btr+ub-relax"]
    failed = rows["btr+ub-relax"]
    assert failed["status"] == "fail" and "time limit" in failed["reason"], failed
    assert all(rows[m]["status"] == "ok" for m in ("dem", "btr", "btr+relax")), rows
    saved = list(csv.DictReader(open(out / "hele_shaw.csv")))
    assert [r["status"] for r in saved] == ["ok", "ok", "ok", "fail"]
    md = (out / "report.md").read_text()
    assert any(x.startswith("| width | 1 | 3 | 120 | btr+ub-relax |") and "| fail |" in x for x in md.splitlines())
    run = json.loads((out / "run.json").read_text())
    assert run["status"] == "ok"
    assert [s["status"] for s in run["steps"]][-1] == "failed"
    pour = json.loads((out / "cases" / "d1mm_w3" / "dem" / "pour_summary.json").read_text())
    assert pour["seed"] == 2
    assert json.loads((out / "cases" / "d1mm_w3" / "dem" / "pour.json").read_text())["settings"]["seed"] == 2


def test_paper_material_by_hand():
    m = hele_shaw.paper_material(2e-3, 2400.0)
    mass = 2400 * math.pi / 6 * 8e-9  # 1.0053096e-5 kg
    assert math.isclose(m["kn"], 2e3 * mass * 9.81 / 2e-3, rel_tol=1e-12)
    assert math.isclose(m["kn"], 98.62087, rel_tol=1e-6)
    assert math.isclose(m["gamma_n"], 50 / math.sqrt(2e-3 / 9.81), rel_tol=1e-12)
    assert m["gamma_t"] == 0 and m["wall_gamma_t"] == m["gamma_n"]


def test_eq9_fit_recovers_known_parameters():
    w = np.array([1.5, 2, 3, 4, 5, 7, 10])
    theta = 24.0 * (1 - (-0.5) * np.exp(-w / 2.5))
    fit, why = hele_shaw.fit_eq9(w, theta)
    assert fit is not None, why
    assert abs(fit["theta_inf"] - 24.0) < 1e-6 and abs(fit["alpha"] + 0.5) < 1e-6 and abs(fit["l_d"] - 2.5) < 1e-6
    assert fit["determined"]
    # Flat, then falling without levelling off (as measured at w <= 10 d): no plateau to pin theta_inf.
    flat_then_falling = np.array([25.7, 25.5, 25.9, 25.2, 23.0, 20.0])
    fit, why = hele_shaw.fit_eq9([1.5, 2, 3, 5, 7, 10], flat_then_falling)
    assert fit is not None, why
    assert not fit["determined"], fit
    fit, why = hele_shaw.fit_eq9(w[:3], theta[:3])
    assert fit is None and "at least 4" in why
    # Widths to 30 d with a plateau and +-0.3 deg noise (fixed draw): the fit is determined and its 1-sigma
    # errors cover the true values within 3 sigma.
    w = np.array([1.5, 2, 3, 5, 7, 10, 15, 20, 30])
    rng = np.random.default_rng(3)
    theta = 20.0 * (1 - (-0.3) * np.exp(-w / 5.0)) + rng.normal(0, 0.3, len(w))
    fit, why = hele_shaw.fit_eq9(w, theta)
    assert fit is not None and fit["determined"], (fit, why)
    for key, true in (("theta_inf", 20.0), ("alpha", -0.3), ("l_d", 5.0)):
        assert abs(fit[key] - true) < 3 * fit[key + "_err"], (key, fit)
    assert fit["theta_inf_err"] < 1.0


def _row(d, w, method, theta, z, wall):
    return {"stage": "width", "d_mm": d, "w_d": w, "n": 10, "method": method, "theta_deg": theta, "z_mean": z,
            "wall_s": wall, "status": "ok"}


def test_comparison_tables_on_known_rows():
    ok = [_row(1.0, 3, "dem", 25.9, 3.61, 10.0), _row(1.0, 3, "btr", 59.1, 5.00, 0.04),
          _row(1.0, 3, "btr+ub-relax", 25.1, 3.78, 6.2), _row(2.0, 3, "dem", 22.8, 3.61, 8.0),
          _row(2.0, 20, "dem", 19.0, 4.0, 80.0), _row(1.0, 20, "dem", 18.5, 4.0, 90.0)]
    md = hele_shaw._comparisons(ok)
    assert "| 1 | 3 | btr | +33.2 | +1.39 | 0.004 |" in md
    assert "| 1 | 3 | btr+ub-relax | -0.8 | +0.17 | 0.62 |" in md
    assert "| 3 | 25.9 | 22.8 | 3.1 |" in md and "| 20 | 18.5 | 19 | 0.5 |" in md
    fit = {"theta_inf": 20.0, "alpha": -0.5, "l_d": 4.0}
    line = hele_shaw._plateau_check(ok, {"all": (fit, "")})[-1]
    # 20 x 0.5 x e^-5 = 0.0674 deg; the DEM angles at 20 d: 18.5 - 20, 19 - 20
    assert "theta(20 d) - theta_inf = +0.07 deg" in line
    assert "-1.50 (d = 1 mm, w = 20 d)" in line and "-1.00 (d = 2 mm, w = 20 d)" in line


def test_scatter_summary_on_known_angles():
    """Per-width mean and sample standard deviation by hand; the fit takes every pour as a point."""
    w = [1.5, 3, 5, 7, 10, 15, 20, 30]
    truth = [20.0 * (1 - (-0.3) * math.exp(-x / 4.0)) for x in w]
    rows = [{"seed": s, "w_d": x, "theta_deg": t + dt} for x, t in zip(w, truth) for s, dt in ((1, -0.5), (2, 0.5))]
    rows.append({"seed": 3, "w_d": 30, "theta_deg": truth[-1] + 1.5})
    per_width, fits = hele_shaw._scatter_summary(rows)
    assert [p["w_d"] for p in per_width] == w
    p30 = per_width[-1]
    assert p30["theta"] == [truth[-1] - 0.5, truth[-1] + 0.5, truth[-1] + 1.5]
    assert math.isclose(p30["mean"], truth[-1] + 0.5, rel_tol=1e-12) and math.isclose(p30["std"], 1.0, rel_tol=1e-12)
    assert math.isclose(per_width[0]["std"], math.sqrt(0.5), rel_tol=1e-12)  # -0.5 and +0.5 about the mean
    fit, _ = fits["all widths"]
    assert fit["points"] == 17 and fit["determined"]
    assert abs(fit["theta_inf"] - 20.0) < 1.0 and abs(fit["l_d"] - 4.0) < 1.5, fit
    assert fits["w >= 5 d"][0]["points"] == 13


def test_dem_scatter_records_a_failed_pour_and_finishes(tmp_path, btr_binary, monkeypatch):
    """A pour that fails is a row with its reason; the other pours run, and the tables are written with them."""
    monkeypatch.setenv("BTR_BINARY", btr_binary)
    angle = {1.5: 26.0, 3: 25.0, 5: 24.0, 7: 22.0, 10: 20.0}

    def fake_case(btr, case_dir, scene, methods, pace, progress):
        w = float(case_dir.name[1:])
        if w == 7:
            def fail():
                raise StepFailed("pour w7: LIGGGHTS exited with status 1")
            return {"dem": fail}
        return {"dem": lambda: (str(w), 1.0, "max-time")}

    monkeypatch.setattr(hele_shaw, "_run_case", fake_case)
    monkeypatch.setattr(hele_shaw, "_measure", lambda csv_path: {"theta": angle[float(csv_path)], "z_mean": 4.0,
                                                               "heap_note": "", "profile": None})
    rows, per_width, _ = hele_shaw.dem_scatter(tmp_path / "sc", [2], [1.5, 3, 5, 7, 10], progress=lambda m: None)
    assert [r["status"] for r in rows] == ["ok", "ok", "ok", "fail", "ok"]
    assert "LIGGGHTS exited with status 1" in rows[3]["reason"]
    assert [p["w_d"] for p in per_width] == [1.5, 3, 5, 10]  # the failed pour is not averaged
    saved = list(csv.DictReader(open(tmp_path / "sc" / "dem_scatter.csv")))
    assert [r["status"] for r in saved] == ["ok", "ok", "ok", "fail", "ok"]
    assert "Failed pours: seed 2 w = 7 d" in (tmp_path / "sc" / "dem_scatter.md").read_text()
    assert json.loads((tmp_path / "sc" / "run.json").read_text())["summary"]["failed"] == 1
