"""settle-matrix (workflows/btrdem/studies/settle_matrix.py): the row scenes, the verdict arithmetic, a refused
settle as a failed row, and the settle method of error-vs-runtime. No engine runs: the pours and `btr settle` are
replaced by BTR deposits of other seeds (cheap packings with real measures) where the flow needs them."""
import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from btrdem.analysis import measures
from btrdem.core import btr_cli
from btrdem.studies import error_runtime, settle_matrix, settle_report, settle_rows
from scenes import tiny_bed_toml


def test_constant_mass_mean_cube_matches_sampling():
    # R = ab / (b - u (b - a)), u uniform: the closed form ab (a + b) / 2 against 200 000 draws
    a, b = 0.5e-3, 1.0e-3
    u = np.random.default_rng(5).random(200_000)
    sampled = np.mean((a * b / (b - u * (b - a))) ** 3)
    assert settle_rows.mean_cube_radius({"distribution": "constant-mass", "min": a, "max": b}) == \
        pytest.approx(sampled, rel=5e-3)
    assert settle_rows.mean_cube_radius({"distribution": "constant-mass", "min": a, "max": b}) == \
        pytest.approx(0.375e-9, rel=1e-12)


def test_bed_sizes_by_hand(tmp_path):
    # monodisperse r = 0.75 mm: 3000 x 4/3 pi r^3 = 5.3014e-6 m^3; / (0.6 x 0.03 m) = 2.9452e-4 m^2; side 17.16 mm
    ratio1 = settle_rows.row_scene(next(r for r in settle_rows.ROWS if r["name"] == "bed_ratio1"), 3000, 0.03)
    assert ratio1["container"]["kind"] == "periodic"
    assert ratio1["container"]["size"] == pytest.approx([0.017162, 0.017162], rel=2e-4)
    # ratio 2, 0.5-1 mm: E[R^3] = 0.375 mm^3, 3000 grains -> 4.7124e-6 m^3 -> 2.618e-4 m^2: side 16.18 mm;
    # the cylinder has the same floor area: radius 16.18 mm / sqrt(pi) = 9.129 mm
    base = settle_rows.row_scene(next(r for r in settle_rows.ROWS if r["name"] == "bed_mu0.5"), 3000, 0.03)
    assert base["container"]["size"][0] == pytest.approx(0.016180, rel=2e-4)
    cyl = settle_rows.row_scene(next(r for r in settle_rows.ROWS if r["name"] == "cylinder_ratio2"), 3000, 0.03)
    assert cyl["container"] == {"kind": "cylinder", "radius": pytest.approx(0.009129, rel=2e-4)}
    # bed3d itself: 10 000 grains in 3 cm x 3 cm are 2.9 cm deep at 0.6
    assert 10000 * 4 / 3 * math.pi * 0.375e-9 / (0.6 * 0.03 ** 2) == pytest.approx(0.0291, rel=2e-3)
    # Hele-Shaw 5 d (d = 1 mm): gap 5 mm, pouring box across the gap less a radius on each side
    hs = settle_rows.row_scene(next(r for r in settle_rows.ROWS if r["name"] == "heap_hele_shaw_5d"), 500, 0.03)
    assert hs["container"]["gap"] == pytest.approx(5e-3)
    assert hs["source"]["y"] == pytest.approx([-2e-3, 2e-3])
    # its Hertz twin differs in the contact model alone
    hz = settle_rows.row_scene(next(r for r in settle_rows.ROWS if r["name"] == "heap_hele_shaw_5d_hertz"), 500, 0.03)
    assert hs["relax"]["model"] == "hooke" and hz["relax"]["model"] == "hertz"
    assert {k: v for k, v in hz.items() if k not in ("relax", "scene")} == \
        {k: v for k, v in hs.items() if k not in ("relax", "scene")}
    friction = {r["name"]: settle_rows.row_scene(r, 100, 0.01)["material"] for r in settle_rows.ROWS if r["kind"] == "bed"}
    assert [friction[f"bed_mu{m}"]["friction"] for m in ("0.1", "0.3", "0.5", "0.8")] == [0.1, 0.3, 0.5, 0.8]
    assert friction["bed_mu0.5_rolling0.1"]["rolling_friction"] == 0.1
    assert friction["bed_mu0.1"]["rolling_friction"] == 0.0


