"""The checklist every distribution function passes, and the registry of edge cases.

Each ``tests/render/df/test_<df>.py`` lists its :class:`DfCase` objects (ordinary and
extreme parameters) and runs the checks below over them (STYLE.md §5):

1. consistency: ``sample``'s pdf and weight equal ``pdf`` and ``eval / pdf`` at the sampled
   ``wi``; ``pdf > 0`` exactly where ``eval > 0``;
2. chi-square of ``sample`` against ``pdf`` (lobes a 101-cell grid resolves);
3. ``∫ pdf <= 1`` (quadrature), and equal to the sampler's success rate (MC);
4. white furnace: the MC albedo is ``<= 1`` (+3 sigma) and ``= 1`` where lossless;
5. reciprocity of reflection lobes;
6. ``albedo()`` agrees with quadrature of ``eval`` and with Monte Carlo;
7. no NaN / inf / negative value for random and degenerate directions.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from render.bsdf import Bsdf
from render.df._kernel_common import refract
from render.testing import (
    chi2_test,
    consistency_error,
    direction,
    half_vector_integral,
    reciprocity_error,
    sample_lanes,
    sphere_integral,
    tile,
)

#: viewing directions (theta, phi in degrees) of the per-direction checks: normal,
#: oblique, grazing to 89.9 degrees, and below the horizon (the two-sided mirror image).
WOS = ((0.0, 0.0), (60.0, 200.0), (89.9, 45.0), (120.0, 300.0))
#: directions of the chi-square tests (one grazing, one from below)
CHI2_WOS = ((0.0, 0.0), (45.0, 30.0), (89.9, 120.0), (130.0, 250.0))
N_MC = 100_000


@dataclass(frozen=True)
class DfCase:
    """One df constructor with edge parameters and what to expect of it.

    Parameters
    ----------
    id : str
    make : callable
        Builds the df.
    geometry : {"diffuse", "glossy", "backscatter", "delta"}
        Shape of the lobe (chooses quadrature centres).
    lossless : bool
        The white MC furnace must give exactly 1 (within noise) at every ``wo``.
    reciprocal : bool
        Check ``f(wo, wi) = f(wi, wo)`` (reflection lobes).
    chi2 : bool
        The lobe is wide enough for the chi-square grid.
    narrow : bool
        The lobe is narrow on ``wo``'s side: integrate it over microfacet normals.
    narrow_t : bool
        The transmitted lobe is narrow (near-matched IORs): integrate it over normals.
    transmits : bool
    ior : (float, float)
        ``(ior_outside, ior_inside)``.
    thin : bool
    albedo_tol : float
        Accuracy of ``albedo()`` (0 for closed forms; the table accuracy otherwise).
    lossless_tol : float
        For ``lossless`` cases whose losslessness rests on a table (the energy
        compensation of ``multiscatter_tint``): the table's accuracy, added to the
        furnace's 3 sigma.
    """

    id: str
    make: Callable[[], Bsdf]
    geometry: str
    lossless: bool = False
    reciprocal: bool = True
    chi2: bool = True
    narrow: bool = False
    narrow_t: bool = False
    transmits: bool = False
    ior: tuple[float, float] = (1.0, 1.0)
    thin: bool = False
    albedo_tol: float = 1e-9
    lossless_tol: float = 0.0
    skip_albedo_wos: tuple = field(default_factory=tuple)
    #: viewing directions of the chi-square tests, if not CHI2_WOS
    chi2_wos: tuple | None = None

    def __str__(self) -> str:
        return self.id


def wo_of(theta_phi) -> np.ndarray:
    return direction(*theta_phi)


def random_dirs(rng: np.random.Generator, n: int) -> np.ndarray:
    v = rng.normal(size=(n, 3))
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def edge_dirs() -> np.ndarray:
    """Poles, the exact horizon, 89.9 degrees and tiny cosines, on both sides."""
    out = []
    for th in (0.0, 1e-9, 45.0, 89.9, 89.999999, 90.0, 90.0000001, 135.0, 179.9, 180.0):
        for ph in (0.0, 33.0, 90.0, 270.0):
            out.append(direction(th, ph))
    out.append([1.0, 0.0, 0.0])
    out.append([0.0, -1.0, 0.0])
    out.append([0.6, 0.8, 1e-300])
    return np.asarray(out)


# --- the checks ---------------------------------------------------------------------------


def check_consistency(case: DfCase, rng: np.random.Generator, n: int = 40_000) -> None:
    bsdf = case.make()
    wo = np.concatenate(
        [random_dirs(rng, n), tile(direction(89.9, 10.0), 2000), tile(direction(91.0, 70.0), 2000)]
    )
    s = bsdf.sample(wo, rng.random(len(wo)), rng.random((len(wo), 2)))
    if bsdf.is_delta:
        assert np.all(s.is_delta[s.valid])
        assert not np.any(bsdf.eval(wo, s.wi)) and not np.any(bsdf.pdf(wo, s.wi))
    else:
        pdf_err, weight_err = consistency_error(bsdf, wo, s)
        assert pdf_err.max(initial=0) < 1e-9, f"sample pdf differs from pdf(): {pdf_err.max()}"
        assert weight_err.max(initial=0) < 1e-9, (
            f"sample weight differs from eval/pdf: {weight_err.max()}"
        )
    # failed samples are all-zero; successful ones have a positive pdf and unit wi
    assert (
        np.all(s.pdf[~s.valid] == 0)
        and np.all(s.weight[~s.valid] == 0)
        and np.all(s.wi[~s.valid] == 0)
    )
    assert np.all(s.pdf[s.valid] > 0)
    assert np.allclose(np.linalg.norm(s.wi[s.valid], axis=1), 1.0, atol=1e-12)
    assert np.all((s.lobe[s.valid] & int(bsdf.lobes)) == s.lobe[s.valid]), (
        "sampled a lobe the df does not declare"
    )
    # pdf > 0 exactly where eval > 0, on random pairs
    wi = random_dirs(rng, len(wo))
    e, p = bsdf.eval(wo, wi), bsdf.pdf(wo, wi)
    assert np.array_equal(e.max(axis=1) > 0, p > 0), "pdf must be positive exactly where eval is"


def check_no_nan(case: DfCase, rng: np.random.Generator, surface: bool = True) -> None:
    """No NaN, inf or negative values at edge and random directions; a surface df
    (``surface``; not a hair fibre, which scatters from every side) scatters nothing
    from its tangent plane."""
    bsdf = case.make()
    d = edge_dirs()
    wo = np.repeat(d, len(d), axis=0)
    wi = np.tile(d, (len(d), 1))
    wo = np.concatenate([wo, random_dirs(rng, 5000)])
    wi = np.concatenate([wi, random_dirs(rng, 5000)])
    e, p = bsdf.eval_pdf(wo, wi)
    assert np.all(np.isfinite(e)) and np.all(e >= 0)
    assert np.all(np.isfinite(p)) and np.all(p >= 0)
    assert np.array_equal(bsdf.eval(wo, wi), e) and np.array_equal(bsdf.pdf(wo, wi), p)
    u1 = np.concatenate(
        [np.zeros(len(wo) // 2), np.full(len(wo) - len(wo) // 2, np.nextafter(1.0, 0.0))]
    )
    u2 = rng.random((len(wo), 2))
    u2[::7] = 0.0
    u2[1::7] = np.nextafter(1.0, 0.0)
    s = bsdf.sample(wo, u1, u2)
    for a in (s.wi, s.pdf, s.weight):
        assert np.all(np.isfinite(a))
    assert np.all(s.pdf >= 0) and np.all(s.weight >= 0)
    a = bsdf.albedo(wo)
    assert np.all(np.isfinite(a)) and np.all(a >= 0) and np.all(a <= 1.0 + 1e-12)
    # tangent-plane viewing directions scatter nothing
    flat = np.abs(wo[:, 2]) <= 1e-10
    if surface:
        assert not np.any(e[flat]) and not np.any(p[flat]) and not np.any(s.valid[flat])


def check_chi2(case: DfCase, theta_phi, test_count: int) -> None:
    res = chi2_test(case.make(), wo_of(theta_phi), sample_count=200_000, test_count=test_count)
    assert res.passed, f"{case.id} wo={theta_phi}: {res}"


def _refracted(wo: np.ndarray, eta_out: float, eta_in: float) -> np.ndarray:
    side = 1.0 if wo[2] >= 0 else -1.0
    e1, e2 = (eta_out, eta_in) if side > 0 else (eta_in, eta_out)
    x, y, z, tir = refract(*wo, 0.0, 0.0, side, e1 / e2)
    return np.array([0.0, 0.0, -side]) if tir else np.array([x, y, z])


def integrate(case: DfCase, bsdf: Bsdf, wo: np.ndarray, f: Callable) -> np.ndarray:
    """``∫ f(wi) dwi`` with the quadrature that suits each side of the case's lobe.

    Wide lobes: polar rings in ``wi`` about the lobe's peak (exact horizon).  Narrow
    lobes: rings over microfacet normals (see ``render.testing``).
    """
    side = 1 if wo[2] >= 0 else -1
    if case.geometry == "diffuse":
        s = -side if case.transmits else side
        return sphere_integral(f, np.array([0.0, 0.0, s]), s, n_beta=128)
    if case.geometry == "backscatter":
        return disk_integral(f, wo)
    # microfacet lobes: the reflection side, then the transmission side
    if case.narrow:
        total = half_vector_integral(f, wo, side, kind="reflect", panels=48)
    else:
        total = sphere_integral(f, wo * [-1.0, -1.0, 1.0], side, n_beta=128)
    if case.transmits:
        if case.narrow or case.narrow_t:
            out, inside = case.ior
            if abs(inside - out) < 1e-4:  # libbsdf's minimum IOR step (inside pushed up)
                inside = out - 1e-4 if inside < out else out + 1e-4
            e1, e2 = (out, inside) if side > 0 or case.thin else (inside, out)
            kind = "thin" if case.thin else "refract"
            # at grazing incidence a near-matched refraction fans out (d theta_t / d eta =
            # tan theta_t) and the horizon cuts the lobe: that needs a much finer rule
            fine = (
                dict(panels=200, n_beta=256)
                if case.narrow_t and abs(wo[2]) < 0.01
                else dict(panels=48)
            )
            total = total + half_vector_integral(f, wo, -side, kind=kind, eta1=e1, eta2=e2, **fine)
        else:
            center = -wo if case.thin else _refracted(wo, *case.ior)
            total = total + sphere_integral(f, center, -side, n_beta=128)
    return total


def disk_integral(f: Callable, wo: np.ndarray, n_beta: int = 128, order: int = 8) -> np.ndarray:
    """``∫ f(wi) dwi`` for the backscattering lobe, over its own disk coordinates.

    The disk point ``(x, y)`` lies at ``P = wo + (x, y, 0)`` on the plane at height
    ``nk1 = wo.z`` (frame mirrored so that ``wo.z > 0``); ``h = P/|P|`` and ``wi`` mirrors
    ``wo`` about ``h``.  Solid angles: ``dh = nk1 / |P|^3 dA`` (the plane seen from the
    origin) and ``dwi = 4 (wo.h) dh``.  The lobe is round in ``(x, y)`` even at grazing
    incidence, where it is a thin sliver in ``wi``.  Only the unit disk carries the lobe.
    """
    s0 = 1.0 if wo[2] >= 0 else -1.0
    flip = np.array([1.0, 1.0, s0])
    k = wo * flip
    x, w = np.polynomial.legendre.leggauss(order)
    x, w = 0.5 * (x + 1), 0.5 * w
    edges = np.concatenate(
        [np.exp(np.linspace(np.log(1e-12), np.log(0.05), 12)), np.linspace(0.1, 1.0, 19)]
    )
    rho = np.concatenate([a + (b - a) * x for a, b in zip(edges[:-1], edges[1:], strict=True)])
    wr = np.concatenate([(b - a) * w for a, b in zip(edges[:-1], edges[1:], strict=True)])
    beta = 2 * np.pi * (np.arange(n_beta) + 0.5) / n_beta  # periodic: midpoint rule
    R, Bt = np.meshgrid(rho, beta, indexing="ij")
    W = (wr * rho)[:, None] * np.full(n_beta, 2 * np.pi / n_beta)[None, :]
    P = np.stack([k[0] + R * np.cos(Bt), k[1] + R * np.sin(Bt), np.full_like(R, k[2])], -1).reshape(
        -1, 3
    )
    dist = np.linalg.norm(P, axis=1)
    h = P / dist[:, None]
    c = h @ k
    wi = 2.0 * c[:, None] * h - k
    jac = 4.0 * c * k[2] / dist**3
    ok = (wi[:, 2] > 0) & (c > 0)
    vals = np.asarray(f(np.where(ok[:, None], wi, [0.0, 0.0, 1.0]) * flip))
    wgt = W.ravel() * np.where(ok, jac, 0.0)
    return np.sum(vals * (wgt if vals.ndim == 1 else wgt[:, None]), axis=0)


def check_integrals(case: DfCase, theta_phi) -> dict:
    """Checks 3, 4 and 6 for one ``wo`` from one MC run and one quadrature pass.

    * ``∫ pdf <= 1`` and equal to the sampler's success rate;
    * the white furnace: MC albedo ``<= 1`` (+3 sigma), ``= 1`` where lossless;
    * ``albedo()`` against MC and against quadrature of ``eval`` (non-delta lobes).

    Returns the measured numbers (for the report).
    """
    bsdf = case.make()
    wo = wo_of(theta_phi)
    s = sample_lanes(bsdf, wo, N_MC, seed=11)
    mean = s.weight.mean(axis=0)
    se = s.weight.std(axis=0) / np.sqrt(N_MC)
    success = s.valid.mean()
    out = {"mc": mean, "se": se, "success": success}
    # furnace
    # (a lobe made lossless by a table, multiscatter_tint's compensation, is exact only to
    # the table's accuracy: lossless_tol, 0 for every other case)
    assert np.all(mean <= 1.0 + 3 * se + case.lossless_tol + 1e-12), (
        f"white furnace gains energy: {mean} ± {se}")
    if case.lossless:
        assert np.all(np.abs(mean - 1.0) <= 3 * se + case.lossless_tol + 1e-12), (
            f"lossless lobe loses energy: {mean} ± {se}"
        )
    alb = bsdf.albedo(wo[None])[0]
    out["albedo"] = alb
    tol = case.albedo_tol
    assert np.all(np.abs(alb - mean) <= 4 * se + tol + 1e-12), f"albedo() {alb} vs MC {mean} ± {se}"
    if bsdf.is_delta:
        return out

    def f(w):
        e, p = bsdf.eval_pdf(tile(wo, len(w)), w)
        return np.concatenate([e, p[:, None]], axis=1)

    q = integrate(case, bsdf, wo, f)
    quad, total = q[:3], float(q[3])
    out["quad"], out["pdf_integral"] = quad, total
    sigma = np.sqrt(max(success * (1 - success), 1.0 / N_MC) / N_MC)
    assert total <= 1.0 + 2e-3, f"pdf integrates to {total}"
    assert abs(total - success) <= 4 * sigma + 2e-3, (
        f"∫pdf = {total} but the sampler succeeds {success}"
    )
    assert np.all(np.abs(alb - quad) <= tol + 2e-4), f"albedo() {alb} vs quadrature {quad}"
    return out


def check_reciprocity(case: DfCase, rng: np.random.Generator, n: int = 20_000) -> None:
    bsdf = case.make()
    wo = random_dirs(rng, n)
    wi = random_dirs(rng, n)
    wi[:, 2] = np.abs(wi[:, 2]) * np.sign(wo[:, 2])  # same side: reflection
    err = reciprocity_error(bsdf, wo, wi)
    f = bsdf.eval(wo, wi) / np.abs(wi[:, 2:3])
    big = f > 1e-12
    assert err[big].max(initial=0) < 1e-9, f"not reciprocal: max relative error {err[big].max()}"


def case_ids(cases) -> list[str]:
    return [c.id for c in cases]


def per_wo(cases, wos=WOS, only=None):
    """(case, wo) pairs for parametrisation, optionally filtered by ``only(case)``.

    With ``wos=CHI2_WOS`` a case's own ``chi2_wos`` take precedence.
    """
    pick = (lambda c: c.chi2_wos or wos) if wos is CHI2_WOS else (lambda c: wos)
    return [(c, w) for c in cases for w in pick(c) if only is None or only(c)]


def pair_ids(pairs) -> list[str]:
    return [f"{c.id}-wo{w[0]:g}" for c, w in pairs]
