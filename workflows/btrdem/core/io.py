"""Packing files (docs/design.md section 2): NAME.csv (id,x,y,z,radius,species) + NAME.json + NAME.vtp,
and scene TOML files. Every write goes to a temporary name and is renamed into place."""
from __future__ import annotations

import json
import math
import os
import tempfile
import tomllib
import zlib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .geometry import Container

HEADER = ["id", "x", "y", "z", "radius", "species"]
# A packing with rigid clusters has a seventh column, cluster (0 = a free grain).
CLUSTER_HEADER = HEADER + ["cluster"]


class InputError(Exception):
    """Bad input: the message names the file, the field and what was expected."""


@dataclass
class Packing:
    ids: np.ndarray        # int64, ascending
    pos: np.ndarray        # (N, 3) centres [m]
    radius: np.ndarray     # (N,) [m]
    species: np.ndarray    # (N,) int
    meta: dict = field(default_factory=dict)  # NAME.json, or {} if there is none
    path: str = ""
    cluster: np.ndarray | None = None  # (N,) int rigid cluster number (0 = free); None: no such column

    def __len__(self):
        return len(self.ids)

    @property
    def dimension(self) -> int:
        return int(self.meta.get("dimension", self.meta.get("scene", {}).get("dimension", 3)))

    def scene(self) -> dict | None:
        return self.meta.get("scene")

    def container(self) -> Container:
        """The container recorded in the packing's JSON."""
        scene = self.scene() or {}
        c = self.meta.get("container", scene.get("container"))
        if c is None:
            raise InputError(f"{self.path}: the packing JSON records no container (key 'container' or "
                             "'scene.container'); pass the scene file")
        return Container.from_json(c, self.dimension, origin=json_path_for(self.path))


def json_path_for(csv_path: str | os.PathLike) -> str:
    p = Path(csv_path)
    return str(p.with_suffix(".json"))


# ---- atomic writes ------------------------------------------------------------------------------

def atomic_write_text(path: str | os.PathLike, text: str) -> None:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix="." + path.name + ".", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "w") as f:
            f.write(text)
        os.chmod(tmp, 0o644)  # mkstemp's 0600 would be kept by the rename
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def _jsonable(x):
    if isinstance(x, dict):
        return {str(k): _jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_jsonable(v) for v in x]
    if isinstance(x, np.ndarray):
        return [_jsonable(v) for v in x.tolist()]
    if isinstance(x, (np.integer,)):
        return int(x)
    if isinstance(x, (np.floating, float)):
        v = float(x)
        return v if math.isfinite(v) else None  # JSON has no inf/nan
    if isinstance(x, (np.bool_,)):
        return bool(x)
    if isinstance(x, Path):
        return str(x)
    return x


def write_json(path: str | os.PathLike, obj) -> None:
    atomic_write_text(path, json.dumps(_jsonable(obj), indent=2) + "\n")


def read_json(path: str | os.PathLike) -> dict:
    try:
        with open(path) as f:
            return json.load(f)
    except FileNotFoundError:
        raise InputError(f"{path}: no such file") from None
    except json.JSONDecodeError as e:
        raise InputError(f"{path}:{e.lineno}: not valid JSON ({e.msg})") from None


# ---- packing CSV ----------------------------------------------------------------------------------

def read_packing(csv_path: str | os.PathLike) -> Packing:
    """Reads NAME.csv and NAME.json beside it (if present). Ids must be unique positive integers."""
    csv_path = str(csv_path)
    try:
        with open(csv_path) as f:
            header = f.readline().strip()
            cols = [c.strip() for c in header.split(",")]
            if cols not in (HEADER, CLUSTER_HEADER):
                raise InputError(f"{csv_path}:1: expected the header '{','.join(HEADER)}' or "
                                 f"'{','.join(CLUSTER_HEADER)}', got '{header}'")
            ncol = len(cols)
            rows = []
            for lineno, line in enumerate(f, start=2):
                line = line.strip()
                if not line:
                    continue
                parts = line.split(",")
                if len(parts) != ncol:
                    raise InputError(f"{csv_path}:{lineno}: expected {ncol} comma-separated values "
                                     f"({','.join(cols)}), got {len(parts)}")
                try:
                    vals = [float(p) for p in parts]
                except ValueError:
                    raise InputError(f"{csv_path}:{lineno}: expected numbers, got '{line}'") from None
                if not all(math.isfinite(v) for v in vals):
                    raise InputError(f"{csv_path}:{lineno}: expected finite numbers, got '{line}'")
                if vals[4] <= 0:
                    raise InputError(f"{csv_path}:{lineno}: radius: expected a positive radius, got {parts[4]}")
                if vals[0] != int(vals[0]) or vals[0] < 1:
                    raise InputError(f"{csv_path}:{lineno}: id: expected an integer >= 1, got {parts[0]}")
                rows.append(vals)
    except FileNotFoundError:
        raise InputError(f"{csv_path}: no such packing file") from None
    a = np.array(rows, dtype=float).reshape(-1, ncol)
    ids = a[:, 0].astype(np.int64)
    order = np.argsort(ids, kind="stable")
    a, ids = a[order], ids[order]
    if len(ids) and np.any(np.diff(ids) == 0):
        dup = int(ids[np.nonzero(np.diff(ids) == 0)[0][0]])
        raise InputError(f"{csv_path}: id: expected unique ids, got {dup} twice")
    meta = {}
    jp = json_path_for(csv_path)
    if os.path.exists(jp):
        meta = read_json(jp)
        _check_against_record(csv_path, jp, meta)
        meta.pop("files", None)  # it describes these files only; a packing written from this one gets its own
    return Packing(ids=ids, pos=a[:, 1:4].copy(), radius=a[:, 4].copy(), species=a[:, 5].astype(int),
                   meta=meta, path=csv_path, cluster=a[:, 6].astype(int) if ncol == 7 else None)