def test_row_scenes_deposit_and_fill_the_requested_depth(tmp_path, btr_binary):
    rows = settle_rows.matrix_rows(yade_count=1000)  # the default counts; each scene deposits 10 grains here
    for row in rows:
        scene = settle_rows.write_row_scene(tmp_path / "scenes", row, row["count"], 0.03)
        dep = btr_cli.deposit(btr_binary, scene, tmp_path / row["name"], "d", count=10, progress=lambda m: None)
        assert json.loads(Path(dep["csv"]).with_suffix(".json").read_text())["scene"]["name"] == row["name"]
    # a real bed: 600 grains sized for 8 mm deep; BTR's bed (packing fraction about 0.55-0.6) is about that deep
    row = next(r for r in rows if r["name"] == "bed_mu0.5")
    scene = settle_rows.write_row_scene(tmp_path / "scenes", row, 600, 0.008)
    dep = btr_cli.deposit(btr_binary, scene, tmp_path / "deep", "d", progress=lambda m: None)
    z = np.loadtxt(dep["csv"], delimiter=",", skiprows=1, usecols=3)
    assert 0.8 * 0.008 < np.percentile(z, 97) < 1.3 * 0.008


def test_judge_and_cost_ratio_by_hand():
    floor = {"packing_fraction": 0.003, "coordination": 0.1, "segregation": 0.0}
    # threshold 2 x 0.003 x sqrt(4/3) = 0.0069282
    j = settle_report.judge({"packing_fraction": 0.006, "coordination": 0.25, "segregation": 0.01}, floor, 3)
    assert j["packing_fraction"] == {"error": 0.006, "error_over_floor": pytest.approx(2.0), "within": True}
    assert j["coordination"]["error_over_floor"] == pytest.approx(2.5) and j["coordination"]["within"] is False
    assert j["segregation"]["error_over_floor"] is None and j["segregation"]["within"] is False
    assert settle_report.judge({"packing_fraction": 0.00693}, floor, 3)["packing_fraction"]["within"] is False
    assert settle_report.threshold_in_floors(3) == pytest.approx(2.3094, rel=1e-4)
    assert settle_report.cost_ratio(30.0, [50.0, 100.0, 150.0]) == pytest.approx(0.3)
    assert settle_report.cost_ratio(30.0, [50.0, None, 150.0]) is None
    assert settle_report.cost_ratio(None, [50.0]) is None


def fake_settle_command(btr, record, calls=None, failing_seed=None):
    """run_command for `btr settle`: a heap scene is refused (exit 2, reason on stderr), and so is failing_seed (exit
    5); a bed at --seed S gets a BTR deposit of seed 8 + S as its settled packing OUTDIR/NAME.csv and settle.json =
    record (with the scene's name and seed). Other commands run for real. calls, a list, gets each settled scene's
    name (with "@S" for a seed other than 1)."""
    real = btr_cli.run_command

    def run(argv, cwd, label, **kw):
        if argv[1] != "settle":
            return real(argv, cwd, label, **kw)
        seed = int(argv[argv.index("--seed") + 1]) if "--seed" in argv else 1
        if calls is not None:
            calls.append(Path(argv[2]).stem + ("" if seed == 1 else f"@{seed}"))
        scene = argv[2]
        err = Path(cwd) / f"{label}.stderr"
        out = Path(cwd) / f"{label}.stdout"
        out.write_text("")
        name = settle_rows.read_scene_toml(scene)["scene"]["name"]
        if "heap" in name:
            err.write_text(f"{scene}: btr settle: a point source on an open floor (a heap) is refused for now\n")
            return {"returncode": 2, "wall_seconds": 0.01, "cpu_seconds": 0.01, "stdout": str(out), "stderr": str(err)}
        if seed == failing_seed:
            err.write_text("btr settle: the engine failed (relax_failure.json)\n")
            return {"returncode": 5, "wall_seconds": 0.01, "cpu_seconds": 0.01, "stdout": str(out), "stderr": str(err)}
        btr_cli.deposit(btr, scene, cwd, name, seed=8 + seed, progress=lambda m: None)
        (Path(cwd) / "settle.json").write_text(json.dumps(dict(record, scene_name=name, engine="liggghts", seed=seed)))
        err.write_text("")
        return {"returncode": 0, "wall_seconds": 0.5, "cpu_seconds": 0.4, "stdout": str(out), "stderr": str(err)}
    return run


