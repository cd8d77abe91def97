"""Run ids as file stems: the formula of the issue 19 contract, safe and unique."""

from __future__ import annotations

import hashlib
import re

import pytest

from rigtools.pipeline import run_file_stem


@pytest.mark.parametrize("run_id", ["LS9-90C", "a/b", "<script>alert(1)</script>",
                                    "\" onerror=\"x", "ünïcode run", "x" * 200, ""])
def test_stem_is_the_contract_formula(run_id: str) -> None:
    expected = (re.sub(r"[^A-Za-z0-9._-]+", "_", run_id)[:48] + "-"
                + hashlib.sha256(run_id.encode("utf-8")).hexdigest()[:8])
    stem = run_file_stem(run_id)
    assert stem == expected
    assert re.fullmatch(r"[A-Za-z0-9._-]{0,48}-[0-9a-f]{8}", stem)


def test_ids_that_differ_only_in_unsafe_characters_get_different_stems() -> None:
    ids = ["a/b", "a_b", "a b", "a<b", "a\\b"]
    assert len({run_file_stem(i) for i in ids}) == len(ids)


def test_a_stem_cannot_climb_out_of_its_folder() -> None:
    stem = run_file_stem("../../etc/passwd")
    assert "/" not in stem and "\\" not in stem


def test_a_non_string_id_is_refused() -> None:
    with pytest.raises(TypeError, match="`run_id` must be a str"):
        run_file_stem(12)  # type: ignore[arg-type]
