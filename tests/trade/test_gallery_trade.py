"""``pwc trade`` in its CI-sized mode on every gallery scene of chapters 12-15 (issue 14's
"done when"): every knob that can change the scene is measured, the numbers are sound,
and the recommendation is a scene file that renders the measured image."""

from __future__ import annotations

import math
import tomllib

import numpy as np
import pytest

from render.library.resources import bundled_scenes
from render.scene import load_scene, parse_scene
from trade.knobs import ci_resolution
from trade.report import write_report
from trade.sweep import pareto_front, run_trade

SCENES = sorted(bundled_scenes().glob("fig_1[2-5]_*.toml"))


def test_the_gallery_has_chapters_12_to_15():
    chapters = {p.stem.split("_")[1] for p in SCENES}
    assert chapters == {"12", "13", "14", "15"} and len(SCENES) >= 30


@pytest.mark.slow
@pytest.mark.parametrize("scene", SCENES, ids=[p.stem for p in SCENES])
def test_trade_in_ci_size_on_every_scene_of_chapters_12_to_15(scene, tmp_path):
    st = load_scene(scene).settings
    res = ci_resolution(st.width, st.height)
    trade = run_trade(scene, tmp_path, size="ci", resolution=res, log=lambda *a: None)
    runs = trade.runs
    base = runs[0]
    # the scene as written first; every knob of the scene measured once
    assert base.label == "the scene as written" and base.patch == {"render": {}, "objects": {}}
    families = {r.family for r in runs}
    assert {"baseline", "samples", "paths"} <= families
    assert trade.lights and [m["name"] for m in trade.modelled] == [
        o.name for o in load_scene(scene).objects]
    # only objects the camera sees diced offer dicing and displacement knobs
    diced = [m for m in trade.modelled if m["diced"]]
    assert ("dicing" in families) == bool(diced)
    assert "displacement" not in families or diced
    displaced = [m for m in trade.modelled if m["displacement"] != "none"]
    assert ("curves" in families) == bool(trade.loads["profiles"])
    assert ("textures" in families) == bool(trade.loads["textures"])
    for r in runs:
        assert r.record["wall_s"] > 0 and r.record["cpu_s"] > 0
        assert r.record["triangles"] > 0 and r.record["rays"] > 0
        assert r.record["peak_mb"] >= 0
        assert all(math.isfinite(v) and v >= 0 for v in r.errors.values()), r.errors
        assert r.meets == (r.errors[trade.metric] <= trade.target)
        assert (tmp_path / r.image).is_file()
        if displaced:
            assert r.geometric_px is not None and r.geometric_px >= 0
    # the Pareto front is the runs no other beats in time and error
    front = pareto_front([(r.cost(trade.cost), r.errors[trade.metric]) for r in runs])
    assert [r.pareto for r in runs] == front and any(front)
    # the recommendation: the fastest measured run that meets the target
    meeting = [r for r in runs if r.meets]
    if meeting:
        assert trade.recommended.cost("wall") == min(r.cost("wall") for r in meeting)
    else:
        assert trade.recommended is None
    files = write_report(trade, tmp_path)
    for name in ("plot", "markdown", "html", "json", "scene"):
        assert files[name].is_file() and files[name].stat().st_size > 0
    md = files["markdown"].read_text()
    assert all(r.label in md for r in runs)
    # the recommended scene file reads back with the recommended settings
    rec = parse_scene(files["scene"].read_text(), str(scene), base_dir=scene.parent)
    chosen = trade.recommended.patch if trade.recommended else {"render": {}, "objects": {}}
    for key, value in chosen["render"].items():
        assert getattr(rec.settings, key) == value, key
    for i, keys in chosen["objects"].items():
        for key, value in keys.items():
            if key in ("dicing_rate", "dicing_tolerance", "displacement_method"):
                assert getattr(rec.objects[i], key) == value, key
    assert tomllib.loads(files["scene"].read_text())["render"]["resolution"] == list(res)


def test_runs_are_deterministic_and_reuse_the_reference(tmp_path):
    scene = bundled_scenes() / "fig_14_28.toml"
    first = run_trade(scene, tmp_path, size="ci", resolution=(16, 12), knobs={"samples"},
                      cost="cpu", log=lambda *a: None)
    assert first.cost == "cpu" and [r.pareto for r in first.runs] == pareto_front(
        [(r.record["cpu_s"], r.errors["flip"]) for r in first.runs])
    logged = []
    again = run_trade(scene, tmp_path, size="ci", resolution=(16, 12), knobs={"samples"},
                      log=logged.append)
    assert first.reference["reused"] is False and again.reference["reused"] is True
    assert any("reusing the reference" in m for m in logged)
    assert [r.label for r in first.runs] == [r.label for r in again.runs]
    for a, b in zip(first.runs, again.runs, strict=True):
        assert a.errors == b.errors  # same seeds, same images, same errors
    # another resolution is another reference
    other = run_trade(scene, tmp_path, size="ci", resolution=(8, 6), knobs={"samples"},
                      log=lambda *a: None)
    assert other.reference["reused"] is False


def test_a_budget_skips_the_runs_past_it(tmp_path):
    scene = bundled_scenes() / "fig_14_28.toml"
    trade = run_trade(scene, tmp_path, size="ci", resolution=(16, 12), budget=1e-9,
                      log=lambda *a: None)
    assert len(trade.runs) == 1 and trade.skipped  # the baseline, then the budget is spent
    assert "spp 1" in trade.skipped


def test_an_unreachable_target_recommends_nothing_and_says_so(tmp_path):
    scene = bundled_scenes() / "fig_14_28.toml"
    trade = run_trade(scene, tmp_path, size="ci", resolution=(16, 12), knobs={"paths"},
                      target=1e-12, log=lambda *a: None)
    assert trade.recommended is None and not any(r.meets for r in trade.runs)
    files = write_report(trade, tmp_path)
    assert "No measured run meets the target" in files["markdown"].read_text()
    text = files["scene"].read_text()
    assert "no run met the target" in text
    original = scene.read_text()
    assert np.all([line in text for line in original.splitlines() if line.startswith("material")])
