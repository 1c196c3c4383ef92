"""Statistical checks for distribution functions: chi-square, quadrature, furnace, reciprocity.

The library behind ``tests/render`` (as ``mitsuba.chi2`` is Mitsuba's and
``shapely.testing`` is shapely's), usable on any :class:`render.bsdf.Bsdf`, mixes and
layers included:

* :func:`chi2_test` — Pearson's chi-square test of ``sample`` against ``pdf``
  integrated over the cells of a ``(cos theta, phi)`` grid (Mitsuba ``chi2.py``, pbrt
  ``bsdfs_test.cpp``), with pooling of sparse cells and a Šidák correction;
* :func:`sphere_integral` / :func:`pdf_integral` / :func:`eval_integral` — deterministic
  quadrature over the sphere in polar coordinates around a chosen direction, with
  log-spaced rings (exact for lobes down to 1e-10 rad wide) and the horizon handled
  exactly, so narrow and wide lobes integrate alike;
* :func:`furnace` — Monte-Carlo directional albedo (mean sample weight) with its
  standard error;
* :func:`reciprocity_error`, :func:`consistency_error` — Helmholtz reciprocity and
  ``sample`` versus ``eval``/``pdf``;
* :func:`light_tables`, :func:`light_samples` — the lights of a scene as the render
  kernels see them, and samples of them by the kernel that renders.

``scipy`` (the ``test`` extra) is imported only by :func:`chi2_test`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from render._typing import Arr, ArrayLike, Vec3
from render.bsdf import Bsdf, BsdfSample
from render.numerics import unitize

__all__ = [
    "light_tables",
    "light_samples",
    "Chi2Result",
    "chi2_test",
    "chi2_tables",
    "sphere_integral",
    "half_vector_integral",
    "pdf_integral",
    "eval_integral",
    "furnace",
    "reciprocity_error",
    "consistency_error",
    "default_centers",
    "direction",
    "tile",
    "sample_lanes",
]


def direction(theta_deg: float, phi_deg: float = 0.0) -> np.ndarray:
    """The unit direction at polar angle ``theta`` and azimuth ``phi`` (degrees), shape (3,).

    Examples
    --------
    >>> np.round(direction(90.0, 90.0), 12).tolist()
    [0.0, 1.0, 0.0]
    """
    t, p = np.radians(theta_deg), np.radians(phi_deg)
    return np.array([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)])


def tile(w: ArrayLike, n: int) -> Vec3:
    """``n`` copies of the direction ``w`` (3,) as an (n, 3) array."""
    return np.tile(np.asarray(w, dtype=np.float64).reshape(1, 3), (n, 1))


def sample_lanes(bsdf: Bsdf, wo: ArrayLike, n: int, seed: int = 0) -> BsdfSample:
    """``n`` samples of ``bsdf`` for the fixed direction ``wo`` (3,) with seeded variates."""
    rng = np.random.default_rng(seed)
    return bsdf.sample(tile(wo, n), rng.random(n), rng.random((n, 2)))


# --- chi-square -------------------------------------------------------------------------


@dataclass
class Chi2Result:
    """Outcome of :func:`chi2_test` (both tables kept for dumping on failure)."""

    passed: bool
    p_value: float
    statistic: float
    dof: int
    significance: float
    observed: np.ndarray
    expected: np.ndarray
    n_samples: int
    n_failed: int
    expected_failed: float
    message: str = ""
    extra: dict = field(default_factory=dict)

    def dump(self, path: str | Path) -> Path:
        """Write both tables (and the scalars) to ``path`` (.npz); returns the path."""
        path = Path(path)
        np.savez_compressed(
            path,
            observed=self.observed,
            expected=self.expected,
            p_value=self.p_value,
            statistic=self.statistic,
            dof=self.dof,
        )
        return path

    def __str__(self) -> str:
        return (
            f"chi2: p = {self.p_value:.4g} (significance {self.significance:.3g}), "
            f"stat = {self.statistic:.1f}, dof = {self.dof}, failed samples "
            f"{self.n_failed} (expected {self.expected_failed:.1f}) {self.message}"
        )


def _gauss(n: int) -> tuple[np.ndarray, np.ndarray]:
    x, w = np.polynomial.legendre.leggauss(n)
    return 0.5 * (x + 1.0), 0.5 * w  # on [0, 1]


def chi2_tables(
    bsdf: Bsdf,
    wo: ArrayLike,
    *,
    sample_count: int = 200_000,
    res: int = 101,
    ires: int = 4,
    seed: int = 0,
    chunk: int = 500_000,
):
    """Observed and expected counts on the ``(cos theta, phi)`` grid.

    Rows: ``res`` cells of ``cos theta`` over [-1, 1]; columns: ``2 res`` cells of
    ``phi`` over [-pi, pi).  Expected counts integrate ``pdf`` per cell with an
    ``ires x ires`` Gauss–Legendre rule (``d omega = d cos theta d phi``).

    Returns
    -------
    observed, expected : (res, 2 res) float64
    n_failed : int
        Samples that failed (lobe 0).
    any_delta : bool
        Whether any sample was a specular (delta) event.
    """
    if res % 2 != 1:
        raise ValueError(f"res must be odd so that the horizon is not a cell edge, got {res}")
    wo = np.asarray(wo, dtype=np.float64).reshape(3)
    n_phi = 2 * res
    s = sample_lanes(bsdf, wo, sample_count, seed)
    ok = s.valid
    ct = np.clip(s.wi[ok, 2], -1.0, 1.0)
    phi = np.arctan2(s.wi[ok, 1], s.wi[ok, 0])
    i = np.clip(np.floor((ct + 1.0) * 0.5 * res).astype(np.int64), 0, res - 1)
    j = np.clip(np.floor((phi + np.pi) / (2 * np.pi) * n_phi).astype(np.int64), 0, n_phi - 1)
    observed = (
        np.bincount(i * n_phi + j, minlength=res * n_phi).reshape(res, n_phi).astype(np.float64)
    )
    # integrate the pdf per cell (Gauss–Legendre, ires x ires nodes)
    x, w = _gauss(ires)
    dc, dp = 2.0 / res, 2.0 * np.pi / n_phi
    ci, cj = (a.ravel() for a in np.meshgrid(np.arange(res), np.arange(n_phi), indexing="ij"))
    nodes = _cell_nodes(bsdf, wo, ci, cj, x, dc, dp, chunk)
    expected = np.einsum("mab,a,b->m", nodes, w, w) * (dc * dp)
    # cells the pdf's support boundary crosses (zero and non-zero nodes: a horizon, a
    # total-internal-reflection edge), cells where the pdf varies by more than 2x between
    # nodes while expecting at least one sample (peaks), and cells where samples landed
    # but no node saw the pdf are integrated again with 4x finer rules
    flat_obs = observed.ravel()
    lo, hi = nodes.min(axis=(1, 2)), nodes.max(axis=(1, 2))
    rough = (
        ((lo <= 0) & (hi > 0))
        | ((hi > 2 * lo) & (expected * sample_count >= 1))
        | ((expected <= 0) & (flat_obs > 0))
    )
    idx = np.nonzero(rough)[0]
    if len(idx):
        xf, wf = _gauss(4 * ires)
        fine = _cell_nodes(bsdf, wo, ci[idx], cj[idx], xf, dc, dp, chunk)
        expected[idx] = np.einsum("mab,a,b->m", fine, wf, wf) * (dc * dp)
    expected = expected.reshape(res, n_phi) * sample_count
    return observed, expected, int(np.count_nonzero(~ok)), bool(np.any(s.is_delta))


def _cell_nodes(bsdf, wo, ci, cj, x, dc, dp, chunk):
    """pdf at the ``k x k`` nodes ``x`` of each listed cell: (m, k, k)."""
    k = len(x)
    c = -1.0 + dc * (ci[:, None, None] + x[None, :, None])  # (m, k, 1)
    p = -np.pi + dp * (cj[:, None, None] + x[None, None, :])  # (m, 1, k)
    c, p = np.broadcast_arrays(c, p)
    st = np.sqrt(np.maximum(1.0 - c * c, 0.0))
    wi = np.stack([st * np.cos(p), st * np.sin(p), c], axis=-1).reshape(-1, 3)
    vals = np.empty(len(wi))
    for i in range(0, len(wi), chunk):
        sl = slice(i, i + chunk)
        vals[sl] = bsdf.pdf(tile(wo, len(wi[sl])), wi[sl])
    return vals.reshape(len(ci), k, k)


def chi2_test(
    bsdf: Bsdf,
    wo: ArrayLike,
    *,
    sample_count: int = 200_000,
    res: int = 101,
    ires: int = 4,
    seed: int = 0,
    significance: float = 0.01,
    test_count: int = 1,
    min_expected: float = 5.0,
    include_failures: bool = False,
) -> Chi2Result:
    """Pearson's chi-square test of ``bsdf.sample`` against ``bsdf.pdf`` for one ``wo``.

    Cells expecting fewer than ``min_expected`` samples are pooled (in order of
    expectation) into groups expecting at least that many.  With ``include_failures``
    the failed samples form one more cell, expected ``N (1 - ∫ pdf)``: this also tests
    that ``pdf`` integrates to the sampler's success rate.  The null hypothesis is
    rejected when ``p < 1 - (1 - significance)^(1/test_count)`` (Šidák), or at once if
    a sample lands in a cell whose expected count is 0.

    Parameters
    ----------
    bsdf : Bsdf
        Not purely specular (delta samples raise ``ValueError``).
    wo : (3,) float64
    sample_count, res, ires, seed, significance, test_count, min_expected, include_failures

    Returns
    -------
    Chi2Result
    """
    from scipy.stats import chi2 as chi2_dist

    observed, expected, n_failed, any_delta = chi2_tables(
        bsdf, wo, sample_count=sample_count, res=res, ires=ires, seed=seed
    )
    if any_delta:
        raise ValueError(
            "chi2_test cannot test specular (delta) samples: check the deterministic "
            "direction and weight instead"
        )
    alpha = 1.0 - (1.0 - significance) ** (1.0 / test_count)
    o, e = observed.ravel(), expected.ravel()
    exp_failed = max(sample_count - e.sum(), 0.0)
    impossible = (e <= 0) & (o > 0)
    if np.any(impossible):
        k = int(np.argmax(o * impossible))
        return Chi2Result(
            False,
            0.0,
            np.inf,
            0,
            alpha,
            observed,
            expected,
            sample_count,
            n_failed,
            exp_failed,
            f"{int(o[impossible].sum())} samples in cells with expected 0 "
            f"(e.g. cell {np.unravel_index(k, observed.shape)})",
        )
    if include_failures:
        o = np.append(o, n_failed)
        e = np.append(e, exp_failed)
    keep = e > 0
    o, e = o[keep], e[keep]
    big = e >= min_expected
    terms_o, terms_e = list(o[big]), list(e[big])
    # pool sparse cells greedily, in order of expectation (a test helper: a plain loop)
    order = np.argsort(e[~big])
    acc_o = acc_e = 0.0
    for so, se in zip(o[~big][order], e[~big][order], strict=True):
        acc_o += so
        acc_e += se
        if acc_e >= min_expected:
            terms_o.append(acc_o)
            terms_e.append(acc_e)
            acc_o = acc_e = 0.0
    if acc_e > 0:
        if terms_e:  # a tail that cannot reach min_expected joins the last pooled group
            terms_o[-1] += acc_o
            terms_e[-1] += acc_e
        else:
            terms_o.append(acc_o)
            terms_e.append(acc_e)
    to, te = np.asarray(terms_o), np.asarray(terms_e)
    stat = float(np.sum((to - te) ** 2 / te))
    dof = len(te) - 1
    p = float(chi2_dist.sf(stat, dof)) if dof > 0 else 1.0
    return Chi2Result(
        p >= alpha, p, stat, dof, alpha, observed, expected, sample_count, n_failed, exp_failed
    )


# --- quadrature over the sphere ---------------------------------------------------------


def _alpha_rule(alpha_min: float = 1e-11, panels: int = 24, order: int = 8, breaks=()):
    """Nodes and weights in the polar angle ``alpha`` on [alpha_min, pi]: Gauss–Legendre
    panels, one per decade up to 0.1 in ``log alpha`` (peaks of any width), then
    ``panels`` uniform ones; extra panel edges at ``breaks`` (discontinuities)."""
    x, w = _gauss(order)
    n_dec = int(round(np.log10(0.1 / alpha_min)))
    edges = np.concatenate(
        [np.geomspace(alpha_min, 0.1, n_dec + 1), np.linspace(0.1, np.pi, panels + 1)]
    )
    extra = [float(b) for b in breaks if alpha_min < b < np.pi]
    edges = np.unique(np.concatenate([edges, extra]))
    nodes, weights = [], []
    for a, b in zip(edges[:-1], edges[1:], strict=True):
        if b <= 0.1 + 1e-12:  # log substitution: d alpha = alpha d s
            la, lb = np.log(a), np.log(b)
            t = np.exp(la + (lb - la) * x)
            nodes.append(t)
            weights.append(w * (lb - la) * t)
        else:
            nodes.append(a + (b - a) * x)
            weights.append(w * (b - a))
    return np.concatenate(nodes), np.concatenate(weights)


def sphere_integral(
    f,
    center: ArrayLike,
    side: int,
    *,
    n_beta: int = 96,
    order: int = 8,
    panels: int = 24,
    breaks=(),
) -> float:
    """``∫ f(w) dw`` over the hemisphere ``side * w.z > 0``, in polar coordinates about ``center``.

    Rings of constant angle ``alpha`` from ``center`` are log-spaced near it (narrow
    lobes centred there integrate exactly); on each ring only the arc on the requested
    side is integrated (Gauss–Legendre in the azimuth ``beta``), so the horizon is exact.

    Parameters
    ----------
    f : callable
        ``(m, 3) directions -> (m,) or (m, k)`` values.
    center : (3,) float64
        Unit direction to centre the rings on (a lobe's peak).
    side : {+1, -1}
        ``+1`` for ``z > 0``, ``-1`` for ``z < 0``.
    n_beta, order, panels : int
        Azimuthal nodes per ring, Gauss order per panel, uniform panels beyond 0.1 rad.
    breaks : sequence of float
        Angles from ``center`` where ``f`` jumps (e.g. a cone's edge): panel edges there.

    Returns
    -------
    float or (k,) float64

    Examples
    --------
    >>> round(float(sphere_integral(lambda w: w[:, 2] / np.pi, [0.3, 0.0, 0.954], +1)), 6)
    1.0
    """
    c = np.asarray(center, dtype=np.float64).reshape(1, 3)
    c = unitize(c)[0]
    # e1: the part of +z orthogonal to c (so e2 = c x e1 has no z component)
    e1, ok = unitize(np.array([[0.0, 0.0, 1.0]]) - c[:, 2:3] * c)
    if not ok[0]:
        e1 = np.array([[1.0, 0.0, 0.0]])
    e2 = np.cross(c, e1)
    cz, e1z = float(c[0, 2]), float(e1[0, 2])
    # rings start / stop touching the horizon at these angles: panel edges there
    tc = float(np.arccos(np.clip(cz, -1.0, 1.0)))
    kinks = (abs(0.5 * np.pi - tc), np.pi - abs(0.5 * np.pi - tc))
    alpha, wa = _alpha_rule(order=order, panels=panels, breaks=tuple(kinks) + tuple(breaks))
    xb, wb = _gauss(n_beta)
    ca, sa = np.cos(alpha), np.sin(alpha)
    # arc of beta on the requested side: side * (ca cz + sa e1z cos beta) > 0
    with np.errstate(divide="ignore", invalid="ignore"):
        gamma = np.where(sa * e1z > 0, -ca * cz / np.where(sa * e1z > 0, sa * e1z, 1.0), np.nan)
    full = np.where(np.isnan(gamma), side * ca * cz > 0, (gamma < -1) if side > 0 else (gamma > 1))
    empty = np.where(
        np.isnan(gamma), side * ca * cz <= 0, (gamma >= 1) if side > 0 else (gamma <= -1)
    )
    g = np.arccos(np.clip(np.nan_to_num(gamma), -1.0, 1.0))
    if side > 0:
        b0, b1 = np.where(full, -np.pi, -g), np.where(full, np.pi, g)
    else:
        b0, b1 = np.where(full, -np.pi, g), np.where(full, np.pi, 2 * np.pi - g)
    b0, b1 = np.where(empty, 0.0, b0), np.where(empty, 0.0, b1)
    beta = b0[:, None] + (b1 - b0)[:, None] * xb[None, :]
    wgt = (wa * sa * (b1 - b0))[:, None] * wb[None, :]
    w = ca[:, None, None] * c[None, :, :] + sa[:, None, None] * (
        np.cos(beta)[:, :, None] * e1[None, :, :] + np.sin(beta)[:, :, None] * e2[None, :, :]
    )
    w = w.reshape(-1, 3)
    vals = np.asarray(f(w), dtype=np.float64)
    mask = side * w[:, 2] > 0
    wflat = wgt.ravel() * mask
    if vals.ndim == 1:
        return float(np.sum(np.where(mask, vals, 0.0) * wflat))
    return np.sum(np.where(mask[:, None], vals, 0.0) * wflat[:, None], axis=0)


def half_vector_integral(
    f,
    wo: ArrayLike,
    side: int,
    *,
    kind: str = "reflect",
    eta1: float = 1.0,
    eta2: float = 1.0,
    h_center: ArrayLike = (0.0, 0.0, 1.0),
    **kw,
):
    """``∫ f(wi) dwi`` over ``side * wi.z > 0``, integrated over microfacet normals ``h``.

    Narrow microfacet lobes are round in ``h`` even where they are thin slivers in
    ``wi`` (grazing reflection, refraction at an almost matched IOR), so this
    quadrature stays exact where :func:`sphere_integral` about the peak cannot.  The
    rings are centred on ``h_center`` (``+z``: the normal; ``wo`` for backscattering)
    over ``h.z > 0``, in the frame mirrored so that ``wo.z > 0``.

    Parameters
    ----------
    f : callable
        ``(m, 3) directions wi -> (m,) or (m, k)``.
    wo : (3,) float64
    side : {+1, -1}
    kind : {"reflect", "thin", "refract"}
        ``wi`` is ``wo`` mirrored about ``h`` (``dwi = 4 |wo.h| dh``), that mirrored
        again through the tangent plane (thin-walled transmission), or ``wo`` refracted
        through ``h`` with ``eta1 / eta2`` (``dwi = (eta1 wo.h + eta2 wi.h)^2 / (eta2^2
        |wi.h|) dh``; total internal reflection contributes nothing).
    eta1, eta2 : float
        IOR on ``wo``'s side and on the far side (``refract`` only).
    h_center : (3,) float64

    Examples
    --------
    The solid angle of a hemisphere, from below (``wo`` points down): ``2 pi``, to the
    accuracy the unresolved horizon allows (the mask ``wi.z > 0`` is not a ring in ``h``):

    >>> one = half_vector_integral(lambda w: np.ones(len(w)), [0.6, 0.0, -0.8], -1, panels=96)
    >>> abs(float(one) / (2 * np.pi) - 1) < 0.01
    True
    """
    wo = np.asarray(wo, dtype=np.float64).reshape(3)
    s0 = 1.0 if wo[2] >= 0 else -1.0
    flip = np.array([1.0, 1.0, s0])
    wo_o = wo * flip

    def g(h):
        c = h @ wo_o
        ok = c > 0
        if kind in ("reflect", "thin"):
            wi = 2.0 * c[:, None] * h - wo_o
            jac = 4.0 * c
            if kind == "thin":
                wi = wi * np.array([1.0, 1.0, -1.0])
        elif kind == "refract":
            b = eta1 / eta2
            ct2 = 1.0 - b * b * (1.0 - c * c)
            ok &= ct2 > 0
            wi = -b * wo_o + (b * c - np.sqrt(np.maximum(ct2, 0.0)))[:, None] * h
            kh2 = np.einsum("ij,ij->i", wi, h)
            den = eta2 * eta2 * np.abs(kh2)
            jac = np.where(den > 0, (eta1 * c + eta2 * kh2) ** 2 / np.where(den > 0, den, 1.0), 0.0)
        else:
            raise ValueError(f"kind must be 'reflect', 'thin' or 'refract', got {kind!r}")
        ok &= side * s0 * wi[:, 2] > 0
        vals = np.asarray(f(np.where(ok[:, None], wi, np.array([0.0, 0.0, side * s0])) * flip))
        jac = np.where(ok, jac, 0.0)
        return vals * (jac if vals.ndim == 1 else jac[:, None])

    return sphere_integral(g, h_center, +1, **kw)


def pdf_integral(bsdf: Bsdf, wo: ArrayLike, centers: dict, **kw) -> float:
    """``∫ pdf(wo, wi) dwi`` over the sphere: one :func:`sphere_integral` per side.

    ``centers`` maps a side (+1 / -1) to the direction the rings are centred on (the
    lobe's peak on that side); sides not listed are skipped.
    """
    wo = np.asarray(wo, dtype=np.float64).reshape(3)
    return sum(
        sphere_integral(lambda w: bsdf.pdf(tile(wo, len(w)), w), c, s, **kw)
        for s, c in centers.items()
    )


def eval_integral(bsdf: Bsdf, wo: ArrayLike, centers: dict, **kw) -> np.ndarray:
    """``∫ eval(wo, wi) dwi`` (the directional albedo of non-delta lobes), (3,)."""
    wo = np.asarray(wo, dtype=np.float64).reshape(3)
    return sum(
        sphere_integral(lambda w: bsdf.eval(tile(wo, len(w)), w), c, s, **kw)
        for s, c in centers.items()
    )


# --- Monte Carlo and pointwise checks ----------------------------------------------------


def furnace(
    bsdf: Bsdf, wo: ArrayLike, n: int = 200_000, seed: int = 0
) -> tuple[np.ndarray, np.ndarray]:
    """Monte-Carlo directional albedo: mean and standard error of the sample weight.

    Returns
    -------
    mean, stderr : (3,) float64
    """
    s = sample_lanes(bsdf, wo, n, seed)
    return s.weight.mean(axis=0), s.weight.std(axis=0) / np.sqrt(n)


def reciprocity_error(bsdf: Bsdf, wo: Vec3, wi: Vec3) -> np.ndarray:
    """Relative asymmetry of ``f = eval / |cos theta_i|`` under swapping ``wo`` and ``wi``.

    Returns
    -------
    (n, 3) float64
        ``|f(wo, wi) - f(wi, wo)| / max(f(wo, wi), f(wi, wo), tiny)``.
    """
    f1 = bsdf.eval(wo, wi) / np.abs(wi[:, 2:3])
    f2 = bsdf.eval(wi, wo) / np.abs(wo[:, 2:3])
    den = np.maximum(np.maximum(f1, f2), 1e-300)
    return np.abs(f1 - f2) / den


def consistency_error(bsdf: Bsdf, wo: Vec3, sample: BsdfSample) -> tuple[Arr, Arr]:
    """Relative errors of a sample's ``pdf`` and ``weight`` against ``pdf``/``eval`` at ``wi``.

    Only successful non-delta lanes are compared.

    Returns
    -------
    pdf_err : (m,) float64
        ``|pdf(wo, wi) / sample.pdf - 1|``.
    weight_err : (m,) float64
        ``max over channels |eval / pdf - weight| / max(weight, 1e-12)``.
    """
    ok = sample.valid & ~sample.is_delta
    e, p = bsdf.eval_pdf(wo[ok], sample.wi[ok])
    sp = sample.pdf[ok]
    pdf_err = np.abs(p / sp - 1.0)
    ratio = e / np.where(p > 0, p, 1.0)[:, None]
    w = sample.weight[ok]
    weight_err = np.max(np.abs(ratio - w) / np.maximum(w, 1e-12), axis=1)
    return pdf_err, weight_err


def _mirror(wo: np.ndarray) -> np.ndarray:
    return np.array([-wo[0], -wo[1], wo[2]])


def default_centers(wo: ArrayLike, transmitted: ArrayLike | None = None) -> dict:
    """Ring centres for a lobe around the mirror direction, and (optionally) a transmitted one."""
    wo = np.asarray(wo, dtype=np.float64).reshape(3)
    side = 1 if wo[2] >= 0 else -1
    out = {side: _mirror(wo)}
    if transmitted is not None:
        out[-side] = np.asarray(transmitted, dtype=np.float64)
    return out


def light_tables(lights, objects=(), selection: str = "uniform", every_delta: bool = False):
    """The render kernels' tables (:class:`render.path.Tables`) of a scene with these
    lights and objects (a small square far behind the camera when there are none),
    lights selected by ``selection`` (``[render] light_selection``), delta lights each
    at every vertex with ``every_delta`` (``[render] every_delta_light``)."""
    from displacement.surfaces import UnitSquare
    from render import material as M
    from render.camera import Camera
    from render.integrator import Integrator
    from render.scene import RenderSettings, Scene, SceneObject, make_transform

    objs = list(objects) or [SceneObject(UnitSquare(), M.material(),
                                         make_transform(translate=(0.0, 0.0, 50.0)))]
    cam = Camera(position=(0, 0, 5), look_at=(0, 0, 0), width=4, height=4)
    scene = Scene(cam, objs, list(lights),
                  RenderSettings(4, 4, spp=1, light_selection=selection,
                                 every_delta_light=every_delta))
    return Integrator(scene, scene.build()).tables


def light_samples(lights, p: ArrayLike, u: ArrayLike, objects=()):
    """Samples of the first light of a scene from points ``p`` (n, 3) with uniforms
    ``u`` (n, 2), by :func:`render.light_sampling.sample_light`: ``(wi, distance, radiance, pdf,
    delta)``, the pdf divided by the light's selection probability."""
    from render.path import sample_lights, selection

    tables = light_tables(lights, objects)
    p = np.asarray(p, dtype=np.float64)
    u = np.column_stack([np.zeros(len(p)), np.asarray(u, dtype=np.float64)])
    wi, dist, li, pdf, delta, _ = sample_lights(tables, p, u)
    return wi, dist, li, pdf / selection(tables, p, np.zeros_like(p))[:, 0], delta
