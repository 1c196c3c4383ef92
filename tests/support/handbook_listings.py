"""The Handbook's MDL listings of Parts 2-5, extracted from its text and made into modules.

The text is the book as printed: each listing is ``Listing N.M`` followed by a fenced code
block (a listing broken by a page continues in the next block, with only blank lines
between), and the code carries the book's margin notes on the same lines and on lines of
their own (``tint: tint));  Using the "tint" parameter``).  :func:`listings` finds the
listings, :func:`clean` removes the notes (a note is English after the end of a code
construct, or a line of English; its continuation lines sit in its column), and
:func:`repair` fixes the two misprints the book repeats: a missing final ``;`` and
unbalanced closing parentheses at the end of a definition (each repair is recorded).

:func:`assemble` makes a listing a module: the standard modules imported, and the
definitions it uses from other listings (the latest printed before it, else the first
after it) or, for what the book never lists, from the workbench's modules
(``::functions``, ``::materials``, ``::pw_curve``...).  Nothing here is specific to one
listing: a listing that does not survive these rules is reported, with the reason.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

from repo import HANDBOOK

from mdl import ast as A
from mdl.diagnostics import MdlError, Source
from mdl.parser import parse_module

__all__ = ["Listing", "listings", "clean", "repair", "assemble", "HANDBOOK"]

KEYWORDS = set("""in return if else for while do let switch case default break continue const
export import using struct enum typedef mdl true false uniform varying material bsdf edf vdf
float double int bool string color texture_2d float2 float3 float4 double2 double3 int2 int3
bool2 auto light_profile bsdf_measurement hair_bsdf annotation float3x3 float4x4 float2x2
cast""".split())
_WORD = re.compile(r"[A-Za-z][A-Za-z'\-]*[,.:]?")
_CODE_CHARS = re.compile(r"""[;(){}=\[\]<>+*/?!&|"]|::|\s-|^-|\s:|^:|\b[a-z_][a-z0-9_]*:\s""")
_CODE_END = re.compile(r"[;,(){}\[\]=+\-*/<>&|?:!]$")

HEADER = """\
mdl 1.7;
import ::df::*;
import ::state::*;
import ::math::*;
import ::tex::*;
import ::anno::*;
import ::debug::*;
import ::base::*;
import ::pw_curve::*;
import ::functions::*;
import ::geometry::*;
import ::materials::*;
"""


@dataclass
class Listing:
    number: str              # "9.18"
    line: int                # 1-based line of "Listing 9.18" in the book
    raw: list[str]           # the printed code lines
    code: str = ""           # notes removed
    repairs: list[str] = field(default_factory=list)
    tree: A.Module | None = None
    error: str = ""          # why it does not parse

    @property
    def chapter(self) -> int:
        return int(self.number.split(".")[0])

    @property
    def key(self) -> tuple[int, int]:
        a, b = self.number.split(".")
        return int(a), int(b)

    def names(self) -> list[str]:
        """The top-level names the listing declares."""
        out = []
        for d in self.tree.decls if self.tree else ():
            if isinstance(d, A.FunctionDecl):
                out.append(d.name)
            elif isinstance(d, (A.StructDecl, A.EnumDecl)):
                out.append(d.name)
                out += [v.name for v in getattr(d, "values", ())]
            elif isinstance(d, A.ConstDecl):
                out += [c.name for c in d.decl.declarators]
            elif isinstance(d, A.Typedef):
                out.append(d.name)
        return out


def _part_bounds(lines: list[str]) -> tuple[int, int]:
    starts = [i for i, x in enumerate(lines) if x.startswith("Part 2 Light interaction")]
    ends = [i for i, x in enumerate(lines) if x.startswith("Part 6 Reference")]
    return starts[-1], ends[-1]


def _block(lines: list[str], j: int) -> tuple[list[str], int]:
    k = j + 1
    while k < len(lines) and not lines[k].startswith("```"):
        k += 1
    return lines[j + 1:k], k


