"""The package itself: its stubs name what the module has, every function says what it does,
and `cmake --install` puts an importable package where the interpreter looks."""

import ast
import os
import pathlib
import subprocess
import sys

import pytest

import hattr


STUB = pathlib.Path(hattr.__file__).with_name("__init__.pyi")


def stub_tree():
    return ast.parse(STUB.read_text())


def stub_names():
    names = set()
    for node in stub_tree().body:
        if isinstance(node, (ast.FunctionDef, ast.ClassDef)):
            names.add(node.name)
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            names.add(node.target.id)
    return names


def test_the_stubs_declare_every_public_name_and_nothing_else():
    declared = {name for name in stub_names() if not name.startswith("_")}  # _Records are stub-only types
    public_in_module = {name for name in dir(hattr._hattr) if not name.startswith("_")}
    assert set(hattr.__all__) == public_in_module, "hattr.__all__ and the extension's names differ"
    assert declared == set(hattr.__all__), f"stubs only: {declared - public_in_module}, module only: " \
                                           f"{public_in_module - declared}"


def stub_parameters(function):
    """The parameter names of a stub def, '*' where keyword-only ones begin; self left out."""
    args = function.args
    names = [a.arg for a in args.posonlyargs + args.args if a.arg != "self"]
    if args.vararg:
        names.append("*" + args.vararg.arg)
    elif args.kwonlyargs:
        names.append("*")
    return names + [a.arg for a in args.kwonlyargs]


def module_parameters(obj):
    """The same from pybind11's signature line (the docstring's first line)."""
    line = obj.__doc__.split("\n", 1)[0]
    inside = line[line.index("(") + 1:line.rindex(") ->")]
    names, depth, current = [], 0, ""
    for ch in inside + ",":
        if ch in "([{":
            depth += 1
        elif ch in ")]}":
            depth -= 1
        if ch == "," and depth == 0:
            name = current.strip().split(":")[0].split("=")[0].strip()
            if name and name != "self":
                names.append(name)
            current = ""
        else:
            current += ch
    return names


def test_the_stub_signatures_match_the_module():
    checked = 0
    for node in stub_tree().body:
        members = [(node.name, node)] if isinstance(node, ast.FunctionDef) else []
        if isinstance(node, ast.ClassDef) and not node.name.startswith("_") and not issubclass(
                getattr(hattr, node.name), BaseException):
            members = [(f"{node.name}.{f.name}", f) for f in node.body if isinstance(f, ast.FunctionDef)
                       and not any(isinstance(d, ast.Name) and d.id == "property" for d in f.decorator_list)
                       and (not f.name.startswith("__") or f.name == "__init__")]
        for qualified, function in members:
            obj = hattr
            for part in qualified.split("."):
                obj = getattr(obj, part)
            assert stub_parameters(function) == module_parameters(obj), qualified
            checked += 1
    assert checked > 30


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
