"""Where the keys of a TOML manifest are, and schema errors that name the key and its line.

A manifest is validated as the parsed document (:func:`rigtools.schemas.iter_errors` reports
violations by JSON path, ``$.run[1].file``); the user needs the key and the line in the text.
:class:`KeyLines` finds the line of every table, ``[[array]]`` entry and key of the text;
:func:`schema_error` turns a violation into a :class:`~rigtools.errors.CampaignError` naming
the key as written (``run[1].file``), its line, and for an unknown key the keys the schema
allows with the closest one. :mod:`rigtools.campaign.manifest` reads campaigns with them.

Paths are tuples as jsonschema reports them: ``("run", 2, "file")`` is the key ``file`` of the
third ``[[run]]``.
"""

from __future__ import annotations

import difflib
import re
from pathlib import Path
from typing import Any

from rigtools.errors import CampaignError
from rigtools.schemas import load_schema

__all__ = [
    "KeyLines",
    "allowed_keys",
    "dotted",
    "parse_json_path",
    "schema_error",
    "table_name",
]

_HEADER = re.compile(r"""^\s*(\[\[?)\s*([A-Za-z0-9_\-."' ]+?)\s*\]\]?\s*(#.*)?$""")
_KEY = re.compile(r"""^\s*("[^"]*"|'[^']*'|[A-Za-z0-9_\-]+(?:\s*\.\s*[A-Za-z0-9_\-]+)*)\s*=""")


def _unquote(part: str) -> str:
    part = part.strip()
    return part[1:-1] if len(part) >= 2 and part[0] == part[-1] and part[0] in "\"'" else part


class KeyLines:
    """Line numbers of the tables, array-of-tables entries and keys of a TOML text.

    Paths are tuples as jsonschema reports them: ``("run", 2, "file")`` is the key ``file`` of
    the third ``[[run]]``. Good for the flat manifests rigtools reads (no multi-line strings
    holding ``key = value`` lines).

    Parameters
    ----------
    text : str
        The TOML text.

    Attributes
    ----------
    lines : dict
        Line (1-based) of every path written in the text, its first occurrence.
    """

    def __init__(self, text: str) -> None:
        self.lines: dict[tuple[Any, ...], int] = {}
        counts: dict[tuple[str, ...], int] = {}
        current: tuple[Any, ...] = ()
        for i, line in enumerate(text.splitlines(), 1):
            h = _HEADER.match(line)
            if h and not _KEY.match(line):
                names = tuple(_unquote(p) for p in h.group(2).split("."))
                if h.group(1) == "[[":
                    n = counts.get(names, 0)
                    counts[names] = n + 1
                    current = (*names, n)
                else:
                    current = names
                self.lines.setdefault(current, i)
                continue
            k = _KEY.match(line)
            if k:
                key = tuple(_unquote(p) for p in k.group(1).split("."))
                self.lines.setdefault((*current, *key), i)

    def line(self, path: tuple[Any, ...]) -> int | None:
        """Line of ``path``, or of its nearest enclosing table that is in the text."""
        p = tuple(path)
        while p:
            if p in self.lines:
                return self.lines[p]
            p = p[:-1]
        return None


_PATH_TOKEN = re.compile(r"\.([A-Za-z_][A-Za-z0-9_]*)|\[(\d+)\]|\['((?:[^'\\]|\\.)*)'\]")


def parse_json_path(json_path: str) -> tuple[Any, ...]:
    """``$.run[1].file`` -> ``("run", 1, "file")``."""
    out: list[Any] = []
    for m in _PATH_TOKEN.finditer(json_path.removeprefix("$")):
        if m.group(1) is not None:
            out.append(m.group(1))
        elif m.group(2) is not None:
            out.append(int(m.group(2)))
        else:
            out.append(m.group(3))
    return tuple(out)


def dotted(path: tuple[Any, ...]) -> str:
    """``("run", 1, "file")`` -> ``"run[1].file"``; ``"the top level"`` for ``()``."""
    s = ""
    for p in path:
        s += f"[{p}]" if isinstance(p, int) else (f".{p}" if s else str(p))
    return s or "the top level"


def table_name(path: tuple[Any, ...]) -> str:
    """The table of a path as written: ``("run", 1)`` -> ``"[[run]]"``, ``("a",)`` -> ``"[a]"``."""
    names = [p for p in path if not isinstance(p, int)]
    if not names:
        return "the top level"
    return f"[[{'.'.join(names)}]]" if path and isinstance(path[-1], int) else \
        f"[{'.'.join(names)}]"


def schema_error(p: Path, lines: KeyLines, json_path: str, message: str,
                 schema: str) -> CampaignError:
    """The error for one schema violation, naming the key and its line.

    Parameters
    ----------
    p : pathlib.Path
        The manifest file.
    lines : KeyLines
        Where the keys of its text are.
    json_path, message : str
        The violation as :func:`rigtools.schemas.iter_errors` reports it.
    schema : str
        The schema's file name in ``data_schemas/`` (for the keys it allows).

    Returns
    -------
    CampaignError
        For unknown keys: the first in file order, with the allowed keys and the closest one;
        for a missing key: the key and its table; else the schema's message.
    """
    path = parse_json_path(json_path)
    unexpected = re.findall(r"'([^']+)'", message.split("(", 1)[1]) if (
        "were unexpected" in message or "was unexpected" in message) else []
    if unexpected:
        # name the first unknown key in file order, with its line
        keyed = sorted((lines.line((*path, k)) or 0, k) for k in unexpected)
        first_line, key = keyed[0]
        allowed = allowed_keys(path, schema)
        close = difflib.get_close_matches(key, allowed, n=1, cutoff=0.6) or [
            a for a in allowed if a.lower() == key.lower()]
        hint = f" (did you mean {close[0]!r}?)" if close else ""
        more = f"; also unknown: {', '.join(k for _, k in keyed[1:])}" if len(keyed) > 1 else ""
        return CampaignError(
            p, f"line {first_line}" if first_line else None,
            f"one of the keys {', '.join(allowed)} in {table_name(path)}"
            if allowed else "no such key",
            f"unknown key {key!r}{hint}{more}")
    line = lines.line(path)
    at = f"line {line}" if line else None
    m = re.match(r"'([^']+)' is a required property", message)
    if m:
        return CampaignError(p, at, f"key {m.group(1)!r} in {table_name(path)}", "none")
    return CampaignError(p, at,
                         f"a value allowed by data_schemas/{schema} for {dotted(path)}",
                         message)


def allowed_keys(path: tuple[Any, ...], schema: str) -> list[str]:
    """The keys ``schema`` allows in the table at ``path`` (its ``properties``, in order)."""
    node: Any = load_schema(schema)
    for part in path:
        if isinstance(part, int):
            node = node.get("items", {})
        else:
            node = node.get("properties", {}).get(part, {})
    return list(node.get("properties", {}))
