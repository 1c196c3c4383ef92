"""The df kernels seen through the numpy ``Bsdf`` / ``Edf`` interface, for the tests.

A df module's scalar kernels (``eval_pdf``, ``sample``, ``albedo``; ``edf_eval_pdf``,
``edf_sample``) run over lanes in small ``numba.njit`` loops, so every check of
``render.testing`` and ``render_df_cases`` (chi-square, quadrature, furnace, consistency,
reciprocity, no NaN) applies to the kernels that render.

:func:`pack` is the tests' tiny stand-in for the lead's packer (``render.program``): it
follows ``SIGNATURE`` (offsets, widths, defaults, clamps).  The adapters place the
node at slot ``b = 3`` behind three NaN slots, so a kernel that reads outside its own
slots returns NaN and fails the tests.
"""

from __future__ import annotations

import numba
import numpy as np

from render.bsdf import Bsdf, BsdfSample, Edf, EdfSample, Lobe
from render.df._signature import MODE_FLAGS, REQUIRED, THIN_WALLED

#: NaN slots in front of the node (its base offset ``b``)
PAD = 3


def flags_of(mode: str = "scatter_reflect", thin_walled: bool = False) -> int:
    """The node's ``flags``: ``df::scatter_mode`` and ``material.thin_walled``."""
    return MODE_FLAGS[mode.removeprefix("df::")] | (THIN_WALLED if thin_walled else 0)


def pack(sig, n: int = 1, **values) -> np.ndarray:
    """(n, sig.width) slot rows of the arguments ``values`` (defaults where absent).

    A value is a constant (scalar, or the parameter's components) or one per lane
    (``(n,)`` / ``(n, width)``).  ``float3x3`` values are packed row-major.  Context names
    ``X_ij`` take ``values["X"][..., i, j]`` (a (3, 3) or (n, 3, 3) matrix); other
    context values default to 1 (the numpy classes' IOR defaults).
    """
    cols = []
    for p in sig.params:
        if not p.width:
            continue
        v = values.pop(p.name, p.default)
        if v is REQUIRED or isinstance(v, str):
            raise ValueError(f"pack: give {p.name} (default {v!r} is not a value)")
        a = np.asarray(v, dtype=np.float64)
        a = a.reshape(n, p.width) if a.size == n * p.width and a.ndim and n > 1 else (
            np.broadcast_to(a.reshape(-1), (n, p.width)))
        if p.clamp is not None:
            lo, hi = p.clamp
            a = np.clip(a, -np.inf if lo is None else lo, np.inf if hi is None else hi)
        cols.append(a)
    mats = {}
    for name in sig.context:
        base, _, ij = name.rpartition("_")
        if base and len(ij) == 2 and ij.isdigit() and base in values:
            m = mats.setdefault(base, np.asarray(values[base], dtype=np.float64))
            cols.append(np.broadcast_to(m[..., int(ij[0]), int(ij[1])], (n,))[:, None])
        else:
            cols.append(np.broadcast_to(np.asarray(values.pop(name, 1.0), float), (n,))[:, None])
    for base in mats:
        values.pop(base)
    if values:
        raise ValueError(f"pack: {sorted(values)} are not parameters of this signature")
    return np.ascontiguousarray(np.concatenate(cols, axis=1) if cols else np.zeros((n, 0)))


