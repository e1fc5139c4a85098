"""Faults: engines end with the `btr` (or workflow) process that started them, sizes that cannot fit are
refused before allocation, a packing's files are whole or refused, a target not reached has its own exit code.

The signal tests run real LIGGGHTS and YADE relaxations and look for every process whose working folder is
the relaxation's output folder (the engine, mpirun and its ranks run there)."""
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from btrdem.core.io import InputError, read_packing, write_packing
from btrdem.core.runner import Interrupted, RunRecord


# ---- helpers --------------------------------------------------------------------------------------

def processes_in(folder: Path) -> list[int]:
    """Ids of the processes whose working folder is `folder` (or inside it)."""
    folder = folder.resolve()
    found = []
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            cwd = Path(os.readlink(f"/proc/{entry}/cwd"))
        except OSError:
            continue
        if cwd == folder or folder in cwd.parents:
            found.append(int(entry))
    return found


def wait_for(predicate, seconds: float, step: float = 0.2):
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        value = predicate()
        if value:
            return value
        time.sleep(step)
    return predicate()


def deposit(btr, source_dir, out: Path, scene="bed3d", count=400, name=None) -> Path:
    name = name or scene
    subprocess.run([btr, "deposit", str(source_dir / "inputs" / f"{scene}.toml"), "-o", str(out), "--count",
                    str(count), "--name", name, "-q"], check=True, timeout=120)
    return out / f"{name}.csv"


def endless(csv: Path) -> Path:
    """The packing with a kinetic stop ratio that never fires and a long time cap: the engine runs until stopped."""
    meta = json.loads(csv.with_suffix(".json").read_text())
    meta["scene"]["relax"].update(stop_kinetic_ratio=1e-30, max_time=1000.0)
    csv.with_suffix(".json").write_text(json.dumps(meta))
    return csv


def kill_leftovers(folder: Path):
    for pid in processes_in(folder):
        try:
            os.kill(pid, signal.SIGKILL)
        except ProcessLookupError:
            pass


# ---- engines end with btr -------------------------------------------------------------------------

@pytest.mark.parametrize("engine,np_,sig", [("liggghts", 2, signal.SIGTERM), ("yade", 1, signal.SIGINT),
                                            ("liggghts", 1, signal.SIGHUP)])
