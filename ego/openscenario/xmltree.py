"""A small XML tree that keeps every element's line: ``FILE:LINE`` in every message.

``xml.etree`` drops line numbers; expat (the parser ``xml.etree`` itself uses) reports them
while parsing, so the tree is built here from expat's callbacks.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from xml.parsers import expat

from ego.params import ConfigError

DOCS = "docs/openscenario.md"


class ScenarioFileError(ConfigError):
    """A scenario or road file that ego refuses, as one line ``FILE:LINE: what``."""

    def __init__(self, file: str | os.PathLike, line: int | None, message: str) -> None:
        where = f"{os.fspath(file)}:{line}" if line else os.fspath(file)
        super().__init__(f"{where}: {message}")
        self.file, self.line, self.detail = os.fspath(file), line, message


@dataclass(slots=True)
class Node:
    """One element: its tag, attributes (as written), children and line (1-based)."""

    tag: str
    attrs: dict[str, str]
    line: int
    children: list[Node] = field(default_factory=list)

    def child(self, tag: str) -> Node | None:
        """The first child named ``tag``, or None."""
        for c in self.children:
            if c.tag == tag:
                return c
        return None

    def all(self, tag: str) -> list[Node]:
        """Every child named ``tag``."""
        return [c for c in self.children if c.tag == tag]


def parse_file(path: str | os.PathLike) -> Node:
    """The root element of the XML file ``path``; malformed XML or an unreadable file is a
    :class:`ScenarioFileError` naming the line."""
    from ego.checks import MAX_XOSC_BYTES, read_limited

    path = Path(path)

    def fail(reason: str) -> ScenarioFileError:
        if reason == "it is a folder":
            reason = "is a folder, expected an .xosc file"
        return ScenarioFileError(path, None, reason if reason == "no such file" else f"cannot read: {reason}")

    data = read_limited(path, "scenario file", MAX_XOSC_BYTES, fail)
    return parse_bytes(data, path)


#: elements nested deeper than this are refused (an OpenSCENARIO file needs ~15)
MAX_DEPTH = 200
#: more parameter declarations than this in one file are refused (while parsing)
MAX_DECLARATIONS = 10_000


#: comments and blanks before an XML declaration (XML allows nothing there; the reference
#: player's two_plus_one_road.xosc starts with four comment lines, and it reads the file)
_BEFORE_DECLARATION = re.compile(rb"\A(?:\xef\xbb\xbf)?(?:\s|<!--.*?-->)+(?=<\?xml\s)", re.S)
_DECLARATION = re.compile(rb"<\?xml\s.*?\?>", re.S)


def declaration_first(data: bytes) -> bytes:
    """``data`` with an XML declaration that follows comments moved to the very start, the
    lines unchanged: the declaration goes before the comments on their first line and its old
    place is blanked (its own line breaks kept), so every element keeps its line."""
    lead = _BEFORE_DECLARATION.match(data)
    if lead is None:
        return data
    decl = _DECLARATION.match(data, lead.end())
    if decl is None:
        return data
    text = decl.group(0)
    blank = bytes(c if c in b"\r\n" else 32 for c in text)
    bom = b"\xef\xbb\xbf" if data.startswith(b"\xef\xbb\xbf") else b""
    one_line = re.sub(rb"[\r\n]", b" ", text)
    return bom + one_line + data[len(bom) : lead.end()] + blank + data[decl.end() :]


def parse_bytes(data: bytes, path: str | os.PathLike = "<string>") -> Node:
    """The root element of ``data`` (see :func:`parse_file`). An XML declaration after leading
    comments, which XML forbids and the reference player reads, is read as if it came first
    (:func:`declaration_first`)."""
    data = declaration_first(data)
    parser = expat.ParserCreate()
    stack: list[Node] = []
    root: list[Node] = []

    declarations = [0]

    def start(tag: str, attrs: dict[str, str]) -> None:
        if len(stack) >= MAX_DEPTH:
            raise ScenarioFileError(
                path, parser.CurrentLineNumber, f"elements nested deeper than {MAX_DEPTH} levels (the limit)"
            )
        if tag == "ParameterDeclaration":
            declarations[0] += 1
            if declarations[0] > MAX_DECLARATIONS:
                raise ScenarioFileError(
                    path, parser.CurrentLineNumber, f"more than {MAX_DECLARATIONS:,} parameter declarations (the limit)"
                )
        node = Node(tag, attrs, parser.CurrentLineNumber)
        if stack:
            stack[-1].children.append(node)
        else:
            root.append(node)
        stack.append(node)

    def end(tag: str) -> None:
        stack.pop()

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    try:
        parser.Parse(data, True)
    except expat.ExpatError as exc:
        raise ScenarioFileError(
            path, exc.lineno, f"malformed XML: {expat.ErrorString(exc.code)} (column {exc.offset + 1})"
        ) from None
    except LookupError as exc:  # <?xml encoding="..."?> names an encoding Python does not know
        raise ScenarioFileError(path, 1, f"unknown XML encoding ({exc})") from None
    except (ValueError, UnicodeError) as exc:
        raise ScenarioFileError(path, parser.CurrentLineNumber, f"cannot decode the XML: {exc}") from None
    return root[0]
