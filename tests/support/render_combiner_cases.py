"""The df checklist for MDL's layers, mixes and modifiers (combiners of other dfs).

The checks of :mod:`render_df_cases` assume a df is either all delta or not delta at
all.  A combiner can be both (a mirror coat over a diffuse base), so this module adds:

* :func:`check_integrals_combined` — one MC run and one quadrature pass per ``wo``:
  the white furnace (``<= 1`` within 4 standard errors for every combiner, no
  exceptions; ``= 1`` where lossless), ``albedo()`` against MC, quadrature of ``eval``
  against the MC mean of the **non-delta** sample weights, and ``∫ pdf`` against the
  rate of successful non-delta samples;
* :class:`NonDelta` — the df with its delta samples turned into failures, so that
  :func:`render.testing.chi2_test` tests the density of the non-delta part (which is
  exactly ``pdf``).

Every check returns the numbers it measured so the tests can report them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from render_df_cases import WOS, DfCase, edge_dirs, integrate, random_dirs, wo_of

from render.bsdf import Bsdf, BsdfSample
from render.testing import chi2_test, sample_lanes, tile

#: Monte-Carlo samples per furnace (fewer than the elemental dfs' 100 000: combiners
#: evaluate every child per sample, and the suite has many of them)
N_MC = 40_000
#: chi-square samples
N_CHI2 = 100_000

#: measured accuracy of a directional combiner's albedo: the children's tables (3e-3) plus
#: the 89-point quadrature of the factor's deviation (render.df._combine.ALBEDO_POINTS):
#: about 5e-3 where the factors are smooth, 2e-2 where they jump (total internal
#: reflection inside a Fresnel coat, the horizon of a tilted layer normal)
COMBINED_ALBEDO_TOL = 6e-3
JUMP_ALBEDO_TOL = 2.5e-2


@dataclass(frozen=True)
class CombinerCase(DfCase):
    """A :class:`DfCase` for combiners.

    Parameters
    ----------
    quad_tol : float
        Accuracy of the quadrature of ``eval`` (lobes whose peak is off the inherited
        mirror direction integrate less exactly).
    """

    quad_tol: float = 2e-3


class NonDelta(Bsdf):
    """``bsdf`` with its delta (specular) samples reported as failures.

    Its successful samples have density ``bsdf.pdf`` (delta events are not part of the
    pdf), so the chi-square test of this wrapper tests the non-delta sampling of a
    combiner that also holds specular lobes.
    """

    def __init__(self, bsdf: Bsdf):
        self.inner = bsdf
        self.lobes = bsdf.lobes

    def eval(self, wo, wi):
        return self.inner.eval(wo, wi)

    def pdf(self, wo, wi):
        return self.inner.pdf(wo, wi)

    def eval_pdf(self, wo, wi):
        return self.inner.eval_pdf(wo, wi)

    def albedo(self, wo):
        return self.inner.albedo(wo)

    def sample(self, wo, u1, u2):
        s = self.inner.sample(wo, u1, u2)
        keep = s.valid & ~s.is_delta
        return BsdfSample(
            np.where(keep[:, None], s.wi, 0.0),
            np.where(keep, s.pdf, 0.0),
            np.where(keep[:, None], s.weight, 0.0),
            np.where(keep, s.lobe, 0).astype(np.int32),
        )


def check_no_nan_combined(case: DfCase, rng: np.random.Generator, n_albedo: int = 500) -> None:
    """:func:`render_df_cases.check_no_nan` for combiners whose albedo is a quadrature.

    The same checks (eval, pdf and sample over every pair of edge directions and 5000
    random pairs; albedo finite and in [0, 1]; nothing scatters from the tangent plane),
    except that ``albedo`` is evaluated on the 43 distinct edge directions and
    ``n_albedo`` random ones instead of all 6849 lanes: a directional combiner integrates
    its albedo through ``2 * ALBEDO_POINTS`` child samples per lane.
    """
    bsdf = case.make()
    d = edge_dirs()
    wo = np.concatenate([np.repeat(d, len(d), axis=0), random_dirs(rng, 5000)])
    wi = np.concatenate([np.tile(d, (len(d), 1)), random_dirs(rng, 5000)])
    e, p = bsdf.eval_pdf(wo, wi)
    assert np.all(np.isfinite(e)) and np.all(e >= 0)
    assert np.all(np.isfinite(p)) and np.all(p >= 0)
    assert np.array_equal(bsdf.eval(wo, wi), e) and np.array_equal(bsdf.pdf(wo, wi), p)
    half = len(wo) // 2
    u1 = np.concatenate([np.zeros(half), np.full(len(wo) - half, np.nextafter(1.0, 0.0))])
    u2 = rng.random((len(wo), 2))
    u2[::7] = 0.0
    u2[1::7] = np.nextafter(1.0, 0.0)
    s = bsdf.sample(wo, u1, u2)
    for a in (s.wi, s.pdf, s.weight):
        assert np.all(np.isfinite(a))
    assert np.all(s.pdf >= 0) and np.all(s.weight >= 0)
    wa = np.concatenate([d, random_dirs(rng, n_albedo)])
    a = bsdf.albedo(wa)
    assert np.all(np.isfinite(a)) and np.all(a >= 0) and np.all(a <= 1.0 + 1e-12)
    flat = np.abs(wo[:, 2]) <= 1e-10
    assert not np.any(e[flat]) and not np.any(p[flat]) and not np.any(s.valid[flat])
    assert not np.any(a[np.abs(wa[:, 2]) <= 1e-10])


def two_wos(cases) -> list:
    """(case, wo) pairs: every case at 60 degrees, plus one of normal incidence, 89.9
    degrees and below the horizon in turn, so the set covers every direction."""
    extra = (WOS[0], WOS[2], WOS[3])
    return [(c, w) for i, c in enumerate(cases) for w in (WOS[1], extra[i % 3])]


def check_chi2_combined(case: DfCase, theta_phi, test_count: int) -> float:
    """Chi-square of the non-delta samples against ``pdf``, failures as one more cell.

    Returns the p-value.
    """
    res = chi2_test(
        NonDelta(case.make()),
        wo_of(theta_phi),
        sample_count=N_CHI2,
        test_count=test_count,
        include_failures=True,
    )
    assert res.passed, f"{case.id} wo={theta_phi}: {res}"
    return res.p_value


def assert_no_gain(mean: np.ndarray, se: np.ndarray, what: str = "") -> None:
    """The white furnace of a combiner: MC albedo ``mean`` (3,) ``<= 1 + 4 se``, per channel."""
    assert np.all(mean <= 1.0 + 4.0 * se + 1e-12), (
        f"white furnace gains energy {what}: {mean} ± {se}"
    )


def check_integrals_combined(case: CombinerCase, theta_phi) -> dict:
    """Furnace, albedo, quadrature of eval and of pdf for one ``wo`` (see the module doc)."""
    bsdf = case.make()
    wo = wo_of(theta_phi)
    s = sample_lanes(bsdf, wo, N_MC, seed=11)
    mean = s.weight.mean(axis=0)
    se = s.weight.std(axis=0) / np.sqrt(N_MC)
    out = {"mc": mean, "se": se}
    assert_no_gain(mean, se, f"{case.id} wo={theta_phi}")
    if case.lossless:
        assert np.all(np.abs(mean - 1.0) <= 3 * se + 1e-12), f"lossless df loses: {mean} ± {se}"
    alb = bsdf.albedo(wo[None])[0]
    out["albedo"] = alb
    assert np.all(np.abs(alb - mean) <= 4 * se + case.albedo_tol + 1e-12), (
        f"albedo() {alb} vs MC {mean} ± {se}"
    )
    if bsdf.is_delta:
        return out
    nd = s.valid & ~s.is_delta
    nd_weight = np.where(nd[:, None], s.weight, 0.0)
    nd_mean = nd_weight.mean(axis=0)
    nd_se = nd_weight.std(axis=0) / np.sqrt(N_MC)
    rate = nd.mean()

    def f(w):
        e, p = bsdf.eval_pdf(tile(wo, len(w)), w)
        return np.concatenate([e, p[:, None]], axis=1)

    q = integrate(case, bsdf, wo, f)
    quad, total = q[:3], float(q[3])
    out["quad"], out["pdf_integral"], out["nd_rate"] = quad, total, rate
    sigma = np.sqrt(max(rate * (1 - rate), 1.0 / N_MC) / N_MC)
    assert total <= 1.0 + 2e-3, f"pdf integrates to {total}"
    assert abs(total - rate) <= 4 * sigma + case.quad_tol, (
        f"∫pdf = {total} but non-delta samples succeed {rate}"
    )
    assert np.all(np.abs(quad - nd_mean) <= 4 * nd_se + case.quad_tol), (
        f"∫eval {quad} vs MC of the non-delta weights {nd_mean} ± {nd_se}"
    )
    return out


# --- the no-gain sweeps of the directional layers --------------------------------------------

#: samples per configuration of the sweeps (each draws a new layer node)
N_SWEEP = 20_000
#: what a sweep puts under the coat and what it uses as the coat
SWEEP_BASES = ("mirror", "glossy", "diffuse", "transmission", "nested")
SWEEP_LAYERS = ("glossy", "nested", "factor")
#: roughness values of the sweeps, smooth to rough: nodes (k/32)^2 of the glossy lobes'
#: lazily built albedo tables (render.df._albedo, 0.3 s per node), so the examples share
#: them (anisotropic coats build several 0.4 s corners each: tested on their own)
SWEEP_ROUGHNESS = tuple((k / 32.0) ** 2 for k in (4, 10, 14, 18, 24, 28, 32))


def sweep_layer(kind: str, roughness: float):
    """A white coat of roughness ``roughness`` for the sweeps (``kind`` in SWEEP_LAYERS)."""
    from render.df import directional_factor, fresnel_layer, simple_glossy_bsdf

    if kind == "glossy":
        return simple_glossy_bsdf(roughness_u=roughness)
    if kind == "nested":
        return fresnel_layer(1.5, 1.0, simple_glossy_bsdf(roughness_u=roughness),
                             simple_glossy_bsdf(roughness_u=0.5 * roughness))
    if kind == "factor":
        return directional_factor(0.9, 1.0, 1.0, 3.0, simple_glossy_bsdf(roughness_u=roughness))
    raise ValueError(f"unknown sweep layer {kind!r}; use one of {SWEEP_LAYERS}")


def sweep_base(kind: str, roughness: float):
    """A white base for the sweeps (``kind`` in SWEEP_BASES; ``roughness`` of the glossy)."""
    from render.df import (
        custom_curve_layer,
        diffuse_reflection_bsdf,
        diffuse_transmission_bsdf,
        simple_glossy_bsdf,
        specular_bsdf,
    )

    if kind == "mirror":
        return specular_bsdf()
    if kind == "glossy":
        return simple_glossy_bsdf(roughness_u=roughness)
    if kind == "diffuse":
        return diffuse_reflection_bsdf()
    if kind == "transmission":
        return diffuse_transmission_bsdf()
    if kind == "nested":
        return custom_curve_layer(0.0, 1.0, 1.0, 1.0, simple_glossy_bsdf(roughness_u=roughness),
                                  specular_bsdf())
    raise ValueError(f"unknown sweep base {kind!r}; use one of {SWEEP_BASES}")


def sweep_furnace(bsdf: Bsdf, theta: float, phi: float = 30.0) -> tuple[np.ndarray, np.ndarray]:
    """MC albedo and standard error of ``bsdf`` at ``direction(theta, phi)``, asserting no gain."""
    from render.testing import direction

    s = sample_lanes(bsdf, direction(theta, phi), N_SWEEP, seed=3)
    mean = s.weight.mean(axis=0)
    se = s.weight.std(axis=0) / np.sqrt(N_SWEEP)
    assert_no_gain(mean, se, f"{bsdf!r} theta={theta}")
    return mean, se
