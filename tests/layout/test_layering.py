"""The tree follows its dependency rule, and the rule's checker finds a break (on a tree built here)."""
import os
from pathlib import Path

from layering import CXX_RULES, PY_RULES, cxx_violations, python_violations

ROOT = Path(os.environ.get("BTR_SOURCE_DIR", Path(__file__).resolve().parents[2]))


def test_cxx_includes_follow_the_rule():
    assert cxx_violations(ROOT) == []


def test_python_imports_follow_the_rule():
    assert python_violations(ROOT) == []


def test_every_source_folder_has_a_rule():
    folders = {p.parent.relative_to(ROOT).as_posix()
               for top in ("btr", "coupling", "app") for p in (ROOT / top).rglob("*.cpp")}
    assert folders <= set(CXX_RULES)
    subpackages = {p.parent.name for p in (ROOT / "workflows/btrdem").glob("*/*.py")}
    assert subpackages <= set(PY_RULES)


def _write(root: Path, rel: str, text: str):
    path = root / rel
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)


def test_checker_finds_breaks(tmp_path):
    for top in ("btr", "coupling", "app"):
        (tmp_path / top).mkdir()
    _write(tmp_path, "btr/verify/check.cpp", '#include "btr/model/grain.h"\n#include "btr/placement/walls.h"\n')
    _write(tmp_path, "btr/measures/m.cpp", '#include "btr/scene/toml_reader.h"\n')
    _write(tmp_path, "coupling/yade/y.cpp", '#include "coupling/liggghts/liggghts_script.h"\n')
    _write(tmp_path, "coupling/dem/d.cpp", '#include "app/commands.h"\n#include "relax.h"\n')
    _write(tmp_path, "btr/newfolder/x.cpp", "")
    found = {(f, why) for f, _h, why in cxx_violations(tmp_path)}
    assert found == {
        ("btr/verify/check.cpp", "btr/verify may not use btr/placement"),
        ("btr/measures/m.cpp", "private to btr/scene"),
        ("coupling/yade/y.cpp", "coupling/yade may not use coupling/liggghts"),
        ("coupling/dem/d.cpp", "coupling/dem may not use app"),
        ("coupling/dem/d.cpp", "include by full path"),
        ("btr/newfolder/x.cpp", "folder btr/newfolder has no rule"),
    }
    _write(tmp_path, "workflows/btrdem/core/io.py", "from ..studies import drum\n")
    _write(tmp_path, "workflows/btrdem/analysis/m.py", "from ..core.io import read\nimport btrdem.dem.pour\n")
    _write(tmp_path, "workflows/btrdem/studies/s.py", "from ..core import io\nfrom ..dem.pour import pour\n")
    found = {(f, why) for f, _m, why in python_violations(tmp_path)}
    assert found == {
        ("workflows/btrdem/core/io.py", "core may not use studies"),
        ("workflows/btrdem/analysis/m.py", "analysis may not use dem"),
    }
