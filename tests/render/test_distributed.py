"""Rendering on a real Dask cluster of worker processes on this machine (issue 15): the
image bit-identical to the in-process one whatever the workers, the scene shipped once
per worker with what its files gave it, a worker killed mid-render, the time budget,
``pwc render --workers/--scheduler``, the errors a user can meet, and whole scenes as
tasks (:func:`render.distributed.map_on_cluster`, for ``pwc gallery`` and ``pwc trade``)."""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import threading
import time
from functools import partial

import numpy as np
import pytest
from repo import ROOT, checkout_env, run_pwc

from render import distributed
from render.distributed import ClusterError, cluster, map_on_cluster, render_on_cluster
from render.film import read_exr
from render.integrator import render
from render.passes import PassPlan
from render.scene import load_scene

#: a mesh, a texture and a profile from files beside the scene, a displaced object
#: (diced on each worker); 48 x 32 at 400 spp is two passes (342 spp, then 58)
SCENE = """\
[camera]
position = [0.0, 1.1, 3.6]
look_at = [0.0, 0.45, 0.0]
fov = 30.0

[render]
resolution = [48, 32]
spp = 400
seed = 11
max_depth = 4

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
name = "box"
mesh = "box.obj"
scale = 0.4
translate = [0.0, 0.2, -0.8]
material = "diffuse(tint: color(0.5))"

[[objects]]
name = "square"
surface = "square"
translate = [-1.1, 0.0, 0.0]
material = "tex2d_diffuse()"

[[objects]]
name = "sphere"
surface = { type = "sphere", radius = 0.5 }
translate = [0.6, 0.5, 0.0]
material = "radial_pwc(pwc: myprof::myprof, surface_material: diffuse())"
"""

#: a cheap scene of many chunks: 64 x 64 at 1024 spp, 64 chunks
MANY_CHUNKS = """\
[camera]
position = [0.0, 0.5, 3.0]
look_at = [0.0, 0.0, 0.0]
fov = 40.0

[render]
resolution = [64, 64]
spp = 1024
seed = 5
max_depth = 3

[[lights]]
type = "point"
position = [1.0, 2.0, 1.0]
intensity = 3.0

[[lights]]
type = "environment"
radiance = 0.2

[[objects]]
surface = { type = "sphere", radius = 0.5 }
material = "diffuse(tint: color(0.8, 0.3, 0.2))"
"""

AOVS = ["albedo", "normal", "depth", "uv", "object_id"]


def write_scene(folder, rng):
    """SCENE and the files it names (a box mesh, a random uv.png, a profile) in folder."""
    import trimesh
    from PIL import Image

    folder.mkdir(parents=True, exist_ok=True)
    trimesh.creation.box((1.0, 1.0, 1.0)).export(folder / "box.obj")
    texels = rng.integers(0, 256, (16, 16, 3), dtype=np.uint8)
    Image.fromarray(texels, "RGB").save(folder / "uv.png")  # found before the bundled one
    (folder / "myprof.pwc").write_text("0 0\n.1 .5 :sag .05\n0 1\n")
    (folder / "scene.toml").write_text(SCENE)
    return folder / "scene.toml"


def assert_same_film(a, b):
    """Every channel of two films equal, bit for bit."""
    assert np.array_equal(a.rgb(), b.rgb())
    assert np.array_equal(a.alpha(), b.alpha())
    assert np.array_equal(a.spp, b.spp)
    for name in a.aov_names:
        assert np.array_equal(a.aov(name), b.aov(name)), name


@pytest.fixture(scope="module")
def client2():
    """A local cluster of two worker processes, one thread each."""
    with cluster(workers=2) as client:
        yield client


@pytest.fixture(scope="module")
def shipped(tmp_path_factory):
    """SCENE loaded, then its files deleted: the workers cannot read them; and its
    in-process render (threads=2)."""
    folder = tmp_path_factory.mktemp("shipped")
    scene = load_scene(write_scene(folder, np.random.default_rng(7)))
    shutil.rmtree(folder)
    return scene, render(scene, aovs=AOVS, progress=False)


