"""Markdown tables and matplotlib (Agg) figures shared by every workflow."""
from __future__ import annotations

import math
import os
import tempfile
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def fmt(v, digits: int = 4) -> str:
    """A table cell: numbers to `digits` significant figures, None as 'n/a'."""
    if v is None:
        return "n/a"
    if isinstance(v, (bool, np.bool_)):
        return "yes" if v else "no"
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    if isinstance(v, (float, np.floating)):
        v = float(v)
        if math.isnan(v):
            return "n/a"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        if v == 0:
            return "0"
        if 1e-3 <= abs(v) < 1e5:
            return f"{v:.{digits}g}"
        return f"{v:.{max(digits - 1, 1)}e}"
    return str(v)


def md_table(headers, rows) -> str:
    def cell(x):
        return (x if isinstance(x, str) else fmt(x)).replace("|", "\\|")

    lines = ["| " + " | ".join(headers) + " |", "|" + "|".join("---" for _ in headers) + "|"]
    for row in rows:
        lines.append("| " + " | ".join(cell(x) for x in row) + " |")
    return "\n".join(lines) + "\n"


def save_figure(fig, path) -> str:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix="." + path.stem + ".", suffix=".tmp.png", dir=path.parent)
    os.close(fd)
    try:
        fig.savefig(tmp, dpi=110, bbox_inches="tight")
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    finally:
        plt.close(fig)
    return str(path)


def displacement_histogram(disp_d, path, thresholds=(0.1, 0.5), local=None):
    fig, ax = plt.subplots(figsize=(6, 4))
    disp_d = np.asarray(disp_d)
    both = np.concatenate([disp_d, np.asarray(local)]) if local is not None else disp_d
    positive = both[both > 0]
    if len(positive):
        lo = max(float(positive.min()), 1e-6)
        hi = max(float(positive.max()), lo * 10)
        bins = np.logspace(np.log10(lo), np.log10(hi), 50)
        ax.hist(disp_d[disp_d > 0], bins=bins, color="tab:blue", label="displacement")
        if local is not None:
            loc = np.asarray(local)
            ax.hist(loc[loc > 0], bins=bins, histtype="step", color="black", lw=1.5,
                    label="local displacement (neighbourhood mean removed)")
        ax.set_xscale("log")
        ax.legend(fontsize=8, loc="upper left")
    for t in thresholds:
        ax.axvline(t, color="tab:red", ls="--", lw=1)
        ax.text(t, ax.get_ylim()[1] * 0.95, f" {t:g} d", color="tab:red", va="top", fontsize=8)
    ax.set_xlabel("displacement / mean diameter")
    ax.set_ylabel("grains")
    ax.set_title(f"Displacement of {len(disp_d)} grains ({np.count_nonzero(disp_d == 0)} did not move)")
    return save_figure(fig, path)


def displacement_vs_height(height_d, disp_d, path, moved=None, local=None):
    fig, ax = plt.subplots(figsize=(6, 4))
    ax.scatter(height_d, np.maximum(disp_d, 1e-8), s=3, alpha=0.5, color="tab:blue", label="displacement")
    if moved is not None and np.any(moved):
        ax.scatter(np.asarray(height_d)[moved], np.maximum(np.asarray(disp_d)[moved], 1e-8), s=5,
                   color="tab:red", label="displacement > 0.1 d")
    if local is not None:
        ax.scatter(height_d, np.maximum(local, 1e-8), s=2, alpha=0.5, color="black", marker="x",
                   label="local displacement")
    ax.set_yscale("log")
    ax.axhline(0.1, color="gray", ls="--", lw=1)
    ax.set_xlabel("BTR height of centre / mean diameter")
    ax.set_ylabel("displacement / mean diameter")
    ax.legend(loc="best", fontsize=8)
    return save_figure(fig, path)


def curves(path, series, xlabel, ylabel, title="", logx=False, logy=False, styles=None):
    """series: list of (label, x, y)."""
    fig, ax = plt.subplots(figsize=(6, 4))
    for k, (label, x, y) in enumerate(series):
        if y is None or len(y) == 0:
            continue
        kw = (styles or {}).get(label, {})
        ax.plot(x, y, label=label, **kw)
    if logx:
        ax.set_xscale("log")
    if logy:
        ax.set_yscale("log")
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    if title:
        ax.set_title(title)
    if ax.get_legend_handles_labels()[0]:
        ax.legend(loc="best", fontsize=8)
    else:
        ax.text(0.5, 0.5, "no data (empty bulk window?)", transform=ax.transAxes, ha="center", va="center")
    return save_figure(fig, path)
