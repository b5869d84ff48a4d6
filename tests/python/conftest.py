"""Fixtures of the Python module's tests: the hattr command to compare with, a simulated
expert and its script, and a small simulated study. ctest sets HATTR_CLI, HATTR_BUILD_DIR and
PYTHONPATH (tests/CMakeLists.txt)."""

import json
import os
import pathlib
import subprocess

import pytest

import hattr

SOURCE_DIR = pathlib.Path(os.environ.get("HATTR_SOURCE_DIR", pathlib.Path(__file__).resolve().parents[2]))
SHARED_SVC2004 = SOURCE_DIR.parent / "shared" / "data" / "svc2004-task2"


def cli_path():
    path = os.environ.get("HATTR_CLI")
    if not path:
        pytest.fail("HATTR_CLI is not set: run these tests through ctest (make test)")
    return path


def run_cli(*args, expect=0):
    """Runs the hattr command; returns (stdout, stderr). Fails unless it exits with `expect`."""
    done = subprocess.run([cli_path(), *map(str, args)], capture_output=True, text=True, timeout=300)
    assert done.returncode == expect, f"hattr {' '.join(map(str, args))} exited {done.returncode}: {done.stderr}"
    return done.stdout, done.stderr


def cli_json(*args):
    return json.loads(run_cli(*args, "--json")[0])


@pytest.fixture(scope="session")
def expert_files(tmp_path_factory):
    """The simulated expert writing 'na' (the study's reference) and the script they meant."""
    folder = tmp_path_factory.mktemp("expert")
    expert, script = folder / "expert.csv", folder / "script.csv"
    run_cli("sim", "expert", "-o", expert, "--script-out", script)
    return expert, script


@pytest.fixture(scope="session")
def small_study(tmp_path_factory):
    """A small simulated study (2 subjects, 1 training and 3 recall trials per mode), run
    through Python, and the database's path."""
    out = tmp_path_factory.mktemp("study")
    result = hattr.simulate_study(out, subjects=2, training_trials=1, recall_trials=3, write_report=False)
    return result
