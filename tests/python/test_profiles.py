"""Profiles in Python: files, arrays (views and copies), metadata, importers, errors."""

import gc
import pathlib

import numpy as np
import pytest

import hattr
from conftest import SHARED_SVC2004, SOURCE_DIR, run_cli

HANDMADE = SOURCE_DIR / "examples" / "handmade.csv"


def test_a_profile_reads_back_bit_for_bit_after_python_writes_it(tmp_path, expert_files):
    expert = hattr.read_profile(expert_files[0])
    hattr.write_profile(expert, tmp_path / "copy.csv")
    again = hattr.read_profile(tmp_path / "copy.csv")
    assert again == expert
    for name in expert.channel_names:
        np.testing.assert_array_equal(again.channel(name), expert.channel(name))


def test_writing_refuses_an_existing_file_unless_told(tmp_path, expert_files):
    expert = hattr.read_profile(expert_files[0])
    target = tmp_path / "out.csv"
    target.write_text("keep me")
    with pytest.raises(hattr.InputError):
        hattr.write_profile(expert, target)
    assert target.read_text() == "keep me"
    hattr.write_profile(expert, target, overwrite=True)
    assert hattr.read_profile(target) == expert


def test_stored_channels_are_read_only_views_that_keep_the_profile_alive():
    profile = hattr.read_profile(HANDMADE)
    x = profile.channel("x")
    positions = profile.p_WT_m
    assert x.dtype == np.float64 and positions.shape == (len(profile), 3)
    assert np.shares_memory(x, positions), "x and p_WT_m[:, 0] are the same memory, not copies"
    np.testing.assert_array_equal(x, positions[:, 0])
    assert not x.flags.writeable
    with pytest.raises(ValueError):
        x[0] = 1.0
    with pytest.raises(ValueError):
        x.setflags(write=True)  # the profile's memory stays read-only
    # The view owns a reference to the profile: it stays alive as long as the view does.
    assert type(x.base) is hattr.HapticProfile and x.base is positions.base
    expected = x.copy()
    del profile, positions
    gc.collect()
    assert type(x.base) is hattr.HapticProfile and len(x.base) == len(expected)
    np.testing.assert_array_equal(x, expected)


def test_derived_channels_and_flags_are_copies_with_the_libraries_values():
    profile = hattr.read_profile(HANDMADE)
    speed = profile.channel("speed")
    np.testing.assert_allclose(speed, np.linalg.norm(profile.v_WT_m_per_s, axis=1), rtol=0, atol=1e-15)
    assert profile.pen_down.dtype == np.bool_
    assert profile.pen_down.sum() == profile.pen_down_count
    assert speed.flags.writeable  # a copy the caller owns


def test_channels_name_every_channel_the_profile_carries():
    profile = hattr.read_profile(HANDMADE)
    channels = profile.channels()
    assert list(channels) == profile.channel_names
    assert "pressure" not in channels and not profile.raw_channels["pressure"]
    with pytest.raises(hattr.InputError, match="pressure"):
        profile.channel("pressure")
    with pytest.raises(hattr.InputError):
        profile.channel("not-a-channel")


def test_a_profile_built_from_arrays_gets_velocity_by_finite_differences():
    t = np.linspace(0.0, 1.0, 101)
    p = np.column_stack([0.02 * t**2, 0.01 * t, np.zeros_like(t)])
    profile = hattr.HapticProfile.from_arrays(t, p, metadata={"subject": "S01", "nominal_rate_hz": 100.0,
                                                              "mode": "ALPHA"})
    inside = slice(1, -1)  # central differences, exact on a parabola; the ends are one-sided
    np.testing.assert_allclose(profile.v_WT_m_per_s[inside, 0], 0.04 * t[inside], atol=1e-12)
    np.testing.assert_allclose(profile.v_WT_m_per_s[:, 1], 0.01, atol=1e-12)
    assert profile.metadata["subject"] == "S01" and profile.metadata["mode"] == "ALPHA"
    assert profile.metadata["nominal_rate_hz"] == 100.0


def test_arguments_of_the_wrong_kind_are_refused_not_converted():
    t = np.array([0.0, 0.1, 0.2])
    with pytest.raises(hattr.InputError, match="t_s: expected numbers"):
        hattr.HapticProfile.from_arrays(["0", "0.1", "0.2"], np.zeros((3, 3)))
    with pytest.raises(hattr.InputError, match="pen_down must be booleans"):
        hattr.HapticProfile.from_arrays(t, np.zeros((3, 3)), pen_down=[0.5, 2, -1])
    with pytest.raises(hattr.InputError, match="nominal_rate_hz: expected a number"):
        hattr.HapticProfile.from_arrays(t, np.zeros((3, 3)), metadata={"nominal_rate_hz": "fast"})
    with pytest.raises(hattr.InputError, match="subject: expected text or a number"):
        hattr.HapticProfile.from_arrays(t, np.zeros((3, 3)), metadata={"subject": None})
    with pytest.raises(TypeError):
        hattr.import_svc2004(HANDMADE, calibration=3)
    profile = hattr.read_profile(HANDMADE)
    assert (profile == None) is False and profile != "a profile"  # noqa: E711


