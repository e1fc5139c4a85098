"""error-vs-runtime on tiny settings: complete tables, no empty cells."""
import json
import re
import subprocess
import sys

import pytest

from scenes import tiny_bed_toml


def table_rows(md: str, header_start: str):
    """Rows (lists of cells) of the Markdown table whose header starts with header_start."""
    lines = md.splitlines()
    k = next(i for i, l in enumerate(lines) if l.startswith("| " + header_start))
    rows = []
    for line in lines[k + 2:]:
        if not line.startswith("|"):
            break
        rows.append([c.strip() for c in line.strip("|").split("|")])
    return lines[k], rows


def run(args, source_dir, timeout=600):
    return subprocess.run([sys.executable, str(source_dir / "workflows" / "btr_workflow.py")] + args,
                          capture_output=True, text=True, timeout=timeout)


def test_error_vs_runtime_tiny(tmp_path, source_dir, btr_binary, liggghts):
    scene = tiny_bed_toml(tmp_path / "evr.toml", count=150, max_time=0.04)
    out = tmp_path / "evr"
    p = run(["error-vs-runtime", scene, "-o", str(out), "--relax-times", "0.005,0.04", "--pours", "0.3:1e-3,1:1e-5",
             "--margin", "2", "--methods", "relax"], source_dir)
    assert p.returncode == 0, p.stdout + p.stderr
    res = json.loads((out / "error_vs_runtime.json").read_text())
    assert res["reference"]["seeds"] == [1, 2, 3]
    assert {"packing_fraction", "coordination", "rdf"} <= set(res["measures"])
    methods = [r["method"] for r in res["rows"]]
    assert methods[0] == "BTR" and sum(m.startswith("BTR + liggghts relax") for m in methods) == 2
    assert sum(m.startswith("DEM pour") for m in methods) == 2
    for r in res["rows"]:
        assert r["status"] == "ok" and r["reason"] == ""
        assert r["wall_seconds"] > 0 and r["cpu_seconds"] > 0
        assert r["cost_seconds"] == r["cpu_seconds"]  # every run here recorded its processor time
        assert all(r["errors"][k] is not None and r["errors"][k] >= 0 for k in res["measures"])
    # the BTR + relaxation rows include the deposit's times; an engine run takes processor time
    btr_row = res["rows"][0]
    assert all(r["wall_seconds"] > btr_row["wall_seconds"] and r["cpu_seconds"] > btr_row["cpu_seconds"]
               for r in res["rows"] if r["kind"] == "relax")
    assert res["verdict"]["cost_basis"] == "cpu"
    assert res["verdict"]["core_measures"] == ["packing_fraction", "coordination", "rdf"]
    md = (out / "error_vs_runtime.md").read_text()
    header, rows = table_rows(md, "method | wall time [s] | CPU time [s] | cost / pour | error:")
    assert len(rows) == 3 + 5
    assert all(cell not in ("", "n/a", "None", "nan") for row in rows for cell in row), rows
    assert res["verdict"]["summary"] in md
    assert (out / "error_vs_runtime.png").read_bytes()[:4] == b"\x89PNG"


def test_error_vs_runtime_keeps_going_when_a_method_fails(tmp_path, btr_binary, liggghts, monkeypatch):
    """A forced engine failure in one method (LIGGGHTS stopped by a 0.01 s wall-time limit) is a row with
    its reason; the methods after it still run and the table is complete."""
    from btrdem.core import btr_cli
    from btrdem.studies import error_runtime

    real_relax = btr_cli.relax

    def relax(*args, **kw):
        if kw.get("label") == "relax_0.005s":
            kw["time_limit"] = 0.01
        return real_relax(*args, **kw)

    monkeypatch.setattr(btr_cli, "relax", relax)
    monkeypatch.setenv("BTR_BINARY", btr_binary)
    scene = tiny_bed_toml(tmp_path / "evr.toml", count=150, max_time=0.04)
    out = tmp_path / "evr"
    res = error_runtime.run_error_vs_runtime(scene, out, relax_times=[0.005, 0.04], pour_variants=[(1.0, 1e-5)],
                                             margin=2.0, progress=lambda m: None, methods=("relax",))
    rows = {r["method"]: r for r in res["rows"]}
    assert list(rows) == ["BTR", "BTR + liggghts relax 0.005 s", "BTR + liggghts relax 0.04 s",
                          "DEM pour pace 1 stop 1e-05"]
    failed = rows["BTR + liggghts relax 0.005 s"]
    assert failed["status"] == "fail" and "time limit" in failed["reason"] and failed["errors"] is None
    for name in ("BTR", "BTR + liggghts relax 0.04 s", "DEM pour pace 1 stop 1e-05"):  # before and after it
        assert rows[name]["status"] == "ok" and rows[name]["errors"]["packing_fraction"] is not None, rows[name]
    saved = json.loads((out / "error_vs_runtime.json").read_text())
    assert [r["status"] for r in saved["rows"]] == ["ok", "fail", "ok", "ok"]
    md = (out / "error_vs_runtime.md").read_text()
    header, table = table_rows(md, "method | status | reason")
    assert table == [["BTR + liggghts relax 0.005 s", "fail", failed["reason"]]]
    header, errors = table_rows(md, "method | wall time [s] | CPU time [s] | cost / pour | error:")
    assert len(errors) == 3 + 3 and "Failed methods" in res["verdict"]["summary"]
    run_json = json.loads((out / "run.json").read_text())
    steps = {s["name"]: s for s in run_json["steps"]}
    assert run_json["status"] == "ok" and steps["BTR + liggghts relax 0.005 s"]["status"] == "failed"


