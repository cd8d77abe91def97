"""Static checks of the report page: what it loads, which markup is live."""

from __future__ import annotations

from html.parser import HTMLParser

__all__ = ["PageScan", "scan"]


class PageScan(HTMLParser):
    """Collect elements, attributes and text of a page (nothing is executed)."""

    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.tags: list[str] = []
        self.attrs: list[tuple[str, str, str | None]] = []
        self.text: list[str] = []

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        self.tags.append(tag)
        self.attrs += [(tag, k, v) for k, v in attrs]

    def handle_startendtag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        self.handle_starttag(tag, attrs)

    def handle_data(self, data: str) -> None:
        self.text.append(data)

    @property
    def event_handlers(self) -> list[tuple[str, str, str | None]]:
        """Attributes named ``on*`` (event handlers)."""
        return [a for a in self.attrs if a[1].lower().startswith("on")]

    @property
    def external_urls(self) -> list[tuple[str, str, str | None]]:
        """``src``/``href`` that leave the page (anything but ``data:`` and ``#`` anchors)."""
        return [a for a in self.attrs if a[1] in ("src", "href", "srcset", "action", "poster")
                and not (a[2] or "").startswith(("data:", "#"))]


def scan(html: str) -> PageScan:
    """Parse ``html``."""
    p = PageScan()
    p.feed(html)
    p.close()
    return p
