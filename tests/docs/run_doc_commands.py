#!/usr/bin/env python3
"""Runs the commands of one Markdown page (README.md, docs/*.md) the way a reader would.

The page's fenced blocks say what they are by their info string:

  ```sh        commands, run in order in one shell in a scratch folder laid out like a clone
               (variables and files carry from block to block). A block whose first line is
               "# not runnable here: REASON", or right below the comment line
               "<!-- not runnable here: REASON -->", is skipped, and REASON is printed.
  ```python    a Python script, run after the sh blocks above it and before those below, by the
               interpreter running this one, with the build's hattr package importable; each
               python block runs on its own (define what it uses). Skipped as a sh block is.
  ```output    lines the sh or python block just above prints, in order, each a whole line (leading and
               trailing blanks aside); "..." stands for any text (numbers that change from run
               to run; a line's start or end).
  ```synopsis  usage lines ("hattr CMD [--option ...]"): each command must exist and each
               --option must appear in its --help.

Any other block (json, cpp, text, diagrams) is not run; an unlabelled block that starts like a
command, or a block labelled bash, shell or console, fails the page (say sh, synopsis or output).
A block that reads ../shared/data (the SVC2004 recordings) is skipped, saying so, when the data
is absent.

A long page can run as several tests (so that no test takes more than a minute): the sh blocks
right below a comment line "<!-- doc-test: own test NAME -->" run in a test of their own
(--part NAME), in page order in their own scratch folder, and the page's test leaves them out.
"<!-- doc-test: own test NAME, after "TEXT" and "TEXT2" -->" first runs the earlier blocks that
contain each TEXT, the nearest one each (what the part needs: a variable, a file; not followed
further, so name every block it needs). The page's test checks that the
page's parts are the ones ctest runs (--parts NAME,NAME, tests/CMakeLists.txt). Each test
prints the blocks that took 2 s or more.

What fails a block: a command whose exit status is not 0, as bash's ERR trap sees it (not the
left side of && or ||, nor a command in an if condition).

Exit status: 0 every command ran and matched; 1 a command failed or an output or synopsis
did not match (the message names the page and line); 2 the page itself is malformed; 77 the
page reads the shared data folder (../shared/data) and it is absent here (ctest: skipped).
"""

from __future__ import annotations

import argparse
import os
import re
import shlex
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

SKIP_MARK = re.compile(r"^(?:#\s*)?not runnable here(?: as written)?:\s*(.*)$")
OWN_TEST = re.compile(r"^<!--\s*doc-test: own test ([a-z0-9-]+)(?:, after (.*?))?\s*-->$")
COMMAND_START = re.compile(r"^\s*(\$?hattr\b|build/|\./|make\b|cmake\b|ctest\b|python3?\b|time\b|/usr/bin/|cd\b|sudo\b|apt(-get)?\b)")
RUNNABLE_LABELS = {"sh", "python"}  # run in order; python blocks by the interpreter running this script
SHELL_LABELS = {"bash", "shell", "console", "zsh", "shell-session", "sh-session"}
COMMAND_WORD = re.compile(r"^[a-z][a-z0-9-]*$")
OPTION = re.compile(r"(?<![\w-])(--[a-z][a-z0-9-]*)")
SKIPPED_EXIT = 77


@dataclass
class Block:
    info: str            # the info string's first word ("" when unlabelled)
    line: int            # 1-based line of the opening fence
    lines: list[str]     # the content
    after_sh: bool = False  # directly below a sh or python block (blank lines between at most)
    note: str = ""          # the line just above the fence when it is an HTML comment

    def content_line(self, i: int) -> int:
        """The page's line number of content line i (0-based)."""
        return self.line + 1 + i


@dataclass
class Page:
    path: Path
    name: str
    blocks: list[Block] = field(default_factory=list)


class PageError(Exception):
    """The page itself is malformed (exit 2)."""


