#!/usr/bin/env python3
"""hattr as a lab installs it (issue 63): `cmake --install` into a fresh prefix, the prefix moved
elsewhere (nothing may depend on where it was installed), the source and build trees hidden
(an empty tmpfs mounted over them in a private mount namespace), and then, from the prefix alone:
`hattr paths`, a glyph, the plugins, `hattr demo`, `import hattr`, the studio under Xvfb, the pen
emulator with its installed firmware, and a C++ program built with find_package(hattr).

Usage: install_test.py --build-dir BUILD --source-dir SOURCE [--keep]
"""
from __future__ import annotations

import argparse
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HIDDEN_MARK = "HATTR_INSTALL_TEST_HIDDEN"
SKIPPED = 77  # ctest's SKIP_RETURN_CODE for this test


def fail(message: str) -> None:
    print(f"install_test: FAILED: {message}", file=sys.stderr)
    sys.exit(1)


def run(cmd: list[str], *, env: dict[str, str], cwd: Path, timeout: float = 300, ok=(0,)) -> subprocess.CompletedProcess:
    """Runs `cmd` in a session of its own, so that a time-out stops everything it started (xvfb-run's
    X server and program too)."""
    print("install_test: $ " + " ".join(str(c) for c in cmd), flush=True)
    process = subprocess.Popen([str(c) for c in cmd], env=env, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                               text=True, start_new_session=True)
    try:
        stdout, stderr = process.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(process.pid, signal.SIGKILL)
        process.communicate()
        fail(f"{cmd[0]} did not finish within {timeout} s")
    done = subprocess.CompletedProcess(process.args, process.returncode, stdout, stderr)
    if done.returncode not in ok:
        fail(f"{cmd[0]} exited {done.returncode}\nstdout:\n{done.stdout[-4000:]}\nstderr:\n{done.stderr[-4000:]}")
    return done


def parsed_json(done: subprocess.CompletedProcess, what: str) -> dict:
    try:
        return json.loads(done.stdout)
    except json.JSONDecodeError:
        fail(f"{what}: expected JSON, got:\n{done.stdout[-2000:]}\nstderr:\n{done.stderr[-2000:]}")
        raise


def install(build: Path, prefix: Path) -> None:
    """Every component into `prefix`, then the prefix moved: a relocated install must work too."""
    staged = prefix.with_name(prefix.name + "-as-installed")
    run(["cmake", "--install", build.resolve(), "--prefix", staged], env=dict(os.environ), cwd=build, timeout=600)
    staged.rename(prefix)


def hide_trees_and_rerun(args: argparse.Namespace, work: Path) -> int:
    """Runs this script again in a private mount namespace where an empty tmpfs covers the source
    and build trees, so that nothing of them can be read (as root; else as a mapped root user)."""
    hidden = [args.source_dir.resolve()]
    if not args.build_dir.resolve().is_relative_to(hidden[0]):
        hidden.append(args.build_dir.resolve())
    # The folders to hide come after the command, as arguments: no quoting of paths in the script.
    mounts = 'for folder in "$@"; do case $folder in --) shift; break;; esac; ' \
             'mount -t tmpfs hattr-hidden "$folder" || exit 1; shift; done; exec "$@"'
    unshare = ["unshare", "--mount", "--propagation", "private"]
    if os.geteuid() != 0:
        unshare.insert(1, "--map-root-user")
    if shutil.which("unshare") is None:
        fail("unshare is missing (Debian's util-linux): the trees cannot be hidden")
    if subprocess.run(unshare + ["true"], capture_output=True).returncode != 0:
        print("install_test: SKIPPED: no private mount namespace can be made here (not root, and unprivileged "
              "user namespaces are off: sysctl kernel.unprivileged_userns_clone): the trees cannot be hidden")
        return SKIPPED
    env = dict(os.environ, **{HIDDEN_MARK: "1"})
    script = work / "install_test.py"  # this script, readable once its tree is hidden
    shutil.copy2(__file__, script)
    cmd = unshare + ["sh", "-c", mounts, "sh", *[str(f) for f in hidden], "--", sys.executable, str(script),
                     "--build-dir", str(args.build_dir), "--source-dir", str(args.source_dir), "--work", str(work)]
    # From the work folder: a working folder inside a hidden tree would still read it through ".".
    return subprocess.run(cmd, env=env, cwd=work).returncode


def clean_env(prefix: Path, home: Path) -> dict[str, str]:
    """The environment of a lab's shell: the prefix's bin on PATH, no HATTR_* variable, no
    PYTHONPATH but the prefix's own, nothing of the build."""
    env = {k: v for k, v in os.environ.items()
           if not k.startswith("HATTR_") and k not in ("PYTHONPATH", "LD_LIBRARY_PATH", "QT_QPA_PLATFORM")}
    env["PATH"] = f"{prefix / 'bin'}:/usr/bin:/bin"
    env["HOME"] = str(home)
    env["XDG_CONFIG_HOME"] = str(home / ".config")
    return env


