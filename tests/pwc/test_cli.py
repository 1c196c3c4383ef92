"""The ``pwc`` command as a user runs it: real subprocesses, exit codes, no tracebacks."""

from __future__ import annotations

import json
import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest
from repo import PWC, ROOT, tree_env

from pwc.emit import from_json, from_npz

SEGMENTS = "0 0\n.7 0\n.7 .4\n3/7 .4\n3/7 4/3\n4/7 1\n"


def pwc(*args, cwd=None, stdin=None) -> subprocess.CompletedProcess:
    return subprocess.run([*PWC, *map(str, args)], cwd=cwd, env=tree_env(),
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
    assert "length      2.00056333" in out and "6 segment" in out and "closed      no" in out
    assert "scale       0.75" in out and "x [0, 0.525]  y [0, 1]" in out


def test_console_script_is_the_module_command():
    """The installed ``pwc`` script and ``python -m pwc`` call the same ``main``; tests run
    the latter so that they exercise the tree under test, not the installed one."""
    script = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["scripts"]["pwc"]
    assert script == "pwc.cli:main"
    r = pwc("--help")
    assert r.returncode == 0 and b"compile" in r.stdout


def test_subprocesses_import_the_tree_under_test(tmp_path):
    code = "import pwc, displacement, render; print(pwc.__file__, displacement.__file__, " \
           "render.__file__)"
    r = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, env=tree_env(),
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
