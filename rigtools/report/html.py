"""The page: report.json content rendered through jinja2 templates with autoescape.

Templates live in ``rigtools/report/templates/`` (``report.html``; ``report.css`` is included
inline). The environment escapes every value (``autoescape=True``): run ids, channel names,
notes and messages from recordings and campaigns are shown as text. The page has no JavaScript
and loads nothing: figures are base64 PNGs in ``data:`` URIs, styles inline, and a
Content-Security-Policy forbids scripts and network access.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from typing import Any, Final

import jinja2

__all__ = ["environment", "format_count", "format_interval", "format_number", "format_percent",
           "render_html"]

_DASH: Final = "\N{EM DASH}"


def format_number(v: Any, digits: int = 3) -> str:
    """A number with ``digits`` significant digits, never in exponent form above 1e-3.

    Examples
    --------
    >>> format_number(6328.98), format_number(0.0324), format_number(None)
    ('6329', '0.0324', '—')
    """
    if v is None or isinstance(v, bool) or not isinstance(v, int | float):
        return _DASH if v is None else str(v)
    f = float(v)
    if not math.isfinite(f):
        return _DASH
    if f == 0:
        return "0"
    if abs(f) < 1e-3 or abs(f) >= 1e9:
        return f"{f:.{digits}g}"
    mag = math.floor(math.log10(abs(f)))
    return f"{f:.{max(0, digits - 1 - mag)}f}"


def format_count(v: Any) -> str:
    """An integer count with thousands separated by a thin space (``76 830``)."""
    if v is None or isinstance(v, bool) or not isinstance(v, int | float):
        return _DASH if v is None else str(v)
    if isinstance(v, float) and not v.is_integer():
        return format_number(v)
    return f"{int(v):,}".replace(",", "\N{THIN SPACE}")


def format_percent(p: Any) -> str:
    """A probability as a percentage (``<1 %`` and ``>99 %`` at the ends)."""
    if p is None or not isinstance(p, int | float) or not math.isfinite(float(p)):
        return _DASH
    x = 100.0 * float(p)
    if 0 < x < 1:
        return "<1 %"
    if 99 < x < 100:
        return ">99 %"
    return f"{x:.0f} %"


def format_interval(q: Mapping[str, Any] | None, digits: int = 3) -> str:
    """``median [q05, q95]`` of a quantity (mean when no median)."""
    if not q:
        return _DASH
    mid = q.get("q50") if q.get("q50") is not None else q.get("mean")
    return (f"{format_number(mid, digits)} [{format_number(q.get('q05'), digits)}, "
            f"{format_number(q.get('q95'), digits)}]")


def _pretty_json(obj: Any) -> str:
    return json.dumps(obj, indent=2, ensure_ascii=False, sort_keys=False)


def environment() -> jinja2.Environment:
    """The jinja2 environment of the report templates (autoescape on, strict undefined)."""
    env = jinja2.Environment(
        loader=jinja2.PackageLoader("rigtools.report", "templates"),
        autoescape=True,
        undefined=jinja2.StrictUndefined,
        trim_blocks=True,
        lstrip_blocks=True,
    )
    env.filters["num"] = format_number
    env.filters["pct"] = format_percent
    env.filters["count"] = format_count
    env.filters["interval"] = format_interval
    env.filters["pretty_json"] = _pretty_json
    return env


def render_html(content: Mapping[str, Any], figures: Mapping[str, str]) -> str:
    """The report page.

    Parameters
    ----------
    content : mapping
        The report.json document (:func:`rigtools.report.content.report_content`).
    figures : mapping of str to str
        Figure key -> base64 PNG: ``verdict``, ``spectrum:<run id>`` and the calibration
        figures by name.

    Returns
    -------
    str
        One self-contained HTML document.
    """
    return environment().get_template("report.html").render(r=content, figs=figures)
