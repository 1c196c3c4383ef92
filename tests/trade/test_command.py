"""``pwc trade`` as a user runs it: a real subprocess, its report opened in a headless
browser, its recommended scene file rendered by ``pwc render``, and its errors."""

from __future__ import annotations

import json
import re
import shutil
import subprocess

import numpy as np
import pytest
from repo import ROOT, run_pwc

from displacement.textures import read_texture
from render.film import read_exr
from trade.metrics import image_errors
from trade.sweep import run_trade

SCENE = ROOT / "gallery" / "scenes" / "fig_14_28.toml"


def chromium() -> str | None:
    return shutil.which("chromium") or shutil.which("chromium-browser")


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    """One CI-sized ``pwc trade`` run of a displaced scene (and its rerun)."""
    out = tmp_path_factory.mktemp("report")
    first = run_pwc("trade", SCENE, "-o", out, "--ci")
    again = tmp_path_factory.mktemp("again")
    for name in ("reference.exr", "reference.json"):
        shutil.copy(out / name, again / name)
    second = run_pwc("trade", SCENE, "-o", again, "--ci", "--knobs", "samples")
    return out, first, second


def test_help():
    r = run_pwc("trade", "--help")
    assert r.returncode == 0
    for word in ("--target-error", "--budget", "--knobs", "--metric", "Pareto", "reference",
                 "--workers N", "--scheduler ADDRESS", "one task each"):
        assert word in r.stdout


def test_the_command_writes_the_report(report):
    out, r, _ = report
    assert r.returncode == 0, r.stderr
    assert "Traceback" not in r.stderr and "wrote" in r.stderr
    for name in ("report.md", "report.html", "error_vs_time.png", "runs.json",
                 "recommended.toml", "reference.exr", "reference.json"):
        assert (out / name).is_file(), name
    data = json.loads((out / "runs.json").read_text())
    assert data["metric"] == "flip" and data["target"] == 0.05 and data["resolution"] == [32, 24]
    families = {run["family"] for run in data["runs"]}
    assert {"samples", "dicing", "displacement", "paths"} <= families  # a displaced square
    assert "pwc trade" in (out / "report.md").read_text()


def test_a_rerun_reuses_the_reference(report):
    out, _, r = report
    assert r.returncode == 0, r.stderr
    assert "reusing the reference" in r.stderr


def test_the_recommended_scene_renders_the_measured_image(report, tmp_path):
    out, _, _ = report
    data = json.loads((out / "runs.json").read_text())
    rec = data["runs"][data["recommended"]] if data["recommended"] is not None else data["runs"][0]
    exr = tmp_path / "rec.exr"
    r = run_pwc("render", out / "recommended.toml", "-o", exr, "--quiet")
    assert r.returncode == 0, r.stderr
    image = read_exr(exr)["RGBA"][..., :3]
    reference = read_texture(out / "reference.exr").data[..., :3]
    errors = image_errors(image, reference)
    for name, value in rec["errors"].items():  # the same image, stored as float32
        assert errors[name] == pytest.approx(value, rel=1e-4, abs=1e-7), name


@pytest.mark.skipif(chromium() is None, reason="chromium is not installed (apt-get install "
                    "chromium, as .ci/run does); the report is opened in a headless browser")
def test_the_report_opens_in_a_headless_browser(report):
    out, _, _ = report
    r = subprocess.run([chromium(), "--headless", "--no-sandbox", "--disable-gpu",
                        "--virtual-time-budget=10000", "--dump-dom",
                        (out / "report.html").resolve().as_uri()],
                       capture_output=True, text=True, timeout=180)
    assert r.returncode == 0, r.stderr[-2000:]
    dom = r.stdout
    # the page's script counts the images the browser decoded once it loaded
    m = re.search(r'<body data-images-loaded="(\d+)/(\d+)"', dom)
    assert m is not None, dom[:2000]
    loaded, total = map(int, m.groups())
    assert total >= 3 and loaded == total  # the plot, the reference, the runs
    data = json.loads((out / "runs.json").read_text())
    assert dom.count("<tr>") == len(data["runs"]) + 1 + len(data["modelled"]) + 1
    assert "Pareto" in dom and "Recommendation" in dom


@pytest.mark.parametrize(("args", "status", "words"), [
    (["--target-error", "0"], 2, "--target-error must be > 0"),
    (["--budget", "-1"], 2, "--budget must be > 0"),
    (["--knobs", "spp"], 2, "unknown knob family 'spp'"),
    (["--reference", "missing.exr"], 3, "missing.exr: no such file"),
    (["--workers", "0"], 2, "--workers must be >= 1, got 0"),
], ids=["target", "budget", "knobs", "reference", "workers"])
def test_bad_command_lines_fail_clearly(args, status, words, tmp_path):
    r = run_pwc("trade", SCENE, "-o", tmp_path / "out", *args, cwd=tmp_path)
    assert r.returncode == status and words in r.stderr and "Traceback" not in r.stderr


def test_a_scene_with_an_error_is_reported_at_its_line(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text(SCENE.read_text().replace('material = "grid()"', 'material = "gird()"'))
    r = run_pwc("trade", bad, "-o", tmp_path / "out", "--ci")
    assert r.returncode == 1 and "Traceback" not in r.stderr
    assert re.search(rf"{re.escape(str(bad))}:\d+:\d+: .*gird", r.stderr), r.stderr


def test_an_unwritable_report_folder_fails_before_any_render(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("")
    r = run_pwc("trade", SCENE, "-o", blocker / "out", "--ci")
    assert r.returncode == 3 and "is a file, not a folder" in r.stderr
    assert not np.any([p.suffix == ".exr" for p in tmp_path.rglob("*")])


def test_runs_on_two_workers_measure_the_in_process_errors(tmp_path):
    """``--workers 2``: each run a task on a local cluster of two processes, timed on its
    worker; the reference is the same image, and every run the same errors (the images
    are deterministic given the seeds).  Which combinations are tried depends on the
    times, so only the runs of both are compared."""
    knobs = {"samples", "displacement"}
    (tmp_path / "here").mkdir()
    here = run_trade(SCENE, tmp_path / "here", size="ci", resolution=(16, 12), knobs=knobs,
                     log=lambda *a: None)
    r = run_pwc("trade", SCENE, "-o", tmp_path / "there", "--ci", "--resolution", 16, 12,
                "--knobs", "samples,displacement", "--workers", 2)
    assert r.returncode == 0 and "Traceback" not in r.stderr, r.stderr
    assert "measuring each run as a task on the cluster" in r.stderr
    there = json.loads((tmp_path / "there" / "runs.json").read_text())
    assert np.array_equal(read_texture(tmp_path / "here" / "reference.exr").data,
                          read_texture(tmp_path / "there" / "reference.exr").data)
    theirs = {run["label"]: run for run in there["runs"]}
    swept = [run for run in here.runs if run.family != "combined"]
    assert len(swept) >= 4 and {run.label for run in swept} == {
        label for label, run in theirs.items() if run["family"] != "combined"}
    for run in here.runs:
        if run.label in theirs:
            assert theirs[run.label]["errors"] == run.errors, run.label
            assert theirs[run.label]["geometric_px"] == run.geometric_px, run.label
    for run in there["runs"]:  # timed on the worker, reading the scene on the client
        assert 0 < run["read_s"] < run["wall_s"] and run["cpu_s"] > 0 and run["rays"] > 0
        assert run["peak_mb"] >= 0
    assert "--workers 2" in (tmp_path / "there" / "report.md").read_text()
