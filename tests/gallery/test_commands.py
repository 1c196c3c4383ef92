"""``pwc gallery render|check|sheet``: what they write, print and return; in-process and
with each figure a task on a real Dask cluster of worker processes."""

from __future__ import annotations

import argparse
import re
import shutil
import tomllib

import numpy as np
import pytest
from PIL import Image
from repo import ROOT, run_pwc

from gallery import commands, compare
from render.distributed import cluster
from render.film import read_exr, write_exr_channels

FIGURE = "13.3"  # diffuse, compiled path: the cheapest figure of the stage
NAME = "fig_13_03"


def pwc_gallery(*argv) -> int:
    """Run ``pwc gallery ARGV`` in this process (the command as registered)."""
    parser = argparse.ArgumentParser(prog="pwc")
    commands.register(parser.add_subparsers())
    args = parser.parse_args(["gallery", *map(str, argv)])
    return args.func(args)


def test_the_command_is_registered_and_every_level_has_help():
    entry = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["entry-points"]
    assert entry["pwc.commands"]["gallery"] == "gallery.commands:register"
    r = run_pwc("gallery", "--help")
    assert r.returncode == 0 and "{render,check,sheet}" in r.stdout, r.stderr
    for sub in ("render", "check", "sheet"):
        r = run_pwc("gallery", sub, "--help")
        assert r.returncode == 0 and "FIGURE" in r.stdout and "example" in r.stdout, sub
        assert "--workers N" in r.stdout and "--scheduler ADDRESS" in r.stdout, sub
        assert "one task each" in r.stdout, sub


def test_render_writes_each_figure_at_the_size_asked(tmp_path, capsys):
    status = pwc_gallery("render", FIGURE, "fig_14_03", "-o", tmp_path, "--spp", 2,
                         "--resolution", 64, 48)
    assert status == 0
    for name in (NAME, "fig_14_03"):
        rgba = read_exr(tmp_path / f"{name}.exr")["RGBA"]
        assert rgba.shape == (48, 64, 4) and np.all(np.isfinite(rgba)) and rgba.max() > 0
        with Image.open(tmp_path / f"{name}.png") as png:
            assert png.size == (64, 48)
    err = capsys.readouterr().err
    assert "Figure   13.3" in err and "64 x 48, 2 spp" in err


def test_render_refuses_bad_input_before_rendering(tmp_path, capsys):
    assert pwc_gallery("render", "99", "-o", tmp_path) == commands.EXIT_USAGE
    assert "no gallery figure matches '99'" in capsys.readouterr().err
    assert pwc_gallery("render", FIGURE, "-o", tmp_path, "--spp", 0) == commands.EXIT_USAGE
    (tmp_path / "file").write_text("")
    assert pwc_gallery("render", FIGURE, "-o", tmp_path / "file") == commands.EXIT_IO
    assert "is a file, not a folder" in capsys.readouterr().err
    assert not list(tmp_path.glob("*.exr"))


def test_check_passes_the_gallerys_own_figure_and_prints_the_table(capsys, tmp_path):
    assert pwc_gallery("check", FIGURE, "--save", tmp_path) == 0
    out = capsys.readouterr().out
    assert "figure" in out and "RMSE" in out and "FLIP" in out
    assert "13.3" in out and "pass" in out and "1 of 1 figures pass" in out
    saved = read_exr(tmp_path / f"{NAME}_img.exr")["RGB"]
    assert saved.shape == (96, 128, 3)
    expected = {f"{NAME}_{tag}.exr" for tag in ("img", "ref", "err")}
    assert {p.name for p in tmp_path.iterdir()} == expected


def _changed_references(folder, scale):
    """A copy of the gallery's reference of FIGURE, its colour scaled (a regression)."""
    src = compare.reference_dir()
    shutil.copy(src / compare.TABLE, folder / compare.TABLE)
    rgba = read_exr(src / f"{NAME}.exr")["RGBA"]
    write_exr_channels(folder / f"{NAME}.exr", {c: (rgba[..., i] * (scale if i < 3 else 1))
                                                 .astype(np.float16)
                                                 for i, c in enumerate("RGBA")})
    shutil.copy(src / f"{NAME}.png", folder / f"{NAME}.png")


