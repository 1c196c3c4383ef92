"""MDL ``df::thin_film``: the interference colours of a thin coating on the Fresnel terms below it.

MDL signature::

    bsdf thin_film(float thickness, color ior, bsdf base);

``thickness`` in nanometres, ``ior`` the film's index of refraction.  Model (the spec,
Appendix H; libbsdf, ``reference/mdl-distribution-functions.md`` §4): the film replaces
the Fresnel reflectance of the df it modifies by the reflectance of a thin layer on
that interface (Airy's sum of the multiply reflected waves), per polarisation::

    R = |r01 + r12 e^(i delta)|^2 / |1 + r01 r12 e^(i delta)|^2,
    delta = 4 pi n_film d cos(theta_film) / lambda

with ``r01``, ``r12`` the complex amplitude coefficients of the top (medium to film) and
bottom (film to the modified interface, dielectric or conducting) boundaries, averaged
over s and p, at 16 wavelengths over 400–700 nm, weighted by the CIE 1931 colour
matching functions (Wyman, Sloan and Shirley's multi-lobe fit, JCGT 2013) and
converted to linear sRGB, normalised so that a flat spectrum is white.  A colour IOR is
taken as a piecewise constant spectrum (blue below 494 nm, green to 588 nm, red above).
``thickness <= 0`` leaves the Fresnel term unchanged.

**Propagation** (spec Appendix H): the film acts on the Fresnel term of its direct
argument, and passes through ``tint``, the mixers and the weighted and measured layers
and factors to the dfs below them.  Implemented here for ``fresnel_layer`` /
``color_fresnel_layer`` (the layer's curve over the layer's IOR), ``fresnel_factor`` (a
film on the conductor) and the specular and glossy lobes in ``scatter_reflect_transmit``
(the film over the material's IOR replaces their Fresnel split: the event is chosen by
the channels' mean reflectance and weighted ``F_c / P`` or ``(1 - F_c) / (1 - P)``; their
albedo tables stay the film-less lobe's, within about 1 % of the filmed one's).

Over the custom curves (MDL 1.8: ``custom_curve_layer``, ``color_custom_curve_layer``,
``directional_factor``) the curve ``C`` is not a Fresnel term, so the film cannot
replace it; as libbsdf does, the curve is read as the reflectance of an interface
(``custom_curve_layer``: a dielectric of IOR ``(1 + sqrt(R0)) / (1 - sqrt(R0))``, R0
clamped to 0.98, :func:`schlick_ior`; ``directional_factor``: a conductor of normal
reflectance ``R0`` and edge tint ``R90 f82``, Gulbrandsen's fit, :func:`edge_tint_ior`)
and takes the film's change of that interface's reflectance,
``C' = saturate(C + film_rgb(d) - film_rgb(0))`` (:func:`film_shift`).  Where the curve
is that interface's Fresnel term, this is the film's Fresnel replacing it.  One
departure: libbsdf subtracts the bare interface's Fresnel per channel; here the bare
reflectance is the same spectral computation at thickness 0 (equal to it for a grey
``R0``, and the shift vanishes as the thickness does for any ``R0``).

On every other df the film is a no-op: diffuse, sheen and measured lobes and plain
reflect/transmit lobes, as the spec says.

The film is a bind-time rewrite of the program (:class:`ThinFilm`): it writes its
thickness and IOR into the affected nodes' film slots (``thin_film_thickness`` and
``thin_film_ior``, parameters of those dfs that are not MDL's) and rebuilds their Ĉ
tables (a curve layer whose curve was constant, and so had none, gets one); the kernels
of those dfs evaluate :func:`film_reflectance` in place of Fresnel, or
:func:`film_shift` on their curve.
"""

from __future__ import annotations

import math

import numpy as np

from render.df._registry import Df
from render.df._signature import REQUIRED, Param, Signature
from render.jit import njit

__all__ = ["ThinFilm", "thin_film", "SIGNATURE", "FILM_PARAMS", "film_reflectance",
           "film_rgb"]

#: ``df::thin_film``
SIGNATURE = Signature("bsdf", (
    Param("thickness", "float", REQUIRED, clamp=(0.0, None)),
    Param("ior", "color", REQUIRED),
    Param("base", "bsdf", REQUIRED),
))
#: the film slots of the dfs a film modifies (not MDL parameters of those dfs)
FILM_PARAMS = (Param("thin_film_thickness", "float", 0.0, clamp=(0.0, None), mdl=False),
               Param("thin_film_ior", "color", (1.0, 1.0, 1.0), mdl=False))

# --- the spectral machinery -------------------------------------------------------------
_N_LAMBDA = 16
_LAMBDA = 400.0 + (np.arange(_N_LAMBDA) + 0.5) * (300.0 / _N_LAMBDA)
#: the channel each wavelength takes a colour IOR from (blue, green, red)
_CHANNEL = np.where(_LAMBDA < 494.0, 2, np.where(_LAMBDA < 588.0, 1, 0)).astype(np.int64)


def _lobe(x, mu, s1, s2):
    s = np.where(x < mu, s1, s2)
    return np.exp(-0.5 * ((x - mu) / s) ** 2)


