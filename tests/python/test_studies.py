"""Studies from Python: a simulated study, its database read back, the analysis equal to the
hattr command's, and a study created and run through Python equal to one run by the CLI."""

import json
import shutil

import numpy as np
import pandas as pd
import pytest

import hattr
from conftest import cli_json, run_cli


def test_a_simulated_study_runs_every_trial_and_analyzes_them(small_study):
    assert small_study["trials"] == 2 * 3 * (1 + 3)
    assert small_study["servo_ticks"] > 0 and small_study["report_html"] is None
    costs = pd.DataFrame(small_study["analysis"]["recall_costs"])
    assert len(costs) == 2 * 3 * 2  # the analyzed recall trials: all but the first
    assert set(costs["mode"]) == {"BASIC", "PCONTROL", "ALPHA"}


def test_a_study_lists_its_subjects_and_trials(small_study):
    with hattr.Study.open(small_study["database"]) as study:
        subjects = study.subjects()
        assert [s["id"] for s in subjects] == ["S01", "S02"]
        assert sorted(subjects[0]["mode_order"]) == ["ALPHA", "BASIC", "PCONTROL"]
        trials = pd.DataFrame(study.trials())
        assert len(trials) == 24 and set(trials["status"]) == {"completed"}
        assert len(study.trials("S02")) == 12
        assert study.definition["protocol"]["recall_trials"] == 3
        assert len(study.expert()) > 1000


def test_a_trials_samples_equal_the_clis_export(tmp_path, small_study):
    database = small_study["database"]
    run_cli("study", "export", "--db", database, "--out", tmp_path / "export")
    study = hattr.Study.open(database)
    trial = study.trials("S01")[-1]
    mine = study.trial_profile(trial["trial_id"])
    name = f"{trial['sequence']:03}_{trial['mode']}_{trial['phase']}_{trial['trial']:02}.csv"
    theirs = hattr.read_profile(tmp_path / "export" / "trials" / trial["subject"] / name)
    for name in theirs.channel_names:
        np.testing.assert_array_equal(mine.channel(name), theirs.channel(name), err_msg=name)


def test_the_analysis_equals_the_clis(tmp_path, small_study):
    copy = tmp_path / "study.sqlite"
    shutil.copy(small_study["database"], copy)
    cli = cli_json("study", "analyze", "--db", copy)
    mine = hattr.Study.open(small_study["database"]).analyze()
    assert mine == cli  # the same numbers, to the last bit, through the same JSON
    assert mine == small_study["analysis"]


def test_a_study_created_and_run_through_python_equals_one_run_by_the_cli(tmp_path, expert_files):
    expert, _ = expert_files
    definition = json.loads(run_cli("study", "example")[0])
    definition["experts"] = {definition["skill"]: str(expert)}
    definition["subjects"]["count"] = 2
    definition["protocol"].update(training_trials=1, recall_trials=2, analyzed_recall_trials=[2])
    (tmp_path / "study.json").write_text(json.dumps(definition))
    run_cli("study", "init", tmp_path / "study.json", "--db", tmp_path / "cli.sqlite")
    run_cli("study", "run", "--db", tmp_path / "cli.sqlite", "--quiet")

    with hattr.create_study(tmp_path / "py.sqlite", definition) as created:
        assert created.name == definition["name"]
    assert hattr.run_study(tmp_path / "py.sqlite", max_trials=5) == 5
    assert hattr.run_study(tmp_path / "py.sqlite") == len(hattr.Study.open(tmp_path / "py.sqlite").trials()) - 5
    assert hattr.run_study(tmp_path / "py.sqlite") == 0

    mine, theirs = hattr.Study.open(tmp_path / "py.sqlite"), hattr.Study.open(tmp_path / "cli.sqlite")
    for a, b in zip(mine.trials(), theirs.trials()):
        assert (a["subject"], a["mode"], a["phase"], a["trial"]) == (b["subject"], b["mode"], b["phase"], b["trial"])
        pa, pb = mine.trial_profile(a["trial_id"]), theirs.trial_profile(b["trial_id"])
        for name in pb.channel_names:
            np.testing.assert_array_equal(pa.channel(name), pb.channel(name), err_msg=name)


def test_a_closed_study_says_so(small_study):
    with hattr.Study.open(small_study["database"]) as study:
        assert len(study.trials()) == 24
    with pytest.raises(hattr.InputError, match="closed"):
        study.trials()


def test_study_errors_raise_input_error(tmp_path, small_study):
    not_a_study = tmp_path / "x.sqlite"
    not_a_study.write_text("hello")
    with pytest.raises(hattr.InputError):
        hattr.Study.open(not_a_study)
    before = small_study["database"].stat().st_size
    with pytest.raises(hattr.InputError):
        hattr.create_study(small_study["database"], json.loads(run_cli("study", "example")[0]))
    assert small_study["database"].stat().st_size == before
    study = hattr.Study.open(small_study["database"])
    with pytest.raises(hattr.InputError):
        study.trial_profile(10**9)


