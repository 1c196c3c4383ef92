"""Parse pwc-list text into a :class:`~pwc.tree.PwcList`, collecting precise diagnostics.

The grammar (spec/pwc-list.md §1), one item per line::

    line     := [list_property | point] [# comment]
    point    := coord coord [property [number]]
    coord    := ['a'] number
    number   := ['-'|'+'] (decimal | decimal '/' decimal | decimal '-' decimal '/' decimal)
    decimal  := digits ['.' digits] [exponent] | '.' digits [exponent]

Errors do not stop the parser at the first line: it reports every bad line it finds.
"""

from __future__ import annotations

import difflib
import math
import re

from pwc.diagnostics import Diagnostic, Loc, PwcSyntaxError
from pwc.tree import LIST_PROPERTIES, POINT_PROPERTIES, Coord, PwcList, PwPoint

__all__ = ["parse", "parse_number", "decode_source", "NUMBER_HELP"]

_DECIMAL = r"(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?"
_NUMBER = re.compile(
    rf"(?P<sign>[-+]?)(?:(?P<whole>{_DECIMAL})-(?P<mnum>{_DECIMAL})/(?P<mden>{_DECIMAL})"
    rf"|(?P<num>{_DECIMAL})/(?P<den>{_DECIMAL})|(?P<dec>{_DECIMAL}))"
)
_TOKEN = re.compile(r"\S+")
MAX_ERRORS = 50  # a file that is not a pwc-list at all should not print 10,000 errors

NUMBER_HELP = (
    "numbers look like 15, -3, 0.375, .5, 1e-3, fractions 1/3, mixed numbers 2-1/3; "
    "prefix a coordinate with 'a' to make it absolute in a :relative list (a2.5)"
)


def parse_number(text: str) -> float:
    """Value of one pwc number token; raises ValueError with the reason.

    Examples
    --------
    >>> [parse_number(s) for s in ["15", "-.25", "1e-3", "-4/3", "2-1/2", "-2-1/2"]]
    [15.0, -0.25, 0.001, -1.3333333333333333, 2.5, -2.5]
    >>> parse_number("1/0")
    Traceback (most recent call last):
    ...
    ValueError: division by zero in '1/0'
    """
    m = _NUMBER.fullmatch(text)
    if m is None:
        if text.lower().lstrip("+-") in ("nan", "inf", "infinity"):
            raise ValueError(f"'{text}' is not a finite number")
        raise ValueError(f"'{text}' is not a number")
    sign = -1.0 if m["sign"] == "-" else 1.0
    if m["dec"] is not None:
        value = float(m["dec"])
    else:
        num, den = (m["num"], m["den"]) if m["num"] is not None else (m["mnum"], m["mden"])
        if float(den) == 0.0:
            raise ValueError(f"division by zero in '{text}'")
        value = float(num) / float(den)
        if m["whole"] is not None:
            value += float(m["whole"])
    if not math.isfinite(value):
        raise ValueError(f"'{text}' is too large to be represented (overflows to infinity)")
    return sign * value


def decode_source(data: bytes, file: str) -> str:
    """Decode a pwc file's bytes as UTF-8 text, rejecting binary data with a located error."""
    bad = data.find(b"\x00")
    if bad < 0:
        try:
            return data.decode("utf-8-sig")
        except UnicodeDecodeError as e:
            bad = e.start
    line = data.count(b"\n", 0, bad) + 1
    col = bad - (data.rfind(b"\n", 0, bad) + 1) + 1
    raise PwcSyntaxError([Diagnostic(
        "error", "this is not a text file (binary data or an encoding other than UTF-8)",
        Loc(file, line, col),
        "a pwc-list is plain UTF-8 text with one point per line, such as '0 0' or '1 1 :angle 90'",
    )])


def _suggest(word: str, choices) -> str:
    near = difflib.get_close_matches(word, list(choices), n=1, cutoff=0.5)
    return f"did you mean ':{near[0]}'?" if near else ""


