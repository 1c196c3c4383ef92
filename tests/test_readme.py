"""The README and the language reference say what the code does: their Python runs,
their pwc-lists compile, and they point to the project's own documents."""

from __future__ import annotations

import re

import pytest
from repo import ROOT

import pwc
from pwc.tree import LIST_PROPERTIES, POINT_PROPERTIES

README = (ROOT / "README.md").read_text(encoding="utf-8")
REFERENCE = (ROOT / "docs" / "pwc-list.md").read_text(encoding="utf-8")


def _blocks(text: str, language: str) -> list[str]:
    return re.findall(rf"^```{language}\n(.*?)^```", text, re.S | re.M)


@pytest.mark.parametrize("code", _blocks(README, "python"))
def test_readme_python_runs(code, monkeypatch):
    monkeypatch.chdir(ROOT)
    namespace: dict = {}
    exec(compile(code, "README.md", "exec"), namespace)  # noqa: S102 - the README's own code
    assert namespace["curve"].name == "ornament_2"
    assert namespace["xy3"].shape == namespace["xy"].shape == (1000, 2)


@pytest.mark.parametrize("text", _blocks(README, "text")[:1] + _blocks(REFERENCE, "text")[:1])
def test_documented_lists_compile_cleanly(text):
    curve, warnings = pwc.compile_source(text, "example", "README.md")
    assert warnings == [] and curve.n > 5


def test_the_reference_is_the_projects_own_and_complete():
    assert "../shared" not in README.split("## Command reference")[0].replace(
        "the project's `../shared` beside the checkout", "")
    assert "[docs/pwc-list.md](docs/pwc-list.md)" in README
    for name in (*LIST_PROPERTIES, *POINT_PROPERTIES):
        assert f"`:{name}" in REFERENCE, name
    for kind in pwc.PwType:
        assert f"`{kind.mdl_name}`" in REFERENCE, kind
    for env in ("PWC_PROFILE_PATH", "--profiles"):
        assert env in REFERENCE and env in README
