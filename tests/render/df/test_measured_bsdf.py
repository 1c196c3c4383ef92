"""df::measured_bsdf and the MBSDF reader: small files written from known analytic lobes
evaluate, sample and render as those lobes; malformed files are clear errors."""

from __future__ import annotations

import struct

import numpy as np
import pytest
from render_df_cases import (
    WOS,
    DfCase,
    check_consistency,
    check_no_nan,
    check_reciprocity,
    random_dirs,
)

from render import df
from render.df._mbsdf import MAGIC, MbsdfError, parse_mbsdf, read_mbsdf, write_mbsdf
from render.testing import chi2_test, direction, sample_lanes


def _grid(nt, nphi):
    t = np.linspace(0.0, np.pi / 2, nt)
    p = np.linspace(0.0, np.pi, nphi)
    return np.meshgrid(t, t, p, indexing="ij")


def phong(nt=31, nphi=61, n=20.0, k=0.8):
    """A reciprocal Phong lobe about the mirror direction, f = k (n + 2)/(2 pi) cos^n(alpha)
    (alpha between wi and wo's mirror image), sampled on the MBSDF grid."""
    ti, to, ph = _grid(nt, nphi)
    # wi at (ti, 0), wo mirrored at (to, ph + pi) -> cos alpha
    c = np.cos(ti) * np.cos(to) - np.sin(ti) * np.sin(to) * np.cos(ph)
    return k * (n + 2) / (2 * np.pi) * np.maximum(c, 0.0) ** n


def phong_eval(wo, wi, n=20.0, k=0.8):
    r = wo * [-1, -1, 1]
    c = np.maximum(np.sum(wi * r, axis=1), 0.0)
    return k * (n + 2) / (2 * np.pi) * c**n * np.maximum(wi[:, 2], 0.0)


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("mbsdf")
    lam = np.full((5, 5, 3), 0.7 / np.pi)
    rgb_r = np.broadcast_to(np.array([0.3, 0.15, 0.06]) / np.pi, (4, 4, 2, 3))
    rgb_t = np.full((4, 4, 2, 3), 0.4 / np.pi)
    return {
        "lambert": write_mbsdf(d / "lambert.mbsdf", reflection=lam,
                               metadata={"name": 'white "paint"', "note": "a\nb"}),
        "phong": write_mbsdf(d / "phong.mbsdf", reflection=phong()),
        "rgb": write_mbsdf(d / "rgb.mbsdf", reflection=rgb_r, transmission=rgb_t),
        "bright": write_mbsdf(d / "bright.mbsdf", reflection=np.full((3, 3, 1), 2.0 / np.pi)),
        "dir": d,
    }


def _cases(files):
    M = df.measured_bsdf
    return [
        DfCase("lambert", lambda: M(files["lambert"]), "diffuse", albedo_tol=1e-6),
        DfCase("phong", lambda: M(files["phong"]), "glossy", albedo_tol=1e-6,
               reciprocal=False),
        DfCase("rgb-rt", lambda: M(files["rgb"], mode="scatter_reflect_transmit"), "diffuse",
               transmits=True, albedo_tol=1e-6, reciprocal=False, chi2=False),
        DfCase("rgb-transmit", lambda: M(files["rgb"], mode="scatter_transmit"), "diffuse",
               transmits=True, albedo_tol=1e-6, reciprocal=False),
    ]


#: the cases' ids and chi-square pairs, known before the files exist (``make`` reads
#: ``files`` only when called)
_NO_FILES = _cases({})
CASE_IDS = [c.id for c in _NO_FILES]
CHI2 = [(c.id, w) for c in _NO_FILES if c.chi2 for w in ((0.0, 0.0), (60.0, 200.0))]


def _case(files, case_id):
    return next(c for c in _cases(files) if c.id == case_id)


@pytest.mark.parametrize("case_id", CASE_IDS)
def test_checklist(files, rng, case_id):
    case = _case(files, case_id)
    check_consistency(case, rng)
    check_no_nan(case, rng)
    if case.reciprocal:
        check_reciprocity(case, rng)


