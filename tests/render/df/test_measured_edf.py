"""df::measured_edf and IES LM-63 light profiles: files written from known analytic
distributions read back and evaluated as those distributions, the edf's normalisation,
sampling (χ², consistency), symmetries, the global frame, and malformed files (located
errors with a fix, never a traceback)."""

from __future__ import annotations

import numpy as np
import pytest
from render_edf_adapter import EdfAsBsdf

from render.df import IesError, LightProfile, measured_edf, read_ies, spot_edf, write_ies
from render.expr import MaterialExprError, parse_material
from render.testing import chi2_test, direction, sample_lanes, sphere_integral

DEG = np.arange(0.0, 90.5, 1.0)


def _file(tmp_path, name, vertical, horizontal, fn, **kw):
    """An IES file of ``fn(gamma, C)`` (degrees) on the grid."""
    g, c = np.meshgrid(np.radians(vertical), np.radians(horizontal))
    return write_ies(tmp_path / name, vertical, horizontal, fn(g, c), **kw)


def _local(e, w):
    return e.eval(w)[:, 0]


def _gamma_c(w):
    return np.arccos(np.clip(w[:, 2], -1, 1)), np.mod(np.arctan2(w[:, 1], w[:, 0]), 2 * np.pi)


def _dirs(rng, n=2000):
    w = rng.normal(size=(n, 3))
    w[:, 2] = np.abs(w[:, 2]) + 0.05
    return w / np.linalg.norm(w, axis=1, keepdims=True)


def test_a_cosine_power_file_reads_back_and_evaluates_as_it(tmp_path, rng):
    """I = 100 cos^n gamma (rotationally symmetric): edf = m (n + 1) cos^(n-1) / (2 pi)."""
    for n in (1, 3):
        path = _file(tmp_path, f"cos{n}.ies", DEG, [0.0], lambda g, c, n=n: 100 * np.cos(g) ** n)
        p = read_ies(path)
        assert np.array_equal(p.vertical, DEG) and np.array_equal(p.horizontal, [0.0])
        assert np.allclose(p.candela[0], 100 * np.cos(np.radians(DEG)) ** n, rtol=1e-15,
                           atol=1e-12)
        e = measured_edf(p, multiplier=2.0, global_distribution=False)
        w = _dirs(rng)
        want = 2.0 * (n + 1) * w[:, 2] ** (n - 1) / (2 * np.pi)
        # the intensity shape edf cos, bilinear between 1-degree steps: (1 deg)^2 / 8 of
        # its curvature, relative to its peak
        got = _local(e, w) * w[:, 2]
        np.testing.assert_allclose(got, want * w[:, 2], rtol=0, atol=2e-4 * want.max())
        # at the file's angles exactly (up to the flux of the interpolant)
        nodes = np.array([direction(a, 0.0) for a in (0.0, 20.0, 45.0, 60.0)])
        ratio = _local(e, nodes) * nodes[:, 2] / (2.0 * (n + 1) * nodes[:, 2] ** n / (2 * np.pi))
        assert np.allclose(ratio, ratio[0], rtol=1e-12) and abs(ratio[0] - 1) < 1e-4


@pytest.mark.parametrize(("last", "fn"), [
    (90.0, lambda g, c: np.cos(g) * (1 + 0.5 * np.cos(2 * c))),
    (180.0, lambda g, c: np.cos(g) * (1 + 0.5 * np.cos(c))),
    (360.0, lambda g, c: np.cos(g) * (1 + 0.5 * np.sin(c))),
])
def test_horizontal_symmetries_cover_the_circle(tmp_path, rng, last, fn):
    h = np.arange(0.0, last + 0.5, 1.0)
    e = measured_edf(_file(tmp_path, "sym.ies", DEG, h, fn), global_distribution=False)
    w = _dirs(rng)
    g, c = _gamma_c(w)
    flux = 2 * np.pi * 0.5  # ∫ cos gamma dw over the hemisphere; the C terms integrate to 0
    want = fn(g, c) / flux
    np.testing.assert_allclose(_local(e, w) * w[:, 2], want, rtol=0, atol=3e-4 * want.max())


