"""Scene files: parsing, located errors (file:line:col), transforms, geometry tables, and
``pwc render`` end to end (EXR + PNG)."""

from __future__ import annotations

import os

import numpy as np
import pytest
from repo import run_pwc

from pwc.cli import main
from render.film import read_exr
from render.integrator import render
from render.lights import ConstantEnvironment, PointLight, SpotLight
from render.scene import Scene, SceneError, load_scene, make_transform, parse_scene

STAGE = """\
[camera]
position = [0.0, 1.1, 3.6]
look_at = [0.0, 0.45, 0.0]
fov = 30.0

[render]
resolution = [32, 24]
spp = 2
seed = 5

[[lights]]
type = "quad"
center = [-2.0, 3.0, 2.0]
normal = [0.5, -0.7, -0.5]
size = [1.0, 1.0]
radiance = [5.0, 5.0, 5.0]

[[lights]]
type = "environment"
radiance = 0.1

[[objects]]
name = "square"
surface = "square"
translate = [-1.1, 0.0, 0.0]
material = "waves(distance: float2(0.02, 0.02), frequency: float2(10.0, 10.0), tint: color(0.6))"

[[objects]]
name = "sphere"
surface = { type = "sphere", radius = 0.5 }
translate = [0.6, 0.5, 0.0]
material = '''glossy(tint: color(0.6, 0.4, 0.0))'''
"""


def test_parse_stage_scene():
    scene = parse_scene(STAGE, "stage.toml")
    assert scene.camera.width == 32 and scene.camera.height == 24
    assert scene.settings.spp == 2 and scene.settings.seed == 5
    names = [o.name for o in scene.objects]
    assert names == ["square", "sphere", "quad_light0"]
    assert [type(light).__name__ for light in scene.lights] == ["ConstantEnvironment"]
    assert scene.objects[0].displacement is not None and scene.objects[1].displacement is None
    # the quad light faces its normal: axis_u x axis_v = normalized normal
    quad = scene.objects[2].surface
    assert np.allclose(quad.normal, np.array([0.5, -0.7, -0.5]) / np.linalg.norm([0.5, -0.7, -0.5]))


def test_only_displaced_objects_are_diced():
    scene = parse_scene(STAGE, "stage.toml")
    geo = scene.build()
    assert [s["diced"] for s in geo.stats] == [True, False, False]
    assert geo.triangle_count == len(geo.faces) == len(geo.face_object) == len(geo.face_normal)
    assert np.allclose(np.linalg.norm(geo.normals, axis=1), 1.0)
    assert np.allclose(np.linalg.norm(geo.face_normal, axis=1), 1.0)
    # geometric normals agree with the shading normals' side
    assert np.all(np.einsum("ij,ij->i", geo.face_normal, geo.normals[geo.faces].sum(axis=1)) > 0)


def test_overrides_and_defaults():
    scene = parse_scene(STAGE, "s.toml", overrides={"spp": 7, "seed": 1, "time": None})
    assert scene.settings.spp == 7 and scene.settings.seed == 1
    scene = parse_scene("[[objects]]\nsurface = 'square'\nmaterial = 'grid()'\n")
    assert scene.camera.width == 256 and scene.settings.max_depth == 8 and scene.lights == []


def test_lights_of_every_kind():
    text = (
        STAGE
        + """
[[lights]]
type = "point"
position = [0, 2, 0]
intensity = [1, 2, 3]

[[lights]]
type = "spot"
position = [0, 2, 0]
look_at = [0, 0, 0]
intensity = 4.0
cutoff_angle = 30.0

[[lights]]
type = "directional"
direction = [0, -1, 0]
irradiance = 2.0

[[lights]]
type = "sphere"
center = [0, 3, 0]
radius = 0.2
intensity = 3.0
"""
    )
    with pytest.raises(SceneError, match="at most one environment"):
        parse_scene(text + '\n[[lights]]\ntype = "environment"\n', "s.toml")
    scene = parse_scene(text, "s.toml")
    kinds = [type(light).__name__ for light in scene.lights]
    assert kinds == ["ConstantEnvironment", "PointLight", "SpotLight", "DirectionalLight"]
    assert isinstance(scene.lights[1], PointLight) and np.allclose(
        scene.lights[1].intensity, [1, 2, 3]
    )
    assert isinstance(scene.lights[2], SpotLight) and np.allclose(
        scene.lights[2].direction, [0, -1, 0]
    )
    assert isinstance(scene.lights[0], ConstantEnvironment)
    assert scene.objects[-1].name == "sphere_light5"
    film = render(scene, progress=False)
    assert np.all(np.isfinite(film.rgb())) and film.rgb().max() > 0