def _padded(rows: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(
        np.concatenate([np.full((len(rows), PAD), np.nan), rows], axis=1))


@numba.njit
def _eval_pdf_lanes(kernel, P, flags, wo, wi):
    n = wo.shape[0]
    f = np.zeros((n, 3))
    pdf = np.zeros(n)
    for i in range(n):
        r = 0 if P.shape[0] == 1 else i
        f[i, 0], f[i, 1], f[i, 2], pdf[i] = kernel(
            P, r, PAD, flags, wo[i, 0], wo[i, 1], wo[i, 2], wi[i, 0], wi[i, 1], wi[i, 2])
    return f, pdf


@numba.njit
def _sample_lanes(kernel, P, flags, wo, u1, u2):
    n = wo.shape[0]
    wi = np.zeros((n, 3))
    pdf = np.zeros(n)
    w = np.zeros((n, 3))
    lobe = np.zeros(n, np.int32)
    for i in range(n):
        r = 0 if P.shape[0] == 1 else i
        wi[i, 0], wi[i, 1], wi[i, 2], pdf[i], w[i, 0], w[i, 1], w[i, 2], lobe[i] = kernel(
            P, r, PAD, flags, wo[i, 0], wo[i, 1], wo[i, 2], u1[i], u2[i, 0], u2[i, 1])
    return wi, pdf, w, lobe


@numba.njit
def _albedo_lanes(kernel, P, flags, wo):
    n = wo.shape[0]
    a = np.zeros((n, 3))
    for i in range(n):
        r = 0 if P.shape[0] == 1 else i
        a[i, 0], a[i, 1], a[i, 2] = kernel(P, r, PAD, flags, wo[i, 0], wo[i, 1], wo[i, 2])
    return a


@numba.njit
def _edf_eval_pdf_lanes(kernel, P, flags, wo):
    n = wo.shape[0]
    e = np.zeros((n, 3))
    pdf = np.zeros(n)
    for i in range(n):
        r = 0 if P.shape[0] == 1 else i
        e[i, 0], e[i, 1], e[i, 2], pdf[i] = kernel(P, r, PAD, flags, wo[i, 0], wo[i, 1], wo[i, 2])
    return e, pdf


@numba.njit
def _edf_sample_lanes(kernel, P, flags, u1, u2):
    n = u1.shape[0]
    wo = np.zeros((n, 3))
    pdf = np.zeros(n)
    w = np.zeros((n, 3))
    for i in range(n):
        r = 0 if P.shape[0] == 1 else i
        wo[i, 0], wo[i, 1], wo[i, 2], pdf[i], w[i, 0], w[i, 1], w[i, 2] = kernel(
            P, r, PAD, flags, u1[i], u2[i, 0], u2[i, 1])
    return wo, pdf, w


def _f64(a, shape):
    return np.ascontiguousarray(np.broadcast_to(np.asarray(a, dtype=np.float64), shape))


class KernelBsdf(Bsdf):
    """A df module's bsdf (or vdf) kernels over lanes, as a :class:`render.bsdf.Bsdf`.

    Parameters
    ----------
    module : module
        ``render.df.<name>`` with ``SIGNATURE`` and the three kernels.
    lobes : Lobe
        What the df can sample (the numpy class's ``lobes``).
    mode, thin_walled : str, bool
        The node's flags.
    n : int
        Lanes of per-lane arguments (1: constants).
    **args
        MDL arguments and context values, as :func:`pack` takes them.
    """

    def __init__(self, module, lobes, mode="scatter_reflect", thin_walled=False, n=1, **args):
        self.module = module
        self.lobes = Lobe(lobes)
        self.flags = flags_of(mode, thin_walled)
        self.P = _padded(pack(module.SIGNATURE, n, **args))

    def eval_pdf(self, wo, wi):
        wo, wi = np.asarray(wo, np.float64), np.asarray(wi, np.float64)
        return _eval_pdf_lanes(self.module.eval_pdf, self.P, self.flags,
                               _f64(wo, wo.shape), _f64(wi, wo.shape))

    def eval(self, wo, wi):
        return self.eval_pdf(wo, wi)[0]

    def pdf(self, wo, wi):
        return self.eval_pdf(wo, wi)[1]

    def sample(self, wo, u1, u2):
        wo = _f64(wo, np.shape(wo))
        n = len(wo)
        wi, pdf, w, lobe = _sample_lanes(self.module.sample, self.P, self.flags, wo,
                                         _f64(u1, (n,)), _f64(u2, (n, 2)))
        return BsdfSample(wi, pdf, w, lobe)

    def albedo(self, wo):
        return _albedo_lanes(self.module.albedo, self.P, self.flags, _f64(wo, np.shape(wo)))


class KernelEdf(Edf):
    """A df module's edf kernels over lanes, as a :class:`render.bsdf.Edf` (see
    :class:`KernelBsdf`)."""

    def __init__(self, module, n=1, **args):
        self.module = module
        self.flags = 0
        self.P = _padded(pack(module.SIGNATURE, n, **args))

    def eval_pdf(self, wo):
        return _edf_eval_pdf_lanes(self.module.edf_eval_pdf, self.P, self.flags,
                                   _f64(wo, np.shape(wo)))

    def eval(self, wo):
        return self.eval_pdf(wo)[0]

    def pdf(self, wo):
        return self.eval_pdf(wo)[1]

    def sample(self, u1, u2):
        n = len(np.asarray(u2))
        wo, pdf, w = _edf_sample_lanes(self.module.edf_sample, self.P, self.flags,
                                       _f64(u1, (n,)), _f64(u2, (n, 2)))
        return EdfSample(wo, pdf, w)


# --- numpy class against kernels ----------------------------------------------------------


def lane_dirs(rng: np.random.Generator, n: int) -> np.ndarray:
    """``n`` random unit directions, then the extremes: poles, grazing to 89.9 degrees and
    beyond, the exact horizon, and their mirror images below it."""
    v = rng.normal(size=(n, 3))
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    edge = []
    for th in (0.0, 1e-7, 30.0, 89.0, 89.9, 89.999, 90.0, 90.001, 90.1, 150.0, 180.0):
        for ph in (0.0, 45.0, 200.0):
            t, p = np.radians(th), np.radians(ph)
            edge.append([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)])
    return np.concatenate([v, np.asarray(edge)])