def test_size_study_new_methods_failed_count_and_reused_pours(tmp_path, btr_binary, liggghts, monkeypatch):
    """--counts: one table per count; a count whose study fails (0 grains: btr deposit refuses it) is a row
    with its reason and the study goes on; both target-phi methods record their compaction (target = the pours'
    mean, and whether it was reached); pre-loading without --preload in this build is a failed row naming the
    option; a rerun with reuse_pours takes the finished reference pours and their recorded times."""
    from btrdem.core import btr_cli
    from btrdem.studies import error_runtime

    monkeypatch.setenv("BTR_BINARY", btr_binary)
    scene = tiny_bed_toml(tmp_path / "evr.toml", count=150, max_time=0.04)
    out = tmp_path / "sizes"
    error_runtime.run_size_study(scene, [0, 150], out, relax_times=[], pour_variants=[], margin=2.0,
                                 progress=lambda m: None,
                                 methods=("target-phi", "target-phi-unbalanced", "shake", "preload", "preload-damped"),
                                 shakes=3)
    study = json.loads((out / "size_study.json").read_text())
    assert [s["count"] for s in study["sizes"]] == [0, 150]
    small, ok = study["sizes"]
    assert small["status"] == "fail" and "deposit" in small["reason"], small
    assert ok["status"] == "ok" and ok["grains"] == 150, ok
    rows = {m["kind"]: m for m in ok["methods"]}
    assert set(rows) == {"btr", "target", "target-ub", "shake", "preload", "preload-damped"}
    has_preload = "--preload" in btr_cli.help_text(btr_binary, "relax")
    if not has_preload:
        assert rows["preload"]["status"] == "fail" and "--preload" in rows["preload"]["reason"]
    else:  # pre-loaded and damped: the relaxation ran with both options
        assert rows["preload-damped"]["status"] == "ok", rows["preload-damped"]
        relaxed = json.loads((out / "n150" / "relax_preload_damped0.5" / "relaxed.json").read_text())
        assert relaxed["relax"]["damping"] == 0.5 and "preload" in relaxed, relaxed["relax"]
    assert ok["cost_basis"] == "cpu"
    for kind in ("btr", "target", "target-ub", "shake"):
        assert rows[kind]["status"] == "ok", rows[kind]
        assert rows[kind]["cost_ratio"] == pytest.approx(rows[kind]["cpu_seconds"] / ok["reference_pour_cost_seconds"])
    res = json.loads((out / "n150" / "error_vs_runtime.json").read_text())
    assert ok["reference_pour_cost_seconds"] == pytest.approx(sum(res["reference"]["cpu_seconds"]) / 3)
    for kind, rule in (("target", "kinetic-energy"), ("target-ub", "unbalanced-force")):
        row = next(r for r in res["rows"] if r["kind"] == kind)
        rec = row["target_phi_record"]
        assert rec["target"] == pytest.approx(res["reference"]["mean"]["packing_fraction"])
        relaxed = json.loads((out / "n150" / ("relax_" + ("target_phi" if kind == "target" else "target_phi_unbalanced"))
                              / "relaxed.json").read_text())
        assert relaxed["relax"]["stop_rule"] == rule
        if rec["compaction_ran"]:  # the BTR bed was looser than the pours: it compacted in the run
            assert rec["initial_bulk_packing_fraction"] < rec["target"]
            assert rec["reached"] == (rec["in_run_packing_fraction_at_end"] >= rec["target"])
    md = (out / "size_study.md").read_text()
    assert "## 0 grains: fail" in md and "## 150 grains" in md
    assert (out / "size_study.png").read_bytes()[:4] == b"\x89PNG"

    again = error_runtime.run_error_vs_runtime(scene, out / "n150", count=150, relax_times=[], pour_variants=[],
                                               margin=2.0, progress=lambda m: None, methods=(), reuse_pours=True)
    assert again["reference"]["reused"] == [True, True, True]
    assert again["reference"]["wall_seconds"] == res["reference"]["wall_seconds"]
    assert again["reference"]["cpu_seconds"] == res["reference"]["cpu_seconds"]


    # a list of compaction dampings runs the target-phi method once per value, each in its own folder
    both = error_runtime.run_error_vs_runtime(scene, out / "n150", count=150, relax_times=[], pour_variants=[],
                                              margin=2.0, progress=lambda m: None, methods=("target-phi-unbalanced",),
                                              reuse_pours=True, compaction_damping=[0.1, 0.3])
    rows = [r for r in both["rows"] if r["kind"] == "target-ub"]
    assert [r["compaction_damping"] for r in rows] == [0.1, 0.3] and len({r["method"] for r in rows}) == 2
    for r in rows:
        assert r["status"] == "ok", r
        relaxed = json.loads((out / "n150" / f"relax_target_phi_unbalanced_cd{r['compaction_damping']:g}"
                              / "relaxed.json").read_text())
        if relaxed["target_phi"]["compaction_ran"]:
            assert relaxed["target_phi"]["compaction_damping"] == r["compaction_damping"]


