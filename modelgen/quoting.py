"""Text that reaches a file the project writes: quoted for that file, by one writer each.

A name read from a user's file -- a geometry's ``name``, a data file's or a trajectory's path, a parameter's reason --
reaches the files sflm writes: a calibrated geometry (TOML), generated C (its provenance comments), an FMU's
``modelDescription.xml``, JSON summaries. Written as it came, a ``"`` ends a TOML string, a newline starts a new TOML
line or leaves a comment, a ``*/`` ends a C comment and lets the rest be code, a ``<`` opens an XML element. Every such
string goes through one of these functions (JSON through :func:`json.dumps`, which quotes everything):

* :func:`toml_string` -- a TOML basic string, quotes included;
* :func:`one_line` -- printable text on one line (a TOML or CSV comment, a message);
* :func:`c_comment` -- a line of a C ``/* ... */`` comment;
* :func:`xml_attribute` -- the value of a double-quoted XML attribute.

>>> toml_string('a "b" \\\\ c\\nd')
'"a \\\\"b\\\\" \\\\\\\\ c\\\\nd"'
>>> c_comment("x */ int y; /* \\n")
'x * / int y; / * <U+000A>'
"""

from __future__ import annotations

import json
from xml.sax.saxutils import escape as _xml_escape

__all__ = ["toml_string", "one_line", "c_comment", "xml_attribute"]


def toml_string(text: str) -> str:
    """``text`` as a TOML basic string, its quotes included.

    Quotes, backslashes and every control character escaped (``\\n``, ``\\u0000``), the rest as it is: a TOML reader
    gives back ``text`` exactly.

    Parameters
    ----------
    text : str
        Any text.
    """
    quoted = json.dumps(str(text), ensure_ascii=False)  # JSON's escapes are TOML's, but for DEL
    return quoted.replace("\x7f", "\\u007f")


def one_line(text: str) -> str:
    """``text`` printable on one line.

    Every control character as its ``\\xNN`` (a newline as ``\\x0a``).

    Parameters
    ----------
    text : str
        Any text.
    """
    return "".join(ch if ch.isprintable() else f"\\x{ord(ch):02x}" if ord(ch) < 0x100 else f"\\u{ord(ch):04x}" for ch in str(text))


def c_comment(text: str) -> str:
    """``text`` fit for a line of a C comment.

    Printable ASCII only (anything else, and the backslash, as ``<U+NNNN>``), no ``*/`` or ``/*`` that would end or nest
    the comment, and no ``??`` that a trigraph could turn into a line splice: a ``*/`` and a newline in a name would let
    it write code.

    Parameters
    ----------
    text : str
        Any text.
    """
    out = "".join(ch if " " <= ch <= "~" and ch != "\\" else f"<U+{ord(ch):04X}>" for ch in str(text))
    while "*/" in out or "/*" in out or "??" in out:
        out = out.replace("*/", "* /").replace("/*", "/ *").replace("??", "? ?")
    return out


def xml_attribute(text: str) -> str:
    """``text`` as the value of a double-quoted XML attribute.

    ``& < > " '`` and line breaks as entities, characters XML 1.0 does not allow dropped.

    Parameters
    ----------
    text : str
        Any text.
    """
    allowed = "".join(ch for ch in str(text) if ch in "\t\n\r" or ord(ch) >= 0x20 and not 0xD800 <= ord(ch) <= 0xDFFF
                      and ch not in "\ufffe\uffff")
    return _xml_escape(allowed, {'"': "&quot;", "'": "&apos;", "\n": "&#10;", "\r": "&#13;", "\t": "&#9;"})
