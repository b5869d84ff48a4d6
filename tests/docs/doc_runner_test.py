#!/usr/bin/env python3
"""Tests of run_doc_commands.py: a page whose command fails, whose output changed, whose
synopsis names a command or option that does not exist, or that hides a command, fails and
names the page and line; a page that matches passes. Uses the real hattr binary given as
the first argument, in a scratch source tree holding only the page."""

import subprocess
import sys
import tempfile
import textwrap
import unittest
from pathlib import Path

HERE = Path(__file__).resolve().parent
HATTR = ""


def run_page(text: str, *extra: str) -> subprocess.CompletedProcess[str]:
    with tempfile.TemporaryDirectory() as source:
        (Path(source) / "page.md").write_text(textwrap.dedent(text))
        return subprocess.run([sys.executable, str(HERE / "run_doc_commands.py"), "page.md", "--source-dir", source,
                               "--hattr", HATTR, "--shared", str(Path(source) / "none"), *extra],
                              capture_output=True, text=True, timeout=120)


class DocRunner(unittest.TestCase):
    def assert_refused(self, message: str, text: str, *extra: str) -> None:
        """The runner refuses the page (exit 2) with `message` on stderr."""
        r = run_page(text, *extra)
        self.assertEqual(r.returncode, 2, r.stdout + r.stderr)
        self.assertIn(message, r.stderr)

    def test_a_page_that_matches_passes(self):
        r = run_page("""\
            Intro.

            ```sh
            hattr world defaults > world.json
            answer=world.json
            ```

            State carries from block to block:

            ```sh
            hattr world check $answer
            ```

            ```output
            world.json: valid; relief ... vertices
            ```

            ```synopsis
            hattr world check FILE [--json]
            ```
            """)
        self.assertEqual(r.returncode, 0, r.stdout + r.stderr)
        self.assertIn("2 block(s) run, 1 synopsis block(s) checked", r.stdout)

    def test_a_failing_command_names_the_page_and_line(self):
        r = run_page("""\
            # Title

            ```sh
            hattr world defaults > world.json
            hattr world check no-such-file.json
            echo never
            ```
            """)
        self.assertEqual(r.returncode, 1, r.stdout + r.stderr)
        self.assertIn("page.md:5: command failed (exit 2): hattr world check no-such-file.json", r.stderr)

    def test_python_blocks_run_in_order_with_the_shell_blocks_and_their_output_is_checked(self):
        r = run_page("""\
            ```sh
            echo 0.5 > half.txt
            ```

            ```python
            import pathlib
            value = float(pathlib.Path("half.txt").read_text())
            print(f"twice is {2 * value}")
            pathlib.Path("one.txt").write_text(str(2 * value))
            ```

            ```output
            twice is 1.0
            ```

            ```sh
            test "$(cat one.txt)" = 1.0
            ```
            """)
        self.assertEqual(r.returncode, 0, r.stdout + r.stderr)
        self.assertIn("3 block(s) run", r.stdout)

    def test_a_failing_python_block_names_its_first_line(self):
        r = run_page("""\
            # Title

            ```python
            x = 1
            raise ValueError("no such trial")
            ```
            """)
        self.assertEqual(r.returncode, 1, r.stdout + r.stderr)
        self.assertIn("page.md:4", r.stdout + r.stderr)
        self.assertIn("no such trial", r.stdout + r.stderr)

    def test_a_renamed_command_fails(self):
        r = run_page("""\
            ```sh
            hattr wrld defaults
            ```
            """)
        self.assertEqual(r.returncode, 1)
        self.assertIn("page.md:2: command failed (exit 2): hattr wrld defaults", r.stderr)
        self.assertIn('did you mean "hattr world"', r.stderr)

    def test_changed_output_names_the_expected_line(self):
        r = run_page("""\
            ```sh
            hattr world defaults > world.json
            hattr world check world.json
            ```

            ```output
            world.json: valid; ...
            world.json: renders at 10 kHz
            ```
            """)
        self.assertEqual(r.returncode, 1, r.stdout + r.stderr)
        self.assertNotIn("page.md:7:", r.stderr)
        self.assertIn("page.md:8: expected output line not printed (in this order): 'world.json: renders at 10 kHz'",
                      r.stderr)

    def test_expected_lines_must_come_in_order(self):
        r = run_page("""\
            ```sh
            echo first; echo second
            ```

            ```output
            second
            first
            ```
            """)
        self.assertEqual(r.returncode, 1)
        self.assertIn("page.md:7: expected output line not printed (in this order): 'first'", r.stderr)

    def test_an_expected_line_is_a_whole_line(self):
        r = run_page("""\
            ```sh
            echo "  S03      15/66   done"
            ```

            ```output
            S03 ... 5/66 ...
            ```
            """)
        self.assertEqual(r.returncode, 1, r.stdout + r.stderr)
        self.assertIn("page.md:6: expected output line not printed", r.stderr)
        r = run_page("""\
            ```sh
            echo "  S03       5/66   done"
            ```

            ```output
            S03 ... 5/66 ...
            ```
            """)
        self.assertEqual(r.returncode, 0, r.stdout + r.stderr)

    def test_a_continued_command_is_named_by_its_first_line(self):
        r = run_page("""\
            ```sh
            echo fine
            hattr world check \\
                no-such-file.json \\
                --json
            ```
            """)
        self.assertEqual(r.returncode, 1, r.stdout + r.stderr)
        self.assertIn("page.md:3: command failed (exit 2): hattr world check", r.stderr)

    def test_a_block_that_runs_too_long_is_named(self):
        r = run_page("""\
            ```sh
            echo quick
            ```

            ```sh
            sleep 30
            ```
            """, "--timeout", "2")
        self.assertEqual(r.returncode, 1, r.stdout + r.stderr)
        self.assertIn("page.md:5: the page's commands took longer than 2.0 s (this block was running)", r.stderr)

    def test_a_synopsis_with_an_unknown_command_or_option_fails(self):
        r = run_page("""\
            ```synopsis
            hattr study run --db study.sqlite [--subject S03]
            hattr study run --db study.sqlite [--subjekt S03]
            hattr study rnu --db study.sqlite
            ```
            """)
        self.assertEqual(r.returncode, 1)
        self.assertNotIn("page.md:2:", r.stderr)
        self.assertIn("page.md:3: `hattr study run` has no option --subjekt", r.stderr)
        self.assertIn("page.md:4: `hattr study rnu --help` failed (exit 2)", r.stderr)

    def test_skipped_blocks_say_why_and_need_a_reason(self):
        r = run_page("""\
            ```sh
            # not runnable here: needs the vendor SDK
            false
            ```

            <!-- not runnable here: two machines -->
            ```sh
            false
            ```
            """)
        self.assertEqual(r.returncode, 0, r.stdout + r.stderr)
        self.assertIn("page.md:1: skipped: not runnable here: needs the vendor SDK", r.stdout)
        self.assertIn("page.md:7: skipped: not runnable here: two machines", r.stdout)
        r = run_page("""\
            ```sh
            # not runnable here:
            false
            ```
            """)
        self.assertEqual(r.returncode, 2)
        self.assertIn("needs its reason", r.stderr)

    def test_an_unlabelled_block_that_holds_a_command_is_refused(self):
        r = run_page("""\
            ```
            hattr study run --db study.sqlite
            ```
            """)
        self.assertEqual(r.returncode, 2)
        self.assertIn("page.md:1: an unlabelled block starts like a command", r.stderr)

    def test_a_block_labelled_bash_is_refused_not_ignored(self):
        r = run_page("""\
            ```bash
            false
            ```
            """)
        self.assertEqual(r.returncode, 2)
        self.assertIn("page.md:1: a block labelled 'bash'", r.stderr)

    def test_blocks_reading_absent_shared_data_are_skipped_and_the_rest_runs(self):
        r = run_page("""\
            ```sh
            hattr import svc2004 ../shared/data/svc2004-task2/U1S1.TXT -o u1s1.csv
            ```
            """)
        self.assertEqual(r.returncode, 77)
        self.assertIn("SKIPPED: page.md:1: the block reads ../shared/data", r.stdout)
        r = run_page("""\
            ```sh
            hattr import svc2004 ../shared/data/svc2004-task2/U1S1.TXT -o u1s1.csv
            ```

            ```sh
            hattr wrld defaults
            ```
            """)
        self.assertEqual(r.returncode, 1)
        self.assertIn("SKIPPED: page.md:1:", r.stdout)
        self.assertIn("page.md:6: command failed", r.stderr)

    def test_a_server_left_running_in_its_own_session_is_stopped(self):
        # setsid: out of the page's process group, as the jobs of a build tool or a daemon are.
        r = run_page("""\
            ```sh
            setsid sleep 301.25 &
            sleep 0.2
            echo started
            ```
            """)
        self.assertEqual(r.returncode, 0, r.stdout + r.stderr)
        still_running = []
        for proc in Path("/proc").glob("[0-9]*"):
            try:
                if (proc / "cmdline").read_bytes() == b"sleep\x00301.25\x00":
                    still_running.append(proc.name)
            except OSError:
                pass
        self.assertEqual(still_running, [])

    PARTS_PAGE = """\
        ```sh
        greeting=hello
        ```

        ```sh
        echo "$greeting" > made.txt
        ```

        <!-- doc-test: own test slow, after "greeting=hello" and "made.txt" -->
        ```sh
        cat made.txt
        echo "$greeting again"
        ```

        ```output
        hello
        hello again
        ```

        ```sh
        echo main
        test ! -e made-in-part.txt
        ```

        <!-- doc-test: own test slow -->
        ```sh
        echo "part's second block" > made-in-part.txt
        ```
        """

    def test_a_pages_own_test_runs_its_blocks_after_the_ones_they_need_and_the_page_leaves_them_out(self):
        main = run_page(self.PARTS_PAGE, "--parts", "slow")
        self.assertEqual(main.returncode, 0, main.stdout + main.stderr)
        self.assertIn("3 block(s) run", main.stdout)
        part = run_page(self.PARTS_PAGE, "--part", "slow", "--parts", "slow")
        self.assertEqual(part.returncode, 0, part.stdout + part.stderr)
        self.assertIn("4 block(s) run", part.stdout)  # the two it needs, then its own two

    def test_a_page_whose_parts_differ_from_ctests_is_refused(self):
        # ctest runs no part: the "slow" blocks would go untested.
        self.assert_refused("page.md: its own-test parts are slow, but ctest runs none besides the page",
                            self.PARTS_PAGE)
        self.assert_refused("--part fast: no block is marked", self.PARTS_PAGE, "--part", "fast", "--parts", "slow")

    def test_a_part_needing_a_block_the_page_does_not_have_is_refused(self):
        self.assert_refused("page.md:2: needs an earlier block with 'no such text': there is none", """\
            <!-- doc-test: own test lonely, after "no such text" -->
            ```sh
            echo alone
            ```
            """, "--part", "lonely", "--parts", "lonely")

    def test_a_misspelt_mark_and_a_part_with_nothing_to_run_are_refused(self):
        self.assert_refused("page.md:1: expected <!-- doc-test: own test NAME -->", """\
            <!-- doc-test: own-test slow -->
            ```sh
            echo hidden
            ```
            """)
        self.assert_refused("--part idle: every block of the part is marked not runnable here", """\
            <!-- doc-test: own test idle -->
            ```sh
            # not runnable here: a real pen
            echo never
            ```
            """, "--part", "idle", "--parts", "idle")

    def test_a_parts_output_block_is_checked(self):
        r = run_page("""\
            <!-- doc-test: own test checked -->
            ```sh
            echo actual
            ```

            ```output
            expected
            ```
            """, "--part", "checked", "--parts", "checked")
        self.assertEqual(r.returncode, 1, r.stdout + r.stderr)
        self.assertIn("expected output line not printed", r.stderr)

    def test_the_blocks_that_took_two_seconds_or_more_are_named(self):
        r = run_page("""\
            ```sh
            sleep 2.2
            ```

            ```sh
            echo quick
            ```
            """)
        self.assertEqual(r.returncode, 0, r.stdout + r.stderr)
        self.assertRegex(r.stdout, r"page.md:1: block took 2\.\d s")
        self.assertNotIn("page.md:5: block took", r.stdout)


if __name__ == "__main__":
    HATTR = sys.argv.pop(1)
    unittest.main(verbosity=2)
