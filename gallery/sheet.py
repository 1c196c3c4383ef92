"""The gallery's contact sheet: an HTML page of every figure beside its reference.

Per figure the page shows the Handbook's number, the scene's title and notes, the
caption (the material calls the Handbook prints under the figure), our render by the
regression rule (:mod:`gallery.compare`), the reference, the FLIP error map between the
two, and the numbers: samples, time and error against the thresholds, and how the
reference was made.  Figures are grouped by part and chapter, in the Handbook's order.

The page's images are files beside it (``sheet/NAME.png``, ``sheet/NAME_flip.png``;
references linked where they are).  A script at the end of the page counts the images
the browser decoded and writes the count into ``<body data-images-loaded="N/M">``, so a
headless browser's ``--dump-dom`` shows whether every image loaded, and marks an image
that did not with a magenta frame a screenshot shows (``tests/gallery/test_sheet.py``).
"""

from __future__ import annotations

import html
import os
import subprocess
from datetime import datetime, timezone
from pathlib import Path

import numpy as np

from gallery.compare import Outcome, reference_dir
from gallery.figures import CHAPTERS, Figure

__all__ = ["write_sheet", "error_map_rgb", "STYLE"]

STYLE = """
body { font: 14px/1.4 system-ui, sans-serif; margin: 1.5em; color: #222; background: #fafafa; }
h1 { font-size: 1.6em; margin-bottom: 0.2em; }
h2 { margin-top: 1.6em; }
h4 { margin: 0 0 0.4em; }
.summary { margin: 0.6em 0 1em; }
.pass { color: #176b2c; }
.fail { color: #b00020; font-weight: bold; }
figure { margin: 0 0 1.2em; padding: 0.8em; background: #fff; border: 1px solid #ddd; }
figure.failed { border: 2px solid #b00020; }
.images { display: flex; gap: 0.8em; flex-wrap: wrap; }
.images div { text-align: center; font-size: 0.85em; color: #555; }
.images img { width: 384px; height: 288px; object-fit: contain; image-rendering: pixelated;
  display: block; background: #000; }
img.broken { outline: 8px solid #ff00ff; outline-offset: -8px; }
figcaption code { background: #f0f0f0; padding: 0 0.2em; }
.notes { color: #555; font-size: 0.9em; max-width: 70em; }
table.numbers { border-collapse: collapse; font-size: 0.85em; margin-top: 0.5em; }
table.numbers td, table.numbers th { border: 1px solid #ddd; padding: 0.15em 0.5em;
  text-align: left; }
"""

_SCRIPT = """
<script>
window.addEventListener("load", function () {
  var images = Array.prototype.slice.call(document.images);
  var loaded = images.filter(function (i) { return i.complete && i.naturalWidth > 0; });
  document.body.setAttribute("data-images-loaded", loaded.length + "/" + images.length);
  images.forEach(function (i) {
    if (!(i.complete && i.naturalWidth > 0)) i.classList.add("broken");
  });
});
</script>
"""


def error_map_rgb(err: np.ndarray) -> np.ndarray:
    """FLIP's magma colour map of an (h, w) error map in [0, 1]: (h, w, 3) in [0, 1]."""
    from matplotlib import colormaps

    return colormaps["magma"](np.clip(err, 0.0, 1.0))[..., :3]


def _save_srgb_png(path: Path, rgb01: np.ndarray) -> None:
    from PIL import Image

    Image.fromarray(np.round(np.clip(rgb01, 0, 1) * 255).astype(np.uint8), "RGB").save(path)


def _commit() -> str:
    """The checkout's commit, when there is one (the page says what it shows)."""
    try:
        r = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=Path(__file__).parent,
                           capture_output=True, text=True, timeout=10)
    except (OSError, subprocess.SubprocessError):
        return ""
    return r.stdout.strip() if r.returncode == 0 else ""