def listings(text: str | None = None) -> list[Listing]:
    """Every listing of Parts 2-5 in printed order, cleaned and parsed (or with the parse
    error)."""
    if text is None:
        text = HANDBOOK.read_text(encoding="utf-8")
    lines = text.split("\n")
    start, end = _part_bounds(lines)
    out = []
    i = start
    while i < end:
        m = re.match(r"^Listing (\d+\.\d+)", lines[i])
        if m:
            j = i + 1
            while not lines[j].startswith("```"):
                j += 1
            code, k = _block(lines, j)
            while True:  # a listing continued after a page break
                n = k + 1
                while n < len(lines) and not lines[n].strip():
                    n += 1
                if n < end and lines[n].strip() == "```":
                    more, k = _block(lines, n)
                    code += more
                else:
                    break
            out.append(_prepare(Listing(m.group(1), i + 1, code)))
            i = k
        i += 1
    return out


def _plain(w: str) -> bool:
    return bool(_WORD.fullmatch(w)) and w.rstrip(",.:") not in KEYWORDS


def is_note(text: str, continuation: bool = False) -> bool:
    """Whether ``text`` (the end of a line, or a line) is English rather than MDL."""
    t = text.strip()
    if not t or t.startswith("//"):
        return False
    if re.search(r"[;{}]|::", t) and not re.match(r"^[A-Z\"']", t):
        return False
    words = t.split()
    if re.match(r"^[\"']", t) or "→" in t or "°" in t:
        return True
    if words[0].rstrip(",);") in KEYWORDS or (re.search(r"[,);]$", words[0])
                                               and len(words) == 1):
        return False
    if words[0][0].isupper() and _plain(words[0]) and not re.search(r"[;{}]|::", t):
        return True
    if continuation and not re.search(r"[;(){}=]|::|\b[a-z_][a-z0-9_]*:\s", t):
        return True
    if not _plain(words[0]) or re.search(r"[,);:]$", words[0]):
        return False  # code: an argument's name (``tint:``), a value followed by ',' ...
    return len(words) > 1 and _plain(words[1])


def clean(raw: list[str]) -> str:
    """The listing's code without the margin notes (lines kept, so line numbers match)."""
    out = []
    note_col = None
    for line in raw:
        line = (line.replace("\u00a0", " ").replace("“", '"').replace("”", '"')
                .replace("’", "'").rstrip())
        indent = len(line) - len(line.lstrip())
        single = len(line.split()) == 1 and _plain(line.strip())
        if line.strip() and is_note(line, continuation=True) and (
                note_col is not None and (indent >= note_col - 6 or single) or indent >= 24):
            out.append("")
            continue
        previous, note_col = note_col, None
        cut = None
        for m in re.finditer(r"(\S)(\s+)(?=\S)", line):
            pre, post = line[:m.end(1)], line[m.end():]
            wide = len(m.group(2)) >= 3 and post[:1].isupper() and is_note(post)
            if not _CODE_END.search(pre) and not wide:
                continue
            if previous is not None and m.end() >= previous - 2 and \
                    is_note(post, continuation=True):
                cut, note_col = m.end(1), previous  # the note of the line above goes on
                break
            statement_end = pre.endswith((";", "{")) and not post.startswith(("}", "//")) \
                and post.split()[0].rstrip(",;") not in KEYWORDS \
                and pre.count("(") == pre.count(")")  # not inside for (...; ...; ...)
            if statement_end or is_note(post):
                cut, note_col = m.end(1), m.end()
                break
        words = line.split()
        if cut is None and words and not _CODE_CHARS.search(line) and \
                words[0] not in KEYWORDS and not line.strip().endswith(",") and \
                (len(words) > 1 or words[0][0].isupper()):
            out.append("")  # a note on a line of its own
            note_col = indent
            continue
        out.append(line[:cut] if cut is not None else line)
    return "\n".join(out).strip("\n") + "\n"


def _parse(code: str, name: str):
    return parse_module(Source(name, "mdl 1.7;\n" + code))


