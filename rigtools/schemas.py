"""Access to the contracts in ``data_schemas/``: JSON Schemas, the reference DBC, message schemas.

In a source checkout the files live in ``data_schemas/`` at the top of the repository; in an
installed wheel the same directory ships as the package ``rigtools._data_schemas``.
"""

from __future__ import annotations

import functools
import json
from pathlib import Path
from typing import Any

__all__ = ["iter_errors", "load_schema", "schema_dir", "schema_path"]


@functools.cache
def schema_dir() -> Path:
    """Directory holding the shipped contracts."""
    try:
        from importlib.resources import files

        d = Path(str(files("rigtools._data_schemas")))
        if (d / "rig_reference.dbc").is_file():
            return d
    except ModuleNotFoundError:
        pass
    return Path(__file__).resolve().parent.parent / "data_schemas"


def schema_path(name: str) -> Path:
    """Path of a shipped contract file, e.g. ``schema_path("rig_reference.dbc")``."""
    p = schema_dir() / name
    if not p.is_file():
        raise FileNotFoundError(f"rigtools ships no contract named {name!r} (looked in {p.parent})")
    return p


@functools.cache
def load_schema(name: str) -> dict[str, Any]:
    """A shipped JSON Schema by file name."""
    return json.loads(schema_path(name).read_text(encoding="utf-8"))


@functools.cache
def _registry() -> Any:
    from referencing import Registry, Resource

    resources = []
    for p in sorted(schema_dir().glob("*.schema.json")):
        doc = json.loads(p.read_text(encoding="utf-8"))
        res = Resource.from_contents(doc)
        resources.append((p.name, res))
        if "$id" in doc:
            resources.append((doc["$id"], res))
    return Registry().with_resources(resources)


def iter_errors(instance: Any, name: str) -> list[tuple[str, str]]:
    """Validate ``instance`` against schema ``name``.

    Returns
    -------
    list of (str, str)
        ``(json_path, message)`` for each violation, best match first; empty when valid.
    """
    from jsonschema import Draft202012Validator
    from jsonschema.exceptions import best_match

    validator = Draft202012Validator(load_schema(name), registry=_registry())
    errors = list(validator.iter_errors(instance))
    if not errors:
        return []
    first = best_match(errors)
    ordered = [first] + [e for e in errors if e is not first]
    return [(e.json_path, e.message) for e in ordered]
