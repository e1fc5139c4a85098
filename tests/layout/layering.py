"""The dependency rule of the source tree, checked on its #include and import lines.

Each folder may use only the folders listed for it (and itself); the CMake targets link the same way
(btr/CMakeLists.txt, coupling/CMakeLists.txt). A header is "used" when a file includes it; a Python module
when a module imports it (relative or absolute).
"""
import re
from pathlib import Path

BTR_ALL = ["btr/model", "btr/scene", "btr/placement", "btr/measures", "btr/dynamics", "btr/verify"]
COUPLING_SHARED = ["coupling/io", "coupling/dem"]

# folder -> the folders its files may include from (besides its own)
CXX_RULES = {
    "btr/model": [],
    "btr/scene": ["btr/model"],
    "btr/placement": ["btr/model", "btr/scene"],
    "btr/measures": ["btr/model", "btr/scene", "btr/placement"],
    "btr/dynamics": ["btr/model", "btr/scene", "btr/placement", "btr/measures"],
    # the self-check must not share code with the placement it checks
    "btr/verify": ["btr/model"],
    "coupling/io": BTR_ALL,
    "coupling/dem": BTR_ALL + ["coupling/io"],
    "coupling/liggghts": BTR_ALL + COUPLING_SHARED,
    "coupling/yade": BTR_ALL + COUPLING_SHARED,
    "coupling": BTR_ALL + COUPLING_SHARED + ["coupling/liggghts", "coupling/yade"],
    "app": BTR_ALL + COUPLING_SHARED + ["coupling/liggghts", "coupling/yade", "coupling"],
}
# headers private to one folder: the TOML reader belongs to the scene parser
PRIVATE_HEADERS = {"btr/scene/toml_reader.h": "btr/scene"}

PY_PACKAGE = "workflows/btrdem"
PY_RULES = {
    "core": [],
    "analysis": ["core"],
    "dem": ["core", "analysis"],
    "studies": ["core", "analysis", "dem"],
}

INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.M)
RELATIVE_IMPORT = re.compile(r"^\s*from\s+(\.+)([\w.]*)\s+import\s+([\w, ()]+)", re.M)
ABSOLUTE_IMPORT = re.compile(r"^\s*(?:from|import)\s+btrdem\.(\w+)", re.M)


def _folder_of(path: Path, root: Path) -> str:
    return path.parent.relative_to(root).as_posix()


def cxx_violations(root: Path):
    """(file, included header, why) for every #include that breaks CXX_RULES or PRIVATE_HEADERS."""
    found = []
    for top in ("btr", "coupling", "app"):
        for f in sorted((root / top).rglob("*")):
            if f.suffix not in (".h", ".cpp"):
                continue
            folder = _folder_of(f, root)
            if folder not in CXX_RULES:
                found.append((f.relative_to(root).as_posix(), "", f"folder {folder} has no rule"))
                continue
            for header in INCLUDE.findall(f.read_text()):
                if "/" not in header:
                    if folder != "app":  # only the program includes its own headers by bare name
                        found.append((f.relative_to(root).as_posix(), header, "include by full path"))
                    continue
                owner = header.rsplit("/", 1)[0]
                private = PRIVATE_HEADERS.get(header)
                if private and folder != private:
                    found.append((f.relative_to(root).as_posix(), header, f"private to {private}"))
                elif owner != folder and owner not in CXX_RULES[folder]:
                    found.append((f.relative_to(root).as_posix(), header, f"{folder} may not use {owner}"))
    return found


def python_violations(root: Path):
    """(module, imported subpackage, why) for every import in workflows/btrdem that breaks PY_RULES."""
    found = []
    package = root / PY_PACKAGE
    for f in sorted(package.rglob("*.py")):
        rel = f.relative_to(package)
        if len(rel.parts) == 1:
            continue  # the package's __init__
        sub = rel.parts[0]
        if sub not in PY_RULES:
            found.append((f.relative_to(root).as_posix(), "", f"subpackage {sub} has no rule"))
            continue
        text = f.read_text()
        used = set(ABSOLUTE_IMPORT.findall(text))
        for dots, module, _names in RELATIVE_IMPORT.findall(text):
            if len(dots) == 2 and module:
                used.add(module.split(".")[0])
        for other in sorted(used):
            if other != sub and other not in PY_RULES[sub]:
                found.append((f.relative_to(root).as_posix(), other, f"{sub} may not use {other}"))
    return found
