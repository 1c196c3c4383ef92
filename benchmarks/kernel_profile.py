"""Where a render's time goes, kernel by kernel: a ``perf`` profile of the stage of
``render_vs_mitsuba.py`` on one thread, with the compiled kernels named.

Run ``python benchmarks/kernel_profile.py`` (``--kind glossy``, ``--spp``; ``--quick``
for a smoke run).  It needs Linux ``perf``, allowed to sample this user's processes
(``perf_event_paranoid`` at most 2), and binutils' ``nm``; without them, it says so and
stops.

``perf`` cannot name code that numba made at run time.  The kernels' machine code comes
from numba's cache (:func:`render.jit.cache_dir`), whose files hold each kernel's object
file: its symbol table gives every function's offset, the entry point's address in this
process gives the base, and the script writes ``/tmp/perf-<pid>.map`` before it renders
(removed after ``perf script`` has read it).
Callees that numba inlined count as their caller (the path kernel's own body).  Only the
render counts: samples between the two marks the render process takes of the monotonic
clock, which ``perf record -k CLOCK_MONOTONIC`` stamps samples with.

Printed: samples per CPU second of the render, and each function's share of the samples,
Embree's functions summed as one.

``--peer`` profiles Mitsuba 3's ``scalar_rgb`` variant instead, on the same triangles
and one thread: C++ that, as our kernels, traces one ray and shades one lane at a time
(Embree 3 underneath), where its ``llvm_ad_rgb`` variant shades 16 lanes at once.  Its
functions are named by its own symbols, their template arguments left out.
"""

from __future__ import annotations

import argparse
import collections
import gc
import glob
import os
import pickle
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))


def _elf_objects(obj):
    """The ELF object files inside an unpickled numba cache entry."""
    if isinstance(obj, bytes):
        if obj[:4] == b"\x7fELF":
            yield obj
    elif isinstance(obj, (tuple, list)):
        for x in obj:
            yield from _elf_objects(x)
    elif isinstance(obj, dict):
        for x in obj.values():
            yield from _elf_objects(x)


def _symbols(elf: bytes) -> tuple[dict, set]:
    """({symbol: (offset, size)} of an object file's functions (``nm -S``), the symbols
    it defines as its own: global, where the callees linked into it are weak)."""
    with tempfile.NamedTemporaryFile(suffix=".o") as f:
        f.write(elf)
        f.flush()
        out = subprocess.run(["nm", "-S", f.name], capture_output=True, text=True).stdout
    syms, own = {}, set()
    for line in out.splitlines():
        p = line.split()
        if len(p) == 4 and p[2] in "TtWw" and int(p[1], 16):
            syms[p[3]] = (int(p[0], 16), int(p[1], 16))
            if p[2] == "T":
                own.add(p[3])
    return syms, own


def _python_name(symbol: str) -> str:
    """``render.path.trace`` from numba's mangled ``_ZN6render4path5traceB...``."""
    s = symbol[3:] if symbol.startswith("_ZN") else symbol
    parts, i = [], 0
    while i < len(s) and s[i].isdigit():
        j = i
        while s[j].isdigit():
            j += 1
        n = int(s[i:j])
        parts.append(s[j:j + n])
        i = j + n
    return ".".join(parts) or symbol


def write_perf_map() -> int:
    """``/tmp/perf-<pid>.map`` of every loaded kernel's functions; returns their count."""
    from numba.core.dispatcher import Dispatcher

    from render.jit import cache_dir

    tables = {}  # a kernel's entry symbol -> the symbols of the object file it is from
    for f in glob.glob(str(cache_dir() / "**" / "*.nbc"), recursive=True):
        try:
            entry = pickle.loads(Path(f).read_bytes())
        except Exception:  # noqa: BLE001 - a stale or foreign file: not ours to name
            continue
        for elf in _elf_objects(entry):
            syms, own = _symbols(elf)
            for name in own:
                tables[name] = syms
    rows = {}
    for d in [o for o in gc.get_objects() if isinstance(o, Dispatcher)]:
        for cres in d.overloads.values():
            entry = cres.fndesc.llvm_func_name
            syms = tables.get(entry)
            address = cres.library.get_pointer_to_function(entry) if syms else 0
            if address:
                base = address - syms[entry][0]
                for name, (offset, size) in syms.items():
                    rows[base + offset] = (size, _python_name(name))
    with open(f"/tmp/perf-{os.getpid()}.map", "w") as fh:
        for a in sorted(rows):
            fh.write(f"{a:x} {rows[a][0]:x} {rows[a][1]}\n")
    return len(rows)