def test_same_image_as_in_process_on_two_workers(client2, shipped):
    scene, want = shipped
    film = render_on_cluster(scene, client2, aovs=AOVS, progress=False)
    assert_same_film(film, want)
    plan = PassPlan.of(scene.settings, 48 * 32)
    assert (plan.passes, film.stats["passes"], film.stats["spp"]) == (2, 2, 400)
    workers = film.stats["workers"]
    assert len(workers) == 2
    assert sum(w["chunks"] for w in workers.values()) == plan.chunk_count
    # the scene travelled once per worker, and each built it (diced) once
    assert all(w["builds"] == 1 for w in workers.values() if w["chunks"])
    assert film.stats["scene_bytes"] > 16 * 16 * 3
    assert film.stats["triangles"] == want.stats["triangles"] > 12 + 2
    # a patch is a pixel range's sums: 342 samples per pixel ship as one row
    assert film.stats["patch_bytes"] < 48 * 32 * 400 * 8
    assert film.stats["chunks_per_task"] == 1 and film.stats["tasks"] == plan.chunk_count
    # tasks of several chunks (as on a large cluster): fewer tasks, the same image
    grouped = render_on_cluster(scene, client2, aovs=AOVS, progress=False, chunks_per_task=4)
    assert_same_film(grouped, want)
    assert grouped.stats["chunks_per_task"] == 4 and grouped.stats["tasks"] < plan.chunk_count
    with pytest.raises(ValueError, match="chunks_per_task must be >= 1"):
        render_on_cluster(scene, client2, chunks_per_task=0)


def test_same_image_on_one_worker_of_two_threads(shipped):
    scene, want = shipped
    with cluster(workers=1, threads_per_worker=2) as client:
        film = render_on_cluster(scene, client, aovs=AOVS, progress=True)
    assert_same_film(film, want)
    assert len(film.stats["workers"]) == 1


@pytest.mark.parametrize("w, h, spp, per_task, threads", [
    (3840, 2160, 64, 16, 100), (48, 32, 400, 4, 2), (64, 64, 1024, 1, 2), (7, 5, 3, 8, 1)])