def _balance(code: str) -> int:
    body = re.sub(r'"(?:\\.|[^"\\])*"', "", re.sub(r"//[^\n]*", "", code))
    return body.count("(") - body.count(")")


def repair(code: str) -> tuple[str, list[str]]:
    """The book's two repeated misprints fixed at the end of the listing: unbalanced
    closing parentheses and a missing final ';'.  Returns (code, repairs)."""
    repairs = []
    text = code.rstrip()
    k = _balance(text)
    if k != 0:
        body = text[:-1] if text.endswith(";") else text
        if k > 0:
            body += ")" * k
            repairs.append(f"added {k} missing ')'")
        else:
            m = re.search(r"\)+\s*$", body)
            if m and len(m.group(0).strip()) >= -k:
                body = body[:len(body.rstrip()) + k]
                repairs.append(f"removed {-k} extra ')'")
        text = body + (";" if text.endswith(";") else "")
    if not text.endswith((";", "}")):
        text += ";"
        repairs.append("added the missing final ';'")
    return text + "\n", repairs


def _prepare(lst: Listing) -> Listing:
    lst.code = clean(lst.raw)
    try:
        lst.tree = _parse(lst.code, f"Listing {lst.number}")
        return lst
    except MdlError as e:
        first = e.first
    fixed, repairs = repair(lst.code)
    try:
        lst.tree = _parse(fixed, f"Listing {lst.number}")
        lst.code, lst.repairs = fixed, repairs
    except MdlError:
        d = first
        lst.error = f"{d.message} (line {d.loc.line - 1}: {d.loc.text.strip()[:60]!r})"
    return lst


def _missing(e: MdlError) -> list[str]:
    out = []
    for d in e.diagnostics:
        m = re.search(r"(?:undeclared identifier|unknown function|unknown type|unknown "
                      r"material) '([A-Za-z_][A-Za-z0-9_]*)'", d.message)
        if m:
            out.append(m.group(1))
    return out


#: the workbench's modules that stand in for definitions the book never lists (or prints
#: unusably): their exported names may be imported by a listing's module
FALLBACK_MODULES = ("::functions", "::pw_curve", "::geometry", "::materials", "::base",
                    "::perlin_noise")


def _signature(d) -> str:
    from mdl.printer import format_expression  # noqa: F401 - the printer's type names

    if not isinstance(d, A.FunctionDecl) or d.params is None:
        return ""
    return ",".join(re.sub(r"\s+", "", str(getattr(p.type, "name", p.type)))
                    for p in d.params)


def _definitions(lst: Listing) -> dict:
    """name -> signature of each top-level definition of ``lst``."""
    out = {}
    for d in lst.tree.decls if lst.tree else ():
        if isinstance(d, A.FunctionDecl):
            out[(d.name, _signature(d))] = d
    for n in lst.names():
        out.setdefault((n, None), None)
    return out


def fallbacks(loader) -> dict[str, str]:
    """Exported name -> the workbench module that exports it."""
    out = {}
    for q in FALLBACK_MODULES:
        for name in loader.load(q).exports():
            out.setdefault(name, q)
    return out


def _workbench_types(loader) -> dict[str, list[str]]:
    """Each enum or struct the fallback modules export, and each enum value, -> the names
    to import for it (the type and all its values)."""
    from mdl import types as T
    from mdl.entities import TypeEntity

    out = {}
    for q in FALLBACK_MODULES:
        for name, ents in loader.load(q).exports().items():
            for ent in ents:
                if isinstance(ent, TypeEntity) and isinstance(ent.type, T.EnumType):
                    names = [name] + [v for v, _ in ent.type.values]
                    for x in names:
                        out.setdefault(x, names)
                elif isinstance(ent, TypeEntity) and isinstance(ent.type, T.StructType):
                    out.setdefault(name, [name])
    return out


_CHECKING: dict[int, bool | None] = {}


