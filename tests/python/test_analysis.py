"""The paper's analysis from Python against the C++ results on the same data (the hattr
command): preprocessing, DTW, the trial scorer, the ANOVA and Tukey HSD. Also: records that
pandas takes as they are, and the GIL released in long calls."""

import csv
import os
from pathlib import Path
import threading

import numpy as np
import pandas as pd
import pytest

import hattr
from conftest import cli_json, run_cli

CHANNELS = ["x", "y", "z", "fx", "fy", "fz"]


@pytest.fixture(scope="module")
def trial_file(tmp_path_factory, expert_files):
    """A trainee's ALPHA trial against the expert (the CLI's), to compare with."""
    out = tmp_path_factory.mktemp("trial") / "trial.csv"
    expert, script = expert_files
    run_cli("train", "--hand", script, "--reference", expert, "--mode", "alpha", "-o", out)
    return out


def test_per_channel_dtw_equals_the_clis(expert_files, trial_file):
    expert, trial = hattr.read_profile(expert_files[0]), hattr.read_profile(trial_file)
    for preprocess in ("paper", "zscore"):
        cli = cli_json("dtw", expert_files[0], trial_file, "--preprocess", preprocess)["cost"]
        for name in CHANNELS:
            a = hattr.normalize(expert.channel(name), preprocess)
            b = hattr.preprocess_trial(trial.t_s, trial.channel(name), expert.t_s, preprocess)
            assert hattr.dtw(a, b) == pytest.approx(cli[name], rel=0, abs=1e-12), (preprocess, name)


def test_a_banded_squared_dtw_with_its_path_equals_the_clis(expert_files, trial_file):
    cli = cli_json("dtw", expert_files[0], trial_file, "--channels", "x", "--cost", "sq", "--band", "0.1", "--path")
    expert, trial = hattr.read_profile(expert_files[0]), hattr.read_profile(trial_file)
    a = hattr.normalize(expert.channel("x"))
    b = hattr.preprocess_trial(trial.t_s, trial.channel("x"), expert.t_s)
    cost, path = hattr.dtw_with_path(a, b, cost="sq", band_fraction=0.1)
    assert cost == pytest.approx(cli["cost"]["x"], rel=0, abs=1e-12)
    assert path.dtype == np.int64 and path.shape[1] == 2
    assert path.tolist() == [list(step) for step in cli["path"]["x"]]
    assert hattr.dtw(a, b, cost="sq", band_fraction=0.1) == cost


def test_the_trial_scorer_equals_the_clis_score(expert_files, trial_file):
    cli = cli_json("dtw", expert_files[0], trial_file, "--score")
    score = hattr.TrialScorer(hattr.read_profile(expert_files[0])).score(hattr.read_profile(trial_file))
    for name in CHANNELS:
        assert score[name] == pytest.approx(cli["cost"][name], rel=0, abs=1e-12), name
    scores = hattr.TrialScorer(hattr.read_profile(expert_files[0])).score_all([hattr.read_profile(trial_file)] * 3,
                                                                               threads=2)
    assert scores == [score] * 3


def test_a_batch_and_a_cost_matrix_give_each_pairs_dtw():
    rng = np.random.default_rng(7)
    a = [rng.normal(size=200) for _ in range(9)]
    b = [rng.normal(size=180) for _ in range(9)]
    batch = hattr.dtw_batch(a, b)
    singles = [hattr.dtw(x, y) for x, y in zip(a, b)]
    np.testing.assert_allclose(batch, singles, rtol=0, atol=1e-12)
    assert np.array_equal(hattr.dtw_batch(a, b, threads=4), batch)  # the same to the bit on any number of threads
    matrix = hattr.dtw_cost_matrix(a, threads=2)
    assert matrix.shape == (9, 9) and np.all(np.diag(matrix) == 0) and np.array_equal(matrix, matrix.T)
    assert matrix[2, 5] == pytest.approx(hattr.dtw(a[2], a[5]), rel=0, abs=1e-12)
    assert np.isinf(hattr.dtw(a[0], b[0], abandon_above=1e-3))