@pytest.mark.parametrize("case_id, w", CHI2, ids=[f"{c}-wo{w[0]:g}" for c, w in CHI2])
def test_chi2(files, case_id, w):
    # the sampling density is piecewise constant over the measurement's cells: its jumps
    # cut the test's cells, so each cell is integrated with 16 x 16 points (the default
    # 4 x 4 misjudges the jumps); the significance is shared by all len(CHI2) tests
    res = chi2_test(_case(files, case_id).make(), direction(*w), sample_count=200_000,
                    ires=16, test_count=len(CHI2))
    assert res.passed, f"{case_id} wo={w}: {res}"


@pytest.mark.parametrize("case_id, w", [(c, w) for c in CASE_IDS for w in WOS],
                         ids=[f"{c}-wo{w[0]:g}" for c in CASE_IDS for w in WOS])
def test_integrals(files, case_id, w):
    _integrals(_case(files, case_id), w)


def _aligned_integral(bsdf, wo, nt, nphi, side, order=8):
    """``∫ (eval, pdf) dwi`` over one side, cell by cell of the measurement's grid (the
    pdf is constant per cell, so this rule is exact for it; the general rings of
    render.testing cut its jumps)."""
    x, w = np.polynomial.legendre.leggauss(order)
    x, w = 0.5 * (x + 1), 0.5 * w
    tg = np.linspace(0, np.pi / 2, max(nt, 2))
    pg = np.linspace(0, np.pi, max(nphi, 2))
    phi_o = np.arctan2(wo[1], wo[0]) if np.hypot(wo[0], wo[1]) > 1e-12 else 0.0
    total = np.zeros(4)
    for a in range(len(tg) - 1):
        c0, c1 = np.cos(tg[a + 1]), np.cos(tg[a])
        cs = c0 + (c1 - c0) * x
        for b in range(len(pg) - 1):
            ph = pg[b] + (pg[b + 1] - pg[b]) * x
            for sign in (1.0, -1.0):
                C, PH = np.meshgrid(cs, phi_o + sign * ph, indexing="ij")
                S = np.sqrt(1 - C**2)
                wi = np.stack([S * np.cos(PH), S * np.sin(PH), side * C], -1).reshape(-1, 3)
                e, p = bsdf.eval_pdf(np.tile(wo, (len(wi), 1)), wi)
                W = (np.outer(w, w) * (c1 - c0) * (pg[b + 1] - pg[b])).ravel()
                total += W @ np.concatenate([e, p[:, None]], axis=1)
    return total


def _integrals(case, theta_phi):
    """The furnace, albedo() against MC and against quadrature of eval, and ∫ pdf against
    the sampler's success rate (both sides for transmitting cases)."""
    bsdf = case.make()
    wo = direction(*theta_phi)
    s = sample_lanes(bsdf, wo, 100_000, seed=11)
    mean, se = s.weight.mean(axis=0), s.weight.std(axis=0) / np.sqrt(100_000)
    assert np.all(mean <= 1.0 + 3 * se + 1e-12), (case.id, mean, se)
    alb = bsdf.albedo(wo[None])[0]
    assert np.all(np.abs(alb - mean) <= 4 * se + case.albedo_tol), (case.id, alb, mean, se)
    m = bsdf.measurement
    nt, _, nphi, _ = (m.reflection if m.reflection is not None else m.transmission).shape
    up = 1.0 if wo[2] >= 0 else -1.0
    q = _aligned_integral(bsdf, wo, nt, nphi, up)
    if case.transmits:
        q = q + _aligned_integral(bsdf, wo, nt, nphi, -up)
    assert q[3] == pytest.approx(s.valid.mean(), abs=4 * np.sqrt(1 / 100_000) + 1e-9), case.id
    assert np.allclose(q[:3], alb, atol=2e-5), (case.id, q, alb)


def test_lambert_file_is_the_lambert_lobe(files, rng):
    b = df.measured_bsdf(files["lambert"])
    d = df.diffuse_reflection_bsdf(tint=0.7)
    wo, wi = random_dirs(rng, 5000), random_dirs(rng, 5000)
    # float32 storage: 0.7/pi to 1e-7 relative
    assert np.allclose(b.eval(wo, wi), d.eval(wo, wi), rtol=1e-7, atol=0)
    assert np.allclose(b.albedo(wo), d.albedo(wo), rtol=1e-7, atol=0)
    m = read_mbsdf(files["lambert"])
    assert m.metadata == {"name": 'white "paint"', "note": "a\nb"}