def test_tangent_u_turns_the_profile(tmp_path):
    e0 = measured_edf(_file(tmp_path, "a.ies", DEG, np.arange(0.0, 360.5, 1.0),
                            lambda g, c: np.cos(g) * (1 + 0.8 * np.cos(c))),
                      global_distribution=False)
    e90 = measured_edf(e0.profile, global_distribution=False, tangent_u=(0.0, 1.0, 0.0))
    w = direction(50.0, 30.0)[None]
    turned = direction(50.0, 120.0)[None]
    assert _local(e90, turned)[0] == pytest.approx(_local(e0, w)[0], rel=1e-6)


@pytest.mark.parametrize("kind", ["cos", "narrow", "lopsided"])
def test_normalised_and_sampled_exactly(tmp_path, kind):
    fns = {"cos": lambda g, c: np.cos(g),
           "narrow": lambda g, c: np.cos(g) ** 40,
           "lopsided": lambda g, c: np.cos(g) * (1.2 + np.cos(c)) * (g < np.radians(70))}
    h = [0.0] if kind != "lopsided" else np.arange(0.0, 360.5, 5.0)
    e = measured_edf(_file(tmp_path, f"{kind}.ies", DEG, h, fns[kind]), multiplier=0.7,
                     global_distribution=False)
    # the interpolant's kinks at the file's angles are panel edges of the quadrature
    rule = dict(n_beta=720, order=8, breaks=tuple(np.radians(DEG[1:-1])))
    total = sphere_integral(lambda w: _local(e, w) * w[:, 2], [0.0, 0.0, 1.0], +1, **rule)
    assert total == pytest.approx(0.7, rel=2e-5)
    # the sampler's density is bilinear on cells of (cos gamma, C): the midpoint rule on
    # sub-cells is exact where it emits everywhere, and it is the success rate
    m, q = 4 * 48, 4 * 72
    mu = (np.arange(m) + 0.5) / m
    c = (np.arange(q) + 0.5) / q * 2 * np.pi
    mu, c = np.meshgrid(mu, c)
    sn = np.sqrt(1 - mu**2)
    w = np.stack([sn * np.cos(c), sn * np.sin(c), mu], axis=-1).reshape(-1, 3)
    pdf = np.sum(e.pdf(w)) * (1 / m) * (2 * np.pi / q)
    if kind != "lopsided":
        assert pdf == pytest.approx(1.0, rel=1e-12)
    res = chi2_test(EdfAsBsdf(e), direction(0.0), test_count=3)
    assert res.passed, str(res)
    s = sample_lanes(EdfAsBsdf(e), direction(0.0), 20_000)
    ok = s.valid
    spread = np.sqrt(max(pdf * (1 - pdf), 0.0) / 20_000)
    assert ok.mean() == pytest.approx(pdf, abs=4 * spread + 1e-3)
    np.testing.assert_allclose(s.pdf[ok], e.pdf(s.wi[ok]), rtol=1e-12)
    np.testing.assert_allclose(s.weight[ok, 0], _local(e, s.wi[ok]) * s.wi[ok, 2] / s.pdf[ok],
                               rtol=1e-12)
    # the sampler follows the profile: the weights' mean is the emitted total
    assert np.mean(np.where(ok, s.weight[:, 0], 0.0)) == pytest.approx(0.7, rel=0.02)


def test_light_above_the_horizon_is_not_emitted(tmp_path, rng):
    """A profile over 0-180 degrees: the front hemisphere's flux normalises it, nothing
    leaves behind the surface."""
    v = np.arange(0.0, 180.5, 1.0)
    e = measured_edf(_file(tmp_path, "both.ies", v, [0.0], lambda g, c: 1.0 + 0 * g),
                     global_distribution=False)
    w = _dirs(rng)
    np.testing.assert_allclose(_local(e, w), 1 / (2 * np.pi * w[:, 2]), rtol=1e-12)
    assert np.all(_local(e, -w) == 0.0)
    with pytest.raises(IesError, match="no light below the horizontal"):
        measured_edf(_file(tmp_path, "up.ies", np.arange(90.0, 180.5, 5.0), [0.0],
                           lambda g, c: 1.0 + 0 * g), global_distribution=False)