def test_refused_heap_is_a_failed_row_and_the_bed_is_judged(tmp_path, btr_binary, monkeypatch):
    monkeypatch.setenv("BTR_BINARY", btr_binary)
    record = {"cpu_seconds": 3.0, "wall_seconds": 4.0, "steps": [{"step": "deposit", "cpu_seconds": 0.1,
                                                                   "wall_seconds": 0.1}],
              "chosen": {"target_phi": {"value": 0.6, "from": "calibration"}}}
    settle_calls = []
    monkeypatch.setattr(btr_cli, "run_command", fake_settle_command(btr_binary, record, settle_calls))
    poured = []

    def fake_pour(scene, folder, seed, engine, ranks, reuse, progress):
        poured.append((Path(scene).stem, seed))
        if Path(scene).stem == "bed_mu0.1" and seed == 2:
            raise btr_cli.StepFailed("pour-seed2: btr pour exited with status 5: the engine failed")
        dep = btr_cli.deposit(btr_binary, scene, folder, "poured", seed=seed, progress=progress)
        return {"packing": dep["csv"], "record_cpu_seconds": 10.0 * seed, "wall_seconds": 1.0,
                "stop_reason": "kinetic-energy"}
    monkeypatch.setattr(settle_matrix, "reference_pour", fake_pour)
    out = tmp_path / "matrix"
    res = settle_matrix.run_settle_matrix(out, count=400, depth=0.006, heap_count=50, margin=1.0,
                                          only=["heap_open_floor", "bed_mu0.5", "bed_mu0.1"], progress=lambda m: None)
    bed, failed, heap = res["rows"]  # in the matrix's order: bed_mu0.5, bed_mu0.1, then heaps
    assert failed["row"] == "bed_mu0.1" and failed["status"] == "fail" and "status 5" in failed["reason"]
    assert heap["row"] == "heap_open_floor" and heap["status"] == "fail"
    assert "btr settle exited with status 2" in heap["reason"] and "open floor (a heap) is refused" in heap["reason"]
    assert ("heap_open_floor", 1) not in poured and [s for n, s in poured if n == "bed_mu0.5"] == [1, 2, 3]
    assert bed["status"] == "ok", bed["reason"]
    # the error / floor of packing fraction and coordination, from the packings' own measures
    refs = [measures.measure(out / "runs" / "bed_mu0.5" / f"pour_seed{s}" / "poured.csv", 1.0) for s in (1, 2, 3)]
    settled = measures.measure(out / "runs" / "bed_mu0.5" / "settle" / "bed_mu0.5.csv", 1.0)
    for key, get in (("packing_fraction", measures.packing_fraction), ("coordination", measures.coordination)):
        vals = [get(m) for m in refs]
        want = abs(get(settled) - np.mean(vals)) / np.std(vals, ddof=1)
        assert bed["settle"]["judged"][key]["error_over_floor"] == pytest.approx(want, rel=1e-9)
        assert bed["settle"]["judged"][key]["within"] == (want <= 2 * math.sqrt(4 / 3))
    assert bed["settle"]["cost_ratio"] == pytest.approx(3.0 / 20.0)  # settle.json's 3 s over the pours' mean 20 s
    assert bed["settle"]["target_phi"] == {"value": 0.6, "from": "calibration"}
    report = (out / "report.md").read_text()
    assert "| heap_open_floor |" in report and "status 2" in report and "| bed_mu0.1 |" in report
    assert (out / "settle_matrix.png").stat().st_size > 0
    assert json.loads((out / "run.json").read_text())["status"] == "ok"
    # again with reuse: bed_mu0.5's finished settle is taken as it is (no new run), the refused heap runs again
    assert settle_calls == ["bed_mu0.5", "heap_open_floor"]
    again = settle_matrix.run_settle_matrix(out, count=400, depth=0.006, heap_count=50, margin=1.0,
                                            only=["heap_open_floor", "bed_mu0.5"], progress=lambda m: None,
                                            reuse_settles=True)
    assert settle_calls == ["bed_mu0.5", "heap_open_floor", "heap_open_floor"]
    assert again["rows"][0]["settle"]["reused"] is True
    assert again["rows"][0]["settle"]["judged"] == bed["settle"]["judged"]
    # another btr program (one more byte: another SHA-256) settles again
    other = tmp_path / "btr_other"
    other.write_bytes(Path(btr_binary).read_bytes() + b"\0")
    other.chmod(0o755)
    monkeypatch.setenv("BTR_BINARY", str(other))
    settle_matrix.run_settle_matrix(out, count=400, depth=0.006, margin=1.0, only=["bed_mu0.5"],
                                    progress=lambda m: None, reuse_settles=True)
    assert settle_calls == ["bed_mu0.5", "heap_open_floor", "heap_open_floor", "bed_mu0.5"]


