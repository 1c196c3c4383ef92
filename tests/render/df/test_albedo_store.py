"""The glossy lobes' albedo columns kept on disk (``render.df._albedo._stored``): a column
read back equals the one computed, bit for bit; a damaged file is computed again; an
unwritable folder only means the column is not kept."""

from __future__ import annotations

import numpy as np
import pytest

import render.df  # noqa: F401 - the df classes and their kernels
from render.df import _albedo
from render.df.simple_glossy_bsdf import simple_glossy_bsdf
from render.jit import cache_dir


@pytest.fixture
def fresh(tmp_path, monkeypatch):
    """An empty cache folder and empty in-process caches."""
    monkeypatch.setenv("PWC_CACHE_DIR", str(tmp_path))
    for f in (_albedo.iso_column, _albedo.aniso_column):
        f.cache_clear()
    yield cache_dir() / "albedo"
    for f in (_albedo.iso_column, _albedo.aniso_column):
        f.cache_clear()


def _no_compute(*args, **kwargs):
    raise AssertionError("computed, not read")


def test_a_column_is_kept_and_read_back_bit_for_bit(fresh, monkeypatch):
    iso = _albedo.iso_column(simple_glossy_bsdf, "scatter_reflect", 1.0, 20)
    aniso = _albedo.aniso_column(simple_glossy_bsdf, "scatter_reflect", 1.0, 12, 30)
    assert len(list(fresh.glob("*.npy"))) == 2
    assert iso.shape == (_albedo.N_MU,) and aniso.shape == (_albedo.N_PHI, _albedo.N_MU_A)
    assert np.all((iso > 0) & (iso <= 1 + 1e-12))
    _albedo.iso_column.cache_clear()
    _albedo.aniso_column.cache_clear()
    monkeypatch.setattr(_albedo, "_mean_weight", _no_compute)
    np.testing.assert_array_equal(
        _albedo.iso_column(simple_glossy_bsdf, "scatter_reflect", 1.0, 20), iso)
    np.testing.assert_array_equal(
        _albedo.aniso_column(simple_glossy_bsdf, "scatter_reflect", 1.0, 12, 30), aniso)


def test_the_columns_of_different_arguments_are_kept_apart(fresh):
    a = _albedo.iso_column(simple_glossy_bsdf, "scatter_reflect", 1.0, 5)
    b = _albedo.iso_column(simple_glossy_bsdf, "scatter_reflect", 1.0, 30)
    _albedo.iso_column.cache_clear()
    assert np.all(_albedo.iso_column(simple_glossy_bsdf, "scatter_reflect", 1.0, 5) == a)
    assert np.all(_albedo.iso_column(simple_glossy_bsdf, "scatter_reflect", 1.0, 30) == b)
    assert not np.array_equal(a, b)  # a smooth lobe keeps more energy at grazing angles


@pytest.mark.parametrize("damage", [b"", b"not a numpy file", b"\x93NUMPY\x01\x00"])
def test_a_damaged_file_is_computed_again(fresh, damage):
    good = _albedo.iso_column(simple_glossy_bsdf, "scatter_reflect", 1.0, 20)
    (path,) = fresh.glob("*.npy")
    path.write_bytes(damage)
    _albedo.iso_column.cache_clear()
    np.testing.assert_array_equal(
        _albedo.iso_column(simple_glossy_bsdf, "scatter_reflect", 1.0, 20), good)
    assert np.array_equal(np.load(path), good)  # and written again, whole


def test_an_unwritable_folder_only_means_the_column_is_not_kept(fresh):
    fresh.parent.mkdir(parents=True)
    fresh.write_text("a file where the folder would be")
    column = _albedo.iso_column(simple_glossy_bsdf, "scatter_reflect", 1.0, 20)
    assert column.shape == (_albedo.N_MU,) and np.all(np.isfinite(column))