def test_arrays_a_profile_cannot_hold_are_refused_with_the_reason():
    t = np.array([0.0, 0.1, 0.1])
    with pytest.raises(hattr.InputError, match="time"):
        hattr.HapticProfile.from_arrays(t, np.zeros((3, 3)))
    with pytest.raises(hattr.InputError, match=r"\(3, 3\)"):
        hattr.HapticProfile.from_arrays(np.array([0.0, 0.1, 0.2]), np.zeros((3, 2)))
    with pytest.raises(hattr.InputError, match="sample 0: channel z"):
        hattr.HapticProfile.from_arrays(np.array([0.0, 0.1]), np.array([[0.0, 0.0, np.nan], [0.0, 0.0, 0.0]]))


def test_metadata_given_in_python_is_written_to_the_file(tmp_path):
    original = hattr.read_profile(HANDMADE)
    metadata = original.metadata
    metadata["trial"] = 7
    metadata["subject"] = "S09"
    profile = original.with_metadata(metadata)
    assert original.metadata["subject"] == "example"  # a profile never changes
    with pytest.raises(AttributeError):
        original.metadata = metadata
    hattr.write_profile(profile, tmp_path / "m.csv")
    stdout, _ = run_cli("profile", "info", tmp_path / "m.csv", "--json")
    assert '"S09"' in stdout
    assert hattr.read_profile(tmp_path / "m.csv").metadata["trial"] == "7"


def test_a_bad_file_raises_input_error_with_the_message_the_cli_prints(tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text(HANDMADE.read_text().replace("0.00,0.75", "0.00,zero", 1))
    with pytest.raises(hattr.InputError) as raised:
        hattr.read_profile(bad)
    assert isinstance(raised.value, ValueError) and isinstance(raised.value, hattr.Error)
    _, stderr = run_cli("profile", "info", bad, expect=2)
    assert str(raised.value) in stderr
    assert str(bad) in str(raised.value)


def svc2004_file():
    if not SHARED_SVC2004.is_dir():
        pytest.skip(f"the SVC2004 recordings are not at {SHARED_SVC2004} (../shared/data beside the project)")
    return SHARED_SVC2004 / "U1S1.TXT"


def test_an_svc2004_import_equals_the_clis(tmp_path):
    source = svc2004_file()
    run_cli("import", "svc2004", source, "-o", tmp_path / "cli.csv")
    cli = hattr.read_profile(tmp_path / "cli.csv")
    imported = hattr.import_svc2004(source)
    for name in cli.channel_names:
        np.testing.assert_array_equal(imported.channel(name), cli.channel(name), err_msg=name)
    assert imported.raw_channels == {"pressure": True, "tilt": True}


def test_a_calibration_dict_overrides_the_formats_defaults():
    source = svc2004_file()
    default = hattr.import_svc2004(source)
    doubled = hattr.import_svc2004(source, calibration={"pressure_max_N": 3.5})  # the default is 1.75 N
    down = default.pen_down
    np.testing.assert_allclose(doubled.f_user_W_N[down], default.f_user_W_N[down] * 2, rtol=1e-12, atol=1e-15)
    with pytest.raises(hattr.InputError, match="pressure_max_N"):
        hattr.import_svc2004(source, calibration={"pressure_max_N": -1})


def test_a_susig_import_equals_the_clis(tmp_path):
    source = tmp_path / "sig.txt"
    source.write_text("X, Y, TStamp, Pres., EndPts\nDataSize: 4\n"
                      "100, 200, 0, 128, 0\n110, 205, 10, 255, 1\n300, 200, 50, 64, 0\n310, 210, 60, 0, 1\n")
    run_cli("import", "susig", source, "-o", tmp_path / "cli.csv")
    cli = hattr.read_profile(tmp_path / "cli.csv")
    imported = hattr.import_susig(source)
    assert imported.channel_names == cli.channel_names and imported.raw_channels["pressure"]
    for name in cli.channel_names:
        np.testing.assert_array_equal(imported.channel(name), cli.channel(name), err_msg=name)
    assert imported.metadata["strokes"] == "2"
    source.write_text("X, Y, TStamp, Pres., EndPts\nDataSize: 3\n100, 200, 0, 128, 0\n")
    with pytest.raises(hattr.InputError, match="sig.txt"):
        hattr.import_susig(source)
