"""Issue 16b's expressions through the one MDL front end, in scene expressions and in MDL
modules: ``df::measured_edf`` over ``light_profile("f.ies")`` (a resource found beside the
module that names it, then beside the scene; a missing or malformed file a located error),
``float3x3`` values reaching a df's ``global_frame`` as the rows ``M[i][j]`` of MDL's
column-major constructor, ``df::fog_vdf`` and ``material_volume.emission_intensity``."""

from __future__ import annotations

import numpy as np
import pytest

from mdl.diagnostics import MdlError
from render import df as rdf
from render.expr import MaterialExprError, parse_material
from render.mdlc import make_loader, material_from_call

DEG = np.arange(0.0, 90.5, 1.0)
BAD = "IESNA:LM-63-2002\nTILT=NONE\n1 -1 1 2 1 1 2 0 0 0\n1 1 0\n0 90\n0\n100 x\n"
#: MDL's float3x3(col0, col1, col2), and the rows the df receives
FRAME = "float3x3(float3(1, 0, 0), float3(0, 0, 1), float3(0, -1, 0))"
ROWS = [[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]]
LAMP = ('df::measured_edf(profile: light_profile("lamp.ies"), multiplier: 2.0, '
        f'global_frame: {FRAME})')
FOG = ("material_volume(scattering: df::fog_vdf(particle_size: 3.0), scattering_coefficient: "
       "color(0.5), emission_intensity: color(0.1, 0.2, 0.3))")


@pytest.fixture(scope="module")
def module(tmp_path_factory):
    """A module using issue 16b's expressions, with an IES file beside it."""
    d = tmp_path_factory.mktemp("issue16b_module")
    rdf.write_ies(d / "lamp.ies", DEG, [0.0], 100.0 * np.cos(np.radians(DEG))[None, :])
    (d / "bad.ies").write_text(BAD, encoding="utf-8")
    lines = ["mdl 1.7;", "import ::df::*;", "",
             "export material lamp() = material(surface: material_surface(emission: "
             f"material_emission({LAMP}, color(5.0))));",
             "export material framed(uniform float3x3 f = float3x3(1.0)) = material(surface: "
             "material_surface(emission: material_emission(df::spot_edf(1.0, "
             "global_frame: f))));",
             f"export material fog() = material(volume: {FOG});",
             "export material missing() = material(surface: material_surface(emission: ",
             '    material_emission(df::measured_edf(light_profile("lamb.ies")))));',
             "export material malformed() = material(surface: material_surface(emission: ",
             '    material_emission(df::measured_edf(light_profile("bad.ies")))));']
    (d / "issue16b.mdl").write_text("\n".join(lines) + "\n", encoding="utf-8")
    return d


def test_the_df_module_declares_fog_vdf_and_measured_edf():
    df = make_loader().load("::df")
    kinds = {o.name: str(o.ret) for o in df.overloads}
    assert kinds["fog_vdf"] == "vdf" and kinds["measured_edf"] == "edf"
    profile = next(o for o in df.overloads if o.name == "measured_edf").params[0]
    assert (profile.name, str(profile.type)) == ("profile", "light_profile")


def test_a_module_lamp_is_the_scene_expression(module, tmp_path):
    m, _ = material_from_call("lamp()", "issue16b.mdl", base_dir=tmp_path, mdl_paths=[module])
    edf = m.surface.emission.emission
    assert edf.name == "measured_edf" and isinstance(edf.kwargs["profile"], rdf.LightProfile)
    assert np.array_equal(np.asarray(edf.kwargs["global_frame"]), ROWS)
    # the same file read once (cached by path and mtime): the same df tree
    want = parse_material("material(surface: material_surface(emission: material_emission("
                          f"{LAMP}, color(5.0))))", base_dir=module).surface.emission.emission
    assert edf.kwargs["profile"] is want.kwargs["profile"]
    assert repr(edf) == repr(want) and "candela" not in repr(edf)


@pytest.mark.parametrize("text", ["float3x3(1, 2, 3, 4, 5, 6, 7, 8, 9)",
                                  "float3x3(float3(1, 2, 3), float3(4, 5, 6), float3(7, 8, 9))"])
def test_float3x3_arguments_of_a_module_material_are_rows(module, tmp_path, text):
    m, _ = material_from_call(f"framed(f: {text})", "issue16b.mdl", base_dir=tmp_path,
                              mdl_paths=[module])
    frame = np.asarray(m.surface.emission.emission.kwargs["global_frame"])
    assert np.array_equal(frame, [[1, 4, 7], [2, 5, 8], [3, 6, 9.0]])


def test_fog_and_emission_intensity_in_a_module_and_a_scene(module, tmp_path):
    m, _ = material_from_call("fog()", "issue16b.mdl", base_dir=tmp_path, mdl_paths=[module])
    want = parse_material(f"material(volume: {FOG})").volume
    assert repr(m.volume) == repr(want)  # df nodes compare by identity
    assert m.volume.scattering.name == "fog_vdf"
    assert np.allclose(m.volume.emission_intensity, (0.1, 0.2, 0.3))
    assert parse_material("material()").volume.emission_intensity == (0.0, 0.0, 0.0)


def test_a_profile_beside_the_scene(module, tmp_path):
    rdf.write_ies(tmp_path / "scene.ies", DEG, [0.0], 50.0 * np.ones((1, DEG.size)))
    m, _ = material_from_call('measured_edf(light_profile("scene.ies"), global_distribution: '
                              'false)', base_dir=tmp_path)
    assert m.kwargs["profile"].name == str(tmp_path / "scene.ies")