def _cmf(lam):
    """CIE 1931 x, y, z colour matching functions (Wyman, Sloan, Shirley 2013)."""
    x = (1.056 * _lobe(lam, 599.8, 37.9, 31.0) + 0.362 * _lobe(lam, 442.0, 16.0, 26.7)
         - 0.065 * _lobe(lam, 501.1, 20.4, 26.2))
    y = 0.821 * _lobe(lam, 568.8, 46.9, 40.5) + 0.286 * _lobe(lam, 530.9, 16.3, 31.1)
    z = 1.217 * _lobe(lam, 437.0, 11.8, 36.0) + 0.681 * _lobe(lam, 459.0, 26.0, 13.8)
    return np.stack([x, y, z], axis=1)


_XYZ_TO_RGB = np.array([[3.2406, -1.5372, -0.4986], [-0.9689, 1.8758, 0.0415],
                        [0.0557, -0.2040, 1.0570]])
#: linear sRGB per unit reflectance at each wavelength, white-balanced (a flat
#: spectrum of reflectance 1 gives (1, 1, 1))
_W = (_cmf(_LAMBDA) @ _XYZ_TO_RGB.T)
_W = np.ascontiguousarray(_W / _W.sum(axis=0))


@njit
def _amplitudes(n_a, n_b, cos_a, sin2_a):
    """Complex s and p amplitude reflection coefficients of the boundary from ``n_a`` (real)
    into ``n_b`` (complex), and the transmitted cosine (complex)."""
    cos_b = np.sqrt(1.0 - (n_a / n_b) ** 2 * sin2_a + 0j)
    rs = (n_a * cos_a - n_b * cos_b) / (n_a * cos_a + n_b * cos_b)
    rp = (n_b * cos_a - n_a * cos_b) / (n_b * cos_a + n_a * cos_b)
    return rs, rp, cos_b


@njit
def film_reflectance(c, n0, n1, n2, k2, d, lam):
    """Unpolarised reflectance of a film (``n1``, ``d`` nm) on a substrate ``n2 + i k2``
    seen from a medium ``n0`` at incidence cosine ``c``, wavelength ``lam`` (nm)."""
    c = min(max(c, 0.0), 1.0)
    s2 = 1.0 - c * c
    n1c = complex(n1, 0.0)
    r01s, r01p, cos1 = _amplitudes(n0, n1c, c, s2)
    sin2_1 = (n0 / n1) ** 2 * s2
    if sin2_1 >= 1.0:
        return 1.0  # total reflection at the film's top
    c1 = math.sqrt(1.0 - sin2_1)
    r12s, r12p, _ = _amplitudes(n1, complex(n2, k2), c1, sin2_1)
    e = np.exp(1j * (4.0 * math.pi * n1 * d * c1 / lam))
    rs = (r01s + r12s * e) / (1.0 + r01s * r12s * e)
    rp = (r01p + r12p * e) / (1.0 + r01p * r12p * e)
    return min(max(0.5 * (abs(rs) ** 2 + abs(rp) ** 2), 0.0), 1.0)


@njit
def film_rgb(c, n0, f0, f1, f2, s0, s1, s2, k0, k1, k2, d):
    """The film's reflectance in linear sRGB: films ``(f0, f1, f2)`` and substrates
    ``(s + i k)`` per channel (red, green, blue), from a medium ``n0``."""
    r = g = b = 0.0
    for j in range(_N_LAMBDA):
        ch = _CHANNEL[j]
        nf = f0 if ch == 0 else (f1 if ch == 1 else f2)
        ns = s0 if ch == 0 else (s1 if ch == 1 else s2)
        ks = k0 if ch == 0 else (k1 if ch == 1 else k2)
        R = film_reflectance(c, n0, nf, ns, ks, d, _LAMBDA[j])
        r += _W[j, 0] * R
        g += _W[j, 1] * R
        b += _W[j, 2] * R
    return min(max(r, 0.0), 1.0), min(max(g, 0.0), 1.0), min(max(b, 0.0), 1.0)


@njit
def film_shift(c, n0, f0, f1, f2, s0, s1, s2, k0, k1, k2, d):
    """What the film changes in the reflectance of its substrate: :func:`film_rgb` at
    thickness ``d`` minus the same at thickness 0 (the bare interface, seen through the
    same spectral weighting), per channel.  The curves a film acts on take this shift
    (libbsdf's ``apply_coating_color_shift``): ``C' = saturate(C + shift)``."""
    r0, r1, r2 = film_rgb(c, n0, f0, f1, f2, s0, s1, s2, k0, k1, k2, d)
    b0, b1, b2 = film_rgb(c, n0, f0, f1, f2, s0, s1, s2, k0, k1, k2, 0.0)
    return r0 - b0, r1 - b1, r2 - b2


@njit
def schlick_ior(r0):
    """The dielectric IOR whose normal reflectance is ``r0`` (clamped to [0, 0.98]):
    ``(1 + sqrt(r0)) / (1 - sqrt(r0))``, the substrate a film sees under a custom curve."""
    q = math.sqrt(min(max(r0, 0.0), 0.98))
    return (1.0 + q) / (1.0 - q)