def parse_page(path: Path, name: str) -> Page:
    """Splits the page into its fenced blocks."""
    page = Page(path, name)
    text = path.read_text(encoding="utf-8").split("\n")
    i = 0
    last_block_end = -10
    last_kind = ""
    while i < len(text):
        opening = re.match(r"^(\s*)(`{3,}|~{3,})\s*([^\s`]*)(.*)$", text[i])
        if not opening:
            i += 1
            continue
        fence = opening.group(2)
        j = i + 1
        while j < len(text) and not re.match(r"^\s*" + re.escape(fence[0]) + "{" + str(len(fence)) + r",}\s*$", text[j]):
            j += 1
        if j == len(text):
            raise PageError(f"{name}:{i + 1}: a fenced block is never closed")
        blank_between = all(not t.strip() for t in text[last_block_end + 1:i])
        above = text[i - 1].strip() if i > 0 else ""
        block = Block(opening.group(3).lower(), i + 1, text[i + 1:j], blank_between and last_kind in RUNNABLE_LABELS,
                      above if above.startswith("<!--") else "")
        page.blocks.append(block)
        last_block_end, last_kind = j, block.info
        i = j + 1
    return page


def check_page_form(page: Page) -> None:
    """Refuses blocks that would hide a command from the test."""
    for b in page.blocks:
        first = next((l for l in b.lines if l.strip() and not l.strip().startswith("#")), "")
        if b.info in SHELL_LABELS:
            raise PageError(f"{page.name}:{b.line}: a block labelled {b.info!r}: label commands sh (run), "
                            f"synopsis (usage) or output")
        if b.info == "" and COMMAND_START.match(first):
            raise PageError(f"{page.name}:{b.line}: an unlabelled block starts like a command "
                            f"({first.strip()!r}): label it sh (run), synopsis (usage) or output")
        if b.info == "output" and not b.after_sh:
            raise PageError(f"{page.name}:{b.line}: an output block must follow a sh or python block (blank lines between at most)")
        if b.info in RUNNABLE_LABELS and skip_reason(b) == "":
            raise PageError(f"{page.name}:{b.line}: \"not runnable here\" needs its reason")


def skip_reason(block: Block) -> str | None:
    """Why a sh block is not run here, or None."""
    note = re.match(r"^<!--\s*(.*?)\s*-->$", block.note)
    for text in ([note.group(1)] if note else []) + block.lines[:1]:
        skip = SKIP_MARK.match(text.strip())
        if skip:
            return skip.group(1).strip()
    return None


def own_test_part(block: Block) -> tuple[str, list[str]] | None:
    """For a block marked to run in a test of its own: the part's name and the texts naming the
    earlier blocks it needs (maybe none); None for any other block."""
    mark = OWN_TEST.match(block.note)
    if mark is None:
        return None
    return mark.group(1), re.findall(r'"([^"]+)"', mark.group(2) or "")


def check_marks(page: Page) -> None:
    """Refuses a "doc-test:" comment that is not a well-formed own-test mark (a typo would
    otherwise leave its block in the page's test, or a need unmet)."""
    for b in page.blocks:
        if re.match(r"^<!--\s*doc-test:", b.note) and own_test_part(b) is None:
            raise PageError(f"{page.name}:{b.line - 1}: expected <!-- doc-test: own test NAME --> or "
                            f"<!-- doc-test: own test NAME, after \"TEXT\" and \"TEXT\" --> (NAME: a-z, 0-9, -), "
                            f"got {b.note}")


