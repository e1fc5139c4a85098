#!/usr/bin/python3
"""Mutated scenes and packings against the `btr` program: every case must end in bounded time with exit 0,
or exit 2 and a message naming the file (and, for a scene value, the field). Anything else is a finding:
a signal, std::bad_alloc, a hang (past the time limit), exit 3 or 4 on a bad value, a refusal that names
neither the file nor the field.

    /usr/bin/python3 scripts/fuzz_inputs.py --cases 3000 -o out/fuzz      # the long run (docs/faults.md, "Fuzzing")

tests/workflows/test_fuzz.py runs a few hundred cases of the same generator in the test suite.

Scene cases: each scene of inputs/ with its grain count lowered (so a valid case runs in milliseconds), then
one mutation: a value (a number in it, or the whole value) replaced by zero, a negative, huge or tiny
number, NaN, infinity, or a value of the wrong type; a line dropped; a line doubled. The scene runs through
the command its tables call for (deposit, shake, drum or redeposit, with --check and one or two cycles or
steps). Packing cases: a deposited packing's CSV or JSON mutated the same way (a field, a row dropped or
doubled, the file cut short), through `btr measure` and `btr export`.
"""
from __future__ import annotations

import argparse
import json
import os
import random
import re
import shutil
import subprocess
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
TIME_LIMIT = 20.0  # s per case: a valid case takes well under a second

NUMBER = re.compile(r"(?<![\w.])[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?(?![\w.])")
NUMBER_MUTANTS = ["0", "-1", "-1e9", "1e9", "1e300", "1e-300", "nan", "inf", "-inf", "1000000000000000000", "0.5"]
VALUE_MUTANTS = ['"text"', "[1.0, 2.0, 3.0]", "true", "{ a = 1 }", "[]", '""']
# Keep a valid case fast: the count of every scene lowered to this (list sources keep their files' rows).
SMALL_COUNT = 60
FIELD_REFERENCE = re.compile(r"\b[a-z_]+(?:\[\d+\])?\.[a-z_]+\b|--[a-z-]+")


# ---- the scenes and their commands ----------------------------------------------------------------

def small_scene_text(path: Path) -> str:
    text = path.read_text()
    if re.search(r'(?m)^\s*file\s*=', text):  # a drop or cluster list decides the count
        return text
    text = re.sub(r"(?m)^(\s*count\s*=\s*)\d+", lambda m: m.group(1) + str(SMALL_COUNT), text)
    text = re.sub(r"(?m)^(\s*cycles\s*=\s*)\d+", lambda m: m.group(1) + "2", text)
    text = re.sub(r"(?m)^(\s*revolutions\s*=\s*)[\d.eE+-]+", lambda m: m.group(1) + "0.02", text)
    return text


def command_for(text: str, scene: Path, out: Path) -> list[str]:
    if re.search(r"(?m)^\[shaking\]", text):
        return ["shake", str(scene), "-o", str(out), "--cycles", "1", "--check", "-q"]
    if re.search(r"(?m)^\[drum\]", text):
        return ["drum", str(scene), "-o", str(out), "--steps", "2", "--check", "-q"]
    if re.search(r"(?m)^\[clusters\]", text):
        return ["redeposit", str(scene), "-o", str(out), "--cycles", "1", "--check", "-q"]
    return ["deposit", str(scene), "-o", str(out), "--check", "-q"]


# ---- mutations ------------------------------------------------------------------------------------

def key_of(line: str, pos: int) -> str:
    """The key a value at `pos` belongs to: the nearest `key =` before it on the line."""
    keys = re.findall(r"([A-Za-z_][\w.]*)\s*=", line[:pos])
    return keys[-1] if keys else ""


def scene_mutations(text: str) -> list[tuple[str, str, str]]:
    """Every (description, mutated text, field) of one scene text."""
    lines = text.splitlines(keepends=True)
    out = []
    for i, line in enumerate(lines):
        body = line.split("#", 1)[0]
        m = re.match(r"\s*([A-Za-z_][\w]*)\s*=\s*(.*?)\s*$", body)
        if not m:
            continue
        key, value = m.group(1), m.group(2)
        vstart = body.index(value, m.start(2)) if value else len(body)

        def replaced(a, b, new):
            return "".join(lines[:i]) + line[:a] + new + line[b:] + "".join(lines[i + 1:])

        for n in NUMBER.finditer(value):
            field = key_of(line, vstart + n.start()) or key
            for mut in NUMBER_MUTANTS:
                out.append((f"line {i + 1} {field}: {n.group()} -> {mut}",
                            replaced(vstart + n.start(), vstart + n.end(), mut), field))
        for mut in VALUE_MUTANTS:
            out.append((f"line {i + 1} {key}: value -> {mut}", replaced(vstart, vstart + len(value), mut), key))
        out.append((f"line {i + 1} {key}: dropped", "".join(lines[:i] + lines[i + 1:]), key))
        out.append((f"line {i + 1} {key}: doubled", "".join(lines[:i + 1] + [line] + lines[i + 1:]), key))
    return out