def _err(text: str) -> SceneError:
    with pytest.raises(SceneError) as info:
        parse_scene(text, "bad.toml")
    return info.value


def test_errors_name_file_line_and_column():
    # a misspelt material parameter: the column inside the TOML line
    e = _err(STAGE.replace("frequency: float2(10.0", "frequncy: float2(10.0"))
    line = (
        STAGE.splitlines().index(
            next(ln for ln in STAGE.splitlines() if ln.startswith('material = "waves'))
        )
        + 1
    )
    col = STAGE.splitlines()[line - 1].index("frequency") + 1
    assert (e.line, e.column) == (line, col)
    assert str(e).startswith(
        f"bad.toml:{line}:{col}: objects[0]: material: "
    ) and "frequency" in str(e)
    # inside a ''' literal string too
    e = _err(STAGE.replace("glossy(tint", "glosy(tint"))
    assert e.line == STAGE.count("\n", 0, STAGE.index("material = '''")) + 1
    assert e.column == len("material = '''") + 1 and "glossy" in e.message
    # TOML syntax
    e = _err("[camera]\nfov = \n")
    assert e.line == 2 and "TOML syntax error" in e.message
    # unknown keys with a suggestion, at their line
    e = _err("[camera]\nfov = 30\nlookat = [0, 0, 0]\n")
    assert (e.line, e.column) == (3, 1) and "did you mean 'look_at'" in e.message
    e = _err(STAGE.replace('surface = "square"', 'surface = "squar"'))
    assert "unknown surface 'squar'" in e.message and e.line > 0
    e = _err(STAGE.replace("radius = 0.5 }", "radius = -0.5 }"))
    assert "radius" in e.message
    e = _err(STAGE.replace('type = "quad"', 'type = "quadd"'))
    assert (
        "type must be one of" in e.message
        and e.line == STAGE.splitlines().index('type = "quad"') + 1
    )
    e = _err(STAGE.replace("resolution = [32, 24]", "resolution = [32, 0]"))
    assert "resolution" in e.message and e.line == 7
    e = _err(STAGE.replace("spp = 2", "spp = 0"))
    assert "spp must be a whole number >= 1" in e.message and e.line == 8
    e = _err(STAGE.replace("fov = 30.0", "fov = 180.0"))
    assert e.line == 4
    e = _err("[camera]\nposition = [0, 0]\n")
    assert "position must be 3 numbers" in e.message and e.line == 2
    e = _err('[[objects]]\nsurface = "square"\n')
    assert "missing material" in e.message and e.line == 1
    e = _err('[[objects]]\nsurface = "square"\nmesh = "x.obj"\nmaterial = "grid()"\n')
    assert "exactly one of" in e.message
    e = _err('[[objects]]\nmesh = "does_not_exist.obj"\nmaterial = "grid()"\n')
    assert "cannot load mesh" in e.message and e.line == 2
    e = _err("[render]\nspp = 1\n")
    assert "no [[objects]]" in e.message
    e = _err('[[objects]]\nsurface = "square"\nmaterial = "grid()"\nscale = 0\n')
    assert "scale must be non-zero" in e.message and e.line == 4
    with pytest.raises(SceneError, match="cannot read the scene file"):
        load_scene("/nonexistent/scene.toml")


def test_make_transform_order_and_extremes():
    m = make_transform(translate=(1, 2, 3), rotate=(90, 0, 0), scale=(2, 1, 1))
    # scale first (x doubled), then x-rotation (y -> z), then translation
    assert np.allclose(m @ [1, 0, 0, 1], [3, 2, 3, 1]) and np.allclose(
        m @ [0, 1, 0, 1], [1, 2, 4, 1]
    )
    tiny = make_transform(scale=1e-9)
    assert np.isclose(np.linalg.det(tiny[:3, :3]), 1e-27)
    for bad in ({"translate": (0, 0)}, {"rotate": (np.nan, 0, 0)}, {"scale": (1, 0, 1)}):
        with pytest.raises(ValueError):
            make_transform(**bad)