def test_a_stop_signal_ends_the_engine_and_btr_says_so(btr_binary, source_dir, tmp_path, engine, np_, sig):
    csv = endless(deposit(btr_binary, source_dir, tmp_path / "dep"))
    out = tmp_path / "relax"
    out.mkdir()
    proc = subprocess.Popen([btr_binary, "relax", str(csv), "--engine", engine, "--np", str(np_), "-o", str(out)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        engine_pids = wait_for(lambda: processes_in(out), 60)
        assert engine_pids, f"no {engine} process started in {out}"
        time.sleep(2.0)  # let mpirun start its ranks
        assert proc.poll() is None, f"btr relax ended before the signal: {proc.communicate()}"
        proc.send_signal(sig)
        _, err = proc.communicate(timeout=60)
        assert proc.returncode == 128 + sig, (proc.returncode, err)
        assert signal.Signals(sig).name in err and "stopped" in err, err
        left = wait_for(lambda: not processes_in(out), 5)
        assert left, f"processes still running in {out} after btr exited: {processes_in(out)}"
    finally:
        proc.kill()
        kill_leftovers(out)


def test_the_engine_ends_when_btr_is_killed(btr_binary, source_dir, tmp_path):
    """SIGKILL cannot be caught: the engine learns of btr's death from the kernel (parent-death signal)."""
    csv = endless(deposit(btr_binary, source_dir, tmp_path / "dep"))
    out = tmp_path / "relax"
    out.mkdir()
    proc = subprocess.Popen([btr_binary, "relax", str(csv), "--engine", "liggghts", "--np", "2", "-o", str(out)],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        assert wait_for(lambda: processes_in(out), 60), "no engine process started"
        time.sleep(2.0)
        proc.kill()
        proc.wait(timeout=10)
        assert wait_for(lambda: not processes_in(out), 30), f"engine processes outlived btr: {processes_in(out)}"
    finally:
        kill_leftovers(out)


def test_a_workflow_stopped_by_sigterm_stops_its_program_and_records_the_case(btr_binary, source_dir, tmp_path):
    """SIGTERM to the pipeline while `btr relax` runs ends the relaxation and its engine, run.json records the
    step as interrupted, and the workflow exits with 128 + SIGTERM."""
    out = tmp_path / "study"
    env = dict(os.environ, BTR_BINARY=btr_binary)
    proc = subprocess.Popen([sys.executable, str(source_dir / "workflows" / "btr_workflow.py"), "pipeline",
                             str(source_dir / "inputs" / "bed3d.toml"), "-o", str(out), "--count", "5000"],
                            env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        relax_dir = wait_for(lambda: next((p for p in out.rglob("in.btr") if processes_in(p.parent)), None), 120)
        assert relax_dir, "the pipeline did not start LIGGGHTS"
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=90)
        assert proc.returncode == 128 + signal.SIGTERM, (proc.returncode, err)
        assert "interrupted by SIGTERM" in err, err
        assert wait_for(lambda: not processes_in(out), 10), f"processes outlived the workflow: {processes_in(out)}"
        record = json.loads((out / "run.json").read_text())
        assert record["status"] == "interrupted"
        assert record["steps"][-1]["status"] == "interrupted", record["steps"][-1]
    finally:
        proc.kill()
        kill_leftovers(out)


def test_an_interrupted_case_is_a_row_with_the_signal_and_the_tables_are_rewritten(tmp_path):
    rows, written = [], []
    rec = RunRecord(tmp_path, "test", argv=["x"])
    rec_ok = {"name": "first"}
    with rec.case("first", rows, rec_ok, on_row=lambda r: written.append(len(r))):
        pass
    with pytest.raises(Interrupted):
        with rec.case("second", rows, {"name": "second"}, on_row=lambda r: written.append(len(r))):
            raise Interrupted(signal.SIGTERM)
    assert [r["status"] for r in rows] == ["ok", "interrupted"]
    assert rows[1]["reason"] == "interrupted by SIGTERM"
    assert written == [1, 2]
    assert json.loads((tmp_path / "run.json").read_text())["status"] == "interrupted"


def test_a_failed_case_keeps_a_whole_refusal_of_btr_as_its_reason(tmp_path):
    # btr settle's refusal of a shallow bed, as the size study met it: 470 characters, what to do at its end
    why = ("btr settle: inputs/bed3d.toml: grains.count: the bed's bulk window (2 largest diameters from the floor, "
           "walls and surface) holds no grain (bed too shallow for a bulk window: lowest surface column at z = "
           "0.00698 m, margin 0.003999 m); settle needs at least 50 there to measure a packing fraction to compact "
           "to and to judge the bed by: give more grains, or pour the scene (`btr pour`)")
    rows = []
    rec = RunRecord(tmp_path, "test", argv=["x"])
    with rec.case("settle", rows, {"name": "settle"}):
        raise RuntimeError("settle: btr settle exited with status 2:\n" + why)
    assert rows[0]["status"] == "fail"
    assert rows[0]["reason"] == "settle: btr settle exited with status 2: " + why
    assert len(rows[0]["reason"]) > 300


# ---- sizes checked before memory ------------------------------------------------------------------

def scene_with(source_dir: Path, tmp_path: Path, scene: str, old: str, new: str) -> Path:
    text = (source_dir / "inputs" / f"{scene}.toml").read_text()
    assert old in text, f"{old!r} not in {scene}.toml"
    path = tmp_path / f"{scene}_mutated.toml"
    path.write_text(text.replace(old, new, 1))
    return path


@pytest.mark.parametrize("scene,old,new,field,reason", [
    # the values that ended in std::bad_alloc: far beyond the placement's precision, refused by the length limit
    ("heap3d", "scatter = 1.0e-3", "scatter = 1e9", "source.scatter", "times the smallest grain radius"),
    ("hele_shaw", "gap = 3.0e-3 ", "gap = 1e9 ", "container.gap", "times the smallest grain radius"),
    # a drum 5000 smallest radii wide: its wall's rolling loses precision long before the length limit
    ("drum2d", "radius = 0.02", "radius = 0.5", "container.radius", "times the smallest grain radius"),
    # within it, but the neighbour grid over the footprint would not fit in memory
    ("heap3d", "scatter = 1.0e-3", "scatter = 400.0", "source.scatter", "GB"),
    ("bed3d", "size = [0.03, 0.03]", "size = [400.0, 400.0]", "container.size", "GB"),
    ("bed3d", "count = 10000", "count = 100000000000", "grains.count", "GB"),
])
def test_a_size_that_cannot_fit_is_refused_up_front(btr_binary, source_dir, tmp_path, scene, old, new, field, reason):
    path = scene_with(source_dir, tmp_path, scene, old, new)
    r = subprocess.run([btr_binary, "deposit", str(path), "-o", str(tmp_path / "out")], capture_output=True, text=True,
                       timeout=30)
    assert r.returncode == 2, (r.returncode, r.stderr)
    assert path.name in r.stderr and field in r.stderr and reason in r.stderr, r.stderr
    assert "bad_alloc" not in r.stderr
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())


def test_a_count_option_that_cannot_fit_is_refused_up_front(btr_binary, source_dir, tmp_path):
    r = subprocess.run([btr_binary, "deposit", str(source_dir / "inputs" / "bed3d.toml"), "-o", str(tmp_path),
                        "--count", "100000000000"], capture_output=True, text=True, timeout=30)
    assert r.returncode == 2, (r.returncode, r.stderr)
    assert "--count" in r.stderr and "100000000000" in r.stderr and "GB" in r.stderr, r.stderr


@pytest.mark.parametrize("block,expect", [("1e-300", "at least 1 mean grain diameter"), ("1e300", "container.size")])
def test_a_meaningless_cluster_block_is_bad_input(btr_binary, source_dir, tmp_path, block, expect):
    path = scene_with(source_dir, tmp_path, "nano_powder", "block = 10.0", f"block = {block}")
    r = subprocess.run([btr_binary, "redeposit", str(path), "-o", str(tmp_path / "out"), "--cycles", "1", "-q"],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 2, (r.returncode, r.stderr)
    assert path.name in r.stderr and expect in r.stderr, r.stderr


def test_more_grains_than_the_drum_holds_is_bad_input(btr_binary, source_dir, tmp_path):
    """Far more than fit at the densest packing: refused before placing; more than the BTR packing holds: refused
    when the drum is full, with the count it held."""
    for count, expect in (("100000", "holds at most about"), ("20000", "as many as the drum held when it was full")):
        path = scene_with(source_dir, tmp_path, "drum2d", "count = 1500", f"count = {count}")
        r = subprocess.run([btr_binary, "drum", str(path), "-o", str(tmp_path / "out"), "--steps", "1", "-q"],
                           capture_output=True, text=True, timeout=120)
        assert r.returncode == 2, (count, r.returncode, r.stderr)
        assert path.name in r.stderr and "grains.count" in r.stderr and expect in r.stderr, r.stderr


@pytest.mark.parametrize("old,new,field", [
    ("min = 0.8e-3", "min = 1e-12", "grains.radius.min"),             # radii a factor 1e9 apart
    ("scatter = 1.0e-3", "scatter = 1e4", "source.scatter"),           # a length of 1e7 grain radii
])
def test_lengths_beyond_the_placements_precision_are_refused(btr_binary, source_dir, tmp_path, old, new, field):
    path = scene_with(source_dir, tmp_path, "heap3d", old, new)
    r = subprocess.run([btr_binary, "deposit", str(path), "-o", str(tmp_path / "out"), "--count", "50"],
                       capture_output=True, text=True, timeout=30)
    assert r.returncode == 2, (r.returncode, r.stderr)
    assert field in r.stderr, r.stderr


# ---- a packing is whole or refused ----------------------------------------------------------------

def test_the_json_records_its_csv_and_a_mixed_set_is_refused_by_every_reader(btr_binary, source_dir, tmp_path):
    a = deposit(btr_binary, source_dir, tmp_path / "a", count=50, name="p")
    b = deposit(btr_binary, source_dir, tmp_path / "b", count=60, name="p")
    meta = json.loads(a.with_suffix(".json").read_text())
    assert meta["files"]["csv"]["bytes"] == a.stat().st_size
    assert set(meta["files"]) == {"csv", "vtp"}
    # A crash between the renames of another writer would leave a new CSV beside the old JSON: refused.
    a.write_bytes(b.read_bytes())
    r = subprocess.run([btr_binary, "measure", str(a)], capture_output=True, text=True, timeout=60)
    assert r.returncode == 2, (r.returncode, r.stderr)
    assert str(a) in r.stderr and "does not match the record" in r.stderr, r.stderr
    with pytest.raises(InputError, match="does not match the record"):
        read_packing(a)


def test_a_packing_written_from_a_read_one_gets_its_own_record(btr_binary, source_dir, tmp_path):
    """Python rewrites (scaled copies, kept subsets) must not carry the source's record."""
    p = read_packing(deposit(btr_binary, source_dir, tmp_path / "a", count=50, name="p"))
    assert "files" not in p.meta
    p.pos = p.pos * 2.0
    out = write_packing(tmp_path / "c", "q", p, vtp=False)
    r = subprocess.run([btr_binary, "measure", out["csv"]], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stderr
    assert read_packing(out["csv"]).meta["scene"] == p.meta["scene"]


def test_writing_leaves_no_temporary_files(btr_binary, source_dir, tmp_path):
    csv = deposit(btr_binary, source_dir, tmp_path / "a", count=50, name="p")
    subprocess.run([btr_binary, "measure", str(csv), "-o", str(tmp_path / "a" / "m.json")], check=True, timeout=60)
    assert sorted(f.name for f in (tmp_path / "a").iterdir()) == ["m.json", "p.csv", "p.json", "p.vtp"]


# ---- a target not reached -------------------------------------------------------------------------

def test_a_target_phi_not_reached_exits_6_with_the_packing_written(btr_binary, source_dir, tmp_path):
    """0.70 is above what frictionless spheres of this size ratio pack to (random close packing, about 0.64-0.67):
    a compaction of 0.02 s cannot reach it."""
    csv = deposit(btr_binary, source_dir, tmp_path / "dep", count=4000)
    out = tmp_path / "relax"
    r = subprocess.run([btr_binary, "relax", str(csv), "-o", str(out), "--target-phi", "0.70", "--max-time", "0.02",
                        "--friction-scales", "0", "--target-margin", "1"], capture_output=True, text=True, timeout=600)
    assert r.returncode == 6, (r.returncode, r.stderr[-2000:])
    assert "was not reached" in r.stderr
    record = json.loads((out / "relaxed.json").read_text())["target_phi"]
    assert record["reached"] is False and record["target"] == 0.70
    assert len(read_packing(out / "relaxed.csv")) == 4000


# ---- command-line values --------------------------------------------------------------------------

@pytest.mark.parametrize("args,expect", [
    (["relax", "{csv}", "-o", "{out}", "--np", "0"], "--np: expected a positive integer, got 0"),
    (["relax", "{csv}", "-o", "{out}", "--damping", "2"], "--damping: expected a damping in [0, 1), got 2"),
    (["deposit", "{scene}", "-o", "{out}", "--count", "-5"], "--count: expected a positive integer, got -5"),
    (["measure", "{csv}", "--margin", "-1"], "--margin: expected a number >= 0, got -1"),
])
def test_command_line_refusals_say_what_was_expected(btr_binary, source_dir, tmp_path, args, expect):
    csv = deposit(btr_binary, source_dir, tmp_path / "dep", count=30)
    argv = [a.format(csv=csv, out=tmp_path / "out", scene=source_dir / "inputs" / "bed3d.toml") for a in args]
    r = subprocess.run([btr_binary] + argv, capture_output=True, text=True, timeout=60)
    assert r.returncode == 2, (r.returncode, r.stderr)
    assert expect in r.stderr, r.stderr
