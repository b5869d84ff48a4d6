"""Trials on the simulated pen from Python: the same recording as the hattr command's, bit for bit."""

import numpy as np
import pytest

import hattr
from conftest import cli_json, run_cli

# Metadata that differs between two runs of one trial: when it was made.
VOLATILE = {"created_utc"}


def assert_same_recording(mine, theirs):
    assert len(mine) == len(theirs)
    for name in theirs.channel_names:
        np.testing.assert_array_equal(mine.channel(name), theirs.channel(name), err_msg=name)
    strip = lambda m: {k: v for k, v in m.items() if k not in VOLATILE}  # noqa: E731
    assert strip(mine.metadata) == strip(theirs.metadata)


@pytest.mark.parametrize("mode", ["basic", "pcontrol", "alpha"])
def test_a_training_trial_through_python_equals_one_through_the_cli(tmp_path, expert_files, mode):
    expert, script = expert_files
    run_cli("train", "--hand", script, "--reference", expert, "--mode", mode, "--trial", 3, "--subject", "S01",
            "-o", tmp_path / "cli.csv")
    run = hattr.run_trial(str(script), str(expert), mode, trial=3, subject="S01")
    assert run["clock"] == "simulated" and run["failure"] == ""
    assert_same_recording(run["profile"], hattr.read_profile(tmp_path / "cli.csv"))
    guided = np.abs(run["profile"].f_guide_W_N).max()
    assert (guided == 0.0) == (mode == "basic")


# The hand writes the expert's own script: on the path the channel gives no force; the others do.
@pytest.mark.parametrize("mode,params,seed,guided", [("channel", {"half_width_mm": 0.5}, 1, False),
                                                     ("error-augmentation", {"gain_N_per_mm": 0.2}, 1, True),
                                                     ("noise", {"rms_N": 0.5}, 9, True), ("playback", {}, 1, True),
                                                     # scheduled: the first trial's law at its gain
                                                     ("fading", {"base": "alpha", "start_gain": 0.5}, 1, True),
                                                     ("assist-as-needed", {"start_gain": 0.0}, 1, False),
                                                     ("partial-then-full", {"partial_trials": 2}, 1, False)])
def test_the_strategies_beyond_the_papers_run_through_python_as_through_the_cli(tmp_path, expert_files, mode, params,
                                                                                seed, guided):
    # Issue 36: the strategy, its parameters by name and the noise's seed, as `hattr train` takes them.
    expert, script = expert_files
    args = [a for k, v in params.items() for a in ("--param", f"{k}={v}")]
    # Played open loop, the expert's press adds to the hand's own: the pen may go through the
    # paper, and the trial is kept, marked disturbed.
    run_cli("train", "--hand", script, "--reference", expert, "--mode", mode, "--seed", seed, *args,
            "--keep-disturbed", "-o", tmp_path / "cli.csv")
    run = hattr.run_trial(str(script), str(expert), mode, params=params, seed=seed)
    assert_same_recording(run["profile"], hattr.read_profile(tmp_path / "cli.csv"))
    assert (np.abs(run["profile"].f_guide_W_N).max() > 0.0) == guided
    with pytest.raises(hattr.InputError, match="expected"):
        hattr.run_trial(str(script), str(expert), mode, params={"no_such": 1.0})


def test_the_strategies_are_listed_as_the_cli_lists_them():
    import json
    listed = json.loads(run_cli("strategies", "--json")[0])["strategies"]
    assert hattr.strategies() == listed
    assert len(listed) >= 14
    assert {"channel", "error-augmentation", "noise", "playback", "fading", "assist-as-needed",
            "partial-then-full"} <= {s["name"] for s in listed}
    fading = next(s for s in listed if s["name"] == "fading")
    assert fading["scheduled"] and fading["parameters"][0] == {
        "name": "base", "default": "pcontrol", "choices": ["pcontrol", "alpha"], "meaning": "the guidance that fades"}


