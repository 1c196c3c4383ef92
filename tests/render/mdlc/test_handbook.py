"""The Handbook's listings of Parts 2-5, as printed, run by the workbench.

Each listing is extracted from the book's text, its margin notes removed and the book's
two repeated misprints repaired (``tests/support/handbook_listings.py``), made a module
with the definitions it uses from other listings, checked, and run:

* a **material** listing is built with its defaults and must shade exactly as the
  project's Python version of that listing (``render.materials``: the same df program,
  parameters per lane, normal, cutout, emission and displacement), to rounding; profile
  coordinates are printed to 9 digits in the emitted modules, hence 1e-7;
* a **function** listing that the workbench's library also has (``::functions``, the
  Python versions) must give the same values per lane on random states and arguments;
* other listings (types, constants, functions without a Python version) must check and
  compile.

:data:`NOT_RUN` says, for every other listing, why it does not run (or differs); the
test fails if a listing's outcome changes either way, so the count and the reasons in
docs/mdl.md stay true.  Run ``python tests/render/mdlc/test_handbook.py`` for the table.
"""

from __future__ import annotations

import importlib
import inspect
import pkgutil
import re

import numpy as np
import pytest
from handbook_listings import Listing, assemble, listings
from repo import HANDBOOK, needs_handbook

from displacement.surfaces import UnitSquare, UVSphere
from mdl import types as T
from mdl.diagnostics import MdlError

#: listing -> why it does not run as printed
NOT_RUN = {
    # not a definition to run: MDL's own declarations, excerpts
    "3.4": "MDL's declaration of df::specular_bsdf (a standard function's signature)",
    "3.7": "MDL's declaration of df::simple_glossy_bsdf (a standard function), printed in "
           "part",
    "4.5": "MDL's definition of the material_volume struct, misprinted "
           "'struct material volume'",
    "11.1": "MDL's definition of the material struct (the language's, not a module's)",
    "11.2": "MDL's definition of the material_geometry struct",
    "6.12": "an excerpt: a df::normalized_mix call, not a definition",
    "8.2": "an excerpt: an expression (with 'state:normal()' misprinted)",
    "12.10": "an excerpt: the surface argument of Listing 12.9",
    "14.24": "an excerpt: array declarations at module level, which MDL does not have",
    # printed in parts: the listing's block holds only the beginning of the definition
    "6.3": "printed in parts: only the signature is in the listing",
    "6.4": "printed in parts: the let block ends outside the listing",
    "8.3": "printed in parts: the let block ends outside the listing",
    "8.4": "printed in parts: the let block ends outside the listing",
    "12.7": "printed in parts: the let block ends outside the listing",
    "13.20": "printed in parts: only the signature is in the listing",
    "15.17": "printed in parts: the let block ends outside the listing",
    # the page layout puts closing braces before the statements they close
    "9.16": "the page layout prints the body's '}' before 'return result;'",
    "10.3": "the page layout prints the closing braces out of order",
    "13.5": "the page layout prints the if block's '}' before its last statements",
    "13.11": "the page layout closes the body before its last statements",
    "13.16": "the page layout prints the body's '}' before its last statements",
    "14.25": "the page layout closes the body after its first statement",
    "15.14": "the page layout closes the body after its first statements",
    # margin notes the extraction cannot separate from the code
    "10.4": "a margin note inside the parameter list splits 'functions::mapping_mode "
            "space'",
    "12.6": "margin notes interleave with a ?: expression over several lines",
    "15.5": "margin notes on lines of their own inside the loop ('Calculate / position in "
            "the / current piece...'); the hand-cleaned copy is pw_curve.mdl's "
            "point_along_pwc (tests/mdl/test_pwc_listings.py)",
    # misprints
    "7.1": "misprint: 'tint: diffuse_color )))' closes the components array early",
    "7.4": "misprint: a parenthesis closes the components array early",
    "12.17": "misprint: 'material surface_property = material() =' does not close the "
             "parameter list",
    "13.8": "misprint: the float2 uv defaults to float(0.0)",
    "14.7": "misprint: 'material material_for_surface = grid() =' does not close the "
            "parameter list",
    "13.15": "calls fit with float3 arguments; the book defines fit for float (12.1) and "
             "double (13.14) only",
    "9.6": "the material is named uv_as_color, like the function it calls (Listing 9.5) "
           "with the same (no) parameters: MDL cannot tell them apart (the project calls "
           "it uv_as_color_material)",
    "8.6": "uses the colour constant 'green', which the book never defines",
    # needs a listing that does not run
    "13.9": "uses texture_2d_sample (Listing 13.8, misprinted)",
    "14.30": "uses profile_lengths (Listing 14.25, broken by the page layout)",
}

