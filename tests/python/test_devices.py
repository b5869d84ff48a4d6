"""The servo check and the device check from Python (issue 41): the library's calls, their
results as the CLI's --json prints them."""

import json
import subprocess

import pytest

import hattr
from conftest import cli_path


def test_the_servo_check_gives_the_clis_schema_and_verdicts():
    mine = hattr.servo_check("sim://pen", seconds=0.2, realtime="skip")
    # A loaded host may FAIL a figure (exit 1); the JSON is printed either way.
    done = subprocess.run([cli_path(), "servo-check", "--seconds", "0.2", "--realtime", "skip", "--json"],
                          capture_output=True, text=True, timeout=60)
    assert done.returncode in (0, 1), done.stderr
    theirs = json.loads(done.stdout)
    assert set(mine) == set(theirs)
    assert set(mine["loop"]) == set(theirs["loop"])
    assert mine["device"] == "sim://pen" and mine["world"] == "defaults"
    assert mine["loop"]["ticks"] > 100
    assert mine["verdict"] in ("PASS", "WARN", "FAIL")
    assert {v["figure"] for v in mine["verdicts"]} == {v["figure"] for v in theirs["verdicts"]}
    assert "link" not in mine


def test_the_device_check_asks_the_person_and_their_answer_decides():
    asked = []

    def no():
        asked.append(True)
        return False

    result = hattr.check_device("sim://pen", seconds=0.2, confirm=no)
    assert asked == [True]
    assert result["force_test"]["confirmed"] is False
    assert result["ok"] is False
    assert abs(result["force_test"]["commanded_N"] - 0.2) < 0.004
    unattended = hattr.check_device("sim://pen", seconds=0.2)
    assert unattended["force_test"]["confirmed"] is None


def test_bad_checks_raise_input_error():
    with pytest.raises(hattr.InputError, match="require, try or skip"):
        hattr.servo_check(seconds=0.1, realtime="always")
    with pytest.raises(hattr.InputError, match="continuous force"):
        hattr.check_device("sim://pen", seconds=0.2, force_N=3.0)
    with pytest.raises(hattr.InputError):
        hattr.check_device("usb://phantom")
