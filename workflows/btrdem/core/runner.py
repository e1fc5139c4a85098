"""Running programs and recording runs.

Every workflow writes into its own output folder a run.json that names the command line, the
inputs (copied into the folder), the program versions, and each step with its status, wall time,
outputs and error. It is rewritten after every step, so a failed step leaves a clear error next to
what the earlier steps wrote."""
from __future__ import annotations

import contextlib
import ctypes
import datetime
import os
import platform
import resource
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

from .io import InputError, read_json, write_json

REPO = Path(__file__).resolve().parents[3]


class StepFailed(Exception):
    """A workflow step failed; the message says which and why."""


def failure_reason(message: str) -> str:
    """A failed row's reason: the message's first line ("X failed:" with the line that says why), up to 600
    characters, so that a whole refusal of btr, what to do included, fits (btr settle's run to 470)."""
    lines = [x.strip() for x in str(message).splitlines() if x.strip()] or ["(no message)"]
    return (" ".join(lines[:2]) if lines[0].endswith(":") else lines[0])[:600]


class Interrupted(KeyboardInterrupt):
    """A stop signal (SIGTERM, SIGINT, SIGHUP) reached the workflow. The command it was running has been
    stopped; the case or step that ran records it, and the workflow ends with exit status 128 + signum."""

    def __init__(self, signum: int):
        self.signum = signum
        super().__init__(f"interrupted by {signal.Signals(signum).name}")


def _raise_interrupted(signum, _frame):
    raise Interrupted(signum)


def stop_on_signals() -> None:
    """SIGTERM, SIGINT and SIGHUP raise Interrupted in the main thread, so a workflow stopped by a scheduler,
    a timeout or Ctrl-C stops the program it runs (run_command) and records the interrupted case."""
    for s in (signal.SIGTERM, signal.SIGINT, signal.SIGHUP):
        signal.signal(s, _raise_interrupted)


_PR_SET_PDEATHSIG = 1


def _die_with_parent() -> None:
    """In the child, before exec: SIGTERM when this workflow dies, however it dies (even SIGKILL); `btr`
    then stops its engine, mpirun its ranks."""
    ctypes.CDLL(None, use_errno=True).prctl(_PR_SET_PDEATHSIG, int(signal.SIGTERM), 0, 0, 0)
    if os.getppid() == 1:  # the workflow died before the line above
        os._exit(127)


def _stop(proc: subprocess.Popen, grace: float = 30.0) -> None:
    """SIGTERM, then SIGKILL after `grace` seconds: btr needs a few to stop an engine and its MPI ranks."""
    if proc.poll() is not None:
        return
    proc.send_signal(signal.SIGTERM)
    try:
        proc.wait(timeout=grace)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()


def find_btr() -> str:
    """The `btr` program: $BTR_BINARY, else build/app/btr in the repository."""
    env = os.environ.get("BTR_BINARY")
    if env:
        if not os.access(env, os.X_OK):
            raise StepFailed(f"BTR_BINARY={env}: not an executable file")
        return env
    default = REPO / "build" / "app" / "btr"
    if os.access(default, os.X_OK):
        return str(default)
    raise StepFailed(f"the btr program was not found: set BTR_BINARY or build it into {default} "
                     "(scripts/setup.sh)")


def _tail(path, n=15) -> str:
    try:
        with open(path, errors="replace") as f:
            lines = f.readlines()
        return "".join(lines[-n:])
    except OSError:
        return ""


def _last_line(path) -> str:
    try:
        with open(path, "rb") as f:
            f.seek(0, os.SEEK_END)
            size = f.tell()
            f.seek(max(0, size - 4096))
            lines = [x for x in f.read().decode(errors="replace").splitlines() if x.strip()]
        return lines[-1].strip()[:120] if lines else ""
    except OSError:
        return ""


