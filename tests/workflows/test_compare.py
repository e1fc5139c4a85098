"""`compare PRE POST` on packings written by the test: outputs, numbers and failure messages."""
import json
from pathlib import Path
import subprocess
import sys

import numpy as np
import pytest

from btrdem.analysis.compare import compare
from btrdem.core.io import InputError, Packing, read_packing, read_vtp_arrays, write_packing
from lattices import fcc
from scenes import packing_with_scene

PNG = b"\x89PNG\r\n\x1a\n"


def write(tmp_path, name, pos, r, L):
    return packing_with_scene(tmp_path / name, name, pos, r, "periodic", 3, L)


@pytest.fixture
def pair(tmp_path):
    pos, r, L = fcc(5, 5, d=2e-3)
    post = pos + np.array([0.3, 0.0, 0.0]) * 2e-3
    post[:, 0] = np.mod(post[:, 0] + 0.5 * L, L) - 0.5 * L
    moved = np.arange(0, len(r), 10)  # every tenth grain moves a further 0.4 d up
    post[moved, 2] += 0.4 * 2e-3
    return write(tmp_path, "pre", pos, r, L), write(tmp_path, "post", post, r, L), moved, len(r)


def test_compare_outputs_and_numbers(tmp_path, pair):
    pre, post, moved, n = pair
    out = tmp_path / "cmp"
    # reach 2.1 d: no FCC neighbour shell lies there (d, 1.41 d, 1.73 d, 2 d, 2.24 d), so no ties
    res = compare(pre, post, str(out), progress=lambda m: None, local_reach_d=2.1)
    expected = np.full(n, 0.3)
    expected[moved] = np.hypot(0.3, 0.4)
    st = res["displacement_d"]
    assert st["mean"] == pytest.approx(expected.mean())
    assert st["max"] == pytest.approx(0.5)
    assert st["fraction_above_0.1"] == 1.0
    assert st["fraction_above_0.5"] == 0.0  # 0.5 exactly is not above 0.5
    # the lattice itself is unchanged in the rigidly shifted part; the raised grains break contacts
    assert res["structure"]["pre"]["bulk"]["mean_coordination"] == 12.0
    assert res["structure"]["post"]["bulk"]["mean_coordination"] < 12.0
    saved = json.loads((out / "compare.json").read_text())
    assert saved["displacement_d"]["mean"] == pytest.approx(st["mean"])
    for name in ("displacement_histogram", "displacement_vs_height", "rdf", "surface_profile"):
        assert (out / "figures" / f"{name}.png").read_bytes()[:8] == PNG
    md = (out / "compare.md").read_text()
    assert "| packing fraction (bulk, margin 3 d_max) |" in md and "| mean coordination (bulk, contact tolerance 1e-07) |" in md and "fraction > 0.1 d" in md and "BTR support" in md
    vtp = read_vtp_arrays(out / "pre_displacement.vtp")
    assert np.allclose(vtp["displacement"], expected)
    assert np.allclose(vtp["radius"], 1e-3)
    rows = (out / "per_grain.csv").read_text().splitlines()
    assert len(rows) == n + 1 and rows[0].startswith("id,displacement_d,local_displacement_d,n_supports")
    # local displacement: the shared shift cancels; what is left is the rise against the neighbourhood
    # (grains within 2.1 d, the grain itself included), brute force with the nearest periodic image
    pre_pos = np.genfromtxt(pre, delimiter=",", skip_header=1)[:, 1:4]
    L = 5 * np.sqrt(2) * 2e-3
    raised = np.zeros(n, bool)
    raised[moved] = True
    expected_local = np.empty(n)
    for i in range(n):
        delta = pre_pos - pre_pos[i]
        delta[:, :2] -= L * np.round(delta[:, :2] / L)
        near = np.linalg.norm(delta, axis=1) <= 2.1 * 2e-3
        expected_local[i] = 0.4 * abs(raised[i] - raised[near].mean())
    assert np.allclose(vtp["local_displacement"], expected_local, atol=1e-9)


def test_compare_refuses_different_ids(tmp_path, pair):
    pre, post, _, _ = pair
    lines = open(post).read().splitlines()
    open(post, "w").write("\n".join(lines[:-1]) + "\n")
    # Edited on purpose: its JSON's record of the CSV goes, as docs/faults.md says ("A packing is whole or refused"), or the record refuses it first.
    meta_path = Path(post).with_suffix(".json")
    meta = json.loads(meta_path.read_text())
    meta.pop("files", None)
    meta_path.write_text(json.dumps(meta))
    with pytest.raises(InputError, match="expected the same grain ids"):
        compare(pre, post, str(tmp_path / "cmp"), progress=lambda m: None)


def test_cli_compare_reports_bad_input(tmp_path, source_dir):
    bad = tmp_path / "bad.csv"
    bad.write_text("id,x,y,z,r,species\n1,0,0,0,1,1\n")
    p = subprocess.run([sys.executable, str(source_dir / "workflows" / "btr_workflow.py"), "compare", str(bad), str(bad),
                        "-o", str(tmp_path / "o")], capture_output=True, text=True)
    assert p.returncode == 2
    assert "bad.csv:1: expected the header 'id,x,y,z,radius,species'" in p.stderr


def test_grains_removed_on_an_open_floor_are_dropped_from_pre(tmp_path):
    """POST from an open-floor relaxation lists removed PRE ids in relax.removed: compare drops them from PRE
    (and only them: a shifted grain would show as a displacement) and renumbers as `btr relax` does."""
    pos, r, L = fcc(5, 5, d=2e-3)
    pre_csv = write(tmp_path, "pre", pos, r, L)
    pre = read_packing(pre_csv)
    removed = [3, 17]
    keep = np.setdiff1d(np.arange(1, len(r) + 1), removed) - 1
    post_meta = dict(pre.meta, relax={"removed": {"count": 2, "ids": removed}})

    def post_packing(name, meta):
        p = Packing(ids=np.arange(1, len(keep) + 1), pos=pos[keep], radius=r[keep], species=np.ones(len(keep), int),
                    meta=meta)
        return write_packing(tmp_path, name, p, vtp=False)["csv"]

    post_csv = post_packing("post", post_meta)
    res = compare(pre_csv, post_csv, str(tmp_path / "out"), progress=lambda *_: None)
    assert res["displacement_d"]["max"] == pytest.approx(0.0, abs=1e-12)
    # Without the list, the grain counts differ: refused as before.
    bad_csv = post_packing("bad", dict(pre.meta, relax={"removed": {"count": 2, "ids": []}}))
    with pytest.raises(InputError):
        compare(pre_csv, bad_csv, str(tmp_path / "out2"), progress=lambda *_: None)
