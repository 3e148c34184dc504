"""Edit a user's MJCF file in place of its text: change a few attributes, add a few elements,
keep every other byte as it was.

``softhand skin apply`` changes a hand's model in a few places (collision flags of the skinned
geoms, the skin's ``<pair>`` elements, asset paths when the file moves to another folder). Writing
the whole model back from a parsed tree (``MjSpec.to_xml`` or ``xml.etree``) would lose or
rewrite what the user wrote: ``to_xml`` drops comments, defaults it does not need and the
``<include>`` structure, and turns ``<position>`` into ``<general>``; ``xml.etree`` (even with
``TreeBuilder(insert_comments=True)``, which keeps comments and attribute order) re-serialises
quotes, character references, whitespace inside tags (attributes on several lines), the XML
declaration and any DOCTYPE. So this module lets the standard library's expat parser (the one
under ``xml.etree``) report where each element starts and ends in the file's bytes, and splices
the changes into the original text:

* an attribute that exists gets its new value between its own quotes; a new attribute goes after
  the tag's last attribute, one space before it, in that attribute's quotes;
* new elements go after the last child of their parent, each on its own line with the
  indentation of that parent's children (or of the root's children and one more level, for a new
  parent), in the file's line ending;
* nothing else changes: comments, attribute order, element order, blank lines, indentation and
  the encoding's bytes outside the edited tags are kept exactly.
"""

from __future__ import annotations

import itertools
import xml.parsers.expat
from dataclasses import dataclass, field
from pathlib import Path

__all__ = ["Element", "MjcfEditor", "MjcfError"]


class MjcfError(ValueError):
    """The MJCF text cannot be read or edited as asked (the message says where and why)."""


@dataclass
class Element:
    """One element of the file: its tag, attributes (in file order), byte offsets of its start
    tag (``start`` .. ``start_end``) and of its end tag (``end`` .. ``end_end``; both equal to
    ``start_end`` when the element is self-closing), its depth (root 0) and children."""

    tag: str
    attrs: dict[str, str]
    start: int
    start_end: int
    depth: int
    end: int = -1
    end_end: int = -1
    children: list[Element] = field(default_factory=list)

    @property
    def self_closing(self) -> bool:
        return self.end == self.start_end and self.end_end == self.start_end


def _tag_end(text: bytes, start: int) -> int:
    """The offset just after the ``>`` that closes the tag starting at ``start`` (quotes
    respected)."""
    quote = None
    for i in range(start, len(text)):
        c = text[i:i + 1]
        if quote:
            if c == quote:
                quote = None
        elif c in (b'"', b"'"):
            quote = c
        elif c == b">":
            return i + 1
    raise MjcfError(f"unterminated tag at byte {start}")


def _parse(text: bytes, name: str) -> Element:
    parser = xml.parsers.expat.ParserCreate()
    stack: list[Element] = []
    root: list[Element] = []

    def start(tag: str, attrs: dict[str, str]) -> None:
        at = parser.CurrentByteIndex
        end = _tag_end(text, at)
        el = Element(tag, dict(attrs), at, end, len(stack))
        if text[end - 2:end] == b"/>":
            el.end = el.end_end = end
        if stack:
            stack[-1].children.append(el)
        else:
            root.append(el)
        stack.append(el)

    def finish(tag: str) -> None:
        el = stack.pop()
        if el.end < 0:
            el.end = parser.CurrentByteIndex
            el.end_end = _tag_end(text, el.end)

    parser.StartElementHandler = start
    parser.EndElementHandler = finish
    try:
        parser.Parse(text, True)
    except xml.parsers.expat.ExpatError as exc:
        raise MjcfError(f"{name} is not well-formed XML: {exc}") from None
    if not root or root[0].tag != "mujoco":
        raise MjcfError(f"{name}: the root element is not <mujoco>")
    return root[0]


def _line_start(text: bytes, offset: int) -> int:
    return text.rfind(b"\n", 0, offset) + 1


def _indent(text: bytes, el: Element) -> bytes | None:
    """The whitespace before ``el`` on its line, or None when something else precedes it."""
    lead = text[_line_start(text, el.start):el.start]
    return lead if lead.strip() == b"" else None


def _escape(value: str, quote: str) -> str:
    value = value.replace("&", "&amp;").replace("<", "&lt;")
    return value.replace('"', "&quot;") if quote == '"' else value.replace("'", "&apos;")


