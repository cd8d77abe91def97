"""Names a package exports but imports only on first access (PEP 562 module ``__getattr__``).

A package whose ``__init__`` should stay light (reading a campaign must not load the signal
analysis; a pipeline worker must not load the calibration or the report) lists those names with
the module that defines each, and takes its module ``__getattr__`` and ``__dir__`` from
:func:`lazy_exports`.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping, MutableMapping, Sequence
from typing import Any

__all__ = ["lazy_exports"]


def lazy_exports(package: str, namespace: MutableMapping[str, Any],
                 on_first_use: Mapping[str, str], exported: Sequence[str]
                 ) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """The ``__getattr__`` and ``__dir__`` of ``package``.

    Parameters
    ----------
    package : str
        The package's ``__name__`` (for the error message).
    namespace : mutable mapping
        The package's ``globals()``: a name, once imported, is stored there.
    on_first_use : mapping
        Name -> the module that defines it.
    exported : sequence of str
        The package's ``__all__``.

    Examples
    --------
    >>> ns: dict = {}
    >>> get, names = lazy_exports("pkg", ns, {"sqrt": "math"}, ["sqrt"])
    >>> get("sqrt")(9.0), "sqrt" in ns, names()
    (3.0, True, ['sqrt'])
    """

    def getattr_(name: str) -> Any:
        module = on_first_use.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(module), name)
        namespace[name] = value
        return value

    def dir_() -> list[str]:
        return sorted(set(namespace) | set(exported))

    return getattr_, dir_