def blocks_of_part(page: Page, runnable: list[tuple[int, Block]], part: str, parts: list[str]) -> list[tuple[int, Block]]:
    """The runnable blocks of one part of the page: part "" is the page without its own-test
    blocks (and checks that its parts are `parts`), part NAME the blocks marked with NAME, after
    the blocks they need."""
    marked = [(k, b, own_test_part(b)) for k, b in enumerate(page.blocks) if b.info in RUNNABLE_LABELS]
    marked = [(k, b, m) for k, b, m in marked if m is not None]
    names = list(dict.fromkeys(m[0] for _, _, m in marked))
    if part == "":
        if sorted(names) != sorted(parts):
            raise PageError(f"{page.name}: its own-test parts are {', '.join(names) or 'none'}, but ctest runs "
                            f"{', '.join(parts) or 'none'} besides the page: name them in tests/CMakeLists.txt "
                            f"(hattr_doc_parts)")
        return [(k, b) for k, b in runnable if own_test_part(b) is None]
    if part not in names:
        raise PageError(f"{page.name}: --part {part}: no block is marked \"doc-test: own test {part}\"")
    mine = [(k, b, m) for k, b, m in marked if m[0] == part]
    if not any(k == k_own for k_own, _, _ in mine for k, _ in runnable):
        return []  # every block of the part skipped (not runnable here, or its data absent)
    chosen = set()
    for k_own, own_block, (_, needs) in mine:
        for text in needs:
            # The nearest earlier block with the text (needs are not followed further).
            found = next(((k, b) for k, b in reversed(runnable) if k < k_own and any(text in l for l in b.lines)), None)
            if found is None:
                raise PageError(f"{page.name}:{own_block.line}: needs an earlier block with {text!r}: there is none")
            chosen.add(found[0])
    chosen |= {k for k, _, _ in mine}
    return [(k, b) for k, b in runnable if k in chosen]


def tracked_entries(source: Path) -> list[str]:
    """The source tree's top-level entries under version control (what a clone has), so a
    page's outputs never land on a developer's own files of the same name; without git, every
    entry but the build, demo and git folders."""
    listed = subprocess.run(["git", "-C", str(source), "ls-files"], capture_output=True, text=True)
    if listed.returncode == 0 and listed.stdout.strip():
        return sorted({line.split("/", 1)[0] for line in listed.stdout.splitlines() if line})
    return sorted(e.name for e in source.iterdir() if e.name not in {"build", ".git", "demo-out"})


def make_scratch(source: Path, hattr: Path, build: Path, shared: Path | None) -> tuple[Path, Path]:
    """A scratch folder laid out like a clone beside ../shared: the source tree's entries by
    link, and build/release/ holding copies of the programs under test (copies, so nothing a
    page runs can write into the real build tree), and bin/ with hattr and python3 on PATH."""
    root = Path(tempfile.mkdtemp(prefix="hattr-doc-"))
    clone = root / "hattr"
    clone.mkdir()
    for name in tracked_entries(source):
        (clone / name).symlink_to(source / name)
    release = clone / "build" / "release"
    (release / "apps" / "hattr").mkdir(parents=True)
    shutil.copy2(hattr, release / "apps" / "hattr" / "hattr")
    for sub, pattern in [("bench", "bench_*"), ("apps/pen-emulator", "hattr-pen-emulator")]:
        (release / sub).mkdir(parents=True, exist_ok=True)
        for program in sorted((build / sub).glob(pattern)) if (build / sub).is_dir() else []:
            if program.is_file():
                shutil.copy2(program, release / sub / program.name)
    # The build folder is a prefix (share/hattr: data and firmware; LIBDIR/hattr/plugins): the
    # copied programs find them relative to themselves, as an installed hattr does.
    if (build / "share").is_dir():
        shutil.copytree(build / "share", release / "share")
    for plugins in sorted(build.glob("lib*/**/hattr/plugins")):
        shutil.copytree(plugins, release / plugins.relative_to(build))
    if (build / "python" / "hattr").is_dir():  # the Python package, for python blocks
        shutil.copytree(build / "python", release / "python")
    if shared is not None and shared.is_dir():
        (root / "shared").symlink_to(shared)
    (root / "bin").mkdir()
    (root / "bin" / "hattr").symlink_to(release / "apps" / "hattr" / "hattr")
    # python3 is the interpreter the build chose (running this script), whatever else is on PATH.
    (root / "bin" / "python3").symlink_to(sys.executable)
    return root, clone


