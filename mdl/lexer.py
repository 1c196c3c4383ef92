"""MDL's tokens: identifiers, keywords, literals and operators (MDL 1.x lexical rules).

* identifiers start with a letter (not ``_``); ``//`` and ``/* */`` comments, block
  comments nest (as the MDL SDK allows, to comment out code);
* integers: decimal, ``0x`` hexadecimal, ``0``-led octal; floats: ``1.``, ``.5``, ``1e-3``,
  with an optional ``f`` (float, the default) or ``d`` (double) suffix;
* strings: ``"..."`` with C escapes (``\\n``, ``\\t``, ``\\"``, ``\\\\``, ``\\xHH``,
  ``\\uXXXX``...),
  adjacent strings are one literal;
* ``[[`` opens an annotation block (its end is two ``]`` tokens, so ``a[b[i]]`` lexes).

Examples
--------
>>> [t.kind for t in tokenize(Source("x", "float2 p = .5f; // note"))]
['ident', 'ident', '=', 'float', ';', 'eof']
"""

from __future__ import annotations

import re
from typing import NamedTuple

from mdl.diagnostics import MdlError, Source

__all__ = ["Token", "tokenize", "KEYWORDS", "RESERVED"]

#: MDL's keywords (they cannot name anything)
KEYWORDS = frozenset(
    "annotation auto break case cast const continue default do else enum export false for "
    "if import in let mdl module return struct switch true typedef uniform using varying "
    "while".split())

#: words MDL reserves for future use (C++ keywords); reported when used as names
RESERVED = frozenset(
    "char class const_cast delete dynamic_cast explicit extern external foreach friend goto "
    "graph half half2 half2x2 half2x3 half2x4 half3 half3x2 half3x3 half3x4 half4 half4x2 "
    "half4x3 half4x4 inline inout lambda long mutable namespace native new operator out "
    "phenomenon private protected public reinterpret_cast sampler shader short signed "
    "sizeof static static_cast technique template this throw try typeid typename union "
    "unsigned virtual void volatile wchar_t".split())

# longest first
_PUNCT = [">>>=", "<<=", ">>=", ">>>", "::", "[[", "&&", "||", "==", "!=", "<=", ">=", "<<",
          ">>", "++", "--", "+=", "-=", "*=", "/=", "%=", "&=", "|=", "^=", "..", "(", ")",
          "{", "}", "[", "]", ";", ",", ":", "=", "?", ".", "+", "-", "*", "/", "%", "<", ">",
          "!", "~", "&", "|", "^"]
# the next token, in one match: whitespace and line comments skipped, then its kind: a
# block comment's, number's or string's start (scanned on by their own methods), a word,
# an operator, the end of the text, or any other character ("bad")
_NEXT = re.compile(r"(?:[ \t\r\n\f\v\ufeff]|//[^\n]*)*(?:(?P<block>/\*)"
                   r"|(?P<number>\.?[0-9])|(?P<word>[A-Za-z][A-Za-z0-9_]*)|(?P<string>\")"
                   r"|(?P<punct>" + "|".join(re.escape(p) for p in _PUNCT) + r")|(?P<end>\Z)"
                   r"|(?P<bad>.))", re.DOTALL)
_WORD = re.compile(r"[A-Za-z0-9_.]+")
_HEX = re.compile(r"0[xX][0-9A-Fa-f]+")
_FLOAT = re.compile(r"(?:\d+\.\d*|\.\d+|\d+)(?:[eE][+-]?\d+)?[fFdD]?")
_ESCAPES = {"a": "\a", "b": "\b", "f": "\f", "n": "\n", "r": "\r", "t": "\t", "v": "\v",
            "\\": "\\", "'": "'", '"': '"', "?": "?"}


class Token(NamedTuple):
    """One token.

    ``kind`` is ``ident``, ``int``, ``float``, ``string``, ``eof``, a keyword, or the
    operator's text; ``value`` the literal's value (``(value, is_double)`` for floats).
    A named tuple: a module's tokens are made by the ten thousand, and a tuple is made
    in a third of a frozen dataclass's time."""

    kind: str
    text: str
    start: int
    end: int
    value: object = None