def _checks(lst: Listing, every, loader_factory) -> bool:
    """Whether ``lst`` makes a module that checks (memoized; a listing being checked
    counts as usable, so mutual use terminates)."""
    key = id(lst)
    if key not in _CHECKING:
        _CHECKING[key] = None
        try:
            assemble(lst, every, loader_factory)
            _CHECKING[key] = True
        except MdlError:
            _CHECKING[key] = False
    return _CHECKING[key] is not False


@dataclass
class Assembled:
    module: object
    listings: list[Listing]      # the other listings whose definitions it uses
    workbench: dict[str, str]    # names taken from the workbench's modules


def assemble(target: Listing, every: list[Listing], loader_factory,
             max_rounds: int = 16) -> Assembled:
    """The checked module of ``target``: its code after the definitions it needs from other
    listings (found by name and signature, transitively; for a function printed with
    several signatures, each one).  A definition the book never lists, or one whose
    listing does not check itself, comes from the workbench's modules.  Raises
    :class:`MdlError` when the module does not check."""
    by_name: dict[str, list[Listing]] = {}
    for lst in every:
        if lst.tree is not None and lst is not target:
            for n in lst.names():
                by_name.setdefault(n, []).append(lst)
    used: list[Listing] = []
    bad: set[int] = set()
    from_workbench: dict[str, str] = {}
    own = set(target.names())
    stand_ins = None
    profiles: set[str] = set()
    types: dict[str, list[str]] = {}  # workbench enum/struct -> the names it brings
    while True:
        parts = sorted(used, key=lambda x: x.key)
        header = HEADER + "".join(f"import {q}::*;\n" for q in sorted(profiles)) + "".join(
            f"using {q} import {n};\n" for n, q in sorted(from_workbench.items()))
        text = header
        ranges = []
        for x in parts + [target]:
            first = text.count("\n") + 1
            text += x.code
            ranges.append((first, text.count("\n"), x))
        loader = loader_factory()
        try:
            module = loader.load_text(text, f"Listing {target.number}.mdl")
            return Assembled(module, parts, from_workbench)
        except MdlError as e:
            max_rounds -= 1
            if max_rounds <= 0:
                raise
            # an error inside another listing's code (not a name it needs in turn): that
            # listing cannot be used
            line = e.first.loc.line
            culprit = next((x for a, b, x in ranges if a <= line <= b and x is not target),
                           None)
            if culprit is not None and not _missing(MdlError([e.first])):
                bad.add(id(culprit))
                used.remove(culprit)
                if stand_ins is None:
                    stand_ins = fallbacks(loader)
                for n in culprit.names():
                    if n in stand_ins and n not in own:
                        from_workbench[n] = stand_ins[n]
                continue
            added = False
            for d in e.diagnostics:
                m = re.search(r"module '(\w+)' is not imported", d.message)
                if m and loader.find("::" + m.group(1)) is not None and \
                        "::" + m.group(1) not in profiles:
                    profiles.add("::" + m.group(1))
                    added = True
            if stand_ins is None:
                stand_ins = fallbacks(loader)
                types = _workbench_types(loader)
            for n in _missing(e):
                if n in own or n in from_workbench:
                    continue
                if n in types:  # the workbench's type (and its values): one type for all
                    for x in types[n]:
                        from_workbench[x] = stand_ins.get(x, stand_ins[n])
                    added = True
                    continue
                providers = [x for x in by_name.get(n, ()) if id(x) not in bad
                             and _checks(x, every, loader_factory)]
                chosen = []
                for sig in {s for x in providers for (m, s) in _definitions(x) if m == n}:
                    group = [x for x in providers if (n, sig) in _definitions(x)]
                    before = [x for x in group if x.key < target.key]
                    chosen.append(before[-1] if before else group[0])
                for pick in chosen:
                    if pick not in used:
                        used.append(pick)
                        added = True
                if not chosen:
                    if stand_ins is None:
                        stand_ins = fallbacks(loader)
                    if n in stand_ins:
                        from_workbench[n] = stand_ins[n]
                        added = True
            if not added:
                raise
