"""Regenerate the golden JSON of every profile (run only after a deliberate change):

    python tests/pwc/golden/regenerate.py

Nothing happens on import: pytest collects with ``--doctest-modules`` and would
otherwise rewrite the goldens from the code under test before comparing against them
(tests/conftest.py also keeps this file out of collection).
"""

import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[2]


def main() -> None:
    """Write ``<profile>.json`` beside this script for every ``profiles/*.pwc``, compiled
    by the ``pwc`` of this tree (not whichever one the environment installed)."""
    sys.path.insert(0, str(ROOT))
    import pwc
    from pwc.emit import to_json

    for path in sorted((ROOT / "profiles").glob("*.pwc")):
        curve = pwc.load(path)
        text = to_json(curve).replace(str(path), f"profiles/{path.name}")
        (HERE / f"{path.stem}.json").write_text(text)
        print(f"{path.stem}.json")


if __name__ == "__main__":
    main()