def test_a_recording_with_the_end_rule_equals_the_clis(tmp_path, expert_files):
    _, script = expert_files
    run_cli("record", "--hand", script, "--pen-up-end", 0.5, "--rate", 2000, "-o", tmp_path / "cli.csv")
    run = hattr.run_trial(str(script), pen_up_end_s=0.5, rate_hz=2000.0)
    assert run["end_reason"] == "pen lifted"
    assert_same_recording(run["profile"], hattr.read_profile(tmp_path / "cli.csv"))


def test_profiles_in_memory_drive_the_same_trial_as_their_files(expert_files):
    expert, script = expert_files
    from_files = hattr.run_trial(str(script), str(expert), "alpha")["profile"]
    from_objects = hattr.run_trial(hattr.read_profile(script), hattr.read_profile(expert), "alpha")["profile"]
    for name in from_files.channel_names:
        np.testing.assert_array_equal(from_objects.channel(name), from_files.channel(name), err_msg=name)
    # Only files have names to record.
    assert from_files.metadata["hand_script"] == str(script) and from_objects.metadata["hand_script"] == ""


def test_bad_trial_settings_raise_input_error(expert_files):
    expert, script = expert_files
    with pytest.raises(hattr.InputError, match="needs a reference"):
        hattr.run_trial(str(script), mode="alpha")
    with pytest.raises(hattr.InputError, match="basic, pcontrol, alpha"):
        hattr.run_trial(str(script), str(expert), "gamma")
    with pytest.raises(hattr.InputError):
        hattr.run_trial(str(script), device="bogus://pen")
    with pytest.raises(hattr.InputError, match="sim or real"):
        hattr.run_trial(str(script), clock="wall")
    with pytest.raises(hattr.InputError, match="time or progress|indexing"):
        hattr.run_trial(str(script), indexing="bogus")
    with pytest.raises(TypeError):
        hattr.run_trial(5)


def test_a_reference_or_hand_the_pen_cannot_render_is_refused_with_the_remedy(tmp_path, expert_files):
    expert, script = expert_files
    # A loop pressing 3.5 N, twice what the default pen holds up (1.75 N).
    heavy = tmp_path / "heavy.csv"
    lines = ["t_s,x_mm,y_mm,z_mm,fx_N,fy_N,fz_N,pen_down_bool"]
    lines += [f"{i * 0.01},{20 * np.sin(0.06 * i)},{10 * np.sin(0.12 * i)},0,0,0,-3.5,1" for i in range(101)]
    heavy.write_text("\n".join(lines) + "\n")
    with pytest.raises(hattr.InputError, match=r"reference .*heavy.csv: it presses up to 3.50 N.*--scale-force 0.5"):
        hattr.run_trial(str(script), str(heavy), "alpha")
    with pytest.raises(hattr.InputError, match=r"^hand .*heavy.csv: it presses up to 3.50 N"):
        hattr.run_trial(str(heavy), str(expert), "pcontrol")
    with pytest.raises(hattr.InputError, match=r"^reference: it presses"):
        hattr.run_trial(str(script), hattr.read_profile(heavy), "alpha")
    # Recording keeps any hand: it records what happens, and marks it.
    assert "under the paper" in hattr.run_trial(str(heavy))["disturbed"]


def test_a_power_analysis_through_python_equals_the_clis():
    """hattr.power_analysis runs ops::runPowerAnalysis, as `hattr sim power` does: the same table
    to the bit (each replicate is, wherever it runs); only the run's timing differs."""
    mine = hattr.power_analysis(subjects=[3], replicates=2, trials=2, seed=3)
    theirs = cli_json("sim", "power", "--subjects", "3", "--replicates", "2", "--trials", "2", "--seed", "3")
    assert mine["run"]["studies"] == 2 and mine["run"]["processes"] == 1
    mine.pop("run")
    theirs.pop("run")
    assert mine == theirs
    with pytest.raises(hattr.InputError, match="subject"):
        hattr.power_analysis(subjects=[1], replicates=2, trials=2)
    with pytest.raises(hattr.InputError, match="expected 2 to 50"):
        hattr.power_analysis(subjects=[3], replicates=2, trials=1)
