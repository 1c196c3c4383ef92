"""``pwc mdl check`` and ``pwc mdl info``: what an author sees for good modules (the
broken ones are tests/mdl/test_broken_modules.py)."""

from __future__ import annotations

from pwc.cli import main

GOOD = """\
mdl 1.6;
import ::df::*;
import ::anno::*;
import ::tex::*;

export enum finish [[ anno::description("how the stone is worked") ]] { honed, polished };

export float gloss(finish f = polished) = f == polished ? 0.1 : 0.4;

export material stone(
    color tint = color(0.7)
        [[ anno::display_name("Tint"), anno::hard_range(color(0.0), color(1.0)) ]],
    uniform finish f = honed)
[[ anno::description("A stone") ]]
= material(surface: material_surface(
    scattering: df::simple_glossy_bsdf(tint: tint, roughness_u: gloss(f))));

export color spot(float2 uv) = tex::lookup_color(texture_2d("no_such_image.png"), uv);
"""


def test_check_a_good_module(tmp_path, capsys):
    f = tmp_path / "stones.mdl"
    f.write_text(GOOD.replace("texture_2d(\"no_such_image.png\")", "texture_2d()"),
                 encoding="utf-8")
    assert main(["mdl", "check", str(f)]) == 0
    assert capsys.readouterr().err.strip() == f"{f}: ok (1 materials, 2 functions)"


def test_warnings_pass_unless_strict(tmp_path, capsys):
    f = tmp_path / "stones.mdl"
    f.write_text(GOOD, encoding="utf-8")
    assert main(["mdl", "check", str(f)]) == 0
    err = capsys.readouterr().err
    assert "warning: texture 'no_such_image.png' not found" in err and "1 warning" in err
    assert main(["mdl", "check", "--strict", str(f)]) == 1


def test_info_lists_exports_signatures_and_annotations(tmp_path, capsys):
    f = tmp_path / "stones.mdl"
    f.write_text(GOOD, encoding="utf-8")
    assert main(["mdl", "info", str(f)]) == 0
    out = capsys.readouterr().out
    assert out.startswith("module ::stones  (mdl 1.6)")
    assert "material stone(color tint = color(0.7), uniform stones::finish f = honed)" in out
    assert '[[ anno::description("A stone") ]]' in out
    assert 'tint: anno::display_name("Tint"), anno::hard_range((0.0, 0.0, 0.0), ' \
           '(1.0, 1.0, 1.0))' in out
    assert "float gloss(stones::finish f = polished)" in out
    assert "enum finish { honed = 0, polished = 1 }" in out


def test_info_of_the_workbenchs_modules(capsys):
    assert main(["mdl", "info", "::base"]) == 0
    out = capsys.readouterr().out
    assert "re-exported:" in out and "color sun_and_sky(uniform bool on = true" in out
    assert "texture_return file_texture(" in out
    assert main(["mdl", "info", "ornament_2"]) == 0  # a profile is a module
    assert "pw_curve::pw_point[34] ornament_2" in capsys.readouterr().out


def test_info_python_prints_the_generated_code(tmp_path, capsys):
    f = tmp_path / "stones.mdl"
    f.write_text(GOOD, encoding="utf-8")
    assert main(["mdl", "info", "--python", str(f)]) == 0
    out = capsys.readouterr().out
    assert "def f_gloss" in out


def test_missing_things_are_io_errors(tmp_path, capsys):
    assert main(["mdl", "check", str(tmp_path / "nothing.mdl")]) == 3
    assert "no such file" in capsys.readouterr().err
    assert main(["mdl", "info", "::no_such_module"]) == 3
    assert "no module ::no_such_module" in capsys.readouterr().err
