"""The report of a trade: Markdown and HTML, the plots, every run, and the recommended
scene file.

Both pages are written from one list of blocks (headings, paragraphs, tables, images,
code), so they say the same.  Files, in the report folder:

* ``report.md``, ``report.html``;
* ``error_vs_time.png``: each run's error against its wall time and against its peak
  memory, the Pareto front drawn through the runs no other beats on both, the target
  dashed, the scene as written and the recommendation marked;
* ``images/``: the reference and every run, sRGB previews;
* ``runs.json``: every number of every run;
* ``recommended.toml``: the recommendation as a scene file (``pwc render`` it).
"""

from __future__ import annotations

import html
import json
from pathlib import Path

from trade.knobs import describe
from trade.metrics import METRICS
from trade.sweep import COSTS

__all__ = ["write_report"]

#: colours of the knob families in the plot
FAMILY_COLORS = {"baseline": "black", "samples": "tab:blue", "dicing": "tab:orange",
                 "displacement": "tab:green", "curves": "tab:purple",
                 "textures": "tab:brown", "paths": "tab:gray", "combined": "tab:red"}


# --------------------------------------------------------------------------- blocks
def _md(blocks) -> str:
    out = []
    for kind, *args in blocks:
        if kind == "h":
            out.append("#" * args[0] + " " + args[1])
        elif kind == "p":
            out.append(args[0])
        elif kind == "ul":
            out.append("\n".join(f"* {x}" for x in args[0]))
        elif kind == "code":
            out.append("```\n" + args[0] + "\n```")
        elif kind == "img":
            out.append(f"![{args[1]}]({args[0]})")
        elif kind == "imgs":
            out.append(" ".join(f"![{cap}]({src})" for src, cap in args[0]) + "\n\n"
                       + " · ".join(f"{i + 1}: {cap}" for i, (_, cap) in enumerate(args[0])))
        elif kind == "table":
            head, rows = args
            out.append("| " + " | ".join(head) + " |\n|" + "---|" * len(head) + "\n"
                       + "\n".join("| " + " | ".join(r) + " |" for r in rows))
    return "\n\n".join(out) + "\n"


def _inline(text: str) -> str:
    """HTML of a Markdown line: escapes, then **bold** and `code`."""
    import re

    t = html.escape(text, quote=False)
    t = re.sub(r"\*\*(.+?)\*\*", r"<b>\1</b>", t)
    return re.sub(r"`(.+?)`", r"<code>\1</code>", t)


def _html(blocks, title: str) -> str:
    body = []
    for kind, *args in blocks:
        if kind == "h":
            body.append(f"<h{args[0]}>{_inline(args[1])}</h{args[0]}>")
        elif kind == "p":
            body.append(f"<p>{_inline(args[0])}</p>")
        elif kind == "ul":
            body.append("<ul>" + "".join(f"<li>{_inline(x)}</li>" for x in args[0]) + "</ul>")
        elif kind == "code":
            body.append(f"<pre><code>{html.escape(args[0])}</code></pre>")
        elif kind == "img":
            body.append(f'<figure><img src="{html.escape(args[0])}" alt="{html.escape(args[1])}">'
                        f"<figcaption>{_inline(args[1])}</figcaption></figure>")
        elif kind == "imgs":
            body.append('<div class="images">' + "".join(
                f'<figure><img class="run" src="{html.escape(src)}" alt="{html.escape(cap)}">'
                f"<figcaption>{_inline(cap)}</figcaption></figure>" for src, cap in args[0])
                + "</div>")
        elif kind == "table":
            head, rows = args
            body.append("<table><thead><tr>" + "".join(f"<th>{_inline(h)}</th>" for h in head)
                        + "</tr></thead><tbody>" + "".join(
                            "<tr>" + "".join(f"<td>{_inline(c)}</td>" for c in r) + "</tr>"
                            for r in rows) + "</tbody></table>")
    style = ("body{font-family:sans-serif;max-width:80em;margin:2em auto;line-height:1.4}"
             "table{border-collapse:collapse;font-size:90%}td,th{border:1px solid #ccc;"
             "padding:2px 6px;text-align:right}td:nth-child(2),th:nth-child(2){text-align:left}"
             "figure{display:inline-block;margin:0 1em 1em 0}img{max-width:100%}"
             "img.run{image-rendering:pixelated;width:256px}code{background:#f4f4f4}")
    # the page counts its images once loaded (tests open it in a headless browser)
    script = ("window.addEventListener('load',()=>{const i=[...document.images];"
              "document.body.dataset.imagesLoaded=i.filter(x=>x.complete&&x.naturalWidth>0)"
              ".length+'/'+i.length;});")
    return (f"<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
            f"<title>{html.escape(title)}</title><style>{style}</style>"
            f"<script>{script}</script></head>\n<body>\n" + "\n".join(body)
            + "\n</body></html>\n")


