"""The ``pwc`` command as a user runs it: real subprocesses, exit codes, no tracebacks."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest
from repo import PROFILES, PWC, ROOT, checkout_env

from pwc import load as lib_load
from pwc.emit import from_json, from_npz

SEGMENTS = "0 0\n.7 0\n.7 .4\n3/7 .4\n3/7 4/3\n4/7 1\n"


#: this checkout first on the path, whatever the current folder of the command
ENV = checkout_env()


def pwc(*args, cwd=None, stdin=None) -> subprocess.CompletedProcess:
    return subprocess.run([*PWC, *map(str, args)], cwd=cwd, env=checkout_env(),
                          capture_output=True, input=stdin, timeout=120)


@pytest.fixture
def seg(tmp_path) -> Path:
    p = tmp_path / "segments.pwc"
    p.write_text(SEGMENTS)
    return p


def _clean(r):
    assert b"Traceback" not in r.stderr and b"Traceback" not in r.stdout, r.stderr.decode()


@pytest.mark.parametrize("command", [[], ["compile"], ["check"], ["info"]])
def test_help_everywhere(command):
    r = pwc(*command, "--help")
    assert r.returncode == 0 and b"usage: pwc" in r.stdout


def test_compile_mdl_writes_the_module_and_the_runtime(seg, tmp_path):
    out = tmp_path / "out"
    r = pwc("compile", seg, "-o", out.as_posix() + "/", cwd=tmp_path)  # a new directory
    _clean(r)
    assert r.returncode == 0, r.stderr
    assert b"segments.pwc -> " in r.stderr and b"(6 pw_points, length 2.00056)" in r.stderr
    text = (out / "segments.mdl").read_text()
    assert "export const float segments_length = 2.00056333;" in text
    assert "export const pw_curve::pw_point[6] segments(" in text
    assert "float2(0.321428571, 1.0)" in text
    assert "export struct pw_point" in (out / "pw_curve.mdl").read_text()


@pytest.mark.parametrize("fmt", ["json", "npz", "svg", "png"])
def test_compile_formats(seg, tmp_path, fmt):
    target = tmp_path / f"x.{fmt}"
    r = pwc("compile", seg, "--format", fmt, "-o", target)
    assert r.returncode == 0, r.stderr
    data = target.read_bytes()
    if fmt == "json":
        c = from_json(data.decode())
        assert c.length == pytest.approx(2.0005633, abs=1e-7) and c.n == 6
    elif fmt == "npz":
        assert from_npz(data).t[1] == pytest.approx(0.26243, abs=5e-6)
    elif fmt == "svg":
        assert data.startswith(b"<svg") and data.count(b"<circle") == 6
    else:
        assert data.startswith(b"\x89PNG")


def test_stdout_and_no_normalize(seg):
    r = pwc("compile", seg, "-f", "json", "--no-normalize", "-o", "-")
    doc = json.loads(r.stdout)
    assert doc["format"] == "pwc-json/1" and doc["scale"] == 1.0
    assert doc["points"][4]["pt"] == pytest.approx([3 / 7, 4 / 3])
    assert doc["points"][4]["line"] == 5 and doc["points"][4]["text"] == "3/7 4/3"


def test_several_files_need_a_directory(seg, tmp_path):
    other = tmp_path / "other.pwc"
    other.write_text("0 0\n1 1 :angle 90\n")
    r = pwc("compile", seg, other, "-f", "json", "-o", tmp_path / "nope.json")
    _clean(r)
    assert r.returncode == 2 and b"existing directory" in r.stderr
    r = pwc("compile", seg, other, "-f", "json", cwd=tmp_path)
    assert r.returncode == 0 and (tmp_path / "other.json").exists()


@pytest.mark.parametrize(("content", "status", "needle"), [
    (b"0 0\n1 1 :sagg .3\n", 1, b"bad.pwc:2:5: error: unknown point property ':sagg'"),
    (b"\x00\x01binary", 1, b"not a text file"),
    (b"", 1, b"no points"),
    (b"0 0\n1 0\n1 0\n", 0, b"warning: segment between two identical points"),
])
def test_diagnostics_and_exit_codes(tmp_path, content, status, needle):
    bad = tmp_path / "bad.pwc"
    bad.write_bytes(content)
    for cmd in ("check", "compile"):
        r = pwc(cmd, bad, cwd=tmp_path)
        _clean(r)
        assert r.returncode == status and needle in r.stderr, r.stderr.decode()


def test_strict_turns_warnings_into_failures(tmp_path):
    p = tmp_path / "w.pwc"
    p.write_text("0 0\n1 0\n1 0\n")
    assert pwc("check", p).returncode == 0
    assert pwc("check", "--strict", p).returncode == 1
    r = pwc("compile", "--strict", p, cwd=tmp_path)
    assert r.returncode == 1 and not (tmp_path / "w.mdl").exists()


def test_io_errors(tmp_path, seg):
    r = pwc("check", tmp_path / "missing.pwc")
    _clean(r)
    assert r.returncode == 3 and b"missing.pwc: no such file" in r.stderr
    r = pwc("check", tmp_path)
    assert r.returncode == 3 and b"is a directory" in r.stderr
    assert pwc("compile", seg, "--format", "dxf").returncode == 2


def test_illegal_mdl_names_are_rejected(tmp_path):
    for stem in ("float", "3d_profile"):
        p = tmp_path / f"{stem}.pwc"
        p.write_text(SEGMENTS)
        r = pwc("compile", p, cwd=tmp_path)
        _clean(r)
        assert r.returncode == 1 and b"rename the file" in r.stderr
    p = tmp_path / "my-profile.pwc"
    p.write_text(SEGMENTS)
    assert pwc("compile", p, cwd=tmp_path).returncode == 0
    assert "my_profile_length" in (tmp_path / "my_profile.mdl").read_text()


def test_info(seg):
    r = pwc("info", seg)
    out = r.stdout.decode()
    assert r.returncode == 0
    assert "length      2.00056333" in out and "(5 pieces: 5 segment ending" in out
    assert "closed      no" in out
    assert "scale       0.75" in out and "x [0, 0.525]  y [0, 1]" in out


def test_console_script_is_the_module_command():
    """The installed ``pwc`` script and ``python -m pwc`` call the same ``entry``; tests run
    the latter so that they exercise the tree under test, not the installed one."""
    script = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["scripts"]["pwc"]
    assert script == "pwc.cli:entry"
    assert "sys.exit(entry())" in (ROOT / "pwc" / "__main__.py").read_text()
    r = pwc("--help")
    assert r.returncode == 0 and b"compile" in r.stdout


def test_subprocesses_import_the_tree_under_test(tmp_path):
    code = "import pwc, displacement, render; print(pwc.__file__, displacement.__file__, " \
           "render.__file__)"
    r = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, env=checkout_env(),
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    for f in r.stdout.split():
        assert Path(f).is_relative_to(ROOT), f


def test_evaluation_matches_between_json_and_compiled(seg, tmp_path):
    import pwc as lib

    r = pwc("compile", seg, "-f", "json", "-o", "-")
    c = from_json(r.stdout.decode())
    s = np.linspace(0, 1, 101)
    np.testing.assert_array_equal(c.evaluate(s), lib.load(seg).evaluate(s))


@pytest.mark.parametrize("path", PROFILES, ids=lambda p: p.stem)
def test_info_piece_counts_add_up(path):
    from pwc.cli import describe

    line = next(x for x in describe(lib_load(path)).splitlines() if x.startswith("pw_points"))
    m = re.search(r"(\d+) pw_points? \((\d+) pieces: (.*) ending at them\)", line) or \
        re.search(r"pw_points\s+(\d+) \((\d+) pieces: (.*) ending at them\)", line)
    n, pieces, kinds = int(m.group(1)), int(m.group(2)), m.group(3)
    assert pieces == n - 1
    assert sum(int(k.split()[0]) for k in kinds.split(", ")) == pieces, line


def test_version_and_python_dash_m(seg):
    r = subprocess.run([sys.executable, "-m", "pwc", "--version"], capture_output=True,
                       timeout=120)
    assert r.returncode == 0 and re.fullmatch(rb"pwc \d+\.\d+\.\d+\S*\n", r.stdout), r
    r = subprocess.run([sys.executable, "-m", "pwc", "check", seg], capture_output=True,
                       timeout=120)
    assert r.returncode == 0 and b"ok (6 pw_points" in r.stdout


def test_profiles_by_name_search_order(tmp_path, monkeypatch):
    """The current folder, then --profiles, then $PWC_PROFILE_PATH, then the bundle."""
    here, opt, env = (tmp_path / d for d in ("here", "opt", "env"))
    for d, y in ((here, 1), (opt, 2), (env, 3)):
        d.mkdir()
        (d / "ornament_2.pwc").write_text(f"0 0\n0 {y}\n")
        (d / f"only_{d.name}.pwc").write_text(f"0 0\n1 {y}\n")
    envvar = {**ENV, "PWC_PROFILE_PATH": os.pathsep.join([str(env), "/nonexistent"])}

    def source(name, *extra, cwd=here):
        r = subprocess.run([sys.executable, "-m", "pwc", "info", name, *extra], cwd=cwd,
                           env=envvar, capture_output=True, timeout=120)
        _clean(r)
        assert r.returncode == 0, r.stderr.decode()
        return r.stdout.decode().splitlines()[1].split(None, 1)[1]

    assert source("ornament_2", "--profiles", opt) == "ornament_2.pwc"  # cwd first
    assert source("ornament_2", "--profiles", opt, cwd=tmp_path) == str(opt / "ornament_2.pwc")
    assert source("ornament_2", cwd=tmp_path) == str(env / "ornament_2.pwc")
    assert source("only_opt.pwc", "--profiles", opt, cwd=tmp_path) == str(opt / "only_opt.pwc")
    bundled = source("torus", cwd=tmp_path)
    assert bundled.endswith("torus.pwc") and Path(bundled).is_file()
    r = subprocess.run([sys.executable, "-m", "pwc", "check", "ornament2"], cwd=tmp_path,
                       capture_output=True, timeout=120, env=ENV)
    _clean(r)
    assert r.returncode == 3 and b"did you mean 'ornament_2'?" in r.stderr


def test_output_paths_one_rule(seg, tmp_path):
    r = pwc("compile", seg, "-o", tmp_path / "new" / "deeper" / "x.json", "-f", "json")
    assert r.returncode == 0 and (tmp_path / "new" / "deeper" / "x.json").is_file()
    (tmp_path / "file").write_text("")
    r = pwc("compile", seg, "-o", tmp_path / "file" / "x.json", "-f", "json")
    _clean(r)
    assert r.returncode == 3 and b"file is a file, not a folder" in r.stderr
    r = pwc("compile", seg, "-o", "/proc/x.json", "-f", "json")
    _clean(r)
    assert r.returncode == 3 and b"does not accept new files" in r.stderr


def test_catalogue_keeps_a_readme_it_did_not_write(tmp_path):
    (tmp_path / "seg.pwc").write_text("# a segment\n" + SEGMENTS)
    mine = tmp_path / "README.md"
    mine.write_text("# my notes\n")
    r = pwc("catalogue", tmp_path)
    _clean(r)
    assert r.returncode == 3 and b"not written by pwc catalogue" in r.stderr
    assert mine.read_text() == "# my notes\n"
    assert pwc("catalogue", tmp_path, "--force").returncode == 0
    assert "Generated by `pwc catalogue" in mine.read_text()
    assert pwc("catalogue", tmp_path).returncode == 0  # its own page: rewritten freely


def _entry(tmp_path, argv: list, before: str = "pass") -> list:
    """``pwc.cli.entry`` run with ``argv`` in a fresh process (after the Python ``before``):
    its status, whether numba and render.df were loaded, whether its objects are frozen
    for the exit, whether anything reported a leak, and the collector's third threshold."""
    code = (f"import gc, sys; {before}; from pwc.cli import entry; sys.argv = {argv!r}; "
            "rc = entry(); "
            "print(rc, 'numba' in sys.modules, 'render.df' in sys.modules, "
            "gc.get_freeze_count() > 0, gc.get_threshold()[2])")
    r = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, env=checkout_env(),
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    *out, threshold = r.stdout.split()[-5:]
    # full passes spaced out for every command (pwc.cli.space_out_full_collections)
    assert threshold == "1000"
    return [*out, "leaked" in r.stderr]


def test_commands_that_do_not_render_do_not_import_the_render_kernels(tmp_path):
    """``pwc compile`` and every ``--help`` register all commands but load no numba kernel
    module (``render.df`` loads on first use): the translator starts in about a third of
    a second, not the renderer's."""
    out = tmp_path / "o.mdl"
    assert _entry(tmp_path, ["pwc", "compile", "ornament_2", "-o", str(out)]) == \
        ["0", "False", "False", "False", False]
    assert out.is_file()


def test_a_command_exits_without_the_collectors_pass_only_after_a_render(tmp_path):
    """After a render the command's objects are frozen for the exit (no collector pass over
    numba's registries: 0.3 s of a render's start, docs/render.md#speed); ``pwc solid``
    exits the ordinary way, so manifold3d finds its objects freed and reports no leak."""
    after_render = _entry(tmp_path, ["pwc", "compile", "ornament_2", "-o", "o.mdl"],
                          before="import render.integrator")
    assert after_render[0] == "0" and after_render[3] == "True"
    solid = _entry(tmp_path, ["pwc", "solid", "corinthian", "--revolve", "-o", "c.stl"])
    assert solid == ["0", "False", "False", "False", False]
    assert (tmp_path / "c.stl").is_file()