def stop_leftovers(root: Path) -> None:
    """Stops every process still working inside the scratch folder (a server a page left
    running, the jobs of a build tool that gives each its own process group)."""
    for proc in Path("/proc").iterdir():
        if not proc.name.isdigit():
            continue
        try:
            cwd = os.readlink(proc / "cwd")
        except OSError:
            continue
        if cwd == str(root) or cwd.startswith(str(root) + "/"):
            try:
                os.kill(int(proc.name), signal.SIGKILL)
            except (ProcessLookupError, PermissionError):
                pass


def build_script(page: Page, runnable: list[tuple[int, Block]], out_dir: Path, fail_file: Path) -> tuple[str, dict[int, int]]:
    """One bash script running every runnable block in order, each block's output to its own
    file; returns the script and a map from script line to page line."""
    lines = [
        "set -o pipefail",
        "set -E",
        f"__doc_fail() {{ echo \"$1 $2\" > {shlex.quote(str(fail_file))}; exit 1; }}",
        "trap '__doc_fail $LINENO $?' ERR",
    ]
    page_line: dict[int, int] = {}
    for k, block in runnable:
        lines.append(f"echo {k} > {shlex.quote(str(out_dir / 'current'))}")
        # Each block's start time, so the runner can say which blocks take the page's time.
        lines.append(f"date +%s.%N > {shlex.quote(str(out_dir / f'{k}.start'))}")
        lines.append("{")
        if block.info == "python":  # the whole block is one script for the interpreter running this one
            lines.append(f"{shlex.quote(sys.executable)} - <<'__HATTR_DOC_PYTHON__'")
            page_line[len(lines)] = block.content_line(0)
            lines += block.lines
            lines.append("__HATTR_DOC_PYTHON__")
            lines.append(f"}} > {shlex.quote(str(out_dir / f'{k}.txt'))} 2>&1")
            continue
        command_start = None
        for i, text in enumerate(block.lines):
            lines.append(text)
            # Every line of a command continued with "\\" names the command's first line.
            command_start = command_start if command_start is not None else block.content_line(i)
            page_line[len(lines)] = command_start
            if not text.rstrip().endswith("\\"):
                command_start = None
        lines.append(f"}} > {shlex.quote(str(out_dir / f'{k}.txt'))} 2>&1")
    return "\n".join(lines) + "\n", page_line


def expected_lines(block: Block) -> list[tuple[int, re.Pattern[str], str]]:
    """Each non-blank line of an output block as a pattern ("..." matches anything)."""
    patterns = []
    for i, text in enumerate(block.lines):
        if not text.strip():
            continue
        parts = [re.escape(p) for p in text.strip().split("...")]
        patterns.append((block.content_line(i), re.compile(".*".join(parts)), text.strip()))
    return patterns


def check_output(page: Page, output: str, block: Block) -> list[str]:
    """The expected lines not found, in order, in the command's output."""
    found_lines = [l.rstrip() for l in re.sub(r"\x1b\[[0-9;]*[A-Za-z]", "", output).replace("\r", "\n").split("\n")]
    failures = []
    at = 0
    for line_no, pattern, text in expected_lines(block):
        match = next((k for k in range(at, len(found_lines)) if pattern.fullmatch(found_lines[k].strip())), None)
        if match is None:
            failures.append(f"{page.name}:{line_no}: expected output line not printed (in this order): {text!r}")
        else:
            at = match + 1
    return failures