def test_environment_map_from_file(tmp_path):
    from render.film import Film
    from render.path import escaped
    from render.testing import light_tables

    sky = Film(8, 4)
    sky.add(
        np.arange(32),
        np.where((np.arange(32) < 8)[:, None], 2.0, 0.0) * np.ones((32, 3)),
        np.ones(32),
    )
    sky.write_exr(tmp_path / "sky.exr")
    text = STAGE.replace("radiance = 0.1", 'file = "sky.exr"\nscale = 0.5\nrotation = 10.0')
    (tmp_path / "s.toml").write_text(text)
    scene = load_scene(tmp_path / "s.toml")
    env = scene.lights[0]
    assert type(env).__name__ == "LatLongEnvironment"
    _, radiance = escaped(light_tables([env]), np.array([[0.0, 1.0, 0.0], [0.0, -1.0, 0.0]]))
    assert np.allclose(radiance, [[1.0] * 3, [0.0] * 3])
    e = _err(STAGE.replace("radiance = 0.1", 'file = "missing.exr"'))
    assert "cannot read environment" in e.message


def test_mesh_object_from_file(tmp_path):
    import trimesh

    box = trimesh.creation.box((1.0, 1.0, 1.0))
    box.export(tmp_path / "box.obj")
    text = """
[camera]
position = [2, 2, 3]
[render]
resolution = [16, 16]
spp = 1
[[lights]]
type = "environment"
[[objects]]
mesh = "box.obj"
material = "diffuse(tint: color(0.5))"
"""
    (tmp_path / "s.toml").write_text(text)
    scene = load_scene(tmp_path / "s.toml")
    geo = scene.build()
    assert geo.triangle_count == 12
    film = render(scene, progress=False, aovs=["object_id"])
    assert (film.aov("object_id") == 0).sum() > 20


def test_pwc_render_end_to_end(tmp_path, capsys):
    (tmp_path / "stage.toml").write_text(STAGE)
    exr, png = tmp_path / "out.exr", tmp_path / "out.png"
    status = main(
        [
            "render",
            str(tmp_path / "stage.toml"),
            "-o",
            str(exr),
            "--png",
            str(png),
            "--spp",
            "2",
            "--aov",
            "albedo,normal,depth,uv,object_id",
            "--seed",
            "3",
            "--quiet",
        ]
    )
    assert status == 0
    ch = read_exr(exr)
    assert ch["RGBA"].shape == (24, 32, 4)
    for name in ("albedo.R", "normal.X", "depth.Z", "uv.U", "object_id.id"):
        assert ch[name].shape == (24, 32)
    assert np.all(np.isfinite(ch["RGBA"])) and ch["RGBA"][..., 3].max() == 1.0
    from PIL import Image

    assert Image.open(png).size == (32, 24)
    # the same seed gives the same image through the CLI
    exr2 = tmp_path / "out2.exr"
    assert (
        main(
            [
                "render",
                str(tmp_path / "stage.toml"),
                "-o",
                str(exr2),
                "--spp",
                "2",
                "--seed",
                "3",
                "--quiet",
            ]
        )
        == 0
    )
    assert np.array_equal(read_exr(exr2)["RGBA"], ch["RGBA"])


def test_pwc_render_summary_names_objects_shaded_in_numpy(tmp_path, capsys):
    # a constant scene stays in the kernels; a varying material is named in the summary
    (tmp_path / "stage.toml").write_text(STAGE)
    assert main(["render", str(tmp_path / "stage.toml"), "-o", str(tmp_path / "a.exr")]) == 0
    summary = capsys.readouterr().err
    assert "Embree" in summary and "numpy" not in summary, summary


