"""The README's chain (btr settle: BTR -> calibration pour -> relaxation; comparison -> report) on a small scene,
with each real engine."""
import json
from pathlib import Path
import subprocess
import sys

import numpy as np
import pytest

from btrdem.core.io import read_packing, read_vtp_arrays
from btrdem.core.report import fmt as report_fmt
from scenes import tiny_bed_toml


@pytest.mark.parametrize("engine", ["liggghts", "yade"])
def test_pipeline_with_each_engine(tmp_path, source_dir, btr_binary, engine):
    scene = tiny_bed_toml(tmp_path / "chain.toml", count=300, max_time=0.2, engine=engine)  # deep enough for a bulk window
    # 650 calibration grains: a cell 10 mean diameters (15 mm) wide, about 5 largest diameters deep
    out = tmp_path / "out"
    p = subprocess.run([sys.executable, str(source_dir / "workflows" / "btr_workflow.py"), "pipeline", scene,
                        "--engine", engine, "-o", str(out), "--calibration-grains", "650"],
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stdout + p.stderr
    assert "== settle" in p.stdout and "pipeline: done" in p.stdout  # progress lines
    run = json.loads((out / "run.json").read_text())
    assert run["status"] == "ok"
    assert [s["name"] for s in run["steps"]] == [f"settle ({engine})", "compare", "report"]
    assert all(s["status"] == "ok" and s["wall_seconds"] >= 0 for s in run["steps"])
    assert run["versions"]["btr"] and (out / "inputs" / "chain.toml").exists()
    settle = out / "settle"
    btr, relaxed = read_packing(settle / "btr" / "chain.csv"), read_packing(settle / "chain.csv")
    res = json.loads((out / "compare" / "compare.json").read_text())
    # the reported displacements are those of the two files (nearest periodic image)
    L = 0.007
    delta = relaxed.pos - btr.pos
    delta[:, :2] -= L * np.round(delta[:, :2] / L)
    disp = np.linalg.norm(delta, axis=1) / (2 * btr.radius.mean())
    assert res["displacement_d"]["max"] == pytest.approx(disp.max(), rel=1e-9)
    assert res["displacement_d"]["fraction_above_0.1"] == pytest.approx(np.mean(disp > 0.1))
    vtp = read_vtp_arrays(out / "compare" / "post_displacement.vtp")
    assert np.allclose(vtp["displacement"], disp) and np.allclose(vtp["points"], relaxed.pos)
    report = (out / "report.md").read_text()
    assert "grains moved > 0.1 d" in report and engine in report
    # the report's costs are settle.json's, and its total is at least the steps' engine time
    record = json.loads((settle / "settle.json").read_text())
    assert f"| total | {report_fmt(record['cpu_seconds'])} |" in report
    assert record["cpu_seconds"] >= sum(s["engine_cpu_seconds"] for s in record["steps"]) > 0
    assert f"Target bulk packing fraction {report_fmt(record['chosen']['target_phi']['value'])}" in report
    # One definition of each measure: the BTR packing's JSON, the settled packing's and compare.json hold the
    # same measures of the same packing, to the last digit.
    btr_json = json.loads((settle / "btr" / "chain.json").read_text())["measures"]
    relaxed_json = json.loads((settle / "chain.json").read_text())["measures"]
    assert res["structure"]["pre"] == btr_json
    assert res["structure"]["post"] == relaxed_json
    assert relaxed_json != btr_json  # the relaxed packing was measured itself, not copied from the deposit
    assert btr_json["bulk"]["valid"] and relaxed_json["bulk"]["valid"]
    # the contact rule counts the grain-grain contacts the engine itself reports (id2 = 0: the floor):
    # exactly for LIGGGHTS; YADE also keeps a few interactions whose grains have just parted
    pairs = np.genfromtxt(settle / "relax" / "contacts.csv", delimiter=",", names=True)
    grain_pairs = int(np.count_nonzero(pairs["id2"] > 0))
    assert relaxed_json["mean_coordination_all_grains"] == pytest.approx(
        2 * grain_pairs / len(relaxed), rel=1e-12 if engine == "liggghts" else 0.01)
    for key in ("packing_fraction", "mean_coordination"):
        assert f"{report_fmt(btr_json['bulk'][key])} |" in report


def test_failed_step_keeps_earlier_outputs(tmp_path, source_dir, btr_binary):
    scene = tiny_bed_toml(tmp_path / "chain.toml", count=300, max_time=0.02)  # a bulk window settle accepts
    out = tmp_path / "out"
    # the engine cannot be started: liggghts is not on PATH
    p = subprocess.run([sys.executable, str(source_dir / "workflows" / "btr_workflow.py"), "pipeline", scene,
                        "-o", str(out)], capture_output=True, text=True, timeout=300,
                       env={"BTR_BINARY": btr_binary, "PATH": "/nonexistent"})
    assert p.returncode == 3
    assert "FAILED: settle (liggghts)" in p.stderr
    run = json.loads((out / "run.json").read_text())
    assert run["status"] == "failed" and run["failed_step"] == "settle (liggghts)"
    assert run["steps"][0]["error"]
    assert (out / "settle" / "btr" / "chain.csv").exists()  # the BTR packing made before the engine failed


def test_relative_output_folders_are_not_nested(tmp_path, source_dir, btr_binary, monkeypatch):
    """btr runs in its output folder: a relative -o must still name the folder the caller meant."""
    from btrdem.core import btr_cli
    monkeypatch.chdir(tmp_path)
    dep = btr_cli.deposit(btr_binary, str(source_dir / "inputs" / "bed3d.toml"), "rel/btr", count=50,
                          progress=lambda *_: None)
    assert Path(dep["csv"]) == tmp_path / "rel" / "btr" / "btr.csv"
    assert (tmp_path / "rel" / "btr" / "btr.csv").is_file()
    assert not (tmp_path / "rel" / "btr" / "rel").exists()


def test_studies_take_a_relative_output_folder(tmp_path, source_dir, btr_binary):
    """A study given -o relative to the working directory writes there, every case ok (its btr runs happen
    inside the case folders, where a relative path would name another folder)."""
    p = subprocess.run([sys.executable, str(source_dir / "workflows" / "btr_workflow.py"), "brazil-nut", "--tiny",
                        "--dims", "2", "-o", "rel"], cwd=tmp_path, capture_output=True, text=True, timeout=300,
                       env=dict(__import__("os").environ, BTR_BINARY=btr_binary))
    assert p.returncode == 0, p.stdout + p.stderr
    run = json.loads((tmp_path / "rel" / "run.json").read_text())
    assert run["status"] == "ok"
    assert "(0 failed)" in p.stdout
