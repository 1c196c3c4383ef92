"""A non-editable install (``pip install .``) carries everything the commands find by
name: the bundled profiles, the gallery's scenes, textures and references, the MDL
runtime."""

from __future__ import annotations

import os
import subprocess
import sys
import tomllib

import pytest
from repo import ROOT

PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))


def test_every_package_is_listed():
    listed = set(PYPROJECT["tool"]["setuptools"]["packages"])
    on_disk = {".".join(p.parent.relative_to(ROOT).parts)
               for top in ("pwc", "mdl", "displacement", "render", "trade", "gallery")
               for p in (ROOT / top).rglob("__init__.py")}
    assert on_disk <= listed, f"add to pyproject.toml's packages: {sorted(on_disk - listed)}"
    mapped = PYPROJECT["tool"]["setuptools"]["package-dir"]
    for package, folder in mapped.items():
        assert package in listed and (ROOT / folder).is_dir()


# the scene loads a texture (travertine.png) and a profile (ornament_2) by name
CHECK = """
import pathlib, sys
import pwc, render, mdl
from render.library.resources import bundled_scenes, bundled_textures, load_texture
from render.scene import load_scene
site = pathlib.Path(sys.argv[1]).resolve()
for module in (pwc, render, mdl):
    assert site in pathlib.Path(module.__file__).resolve().parents, module.__file__
from render.mdlc.natives import LIBRARY_DIR
assert site in LIBRARY_DIR.resolve().parents and (LIBRARY_DIR / "geometry.mdl").is_file()
assert site in bundled_scenes().resolve().parents and site in bundled_textures().resolve().parents
scene = load_scene(bundled_scenes() / "fig_15_22.toml")
assert load_texture("uv.png").data.shape[2] == 3
import gallery
from gallery.compare import read_reference, read_table, reference_dir
from gallery.figures import figures
assert site in pathlib.Path(gallery.__file__).resolve().parents
assert site in reference_dir().resolve().parents
assert set(read_table()) == {f.name for f in figures()}
assert read_reference("fig_15_22").shape == (192, 256, 3)
print("ok", len(scene.objects), bundled_scenes())
"""


@pytest.mark.slow
def test_non_editable_install_finds_its_data_outside_the_source_tree(tmp_path):
    """``pip install --target`` (a real, non-editable install of the built wheel) into a
    temporary folder that is put first on the path, run from a folder elsewhere.  (A
    nested venv would not see the packages of a venv the tests run in.)"""
    site = tmp_path / "site"
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PWC_PROFILE_PATH")}
    r = subprocess.run([sys.executable, "-m", "pip", "install", "--quiet", "--no-deps",
                        "--no-build-isolation", "--disable-pip-version-check", "--target",
                        str(site), str(ROOT)],
                       cwd=tmp_path, env=env, capture_output=True, text=True, timeout=900)
    assert r.returncode == 0, r.stdout + r.stderr
    env["PYTHONPATH"] = str(site)
    work = tmp_path / "elsewhere"
    work.mkdir()

    def run(*args):
        r = subprocess.run([sys.executable, *args], cwd=work, env=env, capture_output=True,
                           text=True, timeout=600)
        assert r.returncode == 0, r.stdout + r.stderr
        return r

    run("-m", "pwc", "compile", "ornament_2", "-o", "out/")
    assert (work / "out" / "ornament_2.mdl").is_file() and (work / "out" / "pw_curve.mdl").is_file()
    source = run("-m", "pwc", "info", "ornament_2").stdout.splitlines()[1].split(None, 1)[1]
    assert source == str(site / "pwc" / "profiles" / "ornament_2.pwc"), source
    assert run("-c", CHECK, str(site)).stdout.startswith("ok")
    assert "{render,check,sheet}" in run("-m", "pwc", "gallery", "--help").stdout
    version = run("-m", "pwc", "--version").stdout.strip()
    assert version == f"pwc {PYPROJECT['project']['version']}"