def test_glossy_file_evaluates_as_its_lobe(files, rng):
    # the 3-degree grid's trilinear interpolation: within 5 % of the lobe's peak where the
    # lobe is, and its albedo against Monte Carlo of the analytic lobe within 1 %
    b = df.measured_bsdf(files["phong"])
    wo = random_dirs(rng, 20_000)
    wo[:, 2] = np.abs(wo[:, 2]) * 0.9 + 0.1
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    wi = wo * [-1, -1, 1] + 0.15 * rng.normal(size=wo.shape)
    wi[:, 2] = np.abs(wi[:, 2])
    wi /= np.linalg.norm(wi, axis=1, keepdims=True)
    got, want = b.eval(wo, wi)[:, 0], phong_eval(wo, wi)
    peak = 0.8 * 22 / (2 * np.pi)
    assert np.max(np.abs(got - want)) < 0.05 * peak
    w = direction(30.0, 40.0)
    s = sample_lanes(b, w, 100_000)
    u = random_dirs(np.random.default_rng(5), 400_000)
    u = u[u[:, 2] > 0]
    mc = 2 * np.pi * np.mean(phong_eval(np.tile(w, (len(u), 1)), u))
    assert b.albedo(w[None])[0, 0] == pytest.approx(mc, rel=0.01)
    assert s.weight.mean(axis=0)[0] == pytest.approx(mc, rel=0.01)


def test_parts_and_modes(files):
    w = direction(35.0)[None]
    c = np.array([0.3, 0.15, 0.06])
    assert np.allclose(df.measured_bsdf(files["rgb"]).albedo(w)[0], c, rtol=1e-6)
    assert np.allclose(df.measured_bsdf(files["rgb"], mode="scatter_transmit").albedo(w)[0],
                       0.4, rtol=1e-6)
    assert np.allclose(df.measured_bsdf(files["rgb"], mode="scatter_reflect_transmit")
                       .albedo(w)[0], c + 0.4, rtol=1e-6)


def test_multiplier_is_bounded_by_the_albedo(files):
    w = direction(20.0)[None]
    b = df.measured_bsdf(files["bright"])  # albedo 2: scaled to 1
    assert b.scale == pytest.approx(0.5, rel=1e-6)
    assert np.allclose(b.albedo(w), 1.0, rtol=1e-6)
    assert np.allclose(df.measured_bsdf(files["bright"], multiplier=0.25).albedo(w), 0.5,
                       rtol=1e-6)
    assert np.allclose(df.measured_bsdf(files["lambert"], multiplier=1.2).albedo(w), 0.84,
                       rtol=1e-6)
    assert not np.any(df.measured_bsdf(files["lambert"], multiplier=0.0).albedo(w))


def test_file_round_trip(tmp_path):
    data = np.random.default_rng(2).random((3, 3, 4, 3)).astype(np.float32)
    p = write_mbsdf(tmp_path / "x.mbsdf", transmission=data)
    m = read_mbsdf(p)
    assert m.reflection is None and np.array_equal(m.transmission, data.astype(np.float64))
    raw = p.read_bytes()
    assert raw.startswith(MAGIC) and b"MBSDF_DATA_TRANSMISSION=\n" in raw
    # the spec's offset order: idx_theta_i * n_phi * n_theta + idx_theta_o * n_phi + idx_phi
    start = raw.index(b"=\n") + 2 + 12
    first = struct.unpack_from("<3f", raw, start + 4 * 3 * (1 * 4 * 3 + 2 * 4 + 3))
    assert np.allclose(first, data[1, 2, 3])