def packing_csv_text(p: Packing) -> str:
    clusters = p.cluster is not None and bool(np.any(p.cluster != 0))
    lines = [",".join(CLUSTER_HEADER if clusters else HEADER)]
    for k, (i, (x, y, z), r, s) in enumerate(zip(p.ids, p.pos, p.radius, p.species)):
        tail = f",{int(p.cluster[k])}" if clusters else ""
        lines.append(f"{int(i)},{x:.17g},{y:.17g},{z:.17g},{r:.17g},{int(s)}{tail}")
    return "\n".join(lines) + "\n"


def bytes_record(data: bytes) -> dict:
    """The size and CRC-32 (zlib's) of a file's bytes, as NAME.json's "files" records them (as btr does)."""
    return {"bytes": len(data), "crc32": zlib.crc32(data)}


def file_record(path: str | os.PathLike) -> dict:
    return bytes_record(Path(path).read_bytes())


def _check_against_record(csv_path: str, json_path: str, meta: dict) -> None:
    """A CSV whose JSON records other bytes belongs to another write (or was cut short): refused."""
    rec = (meta.get("files") or {}).get("csv") if isinstance(meta.get("files"), dict) else None
    if rec is None:
        return
    if not isinstance(rec, dict) or not isinstance(rec.get("bytes"), int) or not isinstance(rec.get("crc32"), int):
        raise InputError(f'{json_path}: files.csv: expected {{"bytes": N, "crc32": N}}, got {rec!r}')
    got = file_record(csv_path)
    if got != {"bytes": rec["bytes"], "crc32": rec["crc32"]}:
        raise InputError(f"{csv_path}: does not match the record in {json_path} ({got['bytes']} bytes, CRC-32 "
                         f"{got['crc32']}; recorded {rec['bytes']} bytes, CRC-32 {rec['crc32']}): the two were not "
                         "written together (an interrupted write, or one file replaced); write the packing again, "
                         'or remove the JSON\'s "files" entry if the CSV was edited on purpose')


def write_packing(directory: str | os.PathLike, name: str, p: Packing, point_data: dict | None = None,
                  vtp: bool = True) -> dict:
    """Writes DIR/NAME.csv, DIR/NAME.json and (vtp=True) DIR/NAME.vtp; returns their paths.
    As btr does: the JSON records the other files' sizes and CRC-32 and is written last, after the previous
    JSON was removed, so a crash part-way leaves no JSON rather than an old one beside new grains."""
    d = Path(directory)
    d.mkdir(parents=True, exist_ok=True)
    out = {"csv": str(d / f"{name}.csv"), "json": str(d / f"{name}.json")}
    Path(out["json"]).unlink(missing_ok=True)
    text = packing_csv_text(p)
    atomic_write_text(out["csv"], text)
    files = {"csv": bytes_record(text.encode())}
    if vtp:
        out["vtp"] = str(d / f"{name}.vtp")
        write_vtp(out["vtp"], p, point_data or {})
        files["vtp"] = file_record(out["vtp"])
    write_json(out["json"], {**{k: v for k, v in p.meta.items() if k != "files"}, "files": files})
    return out


# ---- VTK PolyData ---------------------------------------------------------------------------------

def vtk_available() -> bool:
    try:
        import vtk  # noqa: F401
        return True
    except ImportError:
        return False


