"""The contact sheet in a real headless browser (Debian's chromium): every image loads,
as the page's own count says and a screenshot shows; a missing one is caught."""

from __future__ import annotations

import re
import shutil
import subprocess

import numpy as np
import pytest
from PIL import Image

from gallery import compare
from gallery.figures import figures
from gallery.sheet import write_sheet

CHROMIUM = next((p for p in map(shutil.which, ("chromium", "chromium-browser",
                                                "google-chrome")) if p), None)
pytestmark = pytest.mark.skipif(
    CHROMIUM is None, reason="needs a headless browser: install Debian's chromium "
                             "(apt-get install chromium, as .ci/run does)")

MAGENTA = np.array([255, 0, 255])


def _chromium(tmp_path, *args) -> subprocess.CompletedProcess:
    cmd = [CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars",
           "--no-first-run", f"--user-data-dir={tmp_path / 'profile'}",
           "--virtual-time-budget=10000", *args]
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr[-3000:]
    return r


def _open(tmp_path, page):
    """(loaded, total) images by the page's count, and the screenshot's (h, w, 3) pixels."""
    dom = _chromium(tmp_path, "--dump-dom", page.as_uri()).stdout
    m = re.search(r'data-images-loaded="(\d+)/(\d+)"', dom)
    assert m, "the page's script did not run: " + dom[:500]
    shot = tmp_path / f"{page.stem}.png"
    _chromium(tmp_path, f"--screenshot={shot}", "--window-size=1300,1400", page.as_uri())
    with Image.open(shot) as img:
        pixels = np.asarray(img.convert("RGB"))
    return (int(m.group(1)), int(m.group(2))), pixels


def test_every_image_of_the_sheet_loads_in_a_browser_and_a_missing_one_is_caught(tmp_path):
    table = compare.read_table()
    results = [(fig, compare.check(fig, table)) for fig in figures(["13.3", "14.3"])]
    page = write_sheet(tmp_path / "site" / "index.html", results, table)

    (loaded, total), shot = _open(tmp_path, page)
    assert (loaded, total) == (6, 6)  # render, reference and FLIP map of two figures
    magenta = np.all(shot == MAGENTA, axis=2)
    assert not magenta.any()
    # the images are on the screenshot, not a blank page: Figure 13.3 shows uv as
    # colour(u, v, 0), green where v is large, in its render and its reference
    assert shot.shape[:2] == (1400, 1300)
    r, g, b = (shot[..., c].astype(int) for c in range(3))
    assert ((g > 100) & (g > r + 20) & (g > b + 40)).sum() > 5000

    (page.parent / "sheet" / "fig_13_03_flip.png").unlink()
    (loaded, total), shot = _open(tmp_path, page)
    assert (loaded, total) == (5, 6)
    assert np.all(shot == MAGENTA, axis=2).sum() > 1000  # the broken image's frame