def lane_us(rng: np.random.Generator, n: int) -> tuple[np.ndarray, np.ndarray]:
    """(u1, u2) for ``n`` lanes with 0 and the largest float below 1 mixed in."""
    u1, u2 = rng.random(n), rng.random((n, 2))
    top = np.nextafter(1.0, 0.0)
    u1[::5], u1[1::5] = 0.0, top
    u2[2::7], u2[3::7] = 0.0, top
    u2[4::11, 0], u2[5::11, 1] = 0.5, 0.5
    return u1, u2


def assert_close(got, want, rtol: float, what: str) -> None:
    """``|got - want| <= rtol |want|`` elementwise (``rtol = 0``: bit for bit), with the
    worst lane in the message."""
    got, want = np.asarray(got, np.float64), np.asarray(want, np.float64)
    assert got.shape == want.shape, f"{what}: shape {got.shape} != {want.shape}"
    err = np.abs(got - want)
    bad = ~(err <= rtol * np.abs(want))
    if np.any(bad):
        k = np.unravel_index(np.argmax(np.where(bad, err, -1.0)), err.shape)
        raise AssertionError(
            f"{what}: {np.count_nonzero(bad)} of {bad.size} differ beyond rtol {rtol}; "
            f"worst at {k}: kernel {got[k]!r} numpy {want[k]!r}")


def compare_bsdf(ref: Bsdf, ker: Bsdf, wo, wi, u1, u2, rtol: float = 0.0) -> None:
    """The kernel adapter ``ker`` equals the numpy df ``ref``: eval, pdf, albedo, and the
    samples for the same variates (direction, pdf, weight, lobe)."""
    e0, p0 = ref.eval(wo, wi), ref.pdf(wo, wi)
    e1, p1 = ker.eval_pdf(wo, wi)
    assert_close(e1, e0, rtol, "eval")
    assert_close(p1, p0, rtol, "pdf")
    assert_close(ker.albedo(wo), ref.albedo(wo), rtol, "albedo")
    s0, s1 = ref.sample(wo, u1, u2), ker.sample(wo, u1, u2)
    np.testing.assert_array_equal(s1.lobe, s0.lobe, err_msg="sampled lobe")
    assert_close(s1.wi, s0.wi, rtol, "sample wi")
    assert_close(s1.pdf, s0.pdf, rtol, "sample pdf")
    assert_close(s1.weight, s0.weight, rtol, "sample weight")


def compare_edf(ref: Edf, ker: Edf, wo, u1, u2, rtol: float = 0.0) -> None:
    """The kernel adapter ``ker`` equals the numpy edf ``ref``: eval, pdf and the samples
    for the same variates."""
    e1, p1 = ker.eval_pdf(wo)
    assert_close(e1, ref.eval(wo), rtol, "eval")
    assert_close(p1, ref.pdf(wo), rtol, "pdf")
    s0, s1 = ref.sample(u1, u2), ker.sample(u1, u2)
    assert_close(s1.wo, s0.wo, rtol, "sample wo")
    assert_close(s1.pdf, s0.pdf, rtol, "sample pdf")
    assert_close(s1.weight, s0.weight, rtol, "sample weight")
