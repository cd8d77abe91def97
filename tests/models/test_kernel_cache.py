"""The numba cache tie (models.dynamics.kernel_cache) keeps a dependent kernel's cache fresh.

Behavioural, in fresh interpreters (one per "process" of the story) sharing a temporary
``NUMBA_CACHE_DIR``, on a temporary package of two files: ``a.py`` holds a cached compiled
function ``f``, ``b.py`` a cached kernel ``g`` that calls ``a.f``. numba's cache of ``g``
checks only ``b.py`` (and ``g``'s bytecode), so after ``a.py`` is edited ``g`` keeps loading
the copy of the old ``f`` it inlined, unless ``b`` ties its cache to ``a``. The control (no
tie) shows that stale copy, so the tied test can fail.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

A_SRC = """from numba import njit


@njit(cache={cache})
def f():
    return {value}
"""

B_SRC = """import os
import shutil

from numba import njit

from models.dynamics.kernel_cache import tie_cache
from tiepkg.a import f


@njit(cache={cache})
def g():
    return f()


if {break_cache_dir}:  # the cache directory becomes unusable: a file where it was
    shutil.rmtree(g._cache.cache_path)
    open(g._cache.cache_path, "w").close()
TIE = tie_cache(__name__, ["tiepkg.a"]) if {tied} else None
"""

RUN = """import json

from models.dynamics.kernel_cache import tied_sources
from tiepkg import b

out = {"g": b.g(), "hits": sum(b.g.stats.cache_hits.values()),
       "tied_sources": list(tied_sources("tiepkg.b"))}
if b.TIE is not None:
    out.update(flushed=list(b.TIE.flushed), disabled=list(b.TIE.disabled),
               sources=list(b.TIE.sources))
print(json.dumps(out))
"""


def _package(root: Path, *, value: int, tied: bool = True, cache: bool = True,
             cache_f: bool = True, break_cache_dir: bool = False) -> Path:
    pkg = root / "tiepkg"
    pkg.mkdir(exist_ok=True)
    (pkg / "__init__.py").write_text("")
    _write_a(root, value, cache=cache_f)
    (pkg / "b.py").write_text(
        B_SRC.format(cache=cache, tied=tied, break_cache_dir=break_cache_dir))
    return pkg


def _write_a(root: Path, value: int, *, cache: bool = True) -> None:
    (root / "tiepkg" / "a.py").write_text(A_SRC.format(cache=cache, value=value))


def _run(root: Path) -> dict:
    """Call ``tiepkg.b.g()`` in a fresh interpreter; what it returned and what the tie did."""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(root / "numba-cache"), PYTHONDONTWRITEBYTECODE="1",
               PYTHONPATH=os.pathsep.join([str(root), os.environ.get("PYTHONPATH", "")]))
    proc = subprocess.run([sys.executable, "-c", RUN], cwd=root, env=env, capture_output=True,
                          text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    return json.loads(proc.stdout.strip().splitlines()[-1])


def test_a_tied_kernel_is_recompiled_after_the_file_it_inlines_is_edited(tmp_path):
    """g() follows an edit of a.py (b.py untouched); unchanged sources keep the cache."""
    _package(tmp_path, value=1)
    first = _run(tmp_path)
    assert first["g"] == 1
    assert first["flushed"] == ["g"]  # no stamp yet
    assert first["sources"] == first["tied_sources"] == [str(tmp_path / "tiepkg" / "a.py")]
    again = _run(tmp_path)  # nothing changed: the stamp matches, g comes from the disk cache
    assert (again["g"], again["flushed"], again["disabled"]) == (1, [], [])
    assert again["hits"] >= 1
    _write_a(tmp_path, 2)
    edited = _run(tmp_path)
    assert edited["g"] == 2, edited
    assert edited["flushed"] == ["g"]
    assert edited["hits"] == 0
    after = _run(tmp_path)
    assert (after["g"], after["flushed"], after["hits"] >= 1) == (2, [], True)


def test_without_the_tie_the_kernel_keeps_the_stale_copy(tmp_path):
    """The control: untied, g() still returns a.py's old value from numba's cache."""
    _package(tmp_path, value=1, tied=False)
    assert _run(tmp_path)["g"] == 1
    _write_a(tmp_path, 2)
    stale = _run(tmp_path)
    assert stale["g"] == 1  # the bug the tie exists for
    assert stale["hits"] >= 1
    assert stale["tied_sources"] == []


def test_a_kernel_without_a_disk_cache_is_left_alone(tmp_path):
    """``cache=False`` (numba's NullCache): the tie flushes and disables nothing, no error."""
    _package(tmp_path, value=1, cache=False)
    out = _run(tmp_path)
    assert (out["g"], out["flushed"], out["disabled"]) == (1, [], [])
    assert out["sources"] == [str(tmp_path / "tiepkg" / "a.py")]
    assert not any((tmp_path / "numba-cache").rglob("b.*.cache-tie"))


def test_an_unusable_cache_directory_disables_the_cache_without_an_error(tmp_path):
    """The cache directory cannot be written (a file stands where it was): no stamp can be kept.

    The tie cannot vouch for the cache, so it disables it for the process: g() is compiled
    afresh and returns the right value, no error (``f`` uncached: its own cache shares the
    directory, and numba would fail to save it).
    """
    _package(tmp_path, value=1, cache_f=False, break_cache_dir=True)
    out = _run(tmp_path)
    assert (out["g"], out["flushed"], out["disabled"], out["hits"]) == (1, [], ["g"], 0)