def python_site(prefix: Path) -> Path:
    sites = sorted(prefix.glob("lib/python3*/dist-packages")) + sorted(prefix.glob("lib/python3/dist-packages"))
    if not sites or not (sites[0] / "hattr").is_dir():
        fail(f"no hattr Python package under {prefix}/lib/python3*/dist-packages")
    return sites[0]


def check_paths(prefix: Path, env: dict[str, str], cwd: Path) -> None:
    paths = parsed_json(run(["hattr", "paths", "--json"], env=env, cwd=cwd), "hattr paths --json")
    share = prefix / "share" / "hattr"
    if Path(paths["share_dir"]) != share or Path(paths["data_dir"]) != share or paths["data_dir_from"] != "prefix":
        fail(f"hattr paths: expected the data in {share}, got {paths}")
    if not any(Path(p).is_relative_to(prefix) for p in paths["plugin_search_path"]):
        fail(f"hattr paths: expected a plugin folder under {prefix}, got {paths['plugin_search_path']}")
    if not Path(paths["firmware"]).is_relative_to(share):
        fail(f"hattr paths: expected the firmware under {share}, got {paths['firmware']!r}")


def check_cli(env: dict[str, str], cwd: Path) -> None:
    run(["hattr", "sim", "expert", "--glyph", "a", "-o", "a.csv"], env=env, cwd=cwd)
    info = parsed_json(run(["hattr", "profile", "info", "a.csv", "--json"], env=env, cwd=cwd), "hattr profile info")
    if int(info.get("samples", 0)) < 100:
        fail(f"hattr sim expert --glyph a: expected a profile of the letter, got {info}")
    listed = run(["hattr", "devices"], env=env, cwd=cwd).stdout
    for plugin in ("sim", "replay"):
        if f"  {plugin} " not in listed:
            fail(f"hattr devices: expected the installed plugin {plugin} listed, got:\n{listed}")
    run(["hattr", "record", "--device", "plugin:sim", "--hand", "a.csv", "-o", "take.csv"], env=env, cwd=cwd)
    demo = run(["hattr", "demo", "--out", "demo-out"], env=env, cwd=cwd, timeout=600)
    if not (cwd / "demo-out" / "report.html").is_file() or "Table 1" not in demo.stdout:
        fail(f"hattr demo: expected demo-out/report.html and Table 1, got:\n{demo.stdout[-2000:]}")


def check_python(prefix: Path, env: dict[str, str], cwd: Path) -> None:
    site = python_site(prefix)
    code = ("import hattr, json, sys; "
            "r = hattr.simulate_study('py-study', subjects=2, training_trials=1, recall_trials=2, glyph='a', "
            "write_report=False); print(json.dumps({'file': hattr.__file__, 'trials': r['trials']}))")
    out = parsed_json(run(["/usr/bin/python3", "-c", code], env=dict(env, PYTHONPATH=str(site)), cwd=cwd), "import hattr")
    if not Path(out["file"]).is_relative_to(prefix) or out["trials"] <= 0:
        fail(f"import hattr: expected the prefix's module running a study, got {out}")


def check_studio(prefix: Path, env: dict[str, str], cwd: Path) -> None:
    studio = prefix / "bin" / "hattr-studio"
    if not studio.is_file():
        print("install_test: no hattr-studio in this build (HATTR_BUILD_STUDIO=OFF): skipped")
        return
    if shutil.which("xvfb-run") is None:
        fail("xvfb-run is missing: install Debian's xvfb (scripts/install-deps does)")
    shot = cwd / "studio-installed.png"
    run(["xvfb-run", "-a", "-s", "-screen 0 1280x800x24", studio, "--tab", "record", "--screenshot", shot],
        env=dict(env, QT_QPA_PLATFORM="xcb"), cwd=cwd, timeout=120)
    if not shot.is_file() or shot.stat().st_size < 10_000:
        fail(f"hattr-studio --screenshot: expected a picture of the window in {shot}")