# ---------------------------------------------------------------------------- plots
def plot(trade, path: Path) -> None:
    """``error_vs_time.png``: error against wall time and against peak memory."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker

    runs = trade.runs
    metric = trade.metric
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.6), constrained_layout=True)
    cost = COSTS[trade.cost]
    what = "wall time" if trade.cost == "wall" else "CPU time"
    for ax, key, xlabel in ((axes[0], cost, f"{what} (s): read, dice, trace, denoise"),
                            (axes[1], "peak_mb", "peak memory above the start (MB)")):
        for family in dict.fromkeys(r.family for r in runs):
            pts = [r for r in runs if r.family == family]
            ax.scatter([r.record[key] for r in pts], [max(r.error(metric), 1e-6) for r in pts],
                       s=22, color=FAMILY_COLORS.get(family, "tab:olive"), label=family,
                       zorder=3)
        front = sorted((r for r in runs if r.pareto), key=lambda r: r.record[cost])
        if key == cost and front:
            ax.step([r.record[key] for r in front], [max(r.error(metric), 1e-6) for r in front],
                    where="post", color="tab:red", lw=1.2, alpha=0.7, label="Pareto front",
                    zorder=2)
            ax.scatter([r.record[key] for r in front],
                       [max(r.error(metric), 1e-6) for r in front], s=90, facecolors="none",
                       edgecolors="tab:red", zorder=4)
        ax.axhline(trade.target, color="k", ls="--", lw=0.8, label=f"target {trade.target:g}")
        base = runs[0]
        ax.annotate("as written", (base.record[key], max(base.error(metric), 1e-6)),
                    textcoords="offset points", xytext=(6, 6), fontsize=8)
        if trade.recommended is not None:
            r = trade.recommended
            ax.scatter([r.record[key]], [max(r.error(metric), 1e-6)], marker="*", s=220,
                       color="gold", edgecolors="k", zorder=5, label="recommended")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())  # no crowded labels
        ax.set_xlabel(xlabel)
        ax.set_ylabel(f"{METRICS[metric]} vs reference")
        ax.grid(True, which="both", alpha=0.25)
    axes[0].legend(fontsize=7, loc="best")
    fig.suptitle(f"{trade.scene_path.name}: error against cost "
                 f"({trade.resolution[0]} x {trade.resolution[1]} px)")
    fig.savefig(path, dpi=110)
    plt.close(fig)


# --------------------------------------------------------------------------- report
def _f(v, fmt=".3g") -> str:
    return "—" if v is None else format(v, fmt)


def _blocks(trade, out: Path, command: str) -> list:
    runs, metric, names = trade.runs, trade.metric, trade.names
    base = runs[0]
    rec = trade.recommended
    ref = trade.reference
    b: list = [("h", 1, f"Speed/accuracy trade: {trade.scene_path.name}")]
    b.append(("p", f"Scene `{trade.scene_path.name}` at {trade.resolution[0]} x "
                   f"{trade.resolution[1]} px; target: **{METRICS[metric]} <= "
                   f"{trade.target:g}** against a converged reference; {len(runs)} runs "
                   f"measured in {trade.elapsed_s:.0f} s ({trade.size} sweep"
                   + (f", budget {trade.budget:g} s" if trade.budget else "") + ")."))
    settings = ref.get("settings") or describe(ref["patch"], names)
    if ref.get("spp") is None:
        ref_line = f"Reference: the image {ref['source']} (given)."
    else:
        ref_line = (f"Reference: {ref['spp']} spp, {settings}; rendered in "
                    f"{ref['wall_s']:.1f} s"
                    + (", reused from an earlier run of the same scene, settings and code"
                       if ref.get("reused") else "") + ".")
    b.append(("p", ref_line))
    b.append(("h", 2, "Recommendation"))
    if rec is None:
        best = min(runs, key=lambda r: r.error(metric))
        b.append(("p", f"No measured run meets the target: the most accurate, "
                       f"**{best.label}**, has {metric} {best.error(metric):.4g}. Raise the "
                       f"target, or the samples (the reference settings meet any target). "
                       f"`recommended.toml` is the scene as written."))
    else:
        cost = COSTS[trade.cost]
        speed = base.record[cost] / rec.record[cost]
        b.append(("p", f"**{rec.label}**: {describe(rec.patch, names)}."))
        b.append(("ul", [
            f"{metric} {rec.error(metric):.4g} (target {trade.target:g}); the scene as "
            f"written: {base.error(metric):.4g}",
            f"{rec.record[cost]:.3g} {trade.cost} s against {base.record[cost]:.3g} s as "
            f"written: **{speed:.2f}x** {'faster' if speed >= 1 else 'slower'} (wall "
            f"{rec.record['wall_s']:.3g} s against {base.record['wall_s']:.3g} s)",
            f"peak memory {rec.record['peak_mb']:.0f} MB (as written "
            f"{base.record['peak_mb']:.0f} MB), {rec.record['triangles']:,} triangles "
            f"(as written {base.record['triangles']:,})",
            "written out as `recommended.toml`: `pwc render recommended.toml -o out.exr`",
        ]))
    b.append(("h", 2, "What the scene models"))
    b.append(("p", "Each object as the scene is written (the first run): how its geometry "
                   "was built, how its displacement is modelled, whether a bumped normal is "
                   "evaluated, and the distribution functions its material's programs use. "
                   "Knobs that cannot change the scene are not swept."))
    b.append(("table", ["object", "geometry", "displacement", "normal", "dfs", "emits",
                        "volume"],
              [[m["name"], m["geometry"], m["displacement"], m["normal"],
                ", ".join(m["dfs"]), "yes" if m["emits"] else "no",
                "yes" if m["volume"] else "no"] for m in trade.modelled]))
    loads = trade.loads
    b.append(("p", "Lights: " + (", ".join(trade.lights) or "none") + ". Profiles loaded: "
                   + (", ".join(loads.get("profiles", [])) or "none") + "; image textures: "
                   + (", ".join(loads.get("textures", [])) or "none") + "."))
    b.append(("h", 2, "Error against cost"))
    b.append(("img", "error_vs_time.png", f"{METRICS[metric]} against wall time and peak "
                                          "memory; Pareto front in red; target dashed"))
    b.append(("h", 2, "Every run"))
    b.append(("p", "Wall time covers reading the scene (materials, profiles, textures, "
                   "baked maps), dicing and building the Embree scene, tracing and "
                   "denoising; CPU time is the process's (both threads) over the same "
                   "span, which other programs' load changes much less; speed-ups and the "
                   f"Pareto front are in **{trade.cost}** time. Peak memory is the resident "
                   "set above the process's at the run's start. Geometric error: the "
                   "largest screen distance (px) between the traced triangles and the true "
                   "displaced surface. All runs use the scene's seed (so each is the image "
                   "its scene file renders), the reference another."))
    head = ["#", "run", "knob", "wall s", "CPU s", "speed-up", "peak MB", "triangles",
            "rays (M)", "RMSE", "rel RMSE", "FLIP", "rel mean", "geom px", "meets", "Pareto"]
    rows = []
    for r in runs:
        e = r.errors
        rows.append([str(r.index), r.label, r.family, f"{r.record['wall_s']:.3g}",
                     f"{r.record['cpu_s']:.3g}",
                     f"{base.cost(trade.cost) / r.cost(trade.cost):.2f}x",
                     f"{r.record['peak_mb']:.0f}", f"{r.record['triangles']:,}",
                     f"{r.record['rays'] / 1e6:.2f}", f"{e['rmse']:.3g}",
                     f"{e['rel_rmse']:.3g}", f"{e['flip']:.3g}", f"{e['rel_mean']:.2g}",
                     _f(r.geometric_px), "yes" if r.meets else "no",
                     "**front**" if r.pareto else ""])
    b.append(("table", head, rows))
    if trade.skipped:
        b.append(("p", f"Not run (past the {trade.budget:g} s budget): "
                       + "; ".join(trade.skipped) + "."))
    b.append(("h", 2, "Images"))
    images = ([("images/reference.png", "reference")]
              if (out / "images" / "reference.png").is_file() else [])
    images.append((base.image, "the scene as written"))
    if rec is not None and rec is not base:
        images.append((rec.image, f"recommended: {rec.label}"))
    b.append(("imgs", images))
    b.append(("h", 2, "Reproduce"))
    b.append(("code", command))
    return b


def write_report(trade, out: Path, command: str = "") -> dict[str, Path]:
    """Write the report files into ``out``; returns them by name."""
    out = Path(out)
    files = {"plot": out / "error_vs_time.png", "markdown": out / "report.md",
             "html": out / "report.html", "json": out / "runs.json",
             "scene": out / "recommended.toml"}
    plot(trade, files["plot"])
    blocks = _blocks(trade, out, command or f"pwc trade {trade.scene_path} -o {out}")
    title = f"Speed/accuracy trade: {trade.scene_path.name}"
    files["markdown"].write_text(_md(blocks), encoding="utf-8")
    files["html"].write_text(_html(blocks, title), encoding="utf-8")
    files["json"].write_text(json.dumps({
        "scene": str(trade.scene_path), "resolution": list(trade.resolution),
        "metric": trade.metric, "target": trade.target, "cost": trade.cost,
        "reference": {k: v for k, v in trade.reference.items() if k != "patch"},
        "recommended": trade.recommended.index if trade.recommended else None,
        "modelled": trade.modelled, "lights": trade.lights, "loads": trade.loads,
        "skipped": trade.skipped,
        "runs": [{"index": r.index, "label": r.label, "family": r.family, "patch": r.patch,
                  **{k: v for k, v in r.record.items()}, "errors": r.errors,
                  "geometric_px": r.geometric_px, "meets": r.meets, "pareto": r.pareto,
                  "image": r.image} for r in trade.runs]}, indent=1, default=str),
        encoding="utf-8")
    header = (f"# pwc trade: the cheapest measured settings of {trade.scene_path.name} with "
              f"{trade.metric} <= {trade.target:g}\n"
              + (f"# ({trade.recommended.label})\n" if trade.recommended else
                 "# (no run met the target: the scene as written)\n"))
    scene_file = files["scene"]
    header += (f"# Files it names (meshes, textures, profiles) are found as beside "
               f"{trade.scene_path.name}: keep the two files in one folder.\n")
    scene_file.write_text(header + trade.recommended_text, encoding="utf-8")
    return files