#: listing -> why its material runs but differs from the Python version
DIFFERS = {
    "13.13": "reads weave_depth.png with tex::gamma_default, which for a PNG is sRGB in "
             "MDL; the Python version reads the height map as linear data (the same "
             "with tex::gamma_linear: test_the_weave_bump_differs_only_by_gamma)",
    "13.18": "printed in parts: the block ends inside the material; closed, it has no "
             "emission",
    "13.19": "printed in parts: the block ends inside material_geometry(, so the normal "
             "is lost",
    "15.10": "as printed it looks the texture up at float2(texture_u_scale, "
             "texture_v_scale), one texel for the whole surface; the Python version is "
             "the scaled lookup the figure shows (render/materials/chapter15.py)",
    "15.11": "uses travertine (Listing 15.10): as above",
}

TOLERANCE = 1e-7


def _twins() -> dict:
    """(listing, name) -> the Python function whose docstring starts with that listing."""
    import render.materials as package

    out = {}
    for info in pkgutil.iter_modules(package.__path__):
        mod = importlib.import_module(f"render.materials.{info.name}")
        for name, f in inspect.getmembers(mod, inspect.isfunction):
            m = re.match(r"Listing (\d+\.\d+)", inspect.getdoc(f) or "")
            if m and f.__module__ == mod.__name__:
                out.setdefault((m.group(1), name), f)
    return out


def _states():
    rng = np.random.default_rng(3)
    return [UnitSquare().state_at_uv(rng.uniform(-0.2, 1.2, (64, 2))),
            UVSphere().state_at_uv(rng.random((64, 2)))]


def shading_difference(a, b) -> tuple[float, str]:
    """The largest difference between two materials' shading over the test states (inf
    with the reason when their structure differs)."""
    worst = 0.0
    for s in _states():
        da, db = (np.zeros((len(s), 3)) if m.displacement is None else m.displacement(s)
                  for m in (a, b))
        worst = max(worst, float(np.abs(da - db).max(initial=0.0)))
        sa, sb = a.shade(s), b.shade(s)
        for x, y in ((sa.normal, sb.normal), (sa.cutout_opacity, sb.cutout_opacity),
                     (sa.intensity, sb.intensity), (sa.ior, sb.ior)):
            worst = max(worst, float(np.abs(x - y).max(initial=0.0)))
        for what, x, y in (("bsdf", sa.bsdf, sb.bsdf), ("edf", sa.edf, sb.edf)):
            if (x is None) != (y is None):
                return np.inf, f"one has no {what}"
            if x is None:
                continue
            if not np.array_equal(x.program.code, y.program.code):
                return np.inf, f"another {what} program"
            pa, pb = np.broadcast_arrays(x.program.P, y.program.P)
            worst = max(worst, float(np.abs(pa - pb).max(initial=0.0)))
    return worst, ""


_SIMPLE = (T.Scalar, T.Vector, T.Color, T.EnumType)


def _argument(p, n, rng):
    t = p.type
    if isinstance(t, T.EnumType):
        return t.values[int(rng.integers(len(t.values)))][1]
    if t == T.BOOL:
        return bool(rng.integers(2))
    if t == T.INT:
        return int(rng.integers(1, 5))
    width = T.width(t) if not isinstance(t, T.Scalar) else 1
    # constants: the state varies over the lanes (some Python versions take constants only)
    v = rng.uniform(0.1, 2.0, width)
    return float(v[0]) if width == 1 else tuple(float(x) for x in v)


def function_difference(module, name, loader_factory) -> tuple[float, str] | None:
    """Compare ``name`` of the listing's module with the workbench's ``functions::name``
    on random lanes; None when the library has no such function of the same signature."""
    from render.mdlc import run_function

    ours = module.functions(name)
    if len(ours) != 1 or not all(isinstance(p.type, _SIMPLE) for p in ours[0].params):
        return None
    loader = loader_factory()
    lib = [o for o in loader.load("::functions").functions(name)]
    o = ours[0]
    sig = [str(p.type).split("::")[-1] for p in o.params]
    if not any([str(p.type).split("::")[-1] for p in x.params] == sig for x in lib):
        return None
    if str(o.ret).split("::")[-1] not in {str(x.ret).split("::")[-1] for x in lib}:
        return None
    params = ", ".join(f"{p.type} {p.name}" for p in o.params)
    args = ", ".join(f"{p.name}: {p.name}" for p in o.params)
    wrapper = loader.load_text(
        f"mdl 1.7;\nimport ::functions::*;\nimport ::pw_curve::*;\n"
        f"export {lib[0].ret} call_it({params}) = functions::{name}({args});\n",
        "wrapper.mdl")
    rng = np.random.default_rng(11)
    worst = 0.0
    for s in _states():
        vals = [_argument(p, len(s), rng) for p in o.params]
        a = np.asarray(run_function(module, name, s, *vals), dtype=np.float64)
        try:
            b = np.asarray(run_function(wrapper, "call_it", s, *vals), dtype=np.float64)
        except ValueError as e:
            return np.inf, f"the Python version refuses {vals}: {e}"
        a, b = np.broadcast_arrays(a, b)
        if not (np.isfinite(a).all() and np.isfinite(b).all()):
            return np.inf, "not finite"
        worst = max(worst, float(np.abs(a - b).max(initial=0.0)))
    return worst, ""