def test_bad_series_and_options_raise_input_error():
    with pytest.raises(hattr.InputError):
        hattr.dtw([], [1.0, 2.0])
    with pytest.raises(hattr.InputError, match="finite"):
        hattr.dtw([1.0, np.nan], [1.0, 2.0])
    with pytest.raises(hattr.InputError, match="abs or sq"):
        hattr.dtw([1.0], [1.0], cost="cubic")
    with pytest.raises(hattr.InputError, match="paper, zscore or none"):
        hattr.normalize([1.0, 2.0], "minmax")
    with pytest.raises(hattr.InputError, match="one-dimensional"):
        hattr.dtw(np.zeros((2, 2)), [1.0])
    with pytest.raises(hattr.InputError, match="a: expected numbers"):
        hattr.dtw(["1", "2"], [1.0, 3.0])
    with pytest.raises(hattr.InputError, match=r"b\[1\]: expected numbers"):
        hattr.dtw_batch([[1.0], [2.0]], [[1.0], ["x"]])
    with pytest.raises(hattr.InputError, match="got a string"):
        hattr.two_way_anova("aabb", "abab", [1.0, 2.0, 3.0, 4.0])
    scorer = hattr.TrialScorer(hattr.HapticProfile.from_arrays([0.0, 1.0], np.zeros((2, 3))))
    with pytest.raises(hattr.InputError, match=r"trials\[0\]: expected a hattr.HapticProfile, got NoneType"):
        scorer.score_all([None])


