"""The package itself: its stubs name what the module has, every function says what it does,
and `cmake --install` puts an importable package where the interpreter looks."""

import ast
import os
import pathlib
import subprocess
import sys

import pytest

import hattr


def stub_names():
    stub = pathlib.Path(hattr.__file__).with_name("__init__.pyi")
    tree = ast.parse(stub.read_text())
    names = set()
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.ClassDef)):
            names.add(node.name)
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            names.add(node.target.id)
    return names


def test_the_stubs_declare_every_public_name_and_nothing_else():
    declared = stub_names()
    missing = [name for name in hattr.__all__ if name not in declared]
    assert not missing, f"in hattr.__all__ but not in __init__.pyi: {missing}"
    public_in_module = {name for name in dir(hattr._hattr) if not name.startswith("_")}
    assert set(hattr.__all__) == public_in_module, "hattr.__all__ and the extension's names differ"
    # Records (TypedDicts) and private aliases exist only in the stubs; everything else must exist.
    invented = [n for n in declared - set(hattr.__all__) if not n.startswith("_") and n not in RECORD_TYPES]
    assert not invented, f"declared in __init__.pyi but not in the module: {invented}"


RECORD_TYPES = {"TrialScore", "AnovaRow", "TukeyComparison", "GroupStats", "SubjectRecord", "TrialRecord", "TrialRun",
                "SimulatedStudy"}


def test_every_function_and_class_has_a_docstring():
    undocumented = [name for name in hattr.__all__ if not (getattr(hattr, name).__doc__ or "").strip()]
    assert not undocumented


def test_cmake_install_puts_an_importable_package_where_python_looks(tmp_path):
    build = os.environ.get("HATTR_BUILD_DIR")
    if not build:
        pytest.fail("HATTR_BUILD_DIR is not set: run these tests through ctest (make test)")
    prefix = tmp_path / "prefix"
    subprocess.run(["cmake", "--install", build, "--component", "python", "--prefix", prefix], check=True,
                   capture_output=True)
    version = f"python{sys.version_info.major}.{sys.version_info.minor}"
    site = prefix / "lib" / version / "dist-packages"
    assert (site / "hattr" / "__init__.pyi").is_file() and (site / "hattr" / "py.typed").is_file()
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    env["PYTHONPATH"] = str(site)
    done = subprocess.run([sys.executable, "-c", "import hattr; print(hattr.__file__, hattr.dtw([1.0, 2.0], [1.0, 3.0]))"],
                          env=env, capture_output=True, text=True, check=True)
    location, cost = done.stdout.split()
    assert pathlib.Path(location).is_relative_to(site) and float(cost) == 1.0