def test_settle_seeds_give_each_seeds_verdict_and_their_spread(tmp_path, btr_binary, monkeypatch):
    monkeypatch.setenv("BTR_BINARY", btr_binary)
    record = {"cpu_seconds": 3.0, "wall_seconds": 4.0, "steps": [], "chosen": {"target_phi": {"value": 0.6}}}
    calls = []
    monkeypatch.setattr(btr_cli, "run_command", fake_settle_command(btr_binary, record, calls, failing_seed=4))

    def fake_pour(scene, folder, seed, engine, ranks, reuse, progress):
        dep = btr_cli.deposit(btr_binary, scene, folder, "poured", seed=seed, progress=progress)
        return {"packing": dep["csv"], "record_cpu_seconds": 10.0, "wall_seconds": 1.0,
                "stop_reason": "kinetic-energy"}
    monkeypatch.setattr(settle_matrix, "reference_pour", fake_pour)
    out = tmp_path / "matrix"
    res = settle_matrix.run_settle_matrix(out, count=400, depth=0.006, margin=1.0, only=["bed_mu0.5"],
                                          progress=lambda m: None, settle_seeds=4)
    row = res["rows"][0]
    assert row["status"] == "ok", row["reason"]
    assert calls == ["bed_mu0.5", "bed_mu0.5@2", "bed_mu0.5@3", "bed_mu0.5@4"]
    entries = row["settle_seeds"]["entries"]
    assert [e["seed"] for e in entries] == [1, 2, 3, 4]
    assert [e["status"] for e in entries] == ["ok", "ok", "ok", "fail"]
    assert "status 5" in entries[3]["reason"]
    # each finished seed's packing measured independently: its own folder's CSV, the pours' mean and floor
    runs = out / "runs" / "bed_mu0.5"
    folders = [runs / "settle", runs / "settle_seed2", runs / "settle_seed3"]
    settled = [measures.measure(f / "bed_mu0.5.csv", 1.0) for f in folders]
    refs = [measures.measure(runs / f"pour_seed{s}" / "poured.csv", 1.0) for s in (1, 2, 3)]
    summary = row["settle_seeds"]["summary"]
    assert summary["seeds"] == 4 and summary["finished"] == 3
    for key, get in (("packing_fraction", measures.packing_fraction), ("coordination", measures.coordination)):
        vals, pours = [get(m) for m in settled], [get(m) for m in refs]
        assert len(set(vals)) == 3  # three different packings
        assert summary[key]["mean"] == pytest.approx(np.mean(vals), rel=1e-12)
        assert summary[key]["sd"] == pytest.approx(np.std(vals, ddof=1), rel=1e-9)
        assert summary[key]["mean_error_over_floor"] == pytest.approx(
            (np.mean(vals) - np.mean(pours)) / np.std(pours, ddof=1), rel=1e-9)
        reach = 2 * math.sqrt(4 / 3) * np.std(pours, ddof=1)
        assert summary[key]["within"] == sum(abs(v - np.mean(pours)) <= reach for v in vals)
        assert summary[key]["of"] == 3
    report = (out / "report.md").read_text()
    assert "across its seeds" in report and "seed 4 failed" in report
    # again with reuse: the three finished seeds are taken as they are, the failed one runs again
    again = settle_matrix.run_settle_matrix(out, count=400, depth=0.006, margin=1.0, only=["bed_mu0.5"],
                                            progress=lambda m: None, settle_seeds=4, reuse_settles=True)
    assert calls[4:] == ["bed_mu0.5@4"]
    assert again["rows"][0]["settle_seeds"]["summary"] == summary
    with pytest.raises(btr_cli.StepFailed, match="--settle-seeds"):
        settle_matrix.run_settle_matrix(out, only=["bed_mu0.5"], progress=lambda m: None, settle_seeds=0)