def run_command(argv, cwd, label: str, progress=print, heartbeat: float = 15.0, env: dict | None = None,
                watch: str | None = None, timeout: float | None = None, stdout_name: str | None = None,
                status=None) -> dict:
    """Runs argv in cwd with stdout and stderr in cwd/<label>.stdout / .stderr, printing a progress line
    every `heartbeat` seconds (with status() if given, else the last line of `watch`, a log file the
    program writes).
    Returns {returncode, wall_seconds, cpu_seconds, stdout, stderr}; never raises on a non-zero exit.
    cpu_seconds is the processor time (user + system) of the program and the processes it waited for (an
    engine, mpirun's ranks): unlike the wall time it does not grow when other jobs share the machine.
    Programs are run one at a time, so the change of this process's RUSAGE_CHILDREN is that program's."""
    cwd = Path(cwd)
    cwd.mkdir(parents=True, exist_ok=True)
    safe = label.replace(" ", "_").replace("/", "_")
    out_path = cwd / (stdout_name or f"{safe}.stdout")
    err_path = cwd / f"{safe}.stderr"
    full_env = dict(os.environ)
    full_env.update(env or {})
    t0 = time.monotonic()
    cpu0 = _children_cpu()
    with open(out_path, "w") as out, open(err_path, "w") as err:
        try:
            proc = subprocess.Popen([str(a) for a in argv], cwd=cwd, stdout=out, stderr=err, env=full_env,
                                    preexec_fn=_die_with_parent)
        except OSError as e:
            raise StepFailed(f"{label}: cannot start {argv[0]}: {e}") from None
        next_beat = t0 + heartbeat
        try:
            while True:
                try:
                    rc = proc.wait(timeout=1.0)
                    break
                except subprocess.TimeoutExpired:
                    now = time.monotonic()
                    if timeout is not None and now - t0 > timeout:
                        _stop(proc)
                        raise StepFailed(f"{label}: killed after {timeout:.0f} s (time limit)")
                    if now >= next_beat:
                        if status is not None:
                            last = status()
                        else:
                            last = _last_line(watch) if watch else _last_line(out_path) or _last_line(err_path)
                        progress(f"  [{label}] running {now - t0:.0f} s{': ' + last if last else ''}")
                        next_beat = now + heartbeat
        except BaseException:  # Interrupted, KeyboardInterrupt: the program must not outlive the workflow
            _stop(proc)
            raise
    return {"returncode": rc, "wall_seconds": time.monotonic() - t0, "cpu_seconds": _children_cpu() - cpu0,
            "stdout": str(out_path), "stderr": str(err_path)}


def _children_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def require_success(res: dict, label: str, log: str | None = None):
    if res["returncode"] != 0:
        detail = _tail(res["stderr"]) or _tail(res["stdout"])
        if log:
            detail += ("\n--- " + log + " ---\n" + _tail(log)) if os.path.exists(log) else ""
        raise StepFailed(f"{label}: exit status {res['returncode']}\n{detail.rstrip()}")


def _cmd_version(argv) -> str | None:
    try:
        p = subprocess.run(argv, capture_output=True, text=True, timeout=30)
        return (p.stdout.strip() or p.stderr.strip()).splitlines()[0] if (p.stdout or p.stderr) else None
    except (OSError, subprocess.TimeoutExpired, IndexError):
        return None


def _dpkg_version(pkg) -> str | None:
    try:
        p = subprocess.run(["dpkg-query", "-W", "-f=${Version}", pkg], capture_output=True, text=True, timeout=30)
        return p.stdout.strip() or None
    except (OSError, subprocess.TimeoutExpired):
        return None


def versions(btr: str | None = None) -> dict:
    import matplotlib
    import numpy
    import scipy

    from .. import __version__

    v = {"btrdem_workflows": __version__, "python": platform.python_version(), "numpy": numpy.__version__,
         "scipy": scipy.__version__, "matplotlib": matplotlib.__version__, "platform": platform.platform(),
         "liggghts_package": _dpkg_version("liggghts"), "yade_package": _dpkg_version("yade"),
         "openmpi_package": _dpkg_version("openmpi-bin")}
    if btr:
        v["btr"] = _cmd_version([btr, "--version"])
        v["btr_path"] = btr
    return v


