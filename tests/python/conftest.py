"""Fixtures of the Python module's tests: the hattr command to compare with, a simulated
expert and its script, and a small simulated study. ctest sets HATTR_CLI, HATTR_BUILD_DIR and
PYTHONPATH (tests/CMakeLists.txt)."""

import json
import os
import pathlib
import shutil
import subprocess
import tempfile

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


class PostgresServer:
    """A throwaway PostgreSQL server for the tests (as tests/support/postgres_cluster.hpp):
    initdb and pg_ctl in a temporary folder, a Unix socket there only, trust authentication;
    as root, run by the unprivileged `postgres` user (PostgreSQL refuses root)."""

    def __init__(self, folder):
        # Debian's server binaries (the newest version), else the ones on PATH.
        binaries = sorted(pathlib.Path("/usr/lib/postgresql").glob("*/bin/initdb"),
                          key=lambda p: int(p.parent.parent.name) if p.parent.parent.name.isdigit() else 0)
        if binaries:
            self.bin = binaries[-1].parent
        elif shutil.which("initdb") and shutil.which("createdb"):
            self.bin = pathlib.Path(shutil.which("initdb")).parent
        else:
            pytest.fail("the PostgreSQL tests need a PostgreSQL server's initdb and pg_ctl: install Debian's "
                        "postgresql package (scripts/install-deps)")
        self.as_user = ["runuser", "-u", "postgres", "--"] if os.geteuid() == 0 else []
        self.folder = pathlib.Path(folder)
        if os.geteuid() == 0:
            shutil.chown(self.folder, user="postgres")
        self._run("initdb", "-D", self.folder / "data", "--auth=trust", "--username=postgres", "--no-instructions")
        self._run("pg_ctl", "-D", self.folder / "data", "-l", self.folder / "server.log", "-w", "-o",
                  f"-k {self.folder} -c listen_addresses='' -c fsync=off", "start")
        self.count = 0

    def _run(self, tool, *args):
        subprocess.run([*self.as_user, str(self.bin / tool), *map(str, args)], check=True, capture_output=True)

    def create_database(self, prefix):
        """A new empty database; its address (no password: the server trusts the socket)."""
        self.count += 1
        name = f"{prefix}_{os.getpid()}_{self.count}"
        self._run("createdb", "-h", self.folder, "-U", "postgres", name)
        return f"postgresql:///{name}?host={self.folder}&user=postgres"

    def stop(self):
        subprocess.run([*self.as_user, str(self.bin / "pg_ctl"), "-D", str(self.folder / "data"), "-m", "immediate",
                        "stop"], capture_output=True)


@pytest.fixture(scope="session")
def postgres_server():
    folder = tempfile.mkdtemp(prefix="hattr-pg-")
    server = PostgresServer(folder)
    yield server
    server.stop()
    shutil.rmtree(folder, ignore_errors=True)