def test_a_missing_profile_is_located_in_the_module(module, tmp_path):
    with pytest.raises(MdlError) as e:
        material_from_call("missing()", "issue16b.mdl", base_dir=tmp_path, mdl_paths=[module],
                           source_name="scene.toml", line=3, col=12)
    d = e.value.diagnostics[0]
    text = d.format()
    assert str(module / "issue16b.mdl") in text and "no file 'lamb.ies'" in text
    assert str(module) in text and str(tmp_path) in text  # the folders searched
    assert "did you mean 'lamp.ies'?" in text and "Traceback" not in text
    lines = (module / "issue16b.mdl").read_text(encoding="utf-8").splitlines()
    line = next(k for k, x in enumerate(lines, 1) if "lamb.ies" in x)
    assert (d.loc.line, d.loc.col) == (line, lines[line - 1].index('"lamb') + 1)


def test_a_malformed_profile_says_what_is_wrong(module, tmp_path):
    with pytest.raises(MdlError) as e:
        material_from_call("malformed()", "issue16b.mdl", base_dir=tmp_path,
                           mdl_paths=[module])
    text = e.value.diagnostics[0].format()
    assert "bad.ies:7: candela value 2" in text and "is not a number" in text
    with pytest.raises(MaterialExprError) as e:
        parse_material('material(surface: material_surface(emission: material_emission('
                       'df::measured_edf(light_profile("bad.ies")))))', base_dir=module)
    assert "bad.ies:7: candela value 2" in str(e.value)


# --- df::light_profile_power / _maximum / _isvalid, df::bsdf_measurement_isvalid ---------
def test_profile_power_is_the_integral_over_the_sphere(tmp_path):
    """Power is ``∫ I dw`` of the interpolant the kernels evaluate, whole sphere: closed
    forms for a constant and for an intensity linear in gamma; maximum the largest."""
    iso = rdf.LightProfile(np.array([0.0, 90.0, 180.0]), np.array([0.0]),
                           np.full((1, 3), 100.0))
    assert iso.power == pytest.approx(400.0 * np.pi, rel=1e-12) and iso.maximum == 100.0
    # 200 (1 - gamma / 90 deg) below the horizon: 2 pi * 200 (1 - 2/pi) = 400 pi - 800
    gam = np.linspace(0.0, 90.0, 7)
    lin = rdf.LightProfile(gam, np.array([0.0, 90.0]), np.tile(200.0 * (1 - gam / 90.0), (2, 1)))
    assert lin.power == pytest.approx(400.0 * np.pi - 800.0, rel=1e-12)
    assert lin.maximum == 200.0
    # a quarter-symmetric file expands to the full circle: the same power as written out
    # (cos sampled every degree: the interpolant's integral within 1e-4 of cos's)
    rdf.write_ies(tmp_path / "q.ies", DEG, [0.0, 45.0, 90.0],
                  np.vstack([100.0 * np.cos(np.radians(DEG))] * 3))
    q = rdf.read_ies(tmp_path / "q.ies")
    assert q.power == pytest.approx(2.0 * np.pi * 100.0 * 0.5, rel=1e-4)  # ∫ cos sin = 1/2


QUERIES = """\
mdl 1.6;
import ::df::*;

export float power() = df::light_profile_power(light_profile("lamp.ies"));
export float maximum() = df::light_profile_maximum(light_profile("lamp.ies"));
export bool valid() = df::light_profile_isvalid(light_profile("lamp.ies"));
export bool missing_valid() = df::light_profile_isvalid(light_profile("none.ies"));
export float missing_power() = df::light_profile_power(light_profile("none.ies"));
export bool no_measurement() = df::bsdf_measurement_isvalid(bsdf_measurement("none.mbsdf"));

export material normalised_lamp() = material(surface: material_surface(emission:
    material_emission(df::measured_edf(light_profile("lamp.ies")),
        color(1000.0 / df::light_profile_power(light_profile("lamp.ies"))))));
"""


def test_the_resource_queries_of_df_in_functions_and_materials(module, tmp_path):
    """In functions, a missing resource is MDL's invalid one (isvalid false, power 0); in a
    material's expression the queries' values reach the material."""
    from displacement.surfaces import UnitSquare
    from render.mdlc import run_function

    (module / "queries.mdl").write_text(QUERIES, encoding="utf-8")
    m = make_loader(module).load_file(module / "queries.mdl")
    lamp = rdf.read_ies(module / "lamp.ies")
    s = UnitSquare().state_at_uv(np.full((3, 2), 0.5))
    assert np.allclose(run_function(m, "power", s), lamp.power)
    assert lamp.power == pytest.approx(100.0 * np.pi, rel=1e-4)  # 2 pi * 100 * 1/2
    assert np.allclose(run_function(m, "maximum", s), 100.0)
    assert run_function(m, "valid", s).all()
    assert not run_function(m, "missing_valid", s).any()
    assert np.all(run_function(m, "missing_power", s) == 0.0)
    assert not run_function(m, "no_measurement", s).any()
    mat, _ = material_from_call("normalised_lamp()", "queries.mdl", base_dir=tmp_path,
                                mdl_paths=[module])
    assert np.allclose(mat.surface.emission.intensity, 1000.0 / lamp.power)


def test_profile_power_at_the_extremes():
    """A black profile has power and maximum 0; 1e30 and 1e-300 candela stay finite and
    exact (2 pi I over the lower hemisphere)."""
    black = rdf.LightProfile(np.array([0.0, 180.0]), np.array([0.0]), np.zeros((1, 2)))
    assert (black.power, black.maximum) == (0.0, 0.0)
    for i in (1e30, 1e-300):
        p = rdf.LightProfile(np.array([0.0, 90.0]), np.array([0.0]), np.full((1, 2), i))
        assert np.isfinite(p.power) and p.power == pytest.approx(2.0 * np.pi * i, rel=1e-12)