def test_a_profile_as_cos_power_is_the_spot_edf(tmp_path, rng):
    """spot_edf(k, spread pi) emits I ~ cos^(k+1): the same edf as that profile."""
    k = 3.0
    e = measured_edf(_file(tmp_path, "spot.ies", DEG, [0.0], lambda g, c: np.cos(g) ** (k + 1)),
                     global_distribution=False)
    s = spot_edf(exponent=k, global_distribution=False)
    w = _dirs(rng)
    want = s.eval(w)[:, 0] * w[:, 2]
    # cos^4 bilinear at 1-degree steps: (1 deg)^2 / 8 max |f''| = 1.5e-4 of the peak
    np.testing.assert_allclose(_local(e, w) * w[:, 2], want, rtol=0, atol=3e-4 * want.max())


def test_global_frame_fixes_the_profile_in_object_space(tmp_path):
    path = _file(tmp_path, "g.ies", DEG, [0.0], lambda g, c: np.cos(g) ** 20)
    c, s_ = np.cos(np.radians(30.0)), np.sin(np.radians(30.0))
    o2l = np.array([[1.0, 0.0, 0.0], [0.0, c, -s_], [0.0, s_, c]])
    e = measured_edf(path, object_to_local=o2l)
    peak = o2l @ [0.0, 0.0, 1.0]
    local = measured_edf(path, global_distribution=False)
    # along the turned nadir it emits what the local profile emits along the normal,
    # divided by the cosine to the surface
    assert _local(e, peak[None])[0] == pytest.approx(
        _local(local, np.array([[0.0, 0.0, 1.0]]))[0] / peak[2], rel=1e-9)
    # a global_frame that turns it back is the local profile
    back = measured_edf(path, object_to_local=o2l, global_frame=o2l.T)
    w = np.array([direction(20.0, 40.0)])
    assert _local(back, w)[0] == pytest.approx(_local(local, w)[0], rel=1e-9)
    res = chi2_test(EdfAsBsdf(e), direction(0.0), test_count=1)
    assert res.passed, str(res)


def test_extremes_stay_finite(tmp_path):
    e = measured_edf(_file(tmp_path, "x.ies", DEG, [0.0], lambda g, c: np.cos(g) ** 2),
                     global_distribution=False)
    grazing = np.array([[1.0, 0.0, 0.0], [1.0, 0.0, 1e-12], [0.0, 0.0, 1.0], [0, 0, -1.0]])
    grazing /= np.linalg.norm(grazing, axis=1, keepdims=True)
    v = e.eval(grazing)
    assert np.all(np.isfinite(v)) and v[0, 0] == 0.0 and v[3, 0] == 0.0
    for u in (0.0, 1.0 - 2**-53, 1.0):
        s = e.sample(np.full(4, u), np.full((4, 2), u))
        assert np.all(np.isfinite(s.wo)) and np.all(np.isfinite(s.weight))
    with pytest.raises(ValueError, match="multiplier"):
        measured_edf(e.profile, multiplier=-1.0, global_distribution=False)
    with pytest.raises(ValueError, match="object_to_local"):
        measured_edf(e.profile)


# ------------------------------------------------------------------ malformed files
GOOD = """IESNA:LM-63-2002
[TEST] x
TILT=NONE
1 -1 1 3 1 1 2 0 0 0
1 1 0
0 45 90
0
100 70 0
"""

BAD = [
    ("no TILT", GOOD.replace("TILT=NONE\n", ""), r":\d+: expected a \[KEYWORD\] line", "TILT"),
    ("tilt file", GOOD.replace("TILT=NONE", "TILT=lamp.tlt"), r":3: TILT=LAMP.TLT", "INCLUDE"),
    ("a word", GOOD.replace("100 70 0", "100 seventy 0"), r":8: candela value 2 of 3",
     "decimal"),
    ("cut short", GOOD.replace("100 70 0\n", "100 70\n"), r":8: the file ends before "
     r"candela value 3", "cut short"),
    ("type B", GOOD.replace("1 -1 1 3 1 1 2", "1 -1 1 3 1 2 2"), r":4: photometric type 2 "
     r"\(B\)", "type C"),
    ("decreasing", GOOD.replace("0 45 90", "0 90 45"), r":6: vertical angles must increase: "
     r"angle 3 \(45\) follows 90", "increasing"),
    ("range", GOOD.replace("0 45 90", "10 45 90"), r":6: type C vertical angles", "nadir"),
    ("negative", GOOD.replace("100 70 0", "100 -70 0"), r":8: candela value 2 is -70",
     ">= 0"),
    ("extra", GOOD + "5\n", r":9: unexpected value '5'", "counts"),
    ("count", GOOD.replace("1 -1 1 3 1", "1 -1 1 0 1"), r":4: 0 vertical angles", "give 1"),
    ("empty", "", r":1: the file is empty", "IES"),
]


