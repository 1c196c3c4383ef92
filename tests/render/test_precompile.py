"""The df kernels a second process compiles ahead (:mod:`render.precompile`) are the very
ones the path kernel calls: after :func:`~render.precompile.compile_df_kernels` has run
in one process, a render in another loads every df kernel it calls from the cache and
compiles none of them again (a kernel called with other argument types than
:data:`~render.precompile.KERNEL_ARGS` would be compiled again).  Workers of one machine
on a cold cache take turns (:func:`~render.precompile.first_compile`): one compiles,
the others load."""

from __future__ import annotations

import dataclasses
import json
import os
import subprocess
import sys
import textwrap

import numpy as np
from repo import checkout_env

RENDER = textwrap.dedent("""\
    import dataclasses, json
    from render.integrator import Integrator
    from render.library.resources import bundled_scenes
    from render.precompile import df_kernels
    from render.scene import load_scene
    scene = load_scene(bundled_scenes() / "fig_14_28.toml")
    scene.settings.width = scene.settings.height = 8
    scene.camera = dataclasses.replace(scene.camera, width=8, height=8)
    Integrator(scene, scene.build()).render(spp=1, progress=False, threads=1)
    print(json.dumps([{"name": k.py_func.__module__ + "." + k.__name__,
                       "loaded": sum(k.stats.cache_hits.values()),
                       "compiled": sum(k.stats.cache_misses.values())}
                      for k in df_kernels()]))
""")


def _run(code, env):
    r = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                       text=True, timeout=900)
    assert r.returncode == 0, r.stderr
    return r.stdout


def test_a_render_loads_every_df_kernel_compiled_ahead_and_compiles_none(tmp_path,
                                                                          monkeypatch):
    from render.precompile import compile_df_kernels_aside, cores

    monkeypatch.setenv("PWC_CACHE_DIR", str(tmp_path))
    env = checkout_env({**os.environ, "PWC_CACHE_DIR": str(tmp_path)})
    aside = compile_df_kernels_aside()  # the second process, here first and to its end
    if aside is None:  # one core starts none: what it would run, run here
        assert cores() < 2
        _run("from render.precompile import compile_df_kernels; compile_df_kernels()", env)
    else:
        assert aside.wait(timeout=900) == 0
    rows = json.loads(_run(RENDER, env).strip().splitlines()[-1])
    assert len(rows) > 80  # every df module's kernels the interpreter dispatches to
    assert [x["name"] for x in rows if x["compiled"]] == []
    assert sum(x["loaded"] > 0 for x in rows) > 60  # the render's own, from the cache


def test_workers_of_one_machine_compile_the_kernels_once(tmp_path, monkeypatch):
    """A local cluster of two workers on a cold cache: one worker compiles the path
    kernel (with the df kernels aside), the other waits its turn and loads it, and the
    cache is marked ready.  (That the image is the in-process one: test_distributed.)"""
    from render.distributed import cluster, render_on_cluster
    from render.library.resources import bundled_scenes
    from render.precompile import kernels_ready
    from render.scene import load_scene

    monkeypatch.setenv("PWC_CACHE_DIR", str(tmp_path))  # the workers inherit it
    scene = load_scene(bundled_scenes() / "fig_14_28.toml")
    scene.settings.width = scene.settings.height = 32  # 8 chunks at 512 spp: both trace
    scene.camera = dataclasses.replace(scene.camera, width=32, height=32)

    def trace_stats():  # nested: cloudpickle sends it by value
        from render.path import trace
        return (sum(trace.stats.cache_misses.values()), sum(trace.stats.cache_hits.values()))

    with cluster(workers=2) as client:
        film = render_on_cluster(scene, client, spp=512, seed=3, progress=False)
        stats = client.run(trace_stats)
    assert sorted(stats.values()) == [(0, 1), (1, 0)]  # compiled once, loaded once
    assert kernels_ready()
    assert np.all(film.spp == 512) and np.all(np.isfinite(film.rgb()))