@njit
def edge_tint_ior(r, g):
    """The complex IOR ``(n, k)`` of a conductor with normal reflectance ``r`` and edge
    tint ``g`` (Gulbrandsen, "Artist friendly metallic Fresnel", JCGT 2014; ``r`` pulled
    into [0.01, 0.99] as libbsdf does): the substrate a film sees under a
    ``directional_factor``."""
    r = 0.01 + 0.98 * min(max(r, 0.0), 1.0)
    g = min(max(g, 0.0), 1.0)
    q = math.sqrt(r)
    n = g * (1.0 - r) / (1.0 + r) + (1.0 - g) * (1.0 + q) / (1.0 - q)
    k2 = (r * (n + 1.0) * (n + 1.0) - (n - 1.0) * (n - 1.0)) / (1.0 - r)
    return n, math.sqrt(max(k2, 0.0))


# --- the bind-time rewrite ---------------------------------------------------------------
def _wants_table(prog, k: int) -> bool:
    """Whether the curve layer ``k`` needs a Ĉ table once its curve varies (a constant
    curve had none): it has a layer child that is not a mirror (as
    :func:`render.program._with_chat_table` decides)."""
    from render import program as pg
    from render.df._registry import registry

    lay = prog.kids[prog.code[k, pg.KID0]]
    if lay < 0:
        return False
    return not (registry().nodes[prog.code[lay, pg.OP] - 1].mirror
                and (prog.code[lay, pg.FLAGS] & 3) == 0)


class ThinFilm:
    """``df::thin_film(thickness, ior, base)``: ``base`` with a film written into the
    dfs it modifies (see the module docstring); an instance of ``base``'s class
    (a :class:`~render.program.ProgramBsdf`)."""

    def __new__(cls, thickness, ior, base):
        from render import interpreter
        from render import program as pg
        from render.df._registry import registry

        title = "df::thin_film"
        if base is None:
            return None  # thin_film(..., bsdf()) is black
        if not isinstance(base, pg.ProgramBsdf):
            raise ValueError(f"{title}(base) must be a bound bsdf, got {type(base).__name__}")
        d = pg._as_rows(thickness, 1, f"{title}: thickness")
        n = pg._as_rows(ior, 3, f"{title}: ior")
        if np.any(n <= 0.0):
            raise ValueError(f"{title}: ior must be > 0 (the film's index of refraction), "
                             f"got {ior!r}")
        d = np.maximum(d, 0.0)
        prog = base.program
        rows = pg._rows([prog.P, d, n])
        P = np.array(np.broadcast_to(prog.P, (rows, prog.P.shape[1])))
        code = prog.code.copy()
        nodes = registry().nodes
        hit = []
        todo = [prog.root]
        while todo:
            k = todo.pop()
            node = nodes[code[k, pg.OP] - 1]
            if node.film >= 0:
                if not node.film_always and (code[k, pg.FLAGS] & 3) != 2:
                    continue  # a plain reflect or transmit lobe has no Fresnel to change
                at = code[k, pg.BASE] + node.film
                P[:, at] = np.broadcast_to(d, (rows, 1))[:, 0]
                P[:, at + 1:at + 4] = np.broadcast_to(n, (rows, 3))
                hit.append(k)
            elif node.passes_film:
                k0 = code[k, pg.KID0]
                todo.extend(int(c) for c in prog.kids[k0:k0 + code[k, pg.NKIDS]] if c >= 0)
        tables = prog.tables
        for k in hit:  # the coat's curve changed: its Ĉ table with it
            if nodes[code[k, pg.OP] - 1].role != "layer":
                continue
            if not np.any(d > 0.0):
                continue  # no film: the curve and its table stand
            if code[k, pg.TABLE] == pg.CHAT_NONE and not _wants_table(prog, k):
                continue  # no coat, or a mirror coat: libbsdf's factor is the bound
            if rows > 1 and not np.all(P == P[:1]):
                code[k, pg.TABLE] = pg.CHAT_NONE
                continue
            out = np.zeros((2, 2, pg.CHAT_THETA, 3))
            interpreter.build_chat_table(code, prog.kids, prog.frames, P[:1], tables, 0, k,
                                         pg._chat_directions(), pg.sobol_points(pg.CHAT_POINTS),
                                         out)
            code[k, pg.TABLE] = len(tables)
            tables = np.concatenate([tables, out.ravel()])
        new = pg.Program(prog.kind, code, prog.kids, prog.frames, (P,), tables, prog.lobes)
        obj = pg.ProgramBsdf.__new__(type(base))
        pg.ProgramBsdf.__init__(obj, new)
        obj.__dict__.update({k: v for k, v in base.__dict__.items() if k != "program"})
        obj.__dict__["program"] = new
        return obj


def thin_film(thickness, ior, base):
    """``df::thin_film``: ``base`` with the film's interference in its Fresnel terms."""
    return ThinFilm(thickness, ior, base)


thin_film.mdl_name = "thin_film"
DF = Df("thin_film", SIGNATURE, constructor=thin_film)
