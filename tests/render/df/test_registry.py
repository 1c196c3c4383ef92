"""The registry of dfs (:mod:`render.df._registry`): every fact declared once, in the df's
module, and everything else derived from it.

* the derived facts: opcodes, signatures, overloads, the sets the integrator and
  ``thin_film`` use, the generated dispatch, the kernels the second process compiles;
* no df named by a string in the render core outside :mod:`render.df`;
* adding a df is one module: a module outside the package, on ``$PWC_DF_PATH``, is
  registered, declared in MDL's ``::df``, and renders (the same image as the package's
  ``diffuse_reflection_bsdf``, whose Lambertian lobe it copies).
"""

from __future__ import annotations

import ast
import json
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
from repo import ROOT, checkout_env

from render.df._registry import PHASES, Node, dispatch_source, registry
from render.df._signature import Param, Signature


def test_opcodes_are_the_nodes_places_in_the_registry():
    reg = registry()
    assert [n.op for n in reg.nodes] == list(range(1, len(reg.nodes) + 1))
    assert len({n.name for n in reg.nodes}) == len(reg.nodes)
    for key, d in reg.dfs.items():
        assert d.key == key
        for node in d.nodes:
            assert reg.nodes[node.op - 1] is node


def test_every_kernel_takes_its_phases_arguments():
    # the generated dispatch passes P, row, b, flags, the phase's own arguments and, for
    # a kernel with two more parameters, its node table
    for node in registry().nodes:
        for phase, kernel in node.kernels.items():
            n = len(ast.parse(f"f({PHASES[phase][1]})").body[0].value.args)
            params = len(kernel.py_func.__code__.co_varnames[:kernel.py_func.__code__.co_argcount])
            assert params in (4 + n, 6 + n), (node.name, phase, params)
            assert node.takes_table(phase) == (params == 6 + n)


def test_the_dispatch_has_a_branch_for_every_kernel():
    source = dispatch_source(registry())
    compile(source, "dispatch", "exec")
    for op, node in enumerate(registry().nodes, start=1):
        for phase in node.kernels:
            assert f"k{op}_{phase} = " in source, (node.name, phase)


def test_a_node_declares_only_the_phases_of_its_role():
    sig = Signature("bsdf", (Param("tint", "color", (1.0, 1.0, 1.0)),))
    with pytest.raises(ValueError, match="a leaf has no phase 'scale'"):
        Node("x", "bsdf", "leaf", sig, scale=None)
    with pytest.raises(ValueError, match="role must be one of"):
        Node("x", "bsdf", "lobe", sig)
    with pytest.raises(ValueError, match="kind must be bsdf, edf or vdf"):
        Node("x", "light", "leaf", sig)


def test_the_material_layer_knows_exactly_the_declared_dfs():
    from render.material import DF_SIGNATURES, MDL_NAMES, OVERLOADS

    assert set(DF_SIGNATURES) == set(registry().dfs)
    # the Python constructors' overloads; fresnel_layer's of MDL before 1.4 is deprecated
    # and only the MDL front end chooses it (by its colour ior)
    assert OVERLOADS == {"tint": ("tint", "tint_rt", "tint_edf", "tint_vdf"),
                         "directional_factor": ("directional_factor",
                                                "directional_factor_edf")}
    assert MDL_NAMES["fresnel_layer_before_1_4"] == "fresnel_layer"
    assert MDL_NAMES["tint_rt"] == "tint"


def test_the_capabilities_come_from_the_signatures_and_lobes():
    dfs = registry().dfs
    reads = {k for k, d in dfs.items() if d.reads_outside_ior}
    # issue 32: the four microfacet dfs read the IOR outside (they were left off a list)
    assert {"specular_bsdf", "simple_glossy_bsdf", "microfacet_ggx_smith_bsdf",
            "microfacet_beckmann_smith_bsdf", "microfacet_ggx_vcavities_bsdf",
            "microfacet_beckmann_vcavities_bsdf", "fresnel_layer", "color_fresnel_layer",
            "fresnel_layer_before_1_4", "custom_curve_layer", "color_custom_curve_layer",
            "fresnel_factor",
            "directional_factor", "coat_absorption_factor"} == reads
    assert {k for k, d in dfs.items() if d.lambertian} == {"diffuse_edf"}
    assert dfs["specular_bsdf"].delta_in("scatter_transmit")
    assert not dfs["simple_glossy_bsdf"].delta_in("scatter_transmit")
    assert not dfs["specular_bsdf"].transmits_in("scatter_reflect")
    film = {n.name for n in registry().nodes if n.film >= 0}
    assert film == {"fresnel_layer", "fresnel_factor", "custom_curve_layer",
                    "directional_factor", "specular_bsdf", "simple_glossy_bsdf",
                    "microfacet_ggx_smith_bsdf", "microfacet_beckmann_smith_bsdf",
                    "microfacet_ggx_vcavities_bsdf", "microfacet_beckmann_vcavities_bsdf"}
    assert {n.name for n in registry().nodes if n.object_to_local >= 0} == {
        "spot_edf", "measured_edf"}


