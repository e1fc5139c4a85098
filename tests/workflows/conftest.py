"""Shared fixtures for the workflow tests (run by ctest with BTR_BINARY and BTR_SOURCE_DIR set)."""
import os
import shutil
import sys
from pathlib import Path

import pytest

SOURCE = Path(os.environ.get("BTR_SOURCE_DIR", Path(__file__).resolve().parents[2]))
sys.path.insert(0, str(SOURCE / "workflows"))


@pytest.fixture(scope="session")
def source_dir() -> Path:
    return SOURCE


@pytest.fixture(scope="session")
def btr_binary() -> str:
    """The btr program; the test is skipped (with the reason) only when BTR_BINARY is not set."""
    path = os.environ.get("BTR_BINARY")
    if not path:
        pytest.skip("BTR_BINARY is not set (ctest sets it to the built btr program)")
    assert os.access(path, os.X_OK), f"BTR_BINARY={path} is not an executable file"
    return path


@pytest.fixture(scope="session")
def liggghts() -> str:
    path = shutil.which("liggghts")
    assert path, "liggghts is not on PATH (Debian package liggghts, installed by scripts/setup.sh)"
    return path


@pytest.fixture(scope="session")
def yade() -> str:
    path = shutil.which("yade")
    assert path, "yade is not on PATH (Debian package yade, installed by scripts/setup.sh)"
    return path