class MjcfEditor:
    """The text of one MJCF file and the edits asked of it; `text` applies them.

    Args:
        text: the file's bytes.
        name: how messages name the file.
    """

    def __init__(self, text: bytes, name: str = "the MJCF file") -> None:
        self.original = text
        self.name = name
        self.root = _parse(text, name)
        self.newline = b"\r\n" if b"\r\n" in text else b"\n"
        self._edits: list[tuple[int, int, bytes]] = []
        self._appended: dict[int, list[bytes]] = {}  # id(parent) -> new child elements
        self._parents: dict[int, Element] = {}

    @classmethod
    def from_file(cls, path: str | Path) -> MjcfEditor:
        return cls(Path(path).read_bytes(), str(Path(path).name))

    def iter(self, tag: str | None = None, under: Element | None = None):
        """Every element (or every ``tag``) in document order."""
        todo = [under or self.root]
        while todo:
            el = todo.pop()
            if tag is None or el.tag == tag:
                yield el
            todo.extend(reversed(el.children))

    def find(self, tag: str, **attrs: str) -> list[Element]:
        return [e for e in self.iter(tag) if all(e.attrs.get(k) == v for k, v in attrs.items())]

    def _quote(self, el: Element) -> str:
        """The quote of the tag's last attribute (double if it has none)."""
        tag = self.original[el.start:el.start_end]
        last = max(tag.rfind(b'="'), tag.rfind(b"='"))
        return "'" if last >= 0 and tag[last + 1:last + 2] == b"'" else '"'

    def set_attr(self, el: Element, key: str, value: str) -> None:
        """Give ``el`` the attribute ``key = value``: in place if it has it, else after its last
        attribute."""
        tag = self.original[el.start:el.start_end]
        quote = self._quote(el)
        if key in el.attrs:
            pos = 1 + len(el.tag)
            while True:  # walk the attributes: name, =, quoted value (quotes respected)
                while tag[pos:pos + 1].isspace():
                    pos += 1
                eq = tag.index(b"=", pos)
                attr = tag[pos:eq].strip().decode("utf-8")
                pos = eq + 1
                while tag[pos:pos + 1].isspace():
                    pos += 1
                q = tag[pos:pos + 1]
                close = tag.index(q, pos + 1)
                if attr == key:
                    value_bytes = _escape(value, q.decode()).encode("utf-8")
                    self._edits.append((el.start + pos + 1, el.start + close, value_bytes))
                    return
                pos = close + 1
        cut = len(tag) - (2 if tag.endswith(b"/>") else 1)
        while cut > 0 and tag[cut - 1:cut].isspace():
            cut -= 1
        new = f' {key}={quote}{_escape(value, quote)}{quote}'.encode()
        self._edits.append((el.start + cut, el.start + cut, new))

    def child_indent(self, parent: Element) -> bytes:
        """The indentation of ``parent``'s children (from its first child on a line of its own,
        else its own indentation and one more level of the file's)."""
        for child in parent.children:
            lead = _indent(self.original, child)
            if lead is not None:
                return lead
        own = _indent(self.original, parent) or b""
        return own + self.indent_unit()

    def indent_unit(self) -> bytes:
        """One level of the file's indentation (from the root's children; two spaces if none)."""
        root_lead = _indent(self.original, self.root) or b""
        for child in self.root.children:
            lead = _indent(self.original, child)
            if lead is not None and len(lead) > len(root_lead):
                return lead[len(root_lead):]
        return b"  "

    def append_child(self, parent: Element, element: bytes) -> None:
        """Add ``element`` (its text, one line) as the last child of ``parent``."""
        self._appended.setdefault(id(parent), []).append(element)
        self._parents[id(parent)] = parent

    def prepend_child(self, parent: Element, element: bytes) -> None:
        """Add ``element`` (its text, one line) as the first child of ``parent``."""
        if not parent.children or _indent(self.original, parent.children[0]) is None:
            raise MjcfError(f"{self.name}: cannot place a first child in <{parent.tag}> "
                            "(its first child does not start a line)")
        first = parent.children[0]
        at = _line_start(self.original, first.start)
        self._edits.append((at, at, self.child_indent(parent) + element + self.newline))

    def insert_at_top(self, text: bytes) -> None:
        """Insert ``text`` before the root element's line (after an XML declaration or
        DOCTYPE, whichever comes last before the first comment or the root)."""
        pos = 0
        head = self.original[:self.root.start]
        for marker in (b"<?xml", b"<!DOCTYPE"):
            i = head.find(marker)
            if i >= 0:
                end = head.find(b">", i) + 1
                nl = head.find(b"\n", end)
                pos = max(pos, nl + 1 if nl >= 0 else end)
        self._edits.append((pos, pos, text))

    def text(self) -> bytes:
        """The file with every edit applied."""
        edits = list(self._edits)
        nl = self.newline
        for key, elements in self._appended.items():
            parent = self._parents[key]
            indent = self.child_indent(parent)
            body = b"".join(nl + indent + e for e in elements)
            if parent.self_closing:  # <contact/> -> <contact> ... </contact>
                tag = self.original[parent.start:parent.start_end]
                own = _indent(self.original, parent) or b""
                opened = tag[:-2].rstrip() + b">"
                closed = f"</{parent.tag}>".encode()
                edits.append((parent.start, parent.start_end, opened + body + nl + own + closed))
            elif parent.children:
                at = parent.children[-1].end_end
                edits.append((at, at, body))
            else:
                own = _indent(self.original, parent) or b""
                edits.append((parent.start_end, parent.end, body + nl + own))
        edits.sort(key=lambda e: (e[0], e[1]))
        for (_, a1, _), (b0, _, _) in itertools.pairwise(edits):
            if b0 < a1:
                raise MjcfError(f"{self.name}: two edits overlap at byte {b0} (internal error)")
        out = bytearray(self.original)
        for a, b, new in reversed(edits):
            out[a:b] = new
        return bytes(out)