def test_error_vs_runtime_on_an_open_floor_heap_counts_removed_grains(tmp_path, source_dir, btr_binary, liggghts):
    """A user's heap on an open floor: the pours and relaxations run in a bounded region, grains that slide
    out of it are removed and counted, and the report says how many (the pours' shrink-wrapped box grew
    with every runaway grain before, and the heap angle is the measure compared)."""
    scene = source_dir / "inputs" / "heap3d.toml"
    text = scene.read_text().replace("count = 5000", "count = 1000").replace("max_time = 1.0", "max_time = 0.3")
    text += "open_margin = 1.0\nopen_heap_angle = 80.0\n"  # a narrow region, so some grains leave it
    assert "count = 1000" in text and text.rstrip().endswith("open_heap_angle = 80.0")
    (tmp_path / "heap.toml").write_text(text)
    out = tmp_path / "evr"
    p = run(["error-vs-runtime", str(tmp_path / "heap.toml"), "-o", str(out), "--relax-times", "0.3",
             "--pours", "1:1e-3", "--methods", "relax,target-phi"], source_dir)
    assert p.returncode == 0, p.stdout + p.stderr
    res = json.loads((out / "error_vs_runtime.json").read_text())
    assert "angle_of_repose" in res["measures"]
    # a heap has no bulk window, so no packing fraction to target: that method is a row with its reason
    target = [r for r in res["rows"] if r["kind"] == "target"]
    assert len(target) == 1 and target[0]["status"] == "fail" and "no packing fraction to target" in target[0]["reason"]
    assert all(r["status"] == "ok" for r in res["rows"] if r["kind"] != "target"), \
        [(r["method"], r["reason"]) for r in res["rows"]]
    removed = res["reference"]["removed"] + [r.get("removed", 0) for r in res["rows"]]
    assert sum(removed) > 0
    for k, n in enumerate(res["reference"]["removed"]):  # each pour's packing holds the grains it kept
        poured = out / f"reference_seed{k + 1}" / "poured.csv"
        assert sum(1 for _ in open(poured)) - 1 == 1000 - n
    md = (out / "error_vs_runtime.md").read_text()
    assert "## Grains removed on the open floor" in md
    # with no bulk window, "all" means the measures the heap has, not an empty set every method reaches
    assert res["verdict"]["core_measures"] == [k for k in res["measures"] if k in ("angle_of_repose", "segregation")]
    assert res["verdict"]["core_measures"]
    limit = res["reference"]["reach_threshold"]
    btr_row = res["rows"][0]
    btr_reaches = all(btr_row["errors"][k] <= limit[k] for k in res["verdict"]["core_measures"])
    assert (res["verdict"]["per_measure"]["all"] or {}).get("method") != "BTR" or btr_reaches