def check_emulator(prefix: Path, env: dict[str, str], cwd: Path) -> None:
    if not (prefix / "bin" / "hattr-pen-emulator").is_file():
        print("install_test: no hattr-pen-emulator in this build (simavr missing): skipped")
        return
    link = cwd / "pen.tty"
    log = (cwd / "emulator.out").open("w"), (cwd / "emulator.err").open("w")  # files: nothing fills a pipe
    emulator = subprocess.Popen(["hattr-pen-emulator", "--hangups", "1", "--link", str(link)], env=env, cwd=cwd,
                                stdout=log[0], stderr=log[1], text=True)
    try:
        for _ in range(200):
            if link.exists() or emulator.poll() is not None:
                break
            time.sleep(0.05)
        if not link.exists():
            fail(f"hattr-pen-emulator without --firmware: no pseudo-terminal; stderr:\n{(cwd / 'emulator.err').read_text()}")
        check = run(["hattr", "devices", "check", f"serial://{link}?lockstep=1", "--no-confirm", "--seconds", "1", "--json"],
                    env=env, cwd=cwd, ok=(0, 1))
        if parsed_json(check, "hattr devices check").get("limits") is None:
            fail(f"hattr devices check on the emulated pen: expected its limits, got {check.stdout[:2000]}")
        code = emulator.wait(timeout=60)
        if code != 0:
            fail(f"hattr-pen-emulator --hangups 1 exited {code}: {(cwd / 'emulator.err').read_text()[-2000:]}")
    finally:
        if emulator.poll() is None:
            emulator.send_signal(signal.SIGTERM)
            emulator.wait(timeout=10)
        for f in log:
            f.close()


CONSUMER_CMAKE = """cmake_minimum_required(VERSION 3.25)
project(consumer LANGUAGES CXX)
set(CMAKE_CXX_STANDARD 20)
find_package(hattr 0.1 REQUIRED)
add_executable(consumer main.cpp)
target_link_libraries(consumer PRIVATE hattr::sim hattr::analysis)
target_compile_definitions(consumer PRIVATE "CONSUMER_SHARE_DIR=\\"${hattr_SHARE_DIR}\\"")
"""

CONSUMER_MAIN = """#include <cstdio>
#include <vector>
#include "hattr/analysis/dtw.hpp"
#include "hattr/sim/glyph.hpp"
int main() {
  const hattr::sim::Glyph glyph = hattr::sim::loadGlyph(CONSUMER_SHARE_DIR "/glyphs/na.json");
  const std::vector<double> a{0.0, 1.0, 2.0, 1.0}, b{0.0, 1.0, 1.0, 2.0, 1.0};
  std::printf("%zu %s %g\\n", glyph.strokes.size(), glyph.name.c_str(), hattr::analysis::dtwDistance(a, b));
  return 0;
}
"""


def check_find_package(prefix: Path, env: dict[str, str], cwd: Path) -> None:
    project = cwd / "consumer"
    project.mkdir()
    (project / "CMakeLists.txt").write_text(CONSUMER_CMAKE)
    (project / "main.cpp").write_text(CONSUMER_MAIN)
    run(["cmake", "-S", project, "-B", project / "build", f"-DCMAKE_PREFIX_PATH={prefix}"], env=env, cwd=cwd)
    run(["cmake", "--build", project / "build"], env=env, cwd=cwd, timeout=600)
    printed = run([project / "build" / "consumer"], env=env, cwd=cwd).stdout.split()
    if len(printed) != 3 or printed[1] != "na" or int(printed[0]) < 1 or float(printed[2]) != 0.0:
        fail(f"a program built with find_package(hattr): expected the glyph na and a DTW cost 0, got {printed}")


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--build-dir", type=lambda p: Path(p).resolve(), required=True)
    parser.add_argument("--source-dir", type=lambda p: Path(p).resolve(), required=True)
    parser.add_argument("--work", type=Path, help="(internal) the folder made before the trees were hidden")
    parser.add_argument("--keep", action="store_true", help="Keep the scratch folder")
    args = parser.parse_args()

    if os.environ.get(HIDDEN_MARK) != "1":
        work = Path(tempfile.mkdtemp(prefix="hattr-install-"))
        try:
            install(args.build_dir, work / "opt-hattr")
            code = hide_trees_and_rerun(args, work)
        finally:
            if not args.keep:
                shutil.rmtree(work, ignore_errors=True)
            else:
                print(f"install_test: kept {work}")
        return code

    # From here on the source and build trees are an empty tmpfs.
    if any(args.source_dir.resolve().iterdir()):
        fail(f"the source tree {args.source_dir} is still visible")
    prefix = args.work / "opt-hattr"
    home = args.work / "home"
    home.mkdir()
    env = clean_env(prefix, home)
    check_paths(prefix, env, args.work)
    check_cli(env, args.work)
    check_python(prefix, env, args.work)
    check_studio(prefix, env, args.work)
    check_emulator(prefix, env, args.work)
    check_find_package(prefix, env, args.work)
    print("install_test: the installed hattr works from its prefix alone")
    return 0


if __name__ == "__main__":
    sys.exit(main())
