"""The compiled-kernel cache of :mod:`render.jit` never runs stale machine code.

numba's own ``cache=True`` checks only the file that defines a kernel, so a kernel whose
*callee* (in another file) changed ran the old callee from a warm cache (issue 17: a
changed ``compiled_df.py`` went unnoticed by every render test).  These tests run probe
kernels of their own in a copy of the ``render`` package, so they do not depend on the
renderer's kernels: a caller in one file, its callee in another, a warm cache, then an
edit of the callee alone.
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
import textwrap

import pytest
from repo import ROOT

CALLEE = """\
from render.jit import njit


@njit
def callee(x):
    return x + {offset}
"""

CALLER = """\
from render._probe_callee import callee
from render.jit import njit


@njit
def kernel(x):
    return 2.0 * callee(x)
"""

RUN = textwrap.dedent("""\
    import json
    from render._probe_caller import kernel
    value = kernel(1.0)
    print(json.dumps({"value": value, "hits": sum(kernel.stats.cache_hits.values()),
                      "misses": sum(kernel.stats.cache_misses.values())}))
""")


def _run(tmp_path, pythonpath, env_extra):
    env = {"PATH": "/usr/bin:/bin", "HOME": str(tmp_path), "PYTHONPATH": str(pythonpath),
           "NUMBA_DISABLE_PERFORMANCE_WARNINGS": "1", **env_extra}
    r = subprocess.run([sys.executable, "-c", RUN], cwd=tmp_path, env=env,
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    return json.loads(r.stdout.strip().splitlines()[-1])


@pytest.fixture
def render_copy(tmp_path):
    """A copy of the ``render`` package with the probe kernels added (``PYTHONPATH``)."""
    tree = tmp_path / "tree"
    shutil.copytree(ROOT / "render", tree / "render",
                    ignore=shutil.ignore_patterns("__pycache__"))
    (tree / "render" / "_probe_callee.py").write_text(CALLEE.format(offset="1.0"))
    (tree / "render" / "_probe_caller.py").write_text(CALLER)
    return tree


def test_editing_a_called_kernel_changes_the_result_with_a_warm_cache(tmp_path, render_copy):
    env = {"PWC_CACHE_DIR": str(tmp_path / "cache")}
    first = _run(tmp_path, render_copy, env)
    assert first["value"] == 4.0 and first["misses"] == 1  # 2 * (1 + 1), compiled
    warm = _run(tmp_path, render_copy, env)
    assert warm["value"] == 4.0 and warm["hits"] == 1  # the cache is really used
    # edit the callee's file only; the caller's file is untouched
    (render_copy / "render" / "_probe_callee.py").write_text(CALLEE.format(offset="5.0"))
    edited = _run(tmp_path, render_copy, env)
    assert edited["value"] == 12.0  # 2 * (1 + 5): the new callee, no stale code
    assert edited["hits"] == 0


def test_plain_numba_cache_runs_the_stale_callee(tmp_path):
    """Why :mod:`render.jit` exists: the same probe under numba's own ``cache=True``
    returns the old callee's result after the edit.  If numba ever tracks callees, this
    test fails and render.jit's own keying may be dropped."""
    tree = tmp_path / "plain"
    (tree / "render").mkdir(parents=True)
    (tree / "render" / "__init__.py").write_text("")
    (tree / "render" / "jit.py").write_text(
        "import numba\n\n\ndef njit(f):\n    return numba.njit(cache=True)(f)\n")
    (tree / "render" / "_probe_callee.py").write_text(CALLEE.format(offset="1.0"))
    (tree / "render" / "_probe_caller.py").write_text(CALLER)
    env = {"NUMBA_CACHE_DIR": str(tmp_path / "numba-cache")}
    assert _run(tmp_path, tree, env)["value"] == 4.0
    (tree / "render" / "_probe_callee.py").write_text(CALLEE.format(offset="5.0"))
    stale = _run(tmp_path, tree, env)
    assert stale["hits"] == 1 and stale["value"] == 4.0


TEMPLATE = """\
part = None  # bound per instance


def kernel(x):
    return 2.0 * part(x)
"""

INSTANCE = """\
from render import _probe_template
from render.jit import instantiate, njit


@njit
def part(x):
    return x + {offset}


kernel = instantiate(_probe_template.kernel, __name__, part=part)
"""

BOTH = """\
from render import _probe_template
from render.jit import instantiate, njit


@njit
def one(x):
    return x + 1.0


@njit
def two(x):
    return x + 2.0


kernel_one = instantiate(_probe_template.kernel, __name__, part=one)
kernel_two = instantiate(_probe_template.kernel, __name__, part=two)
"""

RUN_INSTANCES = textwrap.dedent("""\
    import json
    from render import _probe_both, _probe_one, _probe_two
    ks = (_probe_one.kernel, _probe_two.kernel, _probe_both.kernel_one, _probe_both.kernel_two)
    print(json.dumps({"values": [k(1.0) for k in ks],
                      "hits": [sum(k.stats.cache_hits.values()) for k in ks],
                      "misses": [sum(k.stats.cache_misses.values()) for k in ks]}))
""")


def test_instances_of_one_template_are_cached_apart(tmp_path, render_copy):
    """:func:`render.jit.instantiate`: instances share the template's file and line, yet
    the cache gives each its own machine code (keyed by module, and by the instance's
    number within one module), cold and warm, and is used."""
    for name, offset in (("one", "1.0"), ("two", "2.0")):
        (render_copy / "render" / f"_probe_{name}.py").write_text(INSTANCE.format(offset=offset))
    (render_copy / "render" / "_probe_both.py").write_text(BOTH)
    (render_copy / "render" / "_probe_template.py").write_text(TEMPLATE)
    env = {"PATH": "/usr/bin:/bin", "HOME": str(tmp_path), "PYTHONPATH": str(render_copy),
           "PWC_CACHE_DIR": str(tmp_path / "cache")}

    def run():
        r = subprocess.run([sys.executable, "-c", RUN_INSTANCES], cwd=tmp_path, env=env,
                           capture_output=True, text=True, timeout=300)
        assert r.returncode == 0, r.stderr
        return json.loads(r.stdout.strip().splitlines()[-1])

    cold, warm = run(), run()
    assert cold["values"] == [4.0, 6.0] * 2 and cold["misses"] == [1] * 4
    assert warm["values"] == [4.0, 6.0] * 2 and warm["hits"] == [1] * 4


def test_a_kernel_compiles_once_whatever_literal_values_it_is_called_with():
    """numba types ``f(x, 0)`` and ``f(x, False)`` with literal types and compiles ``f``
    once per value; render.jit's dispatcher compiles once per argument types (the cold
    compile's specialisations: 355 -> 305, measured in docs/render.md#speed)."""
    import numba

    from render.jit import njit

    @njit
    def scaled(x, k, flag):
        return x * k + (1.0 if flag else 0.0)

    @njit
    def caller(x):
        return scaled(x, 0, False) + scaled(x, 2, True) + scaled(x, 3, False)

    assert caller(1.5) == 0.0 + 4.0 + 4.5
    assert scaled.signatures == [(numba.float64, numba.int64, numba.boolean)]
    assert scaled(1.5, 2, True) == 4.0  # called from Python: the same specialisation
    assert len(scaled.signatures) == 1