def test_the_second_process_compiles_every_declared_kernel():
    from render.precompile import df_kernels

    declared = {id(k) for n in registry().nodes for k in n.kernels.values()}
    assert {id(k) for k in df_kernels()} == declared


def _df_names_compared(path: Path, names: set):
    """The strings of a module that name a df where code tests for one: in a comparison
    (``node.name == "specular_bsdf"``, ``name in ("fresnel_layer", ...)``) or in a
    collection assigned at module level (a list of names kept by hand)."""
    tree = ast.parse(path.read_text())
    spots = [n for n in ast.walk(tree) if isinstance(n, ast.Compare)]
    spots += [n.value for n in tree.body if isinstance(n, ast.Assign | ast.AnnAssign)
              and isinstance(n.value, ast.Tuple | ast.List | ast.Set | ast.Dict)]
    for spot in spots:
        for n in ast.walk(spot):
            if isinstance(n, ast.Constant) and n.value in names:
                yield n.lineno, n.value


def test_no_df_is_named_by_a_string_in_the_render_core():
    # the integrator, the scene, the programs and the MDL runtime ask the registry; the
    # Handbook's materials (render/materials) call dfs by name as users do
    names = {k for k, d in registry().dfs.items() if not d.struct}
    found = []
    for path in sorted((ROOT / "render").rglob("*.py")):
        rel = path.relative_to(ROOT / "render")
        if rel.parts[0] in ("df", "materials"):
            continue
        found += [f"render/{rel}:{line}: {s!r}" for line, s in _df_names_compared(path, names)]
    assert found == [], "ask render.df._registry instead of naming a df:\n" + "\n".join(found)


