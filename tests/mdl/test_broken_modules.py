"""Bad MDL gets located diagnostics: ``pwc mdl check`` on the broken modules of
``tests/mdl/broken``.

Each module says in its first two lines what the check must report::

    // expect: LINE:COL: message
    // fix: a fragment of the fix

and the check must exit 1 and print ``FILE:LINE:COL: error: message``, the quoted line
with its number, a caret under the column and ``fix: ...`` -- never a traceback.  The
modules cover each stage: characters, syntax, names and imports, types, uniform and
varying, what MDL forbids (recursion, a df in a function), what the workbench does not
implement (3D textures), and a value a material's Python definition refuses.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from pwc.cli import main
from tests.support.repo import run_pwc

BROKEN = Path(__file__).resolve().parent / "broken"
CASES = sorted(BROKEN.glob("*.mdl"))


def expectation(path: Path) -> tuple[int, int, str, str]:
    first, second = path.read_text(encoding="utf-8").split("\n")[:2]
    m = re.fullmatch(r"// expect: (\d+):(\d+): (.+)", first)
    f = re.fullmatch(r"// fix: (.+)", second)
    assert m and f, f"{path.name}: the first two lines must say what to expect"
    return int(m.group(1)), int(m.group(2)), m.group(3), f.group(1)


def test_there_is_a_set_of_broken_modules():
    assert len(CASES) >= 20


@pytest.mark.parametrize("path", CASES, ids=[p.stem for p in CASES])
def test_check_locates_the_error_and_suggests_a_fix(path, capsys):
    line, col, message, fix = expectation(path)
    status = main(["mdl", "check", str(path)])
    err = capsys.readouterr().err
    assert status == 1, err
    assert "Traceback" not in err
    head = f"{path}:{line}:{col}: error: {message}"
    assert head in err, err
    # the quoted line, its number, and a caret under the column
    text = path.read_text(encoding="utf-8").split("\n")[line - 1]
    lines = err.split("\n")
    at = next(i for i, x in enumerate(lines) if x.startswith(head))
    assert lines[at + 1].endswith(f"{line} | {text}"), lines[at + 1]
    bar = lines[at + 1].index("| ") + 2
    assert lines[at + 2][bar + col - 1] == "^", lines[at + 2]
    assert lines[at + 3].startswith("  fix: ") and fix in lines[at + 3], lines[at + 3]


def test_every_error_of_a_module_is_reported_once(tmp_path, capsys):
    """Several broken declarations: each is reported, in order, each with a fix."""
    f = tmp_path / "several.mdl"
    f.write_text("mdl 1.6;\nimport ::math::*;\n"
                 "float a(float x) = math::sine(x);\n"
                 "float b(float x) = y;\n"
                 "const int c = 1.5;\n", encoding="utf-8")
    assert main(["mdl", "check", str(f)]) == 1
    err = capsys.readouterr().err
    heads = re.findall(rf"^{re.escape(str(f))}:(\d+):\d+: error: ", err, re.M)
    assert heads == ["3", "4", "5"]
    assert err.count("  fix: ") == 3


def test_the_command_line_never_shows_a_traceback():
    """The installed command (a subprocess): located errors, exit 1."""
    paths = [str(p) for p in CASES[:3]]
    r = run_pwc("mdl", "check", *paths)
    assert r.returncode == 1, r.stderr
    assert "Traceback" not in r.stderr
    for p in paths:
        assert f"{p}:" in r.stderr