def test_settle_method_in_error_vs_runtime(tmp_path, btr_binary, monkeypatch):
    monkeypatch.setenv("BTR_BINARY", btr_binary)
    record = {"cpu_seconds": 2.5, "wall_seconds": 3.5, "steps": [], "chosen": {"target_phi": {"value": 0.6}}}
    monkeypatch.setattr(btr_cli, "run_command", fake_settle_command(btr_binary, record))

    def fake_pour(packing, outdir, settings, progress):  # reference "pours": deposits of other seeds
        dep = btr_cli.deposit(btr_binary, scene, outdir, "poured", seed=10 + settings.seed, count=150, progress=progress)
        return {"packing": dep["csv"], "wall_seconds": 1.0, "cpu_seconds": 10.0, "stop_reason": "kinetic-energy"}
    monkeypatch.setattr(error_runtime, "pour", fake_pour)
    assert "settle" in error_runtime.METHODS
    scene = tiny_bed_toml(tmp_path / "evr.toml", count=150)
    res = error_runtime.run_error_vs_runtime(scene, tmp_path / "evr", count=150, relax_times=[], pour_variants=[],
                                             margin=1.0, methods=("settle",), progress=lambda m: None)
    row = next(r for r in res["rows"] if r["kind"] == "settle")
    assert row["method"] == "btr settle (liggghts)" and row["status"] == "ok", row["reason"]
    assert row["cost_seconds"] == 2.5  # settle.json's cpu_seconds
    want = abs(measures.packing_fraction(measures.measure(row["path"], 1.0)) -
               res["reference"]["mean"]["packing_fraction"])
    assert row["errors"]["packing_fraction"] == pytest.approx(want, rel=1e-12)


def test_cli_rejects_an_unknown_row(tmp_path, source_dir):
    p = subprocess.run([sys.executable, str(source_dir / "workflows" / "btr_workflow.py"), "settle-matrix", "-o",
                        str(tmp_path / "m"), "--rows", "bed_mu0.5,nope"], capture_output=True, text=True, timeout=120)
    assert p.returncode == 2 and "nope" in p.stderr and "bed_mu0.1" in p.stderr