def test_pwc_render_errors_are_messages_not_tracebacks(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text(STAGE.replace("glossy(tint", "glosy(tint"))
    assert main(["render", str(bad), "-o", str(tmp_path / "x.exr"), "--quiet"]) == 1
    err = capsys.readouterr().err
    assert err.startswith(f"{bad}:") and "Traceback" not in err and "glossy" in err
    assert main(["render", str(bad), "-o", str(tmp_path / "x.png")]) == 2
    assert "must be an .exr" in capsys.readouterr().err
    assert main(["render", str(bad), "-o", str(tmp_path / "x.exr"), "--aov", "colour"]) == 2
    assert "unknown AOV 'colour'" in capsys.readouterr().err
    assert main(["render", str(tmp_path / "missing.toml"), "-o", str(tmp_path / "x.exr")]) == 3
    assert "cannot read the scene file" in capsys.readouterr().err


def test_python_api_render_from_path(tmp_path):
    (tmp_path / "stage.toml").write_text(STAGE)
    film = render(tmp_path / "stage.toml", spp=1, progress=False)
    assert film.rgb().shape == (24, 32, 3) and film.stats["spp"] == 1
    assert isinstance(load_scene(tmp_path / "stage.toml"), Scene)


# every kind of table a scene has, to put wrong values into
ALL_KINDS = STAGE + """
[[lights]]
type = "point"
position = [0.0, 2.0, 0.0]
intensity = 2.0

[[lights]]
type = "spot"
position = [0.0, 2.0, 0.0]
look_at = [0.0, 0.0, 0.0]
cutoff_angle = 30.0

[[lights]]
type = "directional"
direction = [0.0, -1.0, 0.0]

[[lights]]
type = "sphere"
center = [1.0, 2.0, 0.0]
radius = 0.2
intensity = 3.0

[[objects]]
surface = { type = "torus", major = 0.5, minor = 0.1 }
material = "diffuse()"
scale = [1.0, 1.0, 1.0]
resolution = [16, 8]
"""

WRONG_VALUES = [[], {}, "x", True, -1, 1e400, [[1]], ["a", "b", "c"]]


def _tables(data):
    for section, value in data.items():
        if isinstance(value, dict):
            yield section, None, value
        else:
            for i, t in enumerate(value):
                yield section, i, t


@pytest.mark.parametrize("wrong", WRONG_VALUES, ids=repr)
def test_any_wrong_value_is_a_scene_error_not_a_python_one(wrong):
    """Every key of every table, set to a value of the wrong type or range: the answer is
    a SceneError naming the file and line (or the scene parses), never another exception."""
    import tomllib

    data = tomllib.loads(ALL_KINDS)
    assert parse_scene(ALL_KINDS, "s.toml")
    tried = 0
    for section, i, table in list(_tables(data)):
        for key in list(table):
            case = tomllib.loads(ALL_KINDS)
            target = case[section] if i is None else case[section][i]
            target[key] = wrong
            text = _dumps(case)
            try:
                parse_scene(text, "s.toml")
            except SceneError as e:
                assert str(e).startswith("s.toml:"), str(e)
            tried += 1
    assert tried > 30
    # whole sections of the wrong kind
    for section, value in (("lights", {"type": "point"}), ("objects", 3), ("camera", [1]),
                           ("render", "fast"), ("lights", [1])):
        case = tomllib.loads(ALL_KINDS)
        case[section] = value
        with pytest.raises(SceneError):
            parse_scene(_dumps(case), "s.toml")


def _dumps(data) -> str:
    """A tiny TOML writer for the tests' dicts (tables, arrays of tables, values)."""
    import json

    def value(v):
        if isinstance(v, dict):
            return "{ " + ", ".join(f"{k} = {value(x)}" for k, x in v.items()) + " }"
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, float) and not np.isfinite(v):
            return "inf" if v > 0 else "-inf"
        if isinstance(v, list):
            return "[" + ", ".join(value(x) for x in v) + "]"
        return json.dumps(v)

    out = []
    for section, v in data.items():
        if isinstance(v, dict):
            out.append(f"[{section}]")
            out += [f"{k} = {value(x)}" for k, x in v.items()]
        elif isinstance(v, list) and all(isinstance(t, dict) for t in v) and v:
            for t in v:
                out.append(f"[[{section}]]")
                out += [f"{k} = {value(x)}" for k, x in t.items()]
        else:
            out.insert(0, f"{section} = {value(v)}")
    return "\n".join(out) + "\n"