def test_tasks_cover_the_chunks_in_order_within_passes(w, h, spp, per_task, threads):
    """Tasks hold consecutive chunks of one pass, every chunk once and in order, at most
    per_task of them, and no fewer than a quarter of it except at the end of a pass."""
    from render.distributed import _tasks
    from render.scene import RenderSettings

    plan = PassPlan.of(RenderSettings(w, h, spp=spp), w * h)
    tasks = list(_tasks(plan, per_task, threads))
    flat = [item for task in tasks for item in task]
    assert flat == [item for k in range(plan.passes) for item in plan.chunks(k)]
    for task in tasks:
        assert len({k for k, _, _ in task}) == 1 and 1 <= len(task) <= per_task
        k, _, (a, _) = task[-1]
        ends_pass = task[-1] == plan.chunks(k)[-1]
        assert ends_pass or len(task) >= max(1, per_task // 4)
    if per_task > 1 and plan.chunk_count > 4 * threads * per_task:
        assert len(tasks) < plan.chunk_count / 2


def test_other_seed_other_image(client2, shipped):
    scene, want = shipped
    other = render_on_cluster(scene, client2, spp=64, seed=12, progress=False)
    ref = render(scene, spp=64, seed=12, progress=False)
    assert np.array_equal(other.rgb(), ref.rgb())
    assert not np.array_equal(other.rgb(), want.rgb())


def test_time_budget_holds_across_workers(client2, tmp_path):
    (tmp_path / "s.toml").write_text(MANY_CHUNKS)
    scene = load_scene(tmp_path / "s.toml")
    budget = 1.5
    film = render_on_cluster(scene, client2, time=budget, progress=False)
    st = film.stats
    plan = PassPlan.of(scene.settings, 64 * 64, time_budget=budget)
    # whole passes only, every pixel the same samples, and no pass begun after the budget
    assert st["passes"] >= 1 and st["spp"] == st["passes"] * plan.per_pass
    assert np.all(film.spp == st["spp"])
    assert st["time_s"] < budget + 10 * max(w["trace_s"] / w["chunks"]
                                            for w in st["workers"].values() if w["chunks"])
    # the passes kept are the in-process render of as many samples
    ref = render(scene, spp=st["spp"], progress=False)
    assert np.array_equal(film.rgb(), ref.rgb())


def _kill_a_worker_during(work, key_part: str):
    """Run ``work(client)`` on a new local cluster of two workers, SIGKILL the first
    worker seen running a task whose key holds ``key_part``, and return what ``work``
    returned (it must not fail) and the dead worker's address."""
    with cluster(workers=2) as client:
        pids = client.run(os.getpid)
        result = {}

        def run():
            try:
                result["value"] = work(client)
            except Exception as e:  # noqa: BLE001 - reported by the assertion below
                result["error"] = e

        thread = threading.Thread(target=run)
        thread.start()
        victim, deadline = None, time.monotonic() + 300
        while victim is None and time.monotonic() < deadline and thread.is_alive():
            for address, keys in client.processing().items():
                if any(key_part in str(k) for k in keys) and address in pids:
                    victim = address
                    break
            time.sleep(0.01)
        assert victim is not None, f"no worker was seen running a task {key_part!r}"
        os.kill(pids[victim], signal.SIGKILL)
        thread.join(timeout=600)
        assert not thread.is_alive()
    assert "error" not in result, result.get("error")
    return result["value"], victim


def test_a_killed_worker_changes_nothing(tmp_path):
    """SIGKILL a worker process while it renders chunks: the scheduler runs them again
    on the other worker (and its nanny restarts it), and the image is the same."""
    (tmp_path / "s.toml").write_text(MANY_CHUNKS)
    scene = load_scene(tmp_path / "s.toml")
    want = render(scene, progress=False)
    film, victim = _kill_a_worker_during(
        lambda client: render_on_cluster(scene, client, progress=False), "-chunks-")
    assert np.array_equal(film.rgb(), want.rgb()) and np.array_equal(film.spp, want.spp)
    plan = PassPlan.of(scene.settings, 64 * 64)
    # every chunk came back once; the dead worker's unfinished ones from another worker
    assert sum(w["chunks"] for w in film.stats["workers"].values()) == plan.chunk_count
    survivors = [a for a, w in film.stats["workers"].items() if a != victim and w["chunks"]]
    assert survivors


def test_pwc_render_workers_is_the_in_process_image(tmp_path):
    scene = write_scene(tmp_path / "s", np.random.default_rng(3))
    common = ["render", scene, "--spp", "16", "--aov", "albedo,object_id", "--seed", "2"]
    r1 = run_pwc(*common, "-o", tmp_path / "one.exr")
    r2 = run_pwc(*common, "-o", tmp_path / "two.exr", "--workers", "2", "--chunks-per-task", "2")
    assert r1.returncode == 0, r1.stderr
    assert r2.returncode == 0, r2.stderr
    assert "2 workers" in r2.stderr and "Traceback" not in r2.stderr
    a, b = read_exr(tmp_path / "one.exr"), read_exr(tmp_path / "two.exr")
    assert a.keys() == b.keys()
    for name in a:
        assert np.array_equal(a[name], b[name]), name


@pytest.fixture
def dask_scheduler(tmp_path):
    """A ``dask scheduler`` process on the loopback; yields (address, the processes
    list to which tests add their ``dask worker`` processes)."""
    file = tmp_path / "scheduler.json"
    procs = [_dask("scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
                   "--scheduler-file", file)]
    try:
        deadline = time.monotonic() + 120
        while not file.is_file() and time.monotonic() < deadline:
            time.sleep(0.1)
        assert file.is_file(), "dask scheduler did not start"
        time.sleep(0.2)  # written whole
        yield json.loads(file.read_text())["address"], procs
    finally:
        for p in reversed(procs):
            p.terminate()
        for p in procs:
            try:
                p.wait(timeout=30)
            except subprocess.TimeoutExpired:
                p.kill()


def _dask(*args, first=None):
    """A ``dask`` command (scheduler or worker) of this checkout, output discarded;
    ``first``: a folder whose packages it imports before the checkout's (it runs there:
    ``python -m`` imports from its current folder before anything else)."""
    env = checkout_env()
    if first is not None:
        env["PYTHONPATH"] = os.pathsep.join([str(first), env["PYTHONPATH"]])
    return subprocess.Popen(
        [sys.executable, "-m", "distributed.cli.dask_" + args[0], *map(str, args[1:])],
        env=env, cwd=first, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
    )


def test_pwc_render_on_a_running_scheduler(tmp_path, dask_scheduler):
    address, procs = dask_scheduler
    procs.append(_dask("worker", address, "--nworkers", "2", "--nthreads", "1",
                       "--no-dashboard"))
    scene = write_scene(tmp_path / "s", np.random.default_rng(4))
    common = ["render", scene, "--spp", "8", "--seed", "9"]
    r1 = run_pwc(*common, "-o", tmp_path / "one.exr")
    r2 = run_pwc(*common, "-o", tmp_path / "two.exr", "--scheduler", address)
    assert r1.returncode == 0, r1.stderr
    assert r2.returncode == 0, r2.stderr
    assert np.array_equal(read_exr(tmp_path / "one.exr")["RGBA"],
                          read_exr(tmp_path / "two.exr")["RGBA"])


def test_workers_running_other_code_are_refused(tmp_path, dask_scheduler, monkeypatch):
    """A scheduler without workers, and a worker importing a render package whose
    sources differ (one comment added), which would not give the same bits: the client
    says what is wrong and how to fix it."""
    address, procs = dask_scheduler
    scene = load_scene(write_scene(tmp_path / "s", np.random.default_rng(5)))
    monkeypatch.setattr(distributed, "CONNECT_TIMEOUT", 2.0)
    with cluster(scheduler=address) as client, pytest.raises(ClusterError) as e:
        render_on_cluster(scene, client, spp=1, progress=False)
    assert f"no worker joined the scheduler at {address}" in str(e.value)
    assert f"`dask worker {address}`" in str(e.value)
    monkeypatch.setattr(distributed, "CONNECT_TIMEOUT", 120.0)
    other = tmp_path / "other"
    shutil.copytree(ROOT / "render", other / "render",
                    ignore=shutil.ignore_patterns("__pycache__"))
    with open(other / "render" / "film.py", "a") as f:
        f.write("# another revision\n")
    procs.append(_dask("worker", address, "--nthreads", "1", "--no-dashboard", first=other))
    with cluster(scheduler=address) as client, pytest.raises(ClusterError) as e:
        render_on_cluster(scene, client, spp=1, progress=False)
    assert "runs other code: render sources" in str(e.value)
    assert "install the same revision" in str(e.value)


def test_cluster_errors_are_messages(tmp_path, monkeypatch):
    scene = write_scene(tmp_path / "s", np.random.default_rng(6))
    r = run_pwc("render", scene, "-o", tmp_path / "x.exr", "--workers", "0")
    assert r.returncode == 2 and "--workers must be >= 1" in r.stderr
    r = run_pwc("render", scene, "-o", tmp_path / "x.exr", "--workers", "1",
                "--chunks-per-task", "0")
    assert r.returncode == 2 and "--chunks-per-task must be >= 1" in r.stderr
    r = run_pwc("render", scene, "-o", tmp_path / "x.exr", "--workers", "2", "--scheduler",
                "tcp://127.0.0.1:1")
    assert r.returncode == 2 and "not allowed with argument" in r.stderr
    # nothing listens on port 1 of the loopback
    monkeypatch.setattr(distributed, "CONNECT_TIMEOUT", 2.0)
    with pytest.raises(ClusterError, match="cannot reach the Dask scheduler at 'tcp://127.0"):
        with cluster(scheduler="tcp://127.0.0.1:1"):
            pass
    with pytest.raises(ValueError, match="not both or neither"):
        with cluster():
            pass


# ---------------------------------------------------------------------- whole tasks
def test_whole_tasks_come_back_in_order_and_stop_on_request(client2):
    """Results in the jobs' order whatever order the tasks finish in; a task's error as
    it raised it; ``stop`` cancels the unfinished tasks and keeps the finished ones."""

    def slow(job):  # a local function travels by value (cloudpickle)
        import time

        seconds, value = job
        if value is None:
            raise ValueError("no value")
        time.sleep(seconds)
        return value

    jobs = [(0.6, "a"), (0.0, "b"), (0.3, "c"), (0.0, "d")]
    assert list(map_on_cluster(client2, slow, jobs, progress=True)) == [
        (0, "a"), (1, "b"), (2, "c"), (3, "d")]
    with pytest.raises(ValueError, match="no value"):
        list(map_on_cluster(client2, slow, [(0.0, "a"), (0.0, None)], progress=False))
    start = time.monotonic()  # (the last test of client2: the cancelled sleeps go on)
    got = list(map_on_cluster(client2, slow, [(10.0, "late"), (0.0, "b"), (10.0, "never")],
                              progress=False, stop=lambda: True))
    assert got == [(1, "b")] and time.monotonic() - start < 8
    deadline = time.monotonic() + 20  # and the scheduler has forgotten them
    while any(client2.processing().values()) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not any(client2.processing().values())


def test_a_scene_whose_worker_dies_is_rendered_again_elsewhere(tmp_path):
    """Whole scenes as tasks (``pwc gallery``'s figures): SIGKILL the worker rendering
    one; the scheduler runs the task again on another worker and the images are the
    in-process ones."""
    (tmp_path / "s.toml").write_text(MANY_CHUNKS.replace("spp = 1024", "spp = 256"))
    scenes = [load_scene(tmp_path / "s.toml", overrides={"seed": s}) for s in (1, 2)]
    want = [render(scene, progress=False).rgb() for scene in scenes]
    task = partial(render, progress=False, threads=1)
    films, _ = _kill_a_worker_during(lambda client: dict(map_on_cluster(
        client, task, scenes, progress=False, unit="scene")), "pwc-scene-")
    assert sorted(films) == [0, 1]
    for i, image in enumerate(want):
        assert np.array_equal(films[i].rgb(), image), i
