"""The loop pwc -> MDL -> image, closed from the command line.

``pwc compile ornament_2`` writes ``ornament_2.mdl`` and ``pw_curve.mdl``; a module written
in MDL beside the scene (``mouldings.mdl``) imports both and displaces a square along v by
the profile through ``pw_curve::point_along_pwc``; ``pwc render`` renders the scene.  The
image must be statistically the same as the built-in Python material with that profile,
``stone_ornament_2()`` (Listing 15.11, Figure 15.22's scene).

The statistics: pixels are independent samples.  Two renders of each scene with four
different seeds estimate each pixel's variance; over blocks of 8 x 8 pixels the difference
of the two scenes' means, divided by its standard error, must stay within 5 (48 blocks
of a 64 x 48 image, 3 channels: a false alarm has probability below 1e-4), and the whole
image's mean within 4 standard errors.  The same test on a moulding 15 % deeper must fail: the
test can see a difference of that size.
"""

from __future__ import annotations

import numpy as np
import pytest

from pwc.cli import main
from render.film import read_exr
from render.integrator import render
from render.scene import load_scene
from tests.support.repo import ROOT

MOULDINGS = """\
// A moulding written in MDL: ornament_2's profile (ornament_2.mdl, written by
// `pwc compile ornament_2`) swept along v through pw_curve.mdl's point_along_pwc.
mdl 1.6;

import ::df::*;
import ::state::*;
import ::math::*;
import ::pw_curve::*;
import ::ornament_2::*;
import ::materials::travertine;

float3 sweep(uniform pw_curve::pw_point[<N>] pwc, float scale)
{
    float v = state::texture_coordinate(0).y;
    float2 p = pw_curve::point_along_pwc(v, pwc);
    return scale * (p.x * state::normal() + (p.y - v) * state::texture_tangent_v(0));
}

export material stone_molding(float scale = 1.0) = let {
    material stone = materials::travertine(1.0, ornament_2::ornament_2_length);
} in material(
    surface: stone.surface,
    geometry: material_geometry(displacement: sweep(ornament_2::ornament_2, scale)));
"""

RESOLUTION = (64, 48)
SPP = 8


def scene_text(material: str) -> str:
    text = (ROOT / "gallery" / "scenes" / "fig_15_22.toml").read_text(encoding="utf-8")
    assert 'material = """stone_ornament_2()"""' in text
    return text.replace('material = """stone_ornament_2()"""', f"material = {material}")


@pytest.fixture(scope="module")
def loop(tmp_path_factory):
    d = tmp_path_factory.mktemp("loop")
    assert main(["compile", "ornament_2", "-o", f"{d}/"]) == 0
    assert (d / "ornament_2.mdl").is_file() and (d / "pw_curve.mdl").is_file()
    (d / "mouldings.mdl").write_text(MOULDINGS, encoding="utf-8")
    for name, material in [
            ("mdl", '{ module = "mouldings.mdl", call = "stone_molding(scale: 1.0)" }'),
            ("deeper", '{ module = "mouldings.mdl", call = "stone_molding(scale: 1.15)" }'),
            ("builtin", '"""stone_ornament_2()"""')]:
        (d / f"{name}.toml").write_text(scene_text(material), encoding="utf-8")
    return d


def cli_render(path, seed: int, out) -> np.ndarray:
    status = main(["render", str(path), "-o", str(out), "--spp", str(SPP), "--seed", str(seed),
                   "--resolution", *map(str, RESOLUTION), "--quiet"])
    assert status == 0
    return read_exr(out)["RGBA"][..., :3]


def api_render(path, seed: int) -> np.ndarray:
    scene = load_scene(path, overrides={"width": RESOLUTION[0], "height": RESOLUTION[1]})
    rgb = render(scene, spp=SPP, seed=seed, progress=False).rgb()
    return rgb.astype(np.float32).astype(np.float64)  # as the EXR holds it


def z_scores(a1, a2, b1, b2, k: int = 8):
    """Block z-scores of mean(a) - mean(b), the variances from the seed pairs."""
    h, w, _ = a1.shape
    h, w = h // k * k, w // k * k

    def blocks(x):
        return x[:h, :w].reshape(h // k, k, w // k, k, 3)

    diff = blocks((a1 + a2) / 2 - (b1 + b2) / 2).mean(axis=(1, 3))
    var = (blocks((a1 - a2) ** 2).mean(axis=(1, 3)) + blocks((b1 - b2) ** 2).mean(axis=(1, 3))) / 4
    se = np.sqrt(var / (k * k))
    z = np.where(se > 0, diff / np.where(se > 0, se, 1.0), np.where(diff == 0, 0.0, np.inf))
    whole = ((a1 + a2) / 2 - (b1 + b2) / 2).mean(axis=(0, 1))
    whole_se = np.sqrt((((a1 - a2) ** 2).mean(axis=(0, 1)) + ((b1 - b2) ** 2).mean(axis=(0, 1)))
                       / 4 / (h * w))
    return z, whole / whole_se


def test_the_emitted_module_is_the_profile_module(loop):
    """pwc compile's module is the one the workbench makes of ornament_2.pwc."""
    from render.mdlc.natives import WorkbenchModules

    ours = WorkbenchModules().find("::ornament_2").text
    assert (loop / "ornament_2.mdl").read_text(encoding="utf-8") == ours


def test_the_displacement_written_in_mdl_is_the_builtin_one(loop):
    from displacement.surfaces import UnitSquare

    mdl = next(o for o in load_scene(loop / "mdl.toml").objects if o.name == "ornament")
    builtin = next(o for o in load_scene(loop / "builtin.toml").objects if o.name == "ornament")
    s = UnitSquare().state_at_uv(np.random.default_rng(2).random((2000, 2)))
    # the emitted module prints the curve's numbers to 9 significant digits
    np.testing.assert_allclose(mdl.material.displacement(s), builtin.material.displacement(s),
                               rtol=0, atol=1e-8)
    ku, kv = mdl.material.displacement.uv_knots  # the profile's breakpoints, along v
    assert ku is None
    np.testing.assert_allclose(kv, builtin.material.displacement.uv_knots[1], atol=1e-8)


def test_the_loop_renders_the_builtin_image(loop, tmp_path):
    a1 = cli_render(loop / "mdl.toml", 1, tmp_path / "a1.exr")
    a2 = cli_render(loop / "mdl.toml", 2, tmp_path / "a2.exr")
    b1, b2 = api_render(loop / "builtin.toml", 3), api_render(loop / "builtin.toml", 4)
    assert a1.shape == (RESOLUTION[1], RESOLUTION[0], 3)
    z, whole = z_scores(a1, a2, b1, b2)
    assert np.abs(z).max() < 5.0, np.abs(z).max()
    assert np.abs(whole).max() < 4.0, whole
    # the same seed: the same image up to float32 output and dicing rounding
    assert np.abs(a1 - api_render(loop / "builtin.toml", 1)).mean() < 1e-3
    # and the test sees a moulding 15 % deeper
    d1, d2 = api_render(loop / "deeper.toml", 1), api_render(loop / "deeper.toml", 2)
    z, _ = z_scores(d1, d2, b1, b2)
    assert np.abs(z).max() > 8.0