def test_check_fails_a_changed_image_with_exit_status_1(capsys, tmp_path):
    _changed_references(tmp_path, 0.85)
    assert pwc_gallery("check", FIGURE, "--references", tmp_path) == commands.EXIT_FAILED
    out = capsys.readouterr().out
    assert "FAIL" in out and "0 of 1 figures pass, 1 fail" in out and "mean of" in out


def test_check_without_a_reference_fails_and_says_so(capsys, tmp_path):
    (tmp_path / compare.TABLE).write_text("{}")
    assert pwc_gallery("check", FIGURE, "--references", tmp_path) == commands.EXIT_FAILED
    assert "no reference" in capsys.readouterr().out


def test_sheet_writes_the_page_and_its_images(capsys, tmp_path):
    page = tmp_path / "site" / "index.html"
    assert pwc_gallery("sheet", FIGURE, "14.3", "-o", page) == 0
    text = page.read_text()
    assert "Figure 13.3: " in text and "Figure 14.3: " in text
    assert "Chapter 13: Bump mapping" in text and "Part 5 Modifying geometry" in text
    for name in (NAME, "fig_14_03"):
        assert (page.parent / "sheet" / f"{name}.png").is_file()
        assert (page.parent / "sheet" / f"{name}_flip.png").is_file()
    assert "wrote" in capsys.readouterr().out


# ------------------------------------------------------------------ on a Dask cluster
TWO = ("13.3", "14.3")
TWO_NAMES = (NAME, "fig_14_03")


@pytest.fixture(scope="module")
def scheduler():
    """The address of a running local cluster of two worker processes, one thread each."""
    with cluster(workers=2) as client:
        yield client.scheduler.address


def _timeless(text: str) -> str:
    """Command output without its times (``0.1 s``, ``  0.4s``)."""
    return re.sub(r"\d+\.\d ?s\b", "T", text)


def test_render_on_two_workers_writes_the_in_process_images(tmp_path, capsys):
    """``--workers 2``: the command's own local cluster, each figure one task; the client
    writes bit-identical files and prints the same lines in the same order."""
    common = ("render", *TWO, "--resolution", 40, 30, "--spp", 3, "--seed", 5)
    assert pwc_gallery(*common, "-o", tmp_path / "here") == 0
    here = capsys.readouterr().err
    assert pwc_gallery(*common, "-o", tmp_path / "there", "--workers", 2) == 0
    there = capsys.readouterr().err
    for name in TWO_NAMES:
        a, b = (read_exr(tmp_path / d / f"{name}.exr")["RGBA"] for d in ("here", "there"))
        assert a.shape == (30, 40, 4) and a.max() > 0 and np.array_equal(a, b), name
        assert ((tmp_path / "here" / f"{name}.png").read_bytes()
                == (tmp_path / "there" / f"{name}.png").read_bytes()), name
    lines = [line for line in there.splitlines() if line.startswith("Figure")]
    assert [line.split()[1] for line in lines] == list(TWO)
    assert _timeless(here).replace("here", "there") == _timeless(there)


def test_check_on_a_running_cluster_prints_the_in_process_table(scheduler, tmp_path, capsys):
    """``--scheduler ADDRESS``: each check (render and judge) one task; the table is the
    in-process one but for the times, the saved images the same bits."""
    assert pwc_gallery("check", *TWO, "--save", tmp_path / "here") == 0
    here = capsys.readouterr().out
    assert pwc_gallery("check", *TWO, "--save", tmp_path / "there", "--scheduler",
                       scheduler) == 0
    there = capsys.readouterr().out
    assert "2 of 2 figures pass" in there and there.index("13.3") < there.index("14.3")
    assert _timeless(here) == _timeless(there)
    for name in TWO_NAMES:
        for tag in ("img", "ref", "err"):
            a, b = (read_exr(tmp_path / d / f"{name}_{tag}.exr")["RGB"] for d in ("here", "there"))
            assert np.array_equal(a, b), (name, tag)


def test_cluster_options_are_checked(tmp_path, capsys):
    with pytest.raises(SystemExit) as e:
        pwc_gallery("render", FIGURE, "-o", tmp_path, "--workers", 0)
    assert e.value.code == 2 and "--workers must be >= 1, got 0" in capsys.readouterr().err
    with pytest.raises(SystemExit) as e:
        pwc_gallery("check", FIGURE, "--workers", 2, "--scheduler", "tcp://127.0.0.1:1")
    assert e.value.code == 2 and "not allowed with argument" in capsys.readouterr().err
