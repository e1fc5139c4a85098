"""Mutated scenes and packings (scripts/fuzz_inputs.py, a few hundred cases): every case ends in bounded time
with exit 0 or a clear refusal (exit 2 naming the file and the field), never a signal, std::bad_alloc, a hang,
or exit 3/4 for a bad value."""
import sys
from pathlib import Path

SCRIPTS = Path(__file__).resolve().parents[2] / "scripts"
sys.path.insert(0, str(SCRIPTS))

import fuzz_inputs  # noqa: E402


def test_mutated_inputs_run_or_are_refused_clearly(btr_binary, tmp_path):
    result = fuzz_inputs.fuzz(btr_binary, n_scene=400, n_packing=120, seed=1, workdir=tmp_path, progress=lambda _: None)
    failed = [c for c in result["cases"] if c["verdict"] == "failed"]
    assert not failed, "\n".join(f"{c.get('scene', c.get('command'))}: {c['mutation']}: {c['why']}" for c in failed)
    counts = result["counts"]
    assert counts["tried"] == 400 + 2 * 120
    assert counts["ran"] > 20 and counts["refused"] > 200, counts


def test_the_judge_catches_what_it_must():
    """The verdicts themselves, on made-up outcomes: a refusal must name the file and a field."""
    judge = fuzz_inputs.judge
    assert judge({"rc": 0, "stderr": ""}, "s.toml", None)[0] == "ran"
    assert judge({"rc": 2, "stderr": "btr deposit: s.toml:3: source.scatter: expected ..."}, "s.toml", "scatter")[0] == "refused"
    assert judge({"rc": 2, "stderr": "btr deposit: expected a radius"}, "s.toml", "radius")[0] == "failed"
    assert judge({"rc": 2, "stderr": "btr deposit: s.toml: something wrong"}, "s.toml", "radius")[0] == "failed"
    assert judge({"rc": 3, "stderr": "btr deposit: std::bad_alloc"}, "s.toml", None)[0] == "failed"
    assert judge({"rc": 4, "stderr": "check failed"}, "s.toml", None)[0] == "failed"
    assert judge({"rc": -11, "stderr": ""}, "s.toml", None)[0] == "failed"
    assert judge({"rc": None, "stderr": ""}, "s.toml", None)[0] == "failed"
