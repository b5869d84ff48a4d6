"""hattr.Library: the same library, answers and records as `hattr library`."""

import json

import pytest

import hattr
from conftest import SHARED_SVC2004, SOURCE_DIR, run_cli


def needs_svc2004():
    if not SHARED_SVC2004.is_dir():
        pytest.skip(f"the SVC2004 recordings are not at {SHARED_SVC2004} (../shared/data beside the project)")


def test_a_library_made_from_python_is_the_clis(tmp_path):
    lib = hattr.Library(str(tmp_path / "lib.sqlite"), create=True)
    with pytest.raises(hattr.InputError, match="already exists"):
        hattr.Library(str(tmp_path / "lib.sqlite"), create=True)
    with pytest.raises(hattr.InputError, match="no such profile library"):
        hattr.Library(str(tmp_path / "none.sqlite"))
    handmade = hattr.read_profile(SOURCE_DIR / "examples" / "handmade.csv")
    assert lib.add(handmade, key="h/1", person="P", skill="line") == "h/1"
    with pytest.raises(hattr.InputError, match="already in the library"):
        lib.add(handmade, key="h/1", person="P", skill="line")
    out, _ = run_cli("library", "-L", tmp_path / "lib.sqlite", "list", "--json")
    assert [e["key"] for e in json.loads(out)["entries"]] == [e["key"] for e in lib.entries()] == ["h/1"]
    assert lib.profile("h/1").channel("x").tolist() == handmade.channel("x").tolist()
    lib.remove(["h/1"])
    assert lib.entries() == []


def test_identify_and_verify_on_real_writers_match_the_cli(tmp_path):
    needs_svc2004()
    path = tmp_path / "svc.sqlite"
    lib = hattr.Library(str(path), create=True)
    assert lib.import_svc2004(SHARED_SVC2004)["count"] == 1600
    probe = lib.profile("svc2004/U7S14")
    found = lib.identify(probe, skill="signature", top=3)
    hattr.write_profile(probe, tmp_path / "probe.csv")
    out, _ = run_cli("library", "-L", path, "identify", tmp_path / "probe.csv", "--skill", "signature", "--top", "3",
                     "--json")
    assert found["ranked"] == json.loads(out)["ranked"]
    assert found["ranked"] == lib.identify(probe, skill="signature", top=3, brute_force=True)["ranked"]
    verdict = lib.verify(probe, claim="U7", skill="signature", session="1", threshold=1.5)
    assert verdict["references"] == 10 and verdict["accepted"] == (verdict["score"] <= 1.5)
    with pytest.raises(hattr.InputError, match="no signature profiles of U99"):
        lib.verify(probe, claim="U99", skill="signature", threshold=1.0)
    result = lib.evaluate(runs=1)
    assert {s["features"] for s in result["sets"]} >= {"shape", "force", "shape+force", "all"}
    kinds = {r["kind"] for r in result["scores"]}
    assert kinds == {"genuine", "skilled", "random"}
