"""Regenerate the golden JSON of every profile (run only after a deliberate change):

    python tests/pwc/golden/regenerate.py
"""

from pathlib import Path

import pwc
from pwc.emit import to_json

HERE = Path(__file__).resolve().parent
for path in sorted((HERE.parents[2] / "profiles").glob("*.pwc")):
    curve = pwc.load(path)
    text = to_json(curve).replace(str(path), f"profiles/{path.name}")
    (HERE / f"{path.stem}.json").write_text(text)
    print(f"{path.stem}.json")