def test_a_broken_module_on_the_df_path_is_named_with_its_line(tmp_path):
    # every pwc command reports it in one line, without a traceback
    (tmp_path / "broken_bsdf.py").write_text("from render.df._registry import Node\n\n"
                                             "NODE = Node('broken_bsdf', 'bsdf', 'leaf')\n")
    env = checkout_env()
    env["PWC_DF_PATH"] = str(tmp_path)
    r = subprocess.run([sys.executable, "-m", "pwc", "render", "fig_14_28", "-o", "x.exr"],
                       env=env, capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert r.returncode == 2, r.stderr[-2000:]
    assert "Traceback" not in r.stderr
    assert r.stderr.strip() == (
        f"pwc: error: {tmp_path / 'broken_bsdf.py'}, line 3: the df module on $PWC_DF_PATH "
        "does not load (TypeError: Node.__init__() missing 1 required positional argument: "
        "'signature'); fix it, or take its folder off $PWC_DF_PATH")


_TOY = '''\
"""df::toy_lambert_bsdf: a Lambertian lobe, in one module outside the package."""

from render.bsdf import Lobe
from render.df import _kernel_common as kc
from render.df._registry import Df, Node
from render.df._signature import Param, Signature
from render.jit import njit

SIGNATURE = Signature("bsdf", (
    Param("tint", "color", (1.0, 1.0, 1.0), clamp=(0.0, 1.0)),
    Param("handle", "string", "", uniform=True),
))
_TINT = SIGNATURE.offset("tint")


@njit
def eval_pdf(P, row, b, flags, wox, woy, woz, wix, wiy, wiz):
    flip, woz = kc.orient(woz)
    wiz = kc.mirror_z(wiz, flip)
    if not (woz > kc.COS_ZERO and wiz > kc.COS_ZERO):
        return 0.0, 0.0, 0.0, 0.0
    pdf = wiz * kc.INV_PI
    return P[row, b + _TINT] * pdf, P[row, b + _TINT + 1] * pdf, P[row, b + _TINT + 2] * pdf, pdf


@njit
def sample(P, row, b, flags, wox, woy, woz, u1, u2x, u2y):
    flip, woz = kc.orient(woz)
    wix, wiy, wiz = kc.cosine_hemisphere(kc.clamp_u(u2x), kc.clamp_u(u2y))
    if not (woz > kc.COS_ZERO and wiz > kc.COS_ZERO):
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0
    return (wix, wiy, kc.mirror_z(wiz, flip), wiz * kc.INV_PI, P[row, b + _TINT],
            P[row, b + _TINT + 1], P[row, b + _TINT + 2], kc.LOBE_DIFFUSE_REFLECTION)


@njit
def albedo(P, row, b, flags, wox, woy, woz):
    if not abs(woz) > kc.COS_ZERO:
        return 0.0, 0.0, 0.0
    return P[row, b + _TINT], P[row, b + _TINT + 1], P[row, b + _TINT + 2]


NODE = Node("toy_lambert_bsdf", "bsdf", "leaf", SIGNATURE, eval_pdf=eval_pdf, sample=sample,
            albedo=albedo)
DF = Df("toy_lambert_bsdf", SIGNATURE, (NODE,), lobes=Lobe.DIFFUSE_REFLECTION)
ToyLambertBsdf = DF.cls
'''

_RENDER = textwrap.dedent('''\
    import json
    import numpy as np
    from displacement.surfaces import Plane, UVSphere
    from render import material as M
    from render.camera import Camera
    from render.df._registry import registry
    from render.integrator import render
    from render.lights import ConstantEnvironment
    from render.mdlc.natives import df_module_text
    from render.scene import RenderSettings, Scene, SceneObject, make_transform

    def image(df):
        mat = M.material(surface=M.material_surface(df))
        floor = SceneObject(Plane(size=(4.0, 4.0), origin=(-2.0, 0.0, 2.0), axis_u=(1, 0, 0),
                                  axis_v=(0, 0, -1)), mat, name="floor")
        ball = SceneObject(UVSphere(), mat, make_transform(translate=(0, 0.5, 0),
                                                           scale=0.5), name="ball")
        cam = Camera(position=(0.0, 1.2, 3.0), look_at=(0.0, 0.4, 0.0), width=32, height=32)
        scene = Scene(cam, [floor, ball], [ConstantEnvironment(1.0)],
                      RenderSettings(32, 32, spp=16, max_depth=4, seed=3))
        return render(scene, progress=False).rgb()

    toy = image(M.df.toy_lambert_bsdf(tint=(0.7, 0.5, 0.3)))
    ref = image(M.df.diffuse_reflection_bsdf(tint=(0.7, 0.5, 0.3)))
    declared = registry().df("toy_lambert_bsdf")
    import render.df
    print(json.dumps({
        "op": declared.nodes[0].op, "nodes": len(registry().nodes),
        "class": render.df.toy_lambert_bsdf is declared.cls,
        "mdl": "export bsdf toy_lambert_bsdf(" in df_module_text(),
        "finite": bool(np.all(np.isfinite(toy))), "mean": float(toy.mean()),
        "max_diff": float(np.abs(toy - ref).max())}))
''')


@pytest.mark.slow
def test_a_df_from_one_module_outside_the_package_renders(tmp_path):
    # its own kernel cache: the module's source is part of the key (render.jit)
    folder = tmp_path / "dfs"
    folder.mkdir()
    (folder / "toy_lambert_bsdf.py").write_text(_TOY)
    env = checkout_env()
    env["PWC_DF_PATH"] = str(folder)
    r = subprocess.run([sys.executable, "-c", _RENDER], env=env, capture_output=True,
                       text=True, timeout=1500, cwd=tmp_path)
    assert r.returncode == 0, r.stderr[-3000:]
    got = json.loads(r.stdout.strip().splitlines()[-1])
    assert got["nodes"] == len(registry().nodes) + 1  # the package's, and the new one
    assert got["op"] == got["nodes"]  # the df path's modules come after the package's
    assert got["class"] and got["mdl"] and got["finite"]
    assert got["mean"] > 0.05
    # the same lobe as diffuse_reflection_bsdf at roughness 0: the same image
    assert got["max_diff"] < 1e-6 * max(got["mean"], 1.0), got