class _Parser:
    def __init__(self, text: str, file: str):
        self.file = file
        self.text = text
        self.diags: list[Diagnostic] = []
        self.errors = 0

    def error(self, msg: str, line: int, text: str, col: int, width: int, fix: str = "") -> None:
        self.errors += 1
        self.diags.append(Diagnostic("error", msg, Loc(self.file, line, col, width, text), fix))

    def warn(self, msg: str, line: int, text: str, col: int, width: int, fix: str = "") -> None:
        self.diags.append(Diagnostic("warning", msg, Loc(self.file, line, col, width, text), fix))

    def number(self, tok: re.Match, lineno: int, line: str, what: str) -> float | None:
        try:
            return parse_number(tok.group())
        except ValueError as e:
            self.error(f"bad {what}: {e}", lineno, line, tok.start() + 1, len(tok.group()),
                       NUMBER_HELP)
            return None

    def coord(self, tok: re.Match, lineno: int, line: str, what: str) -> Coord | None:
        s = tok.group()
        absolute = s.startswith("a")
        if absolute:
            s = s[1:]
        try:
            return Coord(parse_number(s), absolute)
        except ValueError as e:
            self.error(f"bad {what} coordinate: {e}", lineno, line, tok.start() + 1,
                       len(tok.group()), NUMBER_HELP)
            return None

    def run(self) -> tuple[PwcList, list[Diagnostic]]:
        relative = False
        relative_line = 0
        points: list[PwPoint] = []
        for lineno, raw in enumerate(self.text.splitlines(), start=1):
            code = raw.split("#", 1)[0]
            toks = list(_TOKEN.finditer(code))
            if not toks:
                continue
            first = toks[0]
            if first.group().startswith(":"):
                name = first.group()[1:]
                col, width = first.start() + 1, len(first.group())
                if name in LIST_PROPERTIES:
                    if points:
                        self.error(f"list property ':{name}' after the first point", lineno, raw,
                                   col, width,
                                   f"move ':{name}' to the top of the file, before any point")
                    elif relative:
                        self.warn(f"':{name}' given twice (first on line {relative_line})",
                                  lineno, raw, col, width, "delete this line")
                    relative, relative_line = True, relative_line or lineno
                    for extra in toks[1:]:
                        self.error(f"':{name}' takes no arguments", lineno, raw,
                                   extra.start() + 1, len(extra.group()),
                                   f"write ':{name}' alone on its line")
                        break
                elif name in POINT_PROPERTIES:
                    self.error(f"':{name}' is a point property but this line has no coordinates",
                               lineno, raw, col, width,
                               f"write the point first, e.g. '1 1 :{name}"
                               + (" 90'" if POINT_PROPERTIES[name] else "'"))
                else:
                    hint = _suggest(name, [*LIST_PROPERTIES, *POINT_PROPERTIES])
                    self.error(f"unknown property ':{name}'", lineno, raw, col, width,
                               hint or "list properties: :relative; point properties: "
                               + ", ".join(":" + p for p in POINT_PROPERTIES))
                continue
            point = self.point(toks, lineno, raw, is_first=not points)
            if point is not None:
                points.append(point)
            if self.errors >= MAX_ERRORS:
                self.error(f"too many errors; stopped after {MAX_ERRORS}", lineno, "", 1, 1,
                           "fix the errors above first (is this really a pwc-list?)")
                break
        if not self.errors:
            last = max(1, len(self.text.splitlines()))
            if not points:
                self.error("the list has no points", last, "", 1, 1,
                           "a pwc-list needs at least two points, one per line, such as "
                           "'0 0' then '1 0'")
            elif len(points) == 1:
                p = points[0]
                self.error("the list has only one point", p.loc.line, p.loc.text, 1,
                           len(p.loc.text.rstrip()),
                           "add at least one more point: a curve joins two or more points")
        return PwcList(tuple(points), relative, self.file), self.diags

    def point(self, toks, lineno: int, raw: str, is_first: bool) -> PwPoint | None:
        ok = True
        if len(toks) < 2 or toks[1].group().startswith(":"):
            self.error("a point needs two coordinates, x and y", lineno, raw,
                       toks[0].end() + 1, 1, "write the point as 'X Y', e.g. '0.5 1'")
            return None
        x = self.coord(toks[0], lineno, raw, "x")
        y = self.coord(toks[1], lineno, raw, "y")
        ok = x is not None and y is not None
        prop, arg = None, None
        if len(toks) > 2:
            ptok = toks[2]
            word = ptok.group()
            if not word.startswith(":"):
                self.error(f"unexpected '{word}' after the coordinates", lineno, raw,
                           ptok.start() + 1, len(word),
                           "a point is 'X Y' optionally followed by one property, e.g. "
                           "'1 1 :angle 90' or '1 1 :flare'")
                return None
            name = word[1:]
            if name not in POINT_PROPERTIES:
                if name in LIST_PROPERTIES:
                    fix = f"':{name}' is a list property: put it alone on the first line"
                else:
                    fix = _suggest(name, POINT_PROPERTIES) or (
                        "point properties are " + ", ".join(":" + p for p in POINT_PROPERTIES))
                self.error(f"unknown point property ':{name}'", lineno, raw, ptok.start() + 1,
                           len(word), fix)
                return None
            nargs = POINT_PROPERTIES[name]
            args = toks[3:]
            if len(args) < nargs:
                what = "the arc's angle in degrees" if name == "angle" else "the sagitta distance"
                self.error(f"':{name}' needs one argument, {what}", lineno, raw,
                           ptok.end() + 1, 1, f"write e.g. '{toks[0].group()} "
                           f"{toks[1].group()} :{name} " + ("90'" if name == "angle" else ".25'"))
                return None
            if len(args) > nargs:
                extra = args[nargs]
                n = "no arguments" if nargs == 0 else "one argument"
                self.error(f"':{name}' takes {n}", lineno, raw, extra.start() + 1,
                           args[-1].end() - extra.start(),
                           f"remove '{_span(raw, extra, args[-1])}'")
                return None
            if nargs:
                if args[0].group().startswith("a"):
                    self.error("the 'a' (absolute) prefix applies to coordinates only", lineno,
                               raw, args[0].start() + 1, 1, "remove the 'a'")
                    return None
                arg = self.number(args[0], lineno, raw, f"':{name}' argument")
                ok = ok and arg is not None
            prop = name
            if is_first:
                self.error(f"':{name}' on the list's first point: ':{name}' shapes the "
                           f"piece that ends at its point, and line {lineno} holds the first "
                           "point, which ends no piece", lineno, raw, ptok.start() + 1,
                           args[-1].end() - ptok.start() if args else len(word),
                           "add the starting point on a line before it (e.g. '0 0'), or "
                           f"remove ':{name}'")
                return None
        if not ok:
            return None
        return PwPoint(x, y, prop, arg, Loc(self.file, lineno, toks[0].start() + 1,
                                             len(raw.split("#", 1)[0].strip()), raw))


def _span(raw: str, first: re.Match, last: re.Match) -> str:
    return raw[first.start():last.end()]


def parse(text: str, file: str = "<string>") -> tuple[PwcList, list[Diagnostic]]:
    """Parse pwc-list text.

    Returns the tree and the warnings; raises :class:`PwcSyntaxError` holding every
    error (and warning) if any error was found.

    Examples
    --------
    >>> tree, warnings = parse(":relative\\n0 0\\n1 2-1/2 :angle -90\\n")
    >>> tree.relative, tree.points[1].y.value, tree.points[1].prop, tree.points[1].arg
    (True, 2.5, 'angle', -90.0)
    """
    tree, diags = _Parser(text.lstrip("\ufeff"), file).run()
    if any(d.severity == "error" for d in diags):
        raise PwcSyntaxError(diags)
    return tree, diags