def test_a_study_on_postgresql_reads_and_analyzes_as_on_sqlite(tmp_path, small_study, postgres_server):
    # The same study made on a PostgreSQL server from the SQLite study's export, its trials
    # pushed there (as a station that ran offline would): read and analyzed from Python alike.
    database = small_study["database"]
    run_cli("study", "export", "--db", database, "--out", tmp_path / "export")
    address = postgres_server.create_database("python")
    run_cli("study", "init", tmp_path / "export" / "study.json", "--db", address)
    assert cli_json("study", "push", "--from", database, "--to", address)["pushed"] == 24
    with hattr.Study.open(address) as on_server, hattr.Study.open(database) as on_file:
        assert on_server.subjects() == on_file.subjects()
        trials, on_server_trials = on_file.trials(), on_server.trials()
        assert [(t["subject"], t["sequence"], t["status"]) for t in on_server_trials] == \
            [(t["subject"], t["sequence"], t["status"]) for t in trials]
        mine = on_server.trial_profile(on_server_trials[5]["trial_id"])
        theirs = on_file.trial_profile(trials[5]["trial_id"])
        for name in theirs.channel_names:
            np.testing.assert_array_equal(mine.channel(name), theirs.channel(name), err_msg=name)
        assert on_server.analyze() == on_file.analyze()


def test_a_study_with_a_mentored_mode_runs_from_python_as_from_the_cli(tmp_path, expert_files):
    # Issue 41: run_study builds the expert's station from the study file's mentor block, as
    # `hattr study run` does (it could not before).
    expert, _ = expert_files
    definition = json.loads(run_cli("study", "example")[0])
    definition["experts"] = {definition["skill"]: str(expert)}
    definition["modes"] = ["mentor-position"]
    definition["subjects"]["count"] = 1
    definition["protocol"].update(training_trials=1, recall_trials=1, analyzed_recall_trials=[1])
    (tmp_path / "study.json").write_text(json.dumps(definition))
    run_cli("study", "init", tmp_path / "study.json", "--db", tmp_path / "cli.sqlite")
    run_cli("study", "run", "--db", tmp_path / "cli.sqlite", "--quiet")
    hattr.create_study(tmp_path / "py.sqlite", definition).close()
    assert hattr.run_study(tmp_path / "py.sqlite") == 2

    mine, theirs = hattr.Study.open(tmp_path / "py.sqlite"), hattr.Study.open(tmp_path / "cli.sqlite")
    assert [t["mode"] for t in mine.trials()] == ["MENTOR-POSITION"] * 2
    for a, b in zip(mine.trials(), theirs.trials()):
        pa, pb = mine.trial_profile(a["trial_id"]), theirs.trial_profile(b["trial_id"])
        for name in pb.channel_names:
            np.testing.assert_array_equal(pa.channel(name), pb.channel(name), err_msg=name)


def test_a_design_of_groups_and_sessions_runs_and_analyzes_as_the_cli_does(tmp_path):
    # Issue 35: a design beyond the paper's from Python: created, run, its trials' places, and
    # its own analysis equal to `hattr study analyze --json`. Its experts are named by their
    # glyphs (the character, a built-in name): recorded as the study is made.
    design = json.loads(run_cli("study", "example", "--design", "groups-retention")[0])
    design["experts"] = {"na": "ந", "loop": "loop"}
    design["world"] = {"relief": {"kind": "flat"}}
    for group in design["groups"]:
        group["subjects"]["count"] = 2
    for session in design["sessions"]:
        for block in session["blocks"]:
            block["trials"] = 1
    hattr.create_study(tmp_path / "design.sqlite", design).close()
    assert hattr.run_study(tmp_path / "design.sqlite") == 6 * 6
    with hattr.Study.open(tmp_path / "design.sqlite") as study:
        trials = pd.DataFrame(study.trials())
        assert list(trials[trials["subject"] == "A01"]["phase"]) == [
            "baseline", "training", "training", "post-test", "retention", "transfer"]
        assert list(trials[trials["subject"] == "A01"]["day"]) == [0, 0, 1, 1, 2, 2]
        assert set(trials["group"]) == {"free", "path", "force"}
        assert {s["group"] for s in study.subjects()} == {"free", "path", "force"}
        mine = study.analyze()
    assert mine == cli_json("study", "analyze", "--db", tmp_path / "design.sqlite")
    assert [r["condition"] for r in mine["retention"]] == ["free", "path", "force"]
    assert len(mine["trial_scores"]) == 36
    assert mine["trials_left_out"] == []  # no disturbed trial, no paper recall trial to leave out