def synopsis_failures(page: Page, block: Block, hattr: Path, env: dict[str, str], cwd: Path) -> list[str]:
    """Every `hattr CMD ...` line: the command exists and knows each --option it shows."""
    failures = []
    joined: list[tuple[int, str]] = []
    for i, text in enumerate(block.lines):
        if joined and joined[-1][1].endswith("\\"):
            joined[-1] = (joined[-1][0], joined[-1][1][:-1] + " " + text.strip())
        else:
            joined.append((block.content_line(i), text.strip()))
    for line_no, text in joined:
        words = text.split("#", 1)[0].split()
        if not words or words[0] != "hattr":
            continue
        command = []
        for w in words[1:]:
            if not COMMAND_WORD.match(w):
                break
            command.append(w)
        result = subprocess.run([str(hattr), *command, "--help"], capture_output=True, text=True, env=env, cwd=cwd,
                                timeout=60)
        if result.returncode != 0:
            failures.append(f"{page.name}:{line_no}: `hattr {' '.join(command)} --help` failed "
                            f"(exit {result.returncode}): {result.stderr.strip()[:300]}")
            continue
        for option in OPTION.findall(text):
            if not re.search(r"(?<![\w-])" + re.escape(option) + r"(?![\w-])", result.stdout):
                failures.append(f"{page.name}:{line_no}: `hattr {' '.join(command)}` has no option {option} "
                                f"(not in its --help)")
    return failures