def _figure_html(fig: Figure, outcome: Outcome | None, entry: dict, images: dict,
                 error: str | None) -> str:
    e = html.escape
    ref = entry.get("reference", {})
    test = entry.get("test", {})
    captions = "<br>".join(f"<code>{e(c)}</code>" for c in fig.captions)
    status = ("<span class='fail'>no reference</span>" if error else
              "<span class='pass'>passed</span>" if outcome.passed else
              "<span class='fail'>FAILED: " + e("; ".join(outcome.reasons())) + "</span>")
    cells = []
    for key, label in (("render", "our render"), ("reference", "reference"),
                       ("flip", "FLIP error (render vs reference)")):
        if key in images:
            cells.append(f"<div><img src='{e(images[key])}' alt='{e(fig.name)} {label}'>"
                         f"{label}</div>")
    rows = []
    if outcome is not None:
        w, h = fig.test_resolution
        rows.append(f"<tr><th>render</th><td>{w} x {h}, {outcome.spp} spp, seed "
                    f"{test.get('seed', '')}, {outcome.time_s:.1f} s</td></tr>")
        rows.append(f"<tr><th>error</th><td>RMSE {outcome.rmse:.4f} (max "
                    f"{outcome.rmse_max:.4f}), FLIP {outcome.flip:.4f} (max "
                    f"{outcome.flip_max:.4f}), mean off by "
                    f"{', '.join(f'{d:.4f}' for d in outcome.mean_diff)} (max "
                    f"{', '.join(f'{t:.4f}' for t in outcome.mean_tol)})</td></tr>")
    if ref:
        rw, rh = ref["resolution"]
        rows.append(f"<tr><th>reference</th><td>{rw} x {rh}, {ref['spp']} spp in "
                    f"{ref['batches']} batches, noise {ref['noise']:.2f} of 255 (target "
                    f"{ref['noise_target']:g}), {ref['time_s']:.0f} s</td></tr>")
    klass = " class='failed'" if error or not outcome.passed else ""
    return (f"<figure id='{e(fig.name)}'{klass}>\n<figcaption><h4>Figure {e(fig.number)}: "
            f"{e(fig.title)}</h4>{captions}<p class='notes'>{e(fig.notes)}</p>"
            f"</figcaption>\n<div class='images'>{''.join(cells)}</div>\n"
            f"<table class='numbers'>{''.join(rows)}<tr><th>result</th><td>{status}</td>"
            f"</tr></table>\n</figure>\n")


def write_sheet(path: str | Path, results: list[tuple[Figure, Outcome | None]], table: dict,
                references: Path | None = None) -> Path:
    """Write the contact sheet ``path`` (and its images in ``sheet/`` beside it).

    Parameters
    ----------
    path : path of the HTML page
    results : list of (Figure, Outcome or None)
        The figures in the page's order, each with its checked render (None: the figure
        has no reference, which the page says).
    table : dict
        The references table (:func:`gallery.compare.read_table`).
    references : path, optional
        The folder of the reference images (default: the bundled one).
    """
    from render.film import write_png_rgb

    path = Path(path)
    folder = path.parent / "sheet"
    folder.mkdir(parents=True, exist_ok=True)
    references = references or reference_dir()
    body, part, chapter = [], None, None
    failed = sum(1 for _, o in results if o is None or not o.passed)
    for fig, outcome in results:
        if fig.part != part:
            part = fig.part
            body.append(f"<h2>{html.escape(part)}</h2>\n")
        if fig.chapter != chapter:
            chapter = fig.chapter
            body.append(f"<h3 id='chapter-{chapter}'>Chapter {chapter}: "
                        f"{html.escape(CHAPTERS.get(chapter, ''))}</h3>\n")
        images = {}
        ref_png = references / f"{fig.name}.png"
        if ref_png.is_file():
            images["reference"] = Path(os.path.relpath(ref_png, path.parent)).as_posix()
        if outcome is not None:
            write_png_rgb(folder / f"{fig.name}.png", outcome.image)
            _save_srgb_png(folder / f"{fig.name}_flip.png", error_map_rgb(outcome.error_map))
            images["render"] = f"sheet/{fig.name}.png"
            images["flip"] = f"sheet/{fig.name}_flip.png"
        body.append(_figure_html(fig, outcome, table.get(fig.name, {}), images,
                                 None if outcome is not None else "no reference"))
    contents = " · ".join(f"<a href='#chapter-{c}'>{c}. {html.escape(CHAPTERS.get(c, ''))}</a>"
                          for c in dict.fromkeys(f.chapter for f, _ in results))
    commit = _commit()
    when = datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    verdict = (f"<span class='pass'>all {len(results)} figures pass</span>" if not failed else
               f"<span class='fail'>{failed} of {len(results)} figures fail</span>")
    page = (
        "<!DOCTYPE html>\n<html lang='en'>\n<head>\n<meta charset='utf-8'>\n"
        "<title>Gallery: the MDL Handbook's figures, rendered</title>\n"
        f"<style>{STYLE}</style>\n</head>\n<body>\n"
        "<h1>Gallery: the MDL Handbook's figures, rendered</h1>\n"
        "<p>Each figure: our render by the regression rule (small and noisy on purpose: "
        "the test's image), the converged reference, and FLIP's error map between them "
        "(black: no visible difference; yellow: large).  A render passes when its RMSE and "
        "mean FLIP stay within 1.5 times the largest measured at four other seeds, and its "
        "mean within the seeds' spread.  Generated by <code>pwc gallery sheet</code>"
        f"{' at commit ' + html.escape(commit) if commit else ''}, {when}; do not edit "
        "by hand.</p>\n"
        f"<p class='summary'>{verdict}</p>\n<p>Chapters: {contents}</p>\n" + "".join(body)
        + _SCRIPT + "</body>\n</html>\n")
    path.write_text(page, encoding="utf-8")
    return path