def test_surface_keys_and_types_are_named_with_the_fix():
    e = _err(STAGE.replace("radius = 0.5 }", "radius = 0.5, resolution = [256, 128] }"))
    assert "objects[1]: unknown key 'resolution'; allowed: radius" in e.message
    assert "resolution belongs to the object" in e.message and "[[objects]]" in e.message
    assert e.line == STAGE.splitlines().index(
        'surface = { type = "sphere", radius = 0.5 }') + 1
    e = _err(STAGE.replace("radius = 0.5 }", "radus = 0.5 }"))
    assert "unknown key 'radus' (did you mean 'radius'?); allowed: radius" in e.message
    e = _err(STAGE.replace("radius = 0.5 }", 'radius = "big" }'))
    assert "surface 'sphere': radius must be a number, got 'big'" in e.message
    e = _err(STAGE.replace('{ type = "sphere", radius = 0.5 }',
                           '{ type = "plane", size = [1, 2, 3] }'))
    assert "size must be a list of 2 numbers, e.g. [1.0, 1.0]" in e.message
    e = _err(STAGE.replace('type = "quad"', "type = []"))
    assert "lights[0]: type must be one of" in e.message and "got []" in e.message
    e = _err(STAGE.replace("[camera]", "[[camera]]"))
    assert "[camera] must be a table" in e.message and e.line == 1
    e = _err('[lights]\ntype = "point"\nposition = [0, 1, 0]\n\n'
             '[[objects]]\nsurface = "square"\nmaterial = "diffuse()"\n')
    assert "lights must be tables, each under a [[lights]] line" in e.message
    assert e.line == 1


def _own_profile_scene(folder, profile_name="myprof"):
    folder.mkdir(parents=True, exist_ok=True)
    scene = folder / "own.toml"
    scene.write_text(STAGE.replace(
        "glossy(tint: color(0.6, 0.4, 0.0))",
        f"radial_pwc(pwc: {profile_name}::{profile_name}, surface_material: diffuse())"))
    return scene


def test_profiles_named_in_a_scene_are_searched_beside_it_first(tmp_path, monkeypatch):
    scene = _own_profile_scene(tmp_path / "scenes")
    with pytest.raises(SceneError, match="no profile 'myprof'"):
        load_scene(scene)
    (tmp_path / "scenes" / "myprof.pwc").write_text("0 0\n.1 .5 :sag .05\n0 1\n")
    assert load_scene(scene).objects[1].material is not None
    # --profiles / $PWC_PROFILE_PATH for a profile kept elsewhere
    other = tmp_path / "lib"
    other.mkdir()
    (tmp_path / "scenes" / "myprof.pwc").rename(other / "myprof.pwc")
    assert load_scene(scene, profile_dirs=[other]).objects[1].material is not None
    monkeypatch.setenv("PWC_PROFILE_PATH", f"/nonexistent{os.pathsep}{other}")
    assert load_scene(scene).objects[1].material is not None


def test_pwc_render_own_profile_outputs_checked_first_and_summary(tmp_path):
    """The command: a profile beside the scene, --profiles, a new output folder, the
    summary naming the PNG, no carriage-return progress in a log, and an unwritable
    output refused before a render that would take hours."""
    scene = _own_profile_scene(tmp_path / "s")
    (tmp_path / "s" / "myprof.pwc").write_text("0 0\n.1 .5 :sag .05\n0 1\n")
    out = tmp_path / "new" / "dir"
    r = run_pwc("render", scene, "-o", out / "a.exr", "--png", out / "a.png", "--spp", "1")
    assert r.returncode == 0, r.stderr
    assert (out / "a.exr").is_file() and (out / "a.png").is_file()
    assert f"wrote {out / 'a.exr'} and {out / 'a.png'}: 32x24, 1 spp" in r.stderr
    assert "\r" not in r.stderr and "Traceback" not in r.stderr
    from render.jit import cache_dir  # the render cached its kernels as the notice expects

    assert next(cache_dir().rglob("*.nbi"), None) is not None
    lib = tmp_path / "lib"
    lib.mkdir()
    (tmp_path / "s" / "myprof.pwc").rename(lib / "myprof.pwc")
    r = run_pwc("render", scene, "-o", out / "b.exr", "--spp", "1", "--quiet")
    assert r.returncode == 1 and "no profile 'myprof'" in r.stderr
    r = run_pwc("render", scene, "-o", out / "b.exr", "--spp", "1", "--profiles", lib)
    assert r.returncode == 0, r.stderr
    for bad, why in (("/proc/x.exr", "does not accept new files"),
                     (f"{scene}/x.exr", "own.toml is a file, not a folder")):
        r = run_pwc("render", scene, "-o", bad, "--spp", "1000000", "--profiles", lib,
                    timeout=120)
        assert r.returncode == 3 and why in r.stderr and "Traceback" not in r.stderr
        assert len(r.stderr.strip().splitlines()) == 1
    r = run_pwc("render", tmp_path / "missing.toml", "-o", out / "c.exr")
    assert r.returncode == 3 and "cannot read the scene file" in r.stderr