def write_table(path, rows):
    with open(path, "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(["mode", "subject", "cost"])
        writer.writerows(rows)


@pytest.fixture(scope="module")
def replicated_table(tmp_path_factory):
    """3 modes × 4 subjects × 3 replicates of a random response, as a CSV for the CLI."""
    rng = np.random.default_rng(11)
    rows = [(mode, f"S{s}", float(rng.normal(10 + m, 1.5)))
            for m, mode in enumerate(["BASIC", "PCONTROL", "ALPHA"]) for s in range(1, 5) for _ in range(3)]
    path = tmp_path_factory.mktemp("anova") / "table.csv"
    write_table(path, rows)
    return path, rows


def test_anova_and_tukey_equal_the_clis(replicated_table):
    path, rows = replicated_table
    mode, subject, cost = zip(*rows)
    for random in (False, True):
        extra = ["--random", "subject"] if random else []
        cli = cli_json("anova", path, "--response", "cost", "--factor", "mode", "--factor", "subject",
                       "--tukey", "mode", *extra)
        table = hattr.two_way_anova(mode, subject, np.array(cost), a_name="mode", b_name="subject", b_random=random)
        assert [r["source"] for r in table.rows] == [r["source"] for r in cli["rows"]]
        for mine, theirs in zip(table.rows, cli["rows"]):
            assert mine["df"] == theirs["df"]
            for key, cli_key in (("sum_sq", "ss"), ("mean_sq", "ms"), ("f", "f"), ("p", "p")):
                if theirs[cli_key] is None:
                    assert np.isnan(mine[key])
                else:
                    assert mine[key] == pytest.approx(theirs[cli_key], rel=0, abs=1e-12), (random, key)
        for mine, theirs in zip(table.rows, cli["rows"]):
            assert mine["error_term"] == theirs["error_term"]
            if theirs["partial_eta_sq"] is not None:
                assert mine["partial_eta_sq"] == pytest.approx(theirs["partial_eta_sq"], rel=0, abs=1e-12)
        tukey = hattr.tukey_hsd(mode, subject, np.array(cost), factor="mode", a_name="mode", b_name="subject",
                                b_random=random)
        assert tukey.error_term == cli["tukey"]["error_term"]
        assert len(tukey.comparisons) == len(cli["tukey"]["comparisons"]) == 3
        for mine, theirs in zip(tukey.comparisons, cli["tukey"]["comparisons"]):
            assert mine["comparison"] == theirs["comparison"]
            for key, cli_key in (("diff", "diff"), ("lower", "lwr"), ("upper", "upr"), ("p_adjusted", "p_adj")):
                assert mine[key] == pytest.approx(theirs[cli_key], rel=0, abs=1e-12), (random, key)


def test_statistics_come_back_as_records_pandas_takes_in_one_call(replicated_table):
    _, rows = replicated_table
    frame = pd.DataFrame(rows, columns=["mode", "subject", "cost"])
    table = hattr.two_way_anova(frame["mode"], frame["subject"], frame["cost"], a_name="mode", b_name="subject")
    anova = pd.DataFrame(table.rows).set_index("source")
    assert list(anova.index) == ["mode", "subject", "mode:subject", "Residuals"]
    assert anova.loc["Residuals", "df"] == 24
    assert table.row("mode")["p"] == anova.loc["mode", "p"]
    groups = pd.DataFrame(hattr.describe_groups(frame["mode"], frame["subject"], frame["cost"], by="a"))
    np.testing.assert_allclose(groups.set_index("a")["mean"], frame.groupby("mode", sort=False)["cost"].mean(),
                               rtol=1e-14)


def test_an_unbalanced_design_names_the_missing_cell(replicated_table):
    _, rows = replicated_table
    mode, subject, cost = zip(*rows[:-3])  # the last cell (ALPHA, S4) has no observations
    with pytest.raises(hattr.InputError, match="S4"):
        hattr.two_way_anova(mode, subject, np.array(cost))


def test_a_dtw_batch_lets_other_python_threads_run():
    """While one thread is inside a long batch, the main thread gets the GIL: with the GIL held
    it could only resume once the batch had returned."""
    rng = np.random.default_rng(3)
    a = [rng.normal(size=2000) for _ in range(64)]
    b = [rng.normal(size=2000) for _ in range(64)]
    started, finished = threading.Event(), threading.Event()

    def long_batch():
        started.set()
        hattr.dtw_batch(a, b)
        finished.set()

    worker = threading.Thread(target=long_batch)
    worker.start()
    started.wait()
    seen_running = 0
    while not finished.is_set():  # Python work on this thread while the batch runs on the other
        seen_running += 1
        threading.Event().wait(0.001)
    worker.join()
    assert seen_running > 5, "the main thread never ran while the batch ran: the GIL was held"


LMM_DATA = Path(os.environ.get("HATTR_SOURCE_DIR", ".")) / "tests" / "analysis" / "lmm_reference" / "slopes.csv"
LMM_FORMULA = "cost ~ mode * trial + (1 + trial | subject)"


def test_lmm_of_a_file_a_dict_and_a_dataframe_equal_the_clis():
    """The mixed model (equal to R's lme4 + lmerTest: tests/analysis/lmm_test.cpp) from a path, a dict of
    columns and a pandas DataFrame gives the CLI's fit bit for bit."""
    cli = cli_json("lmm", LMM_DATA, "--formula", LMM_FORMULA, "--reference", "mode=BASIC")["models"][0]
    frame = pd.read_csv(LMM_DATA)
    for data in (LMM_DATA, str(LMM_DATA), {c: list(frame[c]) for c in frame.columns}, frame):
        fit = hattr.lmm(data, LMM_FORMULA, reference={"mode": "BASIC"})
        assert fit == cli, type(data)
    assert [c["name"] for c in cli["fixed_effects"]][:3] == ["(Intercept)", "modeALPHA", "modePCONTROL"]
    assert pd.DataFrame(cli["fixed_effects"]).shape == (6, 8)


def test_compare_lmm_equals_the_clis_likelihood_ratio_tests():
    formulas = ["cost ~ trial + (1 + trial | subject)", "cost ~ mode + trial + (1 + trial | subject)"]
    cli = cli_json("lmm", LMM_DATA, "--formula", formulas[1], "--formula", formulas[0])["likelihood_ratio_tests"]
    assert hattr.compare_lmm(LMM_DATA, formulas) == cli
    assert cli[0]["df"] == 2 and cli[0]["smaller"] == formulas[0]


def test_lmm_bad_input_raises_input_error_naming_the_column():
    with pytest.raises(hattr.InputError, match="column 'sbject', which is not in the table"):
        hattr.lmm(LMM_DATA, "cost ~ mode + (1 | sbject)")
    with pytest.raises(hattr.InputError, match="row 2 of column 'y' is nan"):
        hattr.lmm({"y": [1.0, float("nan"), 2.0, 3.0], "g": ["a", "a", "b", "b"]}, "y ~ 1 + (1 | g)")
    # pandas' missing values in a text column (None, NaN) are missing, not a level "nan"
    for missing in (None, float("nan")):
        frame = pd.DataFrame({"y": [1.0, 2.0, 3.0, 4.0, 5.0, 6.0], "g": ["a", "a", missing, "b", "c", "c"]})
        with pytest.raises(hattr.InputError, match="row 3 of column 'g' is missing"):
            hattr.lmm(frame, "y ~ 1 + (1 | g)")


def test_kinematics_equal_the_clis(expert_files, trial_file):
    cli = cli_json("kinematics", expert_files[0], trial_file)["trials"]
    for path, record in zip((expert_files[0], trial_file), cli):
        mine = hattr.kinematics(hattr.read_profile(path))
        assert mine == {k: v for k, v in record.items() if k != "file"}
    assert hattr.kinematics(hattr.read_profile(trial_file), cutoff_hz=0)["velocity_peaks"] >= cli[1]["velocity_peaks"]


def test_fit_learning_curve_returns_the_records_of_the_fit():
    n = np.arange(1, 12, dtype=float)
    y = 2 + 6 * np.exp(-0.4 * (n - 1))
    fit = hattr.fit_learning_curve(n, y)
    assert fit["rate"]["estimate"] == pytest.approx(0.4, rel=1e-9)
    assert fit["asymptote"]["estimate"] == pytest.approx(2.0, rel=1e-9)
    assert hattr.fit_learning_curve(n, y, law="power")["law"] == "power"
    with pytest.raises(hattr.InputError, match="expected exponential or power"):
        hattr.fit_learning_curve(n, y, law="hyperbolic")