def outcome(lst: Listing, every: list[Listing]) -> tuple[str, str]:
    """("same" | "runs" | "differs" | "fails", detail) for one listing."""
    from render.materials import MATERIALS
    from render.mdlc import make_loader
    from render.mdlc.compiler import module_code
    from render.mdlc.instance import Instantiator, MaterialInstanceError

    if lst.tree is None:
        return "fails", f"does not parse: {lst.error}"
    try:
        built = assemble(lst, every, make_loader)
    except MdlError as e:
        d = e.first
        return "fails", f"does not check: {d.message}"
    m = built.module
    try:
        module_code(m)
    except MdlError as e:
        return "fails", f"does not compile: {e.first.message}"
    twins = _twins()
    compared, worst, notes = 0, 0.0, []
    for o in m.materials():
        if o.name not in lst.names() or o.decl is None:
            continue
        if any(p.default is None for p in o.params):
            notes.append(f"{o.name} needs arguments")
            continue
        try:
            ours = Instantiator().call_overload(o, {}, m, o.decl)
        except MaterialInstanceError as e:
            return "fails", f"{o.name} cannot be built: {e.message}"
        twin = twins.get((lst.number, o.name)) or MATERIALS.get(o.name)
        if twin is None:
            notes.append(f"{o.name} has no Python version")
            continue
        d, why = shading_difference(ours, twin())
        if why or d > TOLERANCE:
            return "differs", f"{o.name}: {why or f'differs by {d:.3g}'}"
        compared += 1
        worst = max(worst, d)
    ran = 0
    for o in m.overloads:
        if o.name not in lst.names() or o.is_material or o.kind != "mdl" or o.decl is None:
            continue
        r = function_difference(m, o.name, make_loader)
        if r is None:
            if run_on_lanes(m, o):
                ran += 1
            continue
        d, why = r
        if why or d > 1e-9:
            return "differs", f"{o.name}: {why or f'differs by {d:.3g}'}"
        compared += 1
        worst = max(worst, d)
    if compared:
        return "same", f"{compared} compared, largest difference {worst:.2g}"
    if ran:
        notes.append(f"{ran} function{'s' if ran > 1 else ''} run on lanes (no Python "
                     "version of this signature)")
    return "runs", "; ".join(notes) or "checks and compiles"


def run_on_lanes(module, o) -> bool:
    """Run function ``o`` on the test states with generated arguments (numbers, vectors,
    colours, enums); False when its parameters are not of those types."""
    from render.mdlc import run_function

    if not all(isinstance(p.type, _SIMPLE) for p in o.params):
        return False
    rng = np.random.default_rng(5)
    for s in _states():  # it runs (generated arguments may leave its domain: no value check)
        run_function(module, o.name, s, *[_argument(p, len(s), rng) for p in o.params],
                     index=module.functions(o.name).index(o))
    return True


@pytest.fixture(scope="module")
def every():
    return listings()


@pytest.fixture(scope="module")
def outcomes(every):
    return {x.number: outcome(x, every) for x in every}


@needs_handbook
def test_the_listings_of_parts_2_to_5_are_found(every):
    assert len(every) == 175
    assert [x.number for x in every[:3]] == ["3.1", "3.2", "3.3"]
    assert every[-1].number == "15.22"


@needs_handbook
def test_each_listing_runs_and_matches_or_is_explained(outcomes):
    unexplained = {n: o for n, o in outcomes.items()
                   if o[0] in ("fails", "differs") and n not in NOT_RUN and n not in DIFFERS}
    assert not unexplained, unexplained
    stale = {n: outcomes[n] for n in (*NOT_RUN, *DIFFERS)
             if outcomes[n][0] in ("same", "runs")}
    assert not stale, f"these run now: update NOT_RUN/DIFFERS and docs/mdl.md: {stale}"


@needs_handbook
def test_the_weave_bump_differs_only_by_gamma(every):
    """Listing 13.13 with weave_depth.png read as linear data is the Python version."""
    import dataclasses

    linear = [dataclasses.replace(x, code=re.sub(
        r'texture_2d\("([^"]+)"\)', r'texture_2d("\1", tex::gamma_linear)', x.code))
        for x in every]
    target = next(x for x in linear if x.number == "13.13")
    assert outcome(target, linear)[0] == "same"


def report(outcomes) -> str:
    counts = {}
    for status, _ in outcomes.values():
        counts[status] = counts.get(status, 0) + 1
    lines = [f"{len(outcomes)} listings: " + ", ".join(f"{k} {v}" for k, v in
                                                     sorted(counts.items()))]
    for n, (status, detail) in outcomes.items():
        lines.append(f"{n:6s} {status:8s} {detail}")
    return "\n".join(lines)


if __name__ == "__main__":  # the table for docs/mdl.md
    import sys
    from pathlib import Path

    sys.path[:0] = [str(Path(__file__).resolve().parents[2] / "support")]
    if not HANDBOOK.is_file():
        raise SystemExit("the Handbook's text is absent")
    every_listing = listings()
    print(report({x.number: outcome(x, every_listing) for x in every_listing}))