@pytest.mark.parametrize(("raw", "match"), [
    (b"NVIDIA ARC MBSDF V2\n", "not an MBSDF file"),
    (MAGIC + b"MBSDF_DATA=\n" + struct.pack("<3I", 2, 2, 2), "type is 2"),
    (MAGIC + b"MBSDF_DATA=\n" + struct.pack("<3I", 0, 0, 2), "resolution is 0 x 2"),
    (MAGIC + b"MBSDF_DATA=\n" + struct.pack("<3I", 0, 2, 2) + b"\0" * 12, "truncated"),
    (MAGIC + b"MBSDF_DATA=\n" + struct.pack("<2I", 0, 2), "truncated"),
    (MAGIC + b'name="x"\n', "no data block"),
    (MAGIC + b"name=x\n", "key=\"value\""),
    (MAGIC + b"MBSDF_DATA=\n" + struct.pack("<3I", 0, 1, 1) + struct.pack("<f", -1.0),
     "negative or non-finite"),
    (MAGIC + b"MBSDF_DATA_TRANSMISSION=\n" + struct.pack("<3If", 0, 1, 1, 0.1)
     + b"MBSDF_DATA_REFLECTION=\n" + struct.pack("<3If", 0, 1, 1, 0.1), "must come before"),
])
def test_malformed_files_name_the_file_and_the_fix(raw, match):
    with pytest.raises(MbsdfError, match=match) as e:
        parse_mbsdf(raw, "bad.mbsdf")
    assert "bad.mbsdf" in str(e.value)


def test_missing_file_and_bad_argument(tmp_path):
    with pytest.raises(MbsdfError, match="cannot read the measurement"):
        df.measured_bsdf(tmp_path / "none.mbsdf")
    with pytest.raises(ValueError, match="must be a bsdf_measurement"):
        df.measured_bsdf(3.0)


def test_parses_in_scene_expressions_and_errors_without_traceback(files, tmp_path):
    from displacement.surfaces import UnitSquare
    from render.expr import MaterialExprError, parse_material

    m = parse_material('material(surface: material_surface(scattering: df::measured_bsdf('
                       'measurement: bsdf_measurement("lambert.mbsdf"), multiplier: 0.5)))',
                       base_dir=files["dir"])
    b = m.surface.scattering.bind(UnitSquare().state_at_uv(np.array([[0.5, 0.5]])))
    assert isinstance(b, df.MeasuredBsdf) and np.allclose(b.albedo(direction(0.0)[None]), 0.35,
                                                          rtol=1e-6)
    (tmp_path / "bad.mbsdf").write_bytes(b"hello")
    with pytest.raises(MaterialExprError, match="bad.mbsdf: not an MBSDF file"):
        parse_material('material(surface: material_surface(scattering: df::measured_bsdf('
                       'bsdf_measurement("bad.mbsdf"))))', base_dir=tmp_path)
    with pytest.raises(MaterialExprError, match="no file 'nothing.mbsdf'"):
        parse_material('material(surface: material_surface(scattering: df::measured_bsdf('
                       'bsdf_measurement("nothing.mbsdf"))))', base_dir=tmp_path)


def test_renders_as_its_lobe(files):
    # a measured Lambertian sphere and a diffuse_reflection_bsdf sphere under the same
    # light: the image means agree within the renders' noise (different samplers)
    from displacement.surfaces import UVSphere
    from render import material as M
    from render.camera import Camera
    from render.integrator import render
    from render.lights import ConstantEnvironment, PointLight
    from render.scene import RenderSettings, Scene, SceneObject

    def scene(bsdf):
        return Scene(Camera(position=(0, 0, 3), look_at=(0, 0, 0), fov_y_deg=30, width=24,
                            height=24),
                     [SceneObject(UVSphere(0.6), M.material(surface=M.material_surface(bsdf)),
                                  name="sphere", resolution=(64, 32))],
                     [ConstantEnvironment(0.5), PointLight((1.0, 1.5, 2.0), 3.0)],
                     RenderSettings(24, 24, spp=1, max_depth=3))

    a = [render(scene(M.df.measured_bsdf(measurement=read_mbsdf(files["lambert"]))),
                spp=32, seed=s, progress=False).rgb() for s in (1, 2)]
    b = [render(scene(M.df.diffuse_reflection_bsdf(tint=0.7)), spp=32, seed=s,
                progress=False).rgb() for s in (1, 2)]
    ma, mb = np.mean(a), np.mean(b)
    se = np.hypot(np.std(a[0] - a[1]), np.std(b[0] - b[1])) / 2 / np.sqrt(a[0].size)
    assert abs(ma - mb) < 4 * se + 1e-4 * mb, (ma, mb, se)
