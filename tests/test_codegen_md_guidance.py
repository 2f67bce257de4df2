"""docs/codegen.md's ``ql_guidance_params`` row names every member of the struct: the members
are :data:`quadland_symbolic.landing.guidance.GUIDANCE_PARAMS`' fields (the generated header
is built from them), read here independently of the page's text."""

import re
from pathlib import Path

from quadland_symbolic.landing.guidance import GUIDANCE_PARAMS

PAGE = Path(__file__).resolve().parents[1] / "docs" / "codegen.md"


def _struct_row() -> str:
    rows = [line for line in PAGE.read_text().splitlines()
            if line.startswith("| `ql_guidance_params` |")]
    assert len(rows) == 1, rows
    return rows[0]


def test_the_guidance_struct_row_names_every_member():
    named = set(re.findall(r"`([a-z_0-9]+)`", _struct_row()))
    missing = [n for n in GUIDANCE_PARAMS.names() if n not in named]
    assert not missing, f"docs/codegen.md's ql_guidance_params row leaves out {missing}"
