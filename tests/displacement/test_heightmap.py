"""Tests for displacement.heightmap: Listing 12.16's image height-map displacement."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from displacement.heightmap import diffuse_weave, image_height_displacement, weave
from displacement.state import ShadingState
from displacement.surfaces import UnitSquare
from displacement.textures import Texture, write_texture

ROOT = Path(__file__).resolve().parents[2]
SQ = UnitSquare()


def test_constant_grey_moves_along_the_normal_by_displace_times_grey():
    f = image_height_displacement(Texture(np.full((3, 3), 0.5)), displace=0.1)
    s = SQ.state_at_uv(np.array([[0.0, 0.0], [1.0, 1.0], [-3.2, 7.5], [1e9, -1e9]]))
    assert np.allclose(f(s), [[0.0, 0.0, 0.05]] * 4)


def test_colour_channels_are_averaged():
    t = Texture(np.full((2, 2, 3), [0.2, 0.4, 0.9]))
    f = image_height_displacement(t, displace=2.0)
    assert np.allclose(f(SQ.state_at_uv(np.array([[0.3, 0.3]]))), [[0, 0, 1.0]])


def test_scale_repeats_the_image_with_frac():
    ramp = Texture(np.arange(8, dtype=float)[None, :] / 7)
    f = diffuse_weave(ramp, scale=(8.0, 4.0), displace=0.05)
    rng = np.random.default_rng(1)
    uv = rng.random((200, 2))
    a = f(SQ.state_at_uv(uv))
    b = f(SQ.state_at_uv(uv + [1 / 8, 1 / 4]))
    c = f(SQ.state_at_uv(uv - [3 / 8, 7 / 4]))
    assert np.allclose(a, b) and np.allclose(a, c)
    # u = 1/16 * (1/8) maps to frac(u * 8) = 1/16: the centre of texel 0 -> grey 0
    s = SQ.state_at_uv(np.array([[1 / 128, 0.5], [15 / 128, 0.5]]))
    assert np.allclose(f(s)[:, 2], [0.0, 0.05])


def test_displacement_follows_the_state_normal():
    rng = np.random.default_rng(2)
    normal = rng.normal(size=(5, 3))
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    s0 = SQ.state_at_uv(rng.random((5, 2)))
    s = ShadingState(s0.position, normal, s0.uv, s0.tangent_u, s0.tangent_v)
    f = image_height_displacement(Texture(np.ones((1, 1))), displace=-0.3)
    assert np.allclose(f(s), -0.3 * normal)


def test_reads_a_path_linear_and_reports_errors(tmp_path):
    write_texture(tmp_path / "h.png", np.full((2, 2), 128 / 255))
    f = weave(tmp_path / "h.png", displace=1.0)
    assert f(SQ.state_at_uv(np.array([[0.5, 0.5]])))[0, 2] == pytest.approx(128 / 255)
    assert f.name == "diffuse_weave"
    with pytest.raises(FileNotFoundError, match="missing.png"):
        diffuse_weave(tmp_path / "missing.png")
    with pytest.raises(ValueError, match="Texture or a path"):
        image_height_displacement(3.0)
    with pytest.raises(ValueError, match="displace must be finite"):
        image_height_displacement(Texture(np.ones((1, 1))), displace=np.nan)
    with pytest.raises(ValueError, match="scale must be finite"):
        image_height_displacement(Texture(np.ones((1, 1))), scale=(np.inf, 1))


def test_gallery_weave_as_displacement_stays_within_its_range():
    f = diffuse_weave(ROOT / "gallery" / "textures" / "weave_depth.png", (8, 4), 0.05)
    d = f(SQ.state_at_uv(np.random.default_rng(3).random((5000, 2))))
    assert np.all(d[:, :2] == 0.0)
    assert d[:, 2].min() >= 0.0 and d[:, 2].max() <= 0.05
    assert d[:, 2].max() - d[:, 2].min() > 0.03