def write_vtp(path: str | os.PathLike, p: Packing, point_data: dict) -> None:
    """Points with radius, id, species and each array of point_data (scalars (N,) or vectors (N, 3)).

    Uses Debian's python3-vtk9 (vtkXMLPolyDataWriter). Without it, an equivalent ASCII VTK XML file
    is written by hand so that ParaView still opens it."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    arrays = {"radius": p.radius, "id": p.ids.astype(float), "species": p.species.astype(float)}
    for k, v in point_data.items():
        v = np.asarray(v, dtype=float)
        if v.shape[0] != len(p):
            raise ValueError(f"point data '{k}': expected {len(p)} values, got {v.shape[0]}")
        arrays[k] = v
    fd, tmp = tempfile.mkstemp(prefix="." + path.name + ".", suffix=".tmp.vtp", dir=path.parent)
    os.close(fd)
    try:
        if vtk_available():
            _write_vtp_vtk(tmp, p.pos, arrays)
        else:
            _write_vtp_ascii(tmp, p.pos, arrays)
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def _write_vtp_vtk(path, pos, arrays):
    import vtk
    from vtk.util import numpy_support as ns

    pts = vtk.vtkPoints()
    pts.SetData(ns.numpy_to_vtk(np.ascontiguousarray(pos, dtype=float), deep=True))
    poly = vtk.vtkPolyData()
    poly.SetPoints(pts)
    verts = vtk.vtkCellArray()
    for i in range(len(pos)):
        verts.InsertNextCell(1)
        verts.InsertCellPoint(i)
    poly.SetVerts(verts)
    for name, v in arrays.items():
        a = ns.numpy_to_vtk(np.ascontiguousarray(v, dtype=float), deep=True)
        a.SetName(name)
        poly.GetPointData().AddArray(a)
    if "radius" in arrays:
        poly.GetPointData().SetActiveScalars("radius")
    w = vtk.vtkXMLPolyDataWriter()
    w.SetFileName(str(path))
    w.SetInputData(poly)
    w.SetDataModeToBinary()
    if not w.Write():
        raise OSError(f"{path}: vtkXMLPolyDataWriter failed")


def _write_vtp_ascii(path, pos, arrays):
    n = len(pos)

    def fmt(a):
        return " ".join(f"{x:.17g}" for x in np.ravel(a))

    parts = ['<?xml version="1.0"?>',
             '<VTKFile type="PolyData" version="0.1" byte_order="LittleEndian">', "<PolyData>",
             f'<Piece NumberOfPoints="{n}" NumberOfVerts="{n}">', '<PointData Scalars="radius">']
    for name, v in arrays.items():
        comps = 1 if np.ndim(v) == 1 else np.shape(v)[1]
        parts.append(f'<DataArray type="Float64" Name="{name}" NumberOfComponents="{comps}" format="ascii">'
                     f"{fmt(v)}</DataArray>")
    parts += ["</PointData>", "<Points>",
              f'<DataArray type="Float64" NumberOfComponents="3" format="ascii">{fmt(pos)}</DataArray>',
              "</Points>", "<Verts>",
              f'<DataArray type="Int64" Name="connectivity" format="ascii">{fmt(np.arange(n))}</DataArray>',
              f'<DataArray type="Int64" Name="offsets" format="ascii">{fmt(np.arange(1, n + 1))}</DataArray>',
              "</Verts>", "</Piece>", "</PolyData>", "</VTKFile>"]
    with open(path, "w") as f:
        f.write("\n".join(parts) + "\n")


def read_vtp_arrays(path: str | os.PathLike) -> dict:
    """Point coordinates and point-data arrays of a .vtp (used by tests and reports)."""
    import vtk
    from vtk.util import numpy_support as ns

    r = vtk.vtkXMLPolyDataReader()
    r.SetFileName(str(path))
    r.Update()
    poly = r.GetOutput()
    out = {"points": ns.vtk_to_numpy(poly.GetPoints().GetData())}
    pd = poly.GetPointData()
    for k in range(pd.GetNumberOfArrays()):
        out[pd.GetArrayName(k)] = ns.vtk_to_numpy(pd.GetArray(k))
    return out


# ---- scene TOML -----------------------------------------------------------------------------------

def read_scene_toml(path: str | os.PathLike) -> dict:
    try:
        with open(path, "rb") as f:
            return tomllib.load(f)
    except FileNotFoundError:
        raise InputError(f"{path}: no such scene file") from None
    except tomllib.TOMLDecodeError as e:
        raise InputError(f"{path}: not valid TOML ({e})") from None


def _toml_value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    if isinstance(v, (float, np.floating)):
        s = repr(float(v))
        return s if ("." in s or "e" in s or "inf" in s or "nan" in s) else s + ".0"
    if isinstance(v, str):
        return json.dumps(v)  # a JSON string is a valid TOML basic string
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{k} = {_toml_value(x)}" for k, x in v.items()) + " }"
    raise TypeError(f"cannot write {type(v).__name__} to TOML")


def dump_scene_toml(scene: dict) -> str:
    """The dict tomllib reads, written back: top-level tables, sub-tables inline, arrays of tables."""
    lines = []
    for table, body in scene.items():
        if not isinstance(body, dict):
            lines.append(f"{table} = {_toml_value(body)}")
            continue
        lines.append(f"[{table}]")
        arrays_of_tables = []
        for k, v in body.items():
            if isinstance(v, list) and v and all(isinstance(x, dict) for x in v):
                arrays_of_tables.append((k, v))
            else:
                lines.append(f"{k} = {_toml_value(v)}")
        for k, items in arrays_of_tables:
            for item in items:
                lines.append("")
                lines.append(f"[[{table}.{k}]]")
                for kk, vv in item.items():
                    lines.append(f"{kk} = {_toml_value(vv)}")
        lines.append("")
    return "\n".join(lines)


def write_scene_toml(path: str | os.PathLike, scene: dict) -> None:
    atomic_write_text(path, dump_scene_toml(scene))