class _Lexer:
    def __init__(self, src: Source):
        self.src = src
        self.text = src.text
        self.tokens: list[Token] = []

    def fail(self, message: str, start: int, end: int | None = None, fix: str = ""):
        raise MdlError([self.src.diagnostic("error", message, start, end, fix)])

    def run(self) -> list[Token]:
        text, n, i, tokens = self.text, len(self.text), 0, self.tokens
        while True:
            m = _NEXT.match(text, i)
            kind = m.lastgroup
            i = m.start(kind)
            if kind == "word":
                word = m.group(kind)
                tokens.append(Token(word if word in KEYWORDS else "ident", word, i, m.end(),
                                    word))
                i = m.end()
            elif kind == "punct":
                op = m.group(kind)
                tokens.append(Token(op, op, i, m.end()))
                i = m.end()
            elif kind == "end":
                break
            elif kind == "number":
                i = self.number(i)
            elif kind == "string":
                i = self.string(i)
            elif kind == "block":
                i = self.block_comment(i)
            else:
                self.unexpected(i)
        tokens.append(Token("eof", "", n, n))
        return tokens

    def unexpected(self, i: int):
        c = self.text[i]
        if c == "'":
            self.fail("quoted identifiers ('...', MDL 1.8) are not supported here", i,
                      fix="use a plain identifier of letters, digits and '_'")
        if c == "_":
            self.fail("unexpected character '_': MDL names start with a letter", i,
                      fix="start the name with a letter")
        shown = repr(c) if c.isprintable() else f"U+{ord(c):04X}"
        self.fail(f"unexpected character {shown}", i,
                  fix="remove it" if c.isprintable() else "remove the invisible character")

    def block_comment(self, start: int) -> int:
        depth, i, text = 0, start, self.text
        while i < len(text):
            if text.startswith("/*", i):
                depth += 1
                i += 2
            elif text.startswith("*/", i):
                depth -= 1
                i += 2
                if depth == 0:
                    return i
            else:
                i += 1
        self.fail("unterminated block comment", start, start + 2,
                  fix="close it with '*/' (block comments nest: close each '/*')")

    def number(self, start: int) -> int:
        text = self.text
        word = _WORD.match(text, start)
        end = word.end()
        # a '.' that starts a member access after an integer (1.x is not a number)
        lit = text[start:end]
        m = _HEX.fullmatch(lit)
        if m:
            value = int(lit, 16)
            self.tokens.append(Token("int", lit, start, end, self.check_int(value, lit, start)))
            return end
        if re.fullmatch(r"\d+", lit):
            if len(lit) > 1 and lit[0] == "0":
                if not re.fullmatch(r"[0-7]+", lit):
                    self.fail(f"invalid octal literal '{lit}'", start, end,
                              fix="a number starting with 0 is octal (digits 0-7); remove the "
                                  "leading zero")
                value = int(lit, 8)
            else:
                value = int(lit)
            self.tokens.append(Token("int", lit, start, end, self.check_int(value, lit, start)))
            return end
        m = _FLOAT.match(text, start)
        # exponent signs are outside _WORD: extend the literal over them
        flen = m.end() if m else start
        end = max(end, flen)
        rest = _WORD.match(text, flen)
        if m is None or (rest is not None and rest.end() > flen):
            bad_end = max(end, rest.end() if rest else end)
            self.fail(f"malformed number '{text[start:bad_end]}'", start, bad_end,
                      fix="write a number such as 1, 0.5, .5, 1e-3 or 2.0f, and separate it "
                          "from the next name")
        lit = m.group()
        is_double = lit[-1] in "dD"
        body = lit.rstrip("fFdD")
        value = float(body)
        if value == float("inf"):
            self.fail(f"floating-point literal '{lit}' is too large", start, flen,
                      fix="numbers must be finite")
        self.tokens.append(Token("float", lit, start, flen, (value, is_double)))
        return flen

    def check_int(self, value: int, lit: str, start: int) -> int:
        if value > 0xFFFFFFFF:
            self.fail(f"integer literal '{lit}' is too large", start, start + len(lit),
                      fix="MDL ints are 32-bit; write a float (1e30) if you mean one")
        return value  # 2^31..2^32-1 wrap to negative when typed (as C does)

    def string(self, start: int) -> int:
        text, i, out = self.text, start + 1, []
        while i < len(text):
            c = text[i]
            if c == '"':
                return self.finish_string(start, i + 1, "".join(out))
            if c == "\n":
                break
            if c == "\\":
                if i + 1 >= len(text):
                    break
                e = text[i + 1]
                if e in _ESCAPES:
                    out.append(_ESCAPES[e])
                    i += 2
                    continue
                m = (re.compile(r"x([0-9A-Fa-f]{1,2})").match(text, i + 1)
                     or re.compile(r"u([0-9A-Fa-f]{4})").match(text, i + 1)
                     or re.compile(r"U([0-9A-Fa-f]{8})").match(text, i + 1)
                     or re.compile(r"([0-7]{1,3})").match(text, i + 1))
                if m:
                    base = 8 if m.group()[0] in "01234567" else 16
                    try:
                        out.append(chr(int(m.group(1), base)))
                    except (ValueError, OverflowError):
                        self.fail("invalid character code in escape", i, m.end())
                    i = m.end()
                    continue
                self.fail(f"unknown escape sequence '\\{e}'", i, i + 2,
                          fix='write \\\\ for a backslash; escapes: \\n \\t \\" \\\\ \\xHH')
            out.append(c)
            i += 1
        self.fail("unterminated string", start, start + 1, fix='close it with " on this line')

    def finish_string(self, start: int, end: int, value: str) -> int:
        last = self.tokens[-1] if self.tokens else None
        if last is not None and last.kind == "string":  # "a" "b" is one literal
            self.tokens[-1] = Token("string", self.text[last.start:end], last.start, end,
                                    last.value + value)
        else:
            self.tokens.append(Token("string", self.text[start:end], start, end, value))
        return end


def tokenize(src: Source) -> list[Token]:
    """The tokens of ``src`` (the last is ``eof``).

    Raises
    ------
    MdlError
        An unexpected character, an unterminated string or comment, a malformed number.
    """
    return _Lexer(src).run()