def packing_mutations(csv_text: str, json_text: str) -> list[tuple[str, str, str, str]]:
    """(description, csv text, json text, file mutated) of one packing."""
    rows = csv_text.splitlines(keepends=True)
    out = []
    for i in range(1, min(len(rows), 6)):
        fields = rows[i].rstrip("\n").split(",")
        for k in range(len(fields)):
            for mut in NUMBER_MUTANTS + ["x", ""]:
                f = list(fields)
                f[k] = mut
                new = rows[:i] + [",".join(f) + "\n"] + rows[i + 1:]
                out.append((f"csv row {i} column {k}: -> {mut!r}", "".join(new), json_text, "csv"))
        out.append((f"csv row {i} dropped", "".join(rows[:i] + rows[i + 1:]), json_text, "csv"))
        out.append((f"csv row {i} doubled", "".join(rows[:i + 1] + [rows[i]] + rows[i + 1:]), json_text, "csv"))
        out.append((f"csv row {i} extra column", "".join(rows[:i] + [rows[i].rstrip("\n") + ",7\n"] + rows[i + 1:]),
                    json_text, "csv"))
    out.append(("csv header changed", "id,x,y,z,r,species\n" + "".join(rows[1:]), json_text, "csv"))
    out.append(("csv cut short", csv_text[: len(csv_text) // 2], json_text, "csv"))
    out.append(("csv empty", "", json_text, "csv"))
    out.append(("json cut short", csv_text, json_text[: len(json_text) // 2], "json"))
    out.append(("json not an object", csv_text, "[1, 2]\n", "json"))
    meta = json.loads(json_text)
    for path in (("dimension",), ("scene", "dimension"), ("scene", "container", "kind"), ("scene", "container", "size_x"),
                 ("scene", "grains", "components"), ("scene", "relax", "engine"), ("scene", "relax", "max_time"),
                 ("files", "csv", "crc32"), ("scene",)):
        for mut in [0, -1, 1e300, "text", None, [], {}]:
            m = json.loads(json_text)
            node = m
            for k in path[:-1]:
                node = node.get(k, {}) if isinstance(node, dict) else {}
            if not isinstance(node, dict) or path[-1] not in node:
                continue
            node[path[-1]] = mut
            out.append((f"json {'.'.join(path)} -> {mut!r}", csv_text, json.dumps(m, indent=1), "json"))
    del meta
    return out


# ---- running a case -------------------------------------------------------------------------------

def run_case(btr: str, args: list[str], cwd: Path, time_limit: float = TIME_LIMIT) -> dict:
    t0 = time.monotonic()
    proc = subprocess.Popen([btr] + args, cwd=cwd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                            start_new_session=True)
    try:
        _, err = proc.communicate(timeout=time_limit)
        rc = proc.returncode
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, 9)
        _, err = proc.communicate()
        rc = None
    return {"rc": rc, "stderr": err.decode(errors="replace"), "seconds": time.monotonic() - t0}


def judge(result: dict, file_name: str, field: str | None) -> tuple[str, str]:
    """("ran" | "refused" | "failed", why) of one case."""
    rc, err = result["rc"], result["stderr"]
    first = err.strip().splitlines()[0][:300] if err.strip() else ""
    if rc is None:
        return "failed", f"hang: no exit within {TIME_LIMIT:.0f} s"
    if rc < 0:
        return "failed", f"killed by signal {-rc}: {first}"
    if "bad_alloc" in err:
        return "failed", f"std::bad_alloc: {first}"
    if rc == 0:
        return "ran", ""
    if rc == 2:
        if file_name not in err:
            return "failed", f"refused without naming {file_name}: {first}"
        # The field: the one mutated, or the one a cross-check names (e.g. a radius refused by container.gap).
        if field and field not in err and not FIELD_REFERENCE.search(err.replace(file_name, "")):
            return "failed", f"refused without naming the field {field}: {first}"
        return "refused", first
    return "failed", f"exit {rc}: {first}"


def scene_cases(rng: random.Random, n: int) -> list[tuple[Path, str, str, str]]:
    """n cases (scene, description, text, field) drawn without replacement, evenly over the scenes."""
    scenes = sorted((REPO / "inputs").glob("*.toml"))
    per_scene = {s: scene_mutations(small_scene_text(s)) for s in scenes}
    pool = [(s, d, t, f) for s in scenes for (d, t, f) in per_scene[s]]
    rng.shuffle(pool)
    return pool[:n]


def fuzz(btr: str, n_scene: int, n_packing: int, seed: int, workdir: Path, progress=print) -> dict:
    """Runs the cases; returns {"cases": [...], "counts": {...}}."""
    rng = random.Random(seed)
    workdir.mkdir(parents=True, exist_ok=True)
    cases = []
    # The scene's companion files (drop and cluster lists) sit beside the mutated scene.
    scene_dir = workdir / "scenes"
    scene_dir.mkdir(exist_ok=True)
    for f in (REPO / "inputs").glob("*.csv"):
        shutil.copy(f, scene_dir / f.name)
    for k, (src, desc, text, field) in enumerate(scene_cases(rng, n_scene)):
        name = f"case{k:05d}_{src.stem}.toml"
        path = scene_dir / name
        path.write_text(text)
        out = workdir / "out" / f"case{k:05d}"
        res = run_case(btr, command_for(text, path, out), workdir)
        verdict, why = judge(res, name, field if res["rc"] == 2 and field else None)
        cases.append({"kind": "scene", "scene": src.name, "mutation": desc, "rc": res["rc"], "verdict": verdict,
                      "why": why, "seconds": round(res["seconds"], 3)})
        shutil.rmtree(out, ignore_errors=True)
        path.unlink()
        if (k + 1) % 100 == 0:
            progress(f"  {k + 1} scene cases, {Counter(c['verdict'] for c in cases)}")
    # Packing cases: one small deposited packing, mutated.
    base = workdir / "base"
    r = run_case(btr, ["deposit", str(REPO / "inputs" / "box3d.toml"), "-o", str(base), "--count", "40", "-q",
                       "--name", "p"], workdir)
    if r["rc"] != 0:
        raise RuntimeError(f"the base packing could not be deposited: {r['stderr']}")
    csv_text, json_text = (base / "p.csv").read_text(), (base / "p.json").read_text()
    pool = packing_mutations(csv_text, json_text)
    rng.shuffle(pool)
    for k, (desc, csv_t, json_t, which) in enumerate(pool[:n_packing]):
        d = workdir / "packings" / f"case{k:05d}"
        d.mkdir(parents=True, exist_ok=True)
        (d / "p.csv").write_text(csv_t)
        (d / "p.json").write_text(json_t)
        for args in (["measure", str(d / "p.csv"), "-o", str(d / "m.json")],
                     ["export", str(d / "p.csv"), "--to", "liggghts", "-o", str(d / "lig")]):
            res = run_case(btr, args, workdir)
            verdict, why = judge(res, f"p.{which}", None)
            cases.append({"kind": "packing", "command": args[0], "mutation": desc, "rc": res["rc"],
                          "verdict": verdict, "why": why, "seconds": round(res["seconds"], 3)})
        shutil.rmtree(d, ignore_errors=True)
    counts = Counter(c["verdict"] for c in cases)
    return {"cases": cases, "counts": {"tried": len(cases), "ran": counts["ran"], "refused": counts["refused"],
                                       "failed": counts["failed"]},
            "slowest_seconds": max((c["seconds"] for c in cases), default=0.0)}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--cases", type=int, default=3000, help="scene cases (the packing cases are a third of it)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("-o", "--out", default=None, help="folder for fuzz.json (default: a temporary folder, removed)")
    ap.add_argument("--btr", default=os.environ.get("BTR_BINARY", str(REPO / "build" / "app" / "btr")))
    a = ap.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="btr_fuzz_") as tmp:
        t0 = time.monotonic()
        result = fuzz(a.btr, a.cases, a.cases // 3, a.seed, Path(tmp))
        result["wall_seconds"] = round(time.monotonic() - t0, 1)
    c = result["counts"]
    print(f"{c['tried']} cases: {c['ran']} ran, {c['refused']} refused clearly, {c['failed']} failed "
          f"(slowest {result['slowest_seconds']:.2f} s; {result['wall_seconds']} s in all)")
    for case in result["cases"]:
        if case["verdict"] == "failed":
            print(f"  FAILED {case.get('scene', case.get('command'))}: {case['mutation']}: {case['why']}")
    if a.out:
        Path(a.out).mkdir(parents=True, exist_ok=True)
        (Path(a.out) / "fuzz.json").write_text(json.dumps(result, indent=1) + "\n")
    return 0 if c["failed"] == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