def child(args) -> None:
    """The profiled process: warm up, write the map, render between two clock marks."""
    from render_vs_mitsuba import stage

    if args.peer:
        import drjit as dr
        import mitsuba as mi
        from render_vs_mitsuba import mitsuba_render, scalar_scene

        dr.set_thread_count(1)
        scene, md, cam = stage(args.kind, args.size[0], args.size[1])
        peer = scalar_scene(mi, md, cam, scene.build(), [o.name for o in scene.objects])
        n = 0

        def render():
            mitsuba_render(mi, peer, args.spp, 1)
    else:
        from render.integrator import Integrator

        scene = stage(args.kind, args.size[0], args.size[1])[0]
        integ = Integrator(scene, scene.build())
        integ.render(spp=1, progress=False, threads=1)  # compiles or loads every kernel
        n = write_perf_map()

        def render():
            integ.render(spp=args.spp, progress=False, threads=1)
    t0, c0 = time.clock_gettime(time.CLOCK_MONOTONIC), time.process_time()
    render()
    t1, c1 = time.clock_gettime(time.CLOCK_MONOTONIC), time.process_time()
    rate = args.size[0] * args.size[1] * args.spp / (c1 - c0) / 1e6
    Path(args.marks).write_text(f"{t0} {t1} {rate} {n} {os.getpid()}\n")


def shares(script: str, t0: float, t1: float) -> tuple[int, list]:
    """(samples, [(share, function)]) of the ``perf script`` lines stamped in [t0, t1]."""
    count = collections.Counter()
    for line in script.splitlines():
        p = line.split(None, 2)
        if len(p) < 3 or not t0 <= float(p[0].rstrip(":")) <= t1:
            continue
        rest = p[2]
        dso = rest[rest.rfind("(") + 1:-1]
        sym = rest[:rest.rfind("(")].strip()
        if "embree" in dso:
            key = "Embree"
        elif re.fullmatch(r"[0-9a-fx]+|\[unknown\]", sym):
            key = f"(unnamed, {Path(dso).name})"
        else:
            key = _without_templates(sym)
        count[key] += 1
    total = sum(count.values())
    return total, [(n / total, k) for k, n in count.most_common()] if total else []


def _without_templates(symbol: str) -> str:
    """A C++ name without its template and call arguments
    (``mitsuba::Mesh<float, ...>::sample_position`` -> ``mitsuba::Mesh::sample_position``)."""
    out, depth = [], 0
    for ch in symbol:
        depth += ch in "<("
        if depth == 0:
            out.append(ch)
        depth -= ch in ">)" and depth > 0
    return "".join(out)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--kind", default="diffuse", choices=("diffuse", "glossy", "layered",
                                                         "mixed"))
    ap.add_argument("--spp", type=int, default=200)
    ap.add_argument("--size", type=int, nargs=2, default=(256, 192), metavar=("W", "H"))
    ap.add_argument("--top", type=int, default=20, help="functions to list")
    ap.add_argument("--quick", action="store_true", help="tiny sizes (a smoke run)")
    ap.add_argument("--peer", action="store_true",
                    help="profile Mitsuba 3's scalar_rgb variant on the same triangles instead")
    ap.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--marks", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.quick:
        args.spp, args.size = 2, (64, 48)
    if args.child:
        child(args)
        return 0
    perf = shutil.which("perf")
    if perf is None or shutil.which("nm") is None or subprocess.run(
            [perf, "record", "-q", "-o", "/dev/null", "true"], capture_output=True).returncode:
        print("kernel_profile: needs Linux perf, allowed to sample here, and nm (apt install "
              "linux-perf binutils; perf_event_paranoid <= 2): nothing measured")
        return 0
    with tempfile.TemporaryDirectory() as tmp:
        data, marks = Path(tmp) / "perf.data", Path(tmp) / "marks"
        cmd = [perf, "record", "-q", "-F", "4000", "-k", "CLOCK_MONOTONIC", "-o", str(data),
               sys.executable, __file__, "--child", "--marks", str(marks), "--kind",
               args.kind, "--spp", str(args.spp), "--size", *map(str, args.size),
               *(["--peer"] if args.peer else [])]
        r = subprocess.run(cmd, capture_output=True, text=True)
        if r.returncode != 0 or not marks.is_file():
            print(r.stderr, file=sys.stderr)
            return 1
        t0, t1, rate, mapped, pid = marks.read_text().split()
        script = subprocess.run([perf, "script", "-i", str(data), "-F", "time,ip,sym,dso"],
                                capture_output=True, text=True).stdout
        Path(f"/tmp/perf-{pid}.map").unlink(missing_ok=True)
    total, rows = shares(script, float(t0), float(t1))
    who = "Mitsuba 3 scalar_rgb" if args.peer else f"ours ({int(mapped)} kernel functions named)"
    print(f"stage {args.kind}, {args.size[0]} x {args.size[1]}, {args.spp} spp, one thread, "
          f"{who}: {float(rate):.3f} M samples per CPU second; {total} samples of the render")
    for share, name in rows[:args.top]:
        print(f"{100 * share:6.1f} %  {name}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
