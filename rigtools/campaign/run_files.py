"""Run files given by glob: one ``[[run]]`` whose ``file`` is a pattern stands for many runs.

A ``file`` holding a glob character (``*``, ``?`` or ``[``) expands to one run per matching
file, in sorted order; each run's id is the ``[[run]]`` id with ``{stem}`` replaced by the
file's stem, or ``<id>-<stem>`` when the id holds no ``{stem}``::

    [[run]]
    id = "LS9-{stem}"
    file = "runs/ls9_*.mcap"     # runs/ls9_90c.mcap -> run "LS9-ls9_90c"

Patterns are relative to the campaign file's folder (or absolute) and follow
:meth:`pathlib.Path.glob` (``**`` matches any number of folders); only files match.
"""

from __future__ import annotations

from pathlib import Path
from typing import Final

__all__ = ["GLOB_CHARACTERS", "STEM_FIELD", "expand_run_files", "is_glob", "run_id_for"]

#: Characters that make a run's ``file`` a pattern.
GLOB_CHARACTERS: Final = "*?["
#: The placeholder of a run id replaced by each matching file's stem.
STEM_FIELD: Final = "{stem}"


def is_glob(file: str) -> bool:
    """Whether a run's ``file`` (as written) is a glob pattern.

    Parameters
    ----------
    file : str
        The ``file`` of a ``[[run]]``.

    Returns
    -------
    bool
        True when it holds ``*``, ``?`` or ``[``.

    Examples
    --------
    >>> is_glob("runs/*.mcap"), is_glob("runs/a.mcap")
    (True, False)
    """
    return any(ch in file for ch in GLOB_CHARACTERS)


def expand_run_files(base: Path, pattern: str) -> list[Path]:
    """The files a pattern matches, sorted.

    Parameters
    ----------
    base : pathlib.Path
        Folder a relative pattern is resolved against (the campaign file's folder).
    pattern : str
        The glob as written (``~`` expanded; absolute or relative to ``base``).

    Returns
    -------
    list of pathlib.Path
        Matching regular files (folders excluded), sorted by path; empty when none match.
    """
    q = Path(pattern).expanduser()
    if q.is_absolute():
        root, rel = Path(q.anchor), q.relative_to(q.anchor)
    else:
        root, rel = base, q
    if not str(rel) or str(rel) == ".":
        return []
    return sorted((f for f in root.glob(str(rel)) if f.is_file()), key=str)


def run_id_for(id_template: str, file: Path) -> str:
    """The id of the run a pattern's match gives.

    Parameters
    ----------
    id_template : str
        The ``[[run]]`` id as written.
    file : pathlib.Path
        The matching file.

    Returns
    -------
    str
        ``id_template`` with every ``{stem}`` replaced by the file's stem (plain replacement,
        no other braces are interpreted), or ``<id_template>-<stem>`` when it holds none.

    Examples
    --------
    >>> run_id_for("LS9-{stem}", Path("runs/a.mcap")), run_id_for("LS9", Path("runs/a.mcap"))
    ('LS9-a', 'LS9-a')
    """
    stem = file.stem
    if STEM_FIELD in id_template:
        return id_template.replace(STEM_FIELD, stem)
    return f"{id_template}-{stem}"
