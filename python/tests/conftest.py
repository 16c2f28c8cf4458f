"""Shared fixtures: the bundled datasets and the command, as CTest passes them."""
import json
import os
import pathlib
import subprocess

import pytest

DATASETS = pathlib.Path(
    os.environ.get("ROVERMAP_DATASETS_DIR", pathlib.Path(__file__).resolve().parents[2] / "datasets"))


@pytest.fixture
def datasets():
    return DATASETS


@pytest.fixture
def rovermap_exe():
    exe = os.environ.get("ROVERMAP_EXECUTABLE")
    if not exe or not os.access(exe, os.X_OK):
        pytest.fail("ROVERMAP_EXECUTABLE must name the built command (CTest sets it)")
    return exe


def run_command(exe, *args):
    """Runs the command; returns (exit status, stdout parsed as JSON or None, stderr)."""
    proc = subprocess.run([exe, *map(str, args)], capture_output=True, text=True, check=False)
    try:
        out = json.loads(proc.stdout)
    except json.JSONDecodeError:
        out = None
    return proc.returncode, out, proc.stderr