class RunRecord:
    """OUTDIR/run.json: what was run, with which inputs and versions, and how each step went."""

    def __init__(self, outdir, workflow: str, argv=None, inputs=(), btr: str | None = None, progress=print,
                 settings: dict | None = None):
        self.outdir = Path(outdir)
        self.outdir.mkdir(parents=True, exist_ok=True)
        self.path = self.outdir / "run.json"
        self.progress = progress
        (self.outdir / "inputs").mkdir(exist_ok=True)
        copied = []
        for src in inputs:
            if src and os.path.exists(src):
                dst = self.outdir / "inputs" / Path(src).name
                if Path(src).resolve() != dst.resolve():
                    shutil.copy2(src, dst)
                copied.append({"original": os.path.abspath(src), "copy": str(dst)})
        self.data = {"workflow": workflow, "command": [sys.executable] + list(argv if argv is not None else sys.argv),
                     "cwd": os.getcwd(), "started": datetime.datetime.now().isoformat(timespec="seconds"),
                     "inputs": copied, "settings": settings or {}, "versions": versions(btr), "steps": [],
                     "status": "running"}
        self.save()

    def save(self):
        write_json(self.path, self.data)

    def _start(self, name: str):
        """A new step entry in run.json, saved at once; returns it and its start time."""
        entry = {"name": name, "status": "running", "started": datetime.datetime.now().isoformat(timespec="seconds")}
        self.data["steps"].append(entry)
        self.save()
        self.progress(f"== {name}")
        return entry, time.monotonic()

    @contextlib.contextmanager
    def step(self, name: str):
        """Times a step and records it; on failure records the error and raises StepFailed."""
        entry, t0 = self._start(name)
        try:
            yield entry
        except BaseException as e:
            interrupted = isinstance(e, Interrupted)
            entry.update(status="interrupted" if interrupted else "failed", wall_seconds=time.monotonic() - t0,
                         error=str(e))
            self.data["status"] = "interrupted" if interrupted else "failed"
            self.data["failed_step"] = name
            self.save()
            if isinstance(e, (KeyboardInterrupt, InputError)):
                raise
            if isinstance(e, StepFailed):
                raise StepFailed(f"{name}: {e}") from e
            raise StepFailed(f"{name}: {type(e).__name__}: {e}") from e
        entry.update(status="ok", wall_seconds=time.monotonic() - t0)
        self.save()
        self.progress(f"   {name}: done in {entry['wall_seconds']:.1f} s")

    @contextlib.contextmanager
    def case(self, name: str, rows: list, row: dict, on_row=None):
        """One case of a study, the way every study runs them: `row` joins `rows` at once with status
        "running"; the body fills it in. If the body raises, the row gets status "fail" and the reason
        (the error's first line), run.json records the error, and the study goes on with the next case
        (only KeyboardInterrupt and bad input stop it). A row the body leaves "running" ends "ok".
        A stop signal (Interrupted) ends the row "interrupted" with the signal as its reason, rewrites the
        tables, and stops the study.
        on_row(rows), if given, rewrites the study's tables after every case, so they grow as it runs."""
        row.setdefault("status", "running")
        row.setdefault("reason", "")
        rows.append(row)
        entry, t0 = self._start(name)
        try:
            yield row
        except Interrupted as e:
            row.update(status="interrupted", reason=str(e))
            entry.update(status="interrupted", wall_seconds=time.monotonic() - t0, error=str(e))
            self.data["status"] = "interrupted"
            self.save()
            if on_row is not None:
                on_row(rows)
            raise
        except (KeyboardInterrupt, InputError):
            entry.update(status="failed", wall_seconds=time.monotonic() - t0)
            self.save()
            raise
        except Exception as e:  # noqa: BLE001 - a failed case is a row with its reason, not a failed study
            message = str(e).strip() or type(e).__name__
            row.update(status="fail", reason=failure_reason(message))
            entry.update(status="failed", wall_seconds=time.monotonic() - t0, error=message[-3000:])
            self.progress(f"   {name}: FAILED ({row['reason']}); the study goes on")
        else:
            if row["status"] == "running":
                row["status"] = "ok"
            entry.update(status="ok", wall_seconds=time.monotonic() - t0)
            self.progress(f"   {name}: {row['status']} in {entry['wall_seconds']:.1f} s")
        self.save()
        if on_row is not None:
            on_row(rows)

    def finish(self, summary: dict | None = None):
        self.data["status"] = "ok"
        self.data["finished"] = datetime.datetime.now().isoformat(timespec="seconds")
        if summary:
            self.data["summary"] = summary
        self.save()


def previous_record(outdir) -> dict | None:
    p = Path(outdir) / "run.json"
    return read_json(p) if p.exists() else None