def run_script(script: Path, cwd: Path, env: dict[str, str], timeout: float) -> subprocess.CompletedProcess[str]:
    """Runs the page's script in its own process group; whatever it left running in the
    background (a server a page forgot to stop) is stopped at the end, and everything on timeout."""
    log = script.with_suffix(".log")
    with open(log, "w") as out:
        process = subprocess.Popen(["bash", str(script)], cwd=cwd, env=env, stdin=subprocess.DEVNULL, stdout=out,
                                   stderr=subprocess.STDOUT, start_new_session=True)
        try:
            process.wait(timeout=timeout)
        finally:
            try:
                os.killpg(process.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
            stop_leftovers(script.parent)
    return subprocess.CompletedProcess(process.args, process.returncode, "", log.read_text(errors="replace"))


def tail(text: str, lines: int = 25) -> str:
    return "\n".join("    | " + l for l in text.rstrip().split("\n")[-lines:])


def print_slow_blocks(page: Page, runnable: list[tuple[int, Block]], out_dir: Path, at_least: float = 2.0) -> None:
    """The blocks that took at least `at_least` seconds, longest first (from each block's start
    time to the next's, the last to now)."""
    starts = [(b, float((out_dir / f"{k}.start").read_text())) for k, b in runnable if (out_dir / f"{k}.start").exists()]
    ends = [t for _, t in starts[1:]] + [time.time()]
    took = sorted(((end - start, b) for (b, start), end in zip(starts, ends)), key=lambda x: -x[0])
    for seconds, b in took:
        if seconds >= at_least:
            print(f"{page.name}:{b.line}: block took {seconds:.1f} s")


def run_page(args: argparse.Namespace) -> int:
    source = Path(args.source_dir).resolve()
    doc = source / args.page
    page = parse_page(doc, args.page)
    check_page_form(page)
    check_marks(page)
    hattr = Path(args.hattr).resolve()
    build = Path(args.build_dir).resolve() if args.build_dir else hattr.parent.parent.parent
    shared = Path(args.shared).resolve() if args.shared else (source.parent / "shared")

    runnable = []
    data_absent = 0
    for k, b in enumerate(page.blocks):
        if b.info not in RUNNABLE_LABELS:
            continue
        reason = skip_reason(b)
        if reason is not None:
            print(f"{page.name}:{b.line}: skipped: not runnable here: {reason}")
            continue
        if "../shared/data" in "\n".join(b.lines) and not (shared / "data").is_dir():
            print(f"SKIPPED: {page.name}:{b.line}: the block reads ../shared/data (the SVC2004 recordings), "
                  f"absent here: {shared / 'data'}")
            data_absent += 1
            continue
        runnable.append((k, b))
    runnable = blocks_of_part(page, runnable, args.part, [p for p in args.parts.split(",") if p])
    if args.part and not runnable:  # the part's own blocks were all skipped
        if data_absent:
            return SKIPPED_EXIT
        raise PageError(f"{page.name}: --part {args.part}: every block of the part is marked not runnable here")
    if data_absent and not runnable and not any(b.info == "synopsis" for b in page.blocks):
        return SKIPPED_EXIT

    root, clone = make_scratch(source, hattr, build, shared if shared.is_dir() else None)
    failures: list[str] = []
    try:
        env = dict(os.environ)
        env["PATH"] = f"{root / 'bin'}:{env.get('PATH', '')}"
        env.pop("TERM", None)
        # Benchmarks run briefly: the page's commands are checked, not its figures.
        env["BENCHMARK_MIN_TIME"] = "0.001"
        # python blocks import the build's package (copied into the scratch clone).
        env["PYTHONPATH"] = str(clone / "build" / "release" / "python")
        for b in page.blocks if args.part == "" else []:  # a part runs its blocks only
            if b.info == "synopsis":
                failures += synopsis_failures(page, b, hattr, env, clone)

        out_dir = root / "outputs"
        out_dir.mkdir()
        fail_file = root / "failed"
        script, page_line = build_script(page, runnable, out_dir, fail_file)
        (root / "page.sh").write_text(script)
        try:
            result = run_script(root / "page.sh", clone, env, args.timeout)
        except subprocess.TimeoutExpired:
            running = page.blocks[int((out_dir / "current").read_text())]
            failures.append(f"{page.name}:{running.line}: the page's commands took longer than {args.timeout} s "
                            f"(this block was running)")
            return 1
        failed_block = None
        if fail_file.exists():
            script_line, status = (fail_file.read_text().split() + ["?"])[:2]
            line_no = page_line.get(int(script_line))
            failed_block = int((out_dir / "current").read_text())
            where = f"{page.name}:{line_no}" if line_no else f"{page.name}:{page.blocks[failed_block].line}"
            command = doc.read_text(encoding="utf-8").split("\n")[line_no - 1].strip() if line_no else "?"
            output = (out_dir / f"{failed_block}.txt").read_text(errors="replace")
            failures.append(f"{where}: command failed (exit {status}): {command}\n{tail(output)}")
        elif result.returncode != 0:
            failures.append(f"{page.name}: the page's commands ended with exit {result.returncode}: {result.stderr.strip()[:500]}")

        # Each finished block's output against the output block below it.
        for k, b in runnable:
            if failed_block is not None and k >= failed_block:
                break
            following = page.blocks[k + 1] if k + 1 < len(page.blocks) else None
            if following is not None and following.info == "output" and following.after_sh:
                output = (out_dir / f"{k}.txt").read_text(errors="replace")
                mismatch = check_output(page, output, following)
                if mismatch:
                    failures += mismatch
                    failures.append(f"{page.name}:{b.line}: what the block printed:\n{tail(output, 40)}")
        ran = sum(1 for _ in runnable)
        print_slow_blocks(page, runnable, out_dir)
        print(f"{page.name}: {ran} block(s) run, {sum(1 for b in page.blocks if b.info == 'synopsis')} synopsis block(s) "
              f"checked, in {clone}")
    finally:
        if not args.keep:
            shutil.rmtree(root, ignore_errors=True)
        for f in failures:
            print(f, file=sys.stderr)
    return 1 if failures else 0


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("page", help="the page, relative to --source-dir (README.md, docs/studies.md, ...)")
    parser.add_argument("--source-dir", required=True, help="the project's source tree")
    parser.add_argument("--hattr", required=True, help="the hattr binary under test")
    parser.add_argument("--build-dir", help="the build tree (default: three folders above --hattr)")
    parser.add_argument("--shared", help="the shared folder beside the clone (default: SOURCE/../shared)")
    parser.add_argument("--timeout", type=float, default=900, help="seconds for the whole page")
    parser.add_argument("--part", default="", help="NAME: the page's blocks marked \"own test NAME\" (default: the rest)")
    parser.add_argument("--parts", default="", help="the page's part names, comma-separated (checked by the page's test)")
    parser.add_argument("--keep", action="store_true", help="keep the scratch folder")
    args = parser.parse_args()
    try:
        return run_page(args)
    except PageError as e:
        print(f"malformed page: {e}", file=sys.stderr)
        return 2
    except subprocess.TimeoutExpired:
        print(f"{args.page}: the page's commands took longer than {args.timeout} s", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