def test_a_scene_of_parametric_surfaces_loads_and_builds_without_trimesh():
    """trimesh takes 0.45 s to import, a third of a cached start (docs/render.md#speed):
    a bundled scene of a displaced plane and a quad light is read and built for Embree
    without it."""
    import subprocess
    import sys

    from repo import checkout_env

    code = ("import sys\n"
            "from render.library.resources import bundled_scenes\n"
            "from render.scene import load_scene\n"
            "scene = load_scene(bundled_scenes() / 'fig_14_28.toml')\n"
            "scene.build()\n"
            "print(sorted(m for m in sys.modules if m.split('.')[0] == 'trimesh'))\n")
    r = subprocess.run([sys.executable, "-c", code], env=checkout_env(), capture_output=True,
                       text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    assert r.stdout.strip().splitlines()[-1] == "[]"


def test_first_compile_notice_only_on_a_cold_cache_once_per_process(tmp_path, monkeypatch,
                                                                   capsys):
    from render.jit import cache_dir
    from render.precompile import READY, first_compile, notice_first_compile

    monkeypatch.setenv("PWC_CACHE_DIR", str(tmp_path))
    assert notice_first_compile("pwc render", quiet=True) is True
    assert capsys.readouterr().err == ""
    assert notice_first_compile("pwc render") is True
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "compiling render kernels, once per machine" in err
    assert notice_first_compile("pwc") is True  # said once per process, whoever asks
    assert capsys.readouterr().err == ""
    # kernels in the cache are not enough: a render must have run to its end
    (cache_dir() / "path").mkdir(parents=True)
    (cache_dir() / "path" / "trace-12.py311.nbi").write_bytes(b"")
    assert notice_first_compile("pwc render") is True
    (cache_dir() / READY).write_bytes(b"")
    assert notice_first_compile("pwc render") is False
    with first_compile() as compiling:  # ready: no turn taken, nothing compiled
        assert compiling is False
    assert not (cache_dir() / "compile.lock").exists()


def _twice(x):
    return 2.0 * x


def test_on_a_ready_cache_a_render_that_compiles_says_so_once(tmp_path, monkeypatch, capsys):
    """A kernel only some scenes call compiles on its first use (docs/render.md,
    "Start-up"): on a ready cache the notice waits for numba's compile event, from a
    kernel of the workbench's, and is said once per process; loading says nothing."""
    import numba
    from numba.core import event

    from render import precompile
    from render.jit import cache_dir, instantiate

    monkeypatch.setenv("PWC_CACHE_DIR", str(tmp_path))
    cache_dir().mkdir(parents=True)
    (cache_dir() / precompile.READY).write_bytes(b"")
    monkeypatch.setattr(precompile, "_said", set())
    try:
        assert precompile.notice_first_compile("pwc render") is False
        assert capsys.readouterr().err == ""
        numba.njit(_twice)(1.0)  # not the workbench's: compiled, not said
        assert capsys.readouterr().err == ""
        assert instantiate(_twice, "render._probe_notice")(2.0) == 4.0  # compiles: said
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "compiling the render kernels this scene needs" in err
        assert instantiate(_twice, "render._probe_notice")(3.0) == 6.0  # said once
        assert capsys.readouterr().err == ""
    finally:  # the rest of the test process compiles unannounced, as before
        if precompile._compile_notice.registered:
            event.unregister("numba:compile", precompile._compile_notice)
            precompile._compile_notice.registered = False


def test_a_cache_folder_that_cannot_be_made_takes_no_turn(tmp_path, monkeypatch):
    from render.precompile import first_compile, kernels_ready, notice_first_compile

    (tmp_path / "file").write_text("not a folder")
    monkeypatch.setenv("PWC_CACHE_DIR", str(tmp_path / "file"))
    assert notice_first_compile("pwc render", quiet=True) is True
    with first_compile() as compiling:  # numba caches elsewhere, or not at all
        assert compiling is False
    assert not kernels_ready()


def test_pwc_render_a_bundled_scene_by_name_from_anywhere(tmp_path):
    r = run_pwc("render", "fig_14_28", "-o", "x.exr", "--spp", "1", "--resolution", "8", "6",
                cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert read_exr(tmp_path / "x.exr")["RGBA"].shape == (6, 8, 4)
    r = run_pwc("render", "fig_14_99", "-o", "x.exr", cwd=tmp_path)
    assert r.returncode == 3 and "cannot read the scene file" in r.stderr