@pytest.mark.parametrize(("what", "text", "message", "fix"), BAD, ids=[b[0] for b in BAD])
def test_malformed_files_are_located_errors(tmp_path, what, text, message, fix):
    path = tmp_path / "lamp.ies"
    path.write_text(text)
    with pytest.raises(IesError) as err:
        read_ies(path)
    msg = str(err.value)
    assert msg.startswith(str(path) + ":"), msg
    assert __import__("re").search(message, msg), msg
    assert fix in msg, msg


def test_a_good_file_reads(tmp_path):
    path = tmp_path / "lamp.ies"
    path.write_text(GOOD)
    p = read_ies(path)
    assert isinstance(p, LightProfile) and p.candela.tolist() == [[100.0, 70.0, 0.0]]
    # and with a tilt block that is read past
    path.write_text(GOOD.replace("TILT=NONE", "TILT=INCLUDE\n1\n2\n0 90\n1 0.5"))
    assert read_ies(path).candela.tolist() == [[100.0, 70.0, 0.0]]


def test_in_a_material_expression(tmp_path):
    write_ies(tmp_path / "lamp.ies", DEG, [0.0], 100 * np.cos(np.radians(DEG))[None, :])
    m = parse_material(
        'material(surface: material_surface(emission: material_emission(emission: '
        'df::measured_edf(profile: light_profile("lamp.ies"), multiplier: 2.0, '
        'global_distribution: true, global_frame: float3x3(float3(1, 0, 0), float3(0, 0, 1), '
        'float3(0, -1, 0))), intensity: color(5.0))))', base_dir=tmp_path)
    edf = m.surface.emission.emission
    assert edf.name == "measured_edf" and edf.kwargs["multiplier"] == 2.0
    assert np.allclose(edf.kwargs["global_frame"], [[1, 0, 0], [0, 0, -1], [0, 1, 0]])
    (tmp_path / "bad.ies").write_text(GOOD.replace("100 70 0", "100 x 0"))
    text = 'df::measured_edf(profile: light_profile("bad.ies"))'
    with pytest.raises(MaterialExprError) as err:
        parse_material(f"material(surface: material_surface(emission: material_emission("
                       f"emission: {text})))", base_dir=tmp_path)
    assert "bad.ies:8: candela value 2 of 3" in str(err.value)
    with pytest.raises(MaterialExprError, match="no file 'nope.ies'"):
        parse_material('material(surface: material_surface(emission: material_emission('
                       'emission: df::measured_edf(profile: light_profile("nope.ies")))))',
                       base_dir=tmp_path)


@pytest.mark.parametrize(("text", "want"), [
    ("float3x3(2.0)", np.diag([2.0, 2.0, 2.0])),
    ("float3x3(1, 2, 3, 4, 5, 6, 7, 8, 9)", np.array([[1, 4, 7], [2, 5, 8], [3, 6, 9.0]])),
    ("float3x3(float3(1, 2, 3), float3(4, 5, 6), float3(7, 8, 9))",
     np.array([[1, 4, 7], [2, 5, 8], [3, 6, 9.0]])),
])
def test_float3x3_constructors(text, want):
    m = parse_material(f"material(surface: material_surface(emission: material_emission("
                       f"emission: df::spot_edf(exponent: 1.0, global_frame: {text}))))")
    assert np.array_equal(np.asarray(m.surface.emission.emission.kwargs["global_frame"]), want)


def test_float3x3_errors():
    with pytest.raises(MaterialExprError, match="float3x3"):
        parse_material("material(surface: material_surface(emission: material_emission("
                       "emission: df::spot_edf(exponent: 1.0, global_frame: float3x3(1, 2)))))")
