"""An optimization level's own flags (``quadland.engine.build.LEVEL_FLAGS``).

-Os compiles CasADi's straight-line C without GCC's partial-redundancy passes and
its second scheduling pass (a quarter of the paper simulator's compile time). A
library built so is keyed apart from one built at plain -Os: both the library's
key and the simulator's recipe key name every flag.
"""

from __future__ import annotations

import pytest

from quadland.engine import build, recall
from quadland_symbolic.paper_loop import paper_loop_recipe

pytestmark = pytest.mark.skipif(not build.have_compiler(), reason="no C compiler")


GCC = build.have_compiler() and build.level_flags("-Os", build.find_compiler()) != ("-Os",)


@pytest.mark.parametrize("identity,flags", [
    ("/usr/bin/cc\ncc (Debian 12.2.0-14+deb12u1) 12.2.0\nCopyright (C) 2022 Free Software "
     "Foundation, Inc.", build.LEVEL_FLAGS["-Os"]),
    ("/usr/bin/cc\nDebian clang version 14.0.6\nTarget: x86_64-pc-linux-gnu", ("-Os",)),
    ("/usr/bin/tcc\ntcc version 0.9.27 (x86_64 Linux)", ("-Os",))])
def test_the_level_flags_are_gccs_alone(monkeypatch, identity, flags):
    """GCC's passes are turned off on GCC only (its --version names the Free Software
    Foundation; clang's and others' do not, and clang rejects -fno-code-hoisting)."""
    monkeypatch.setattr(build, "compiler_identity", lambda cc: identity)
    assert build.level_flags("-Os", "cc") == flags
    assert build.level_flags("-O2", "cc") == ("-O2",)


@pytest.mark.skipif(not GCC, reason="the level's own flags are GCC's")
def test_os_compiles_with_its_flags_and_keys_them(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    commands: list[list[str]] = []
    real = build.run_compilers

    def recording(cmds, *args, **kwargs):
        commands.extend(cmds)
        return real(cmds, *args, **kwargs)

    monkeypatch.setattr(build, "run_compilers", recording)
    files = {"sq.c": "double sq(double x) { return x * x; }\n"}
    lib = build.build_library(files, ("sq.c",), opt="-Os", name="libsq", strict=False)
    compile_ = next(c for c in commands if "-c" in c)
    at = compile_.index("-Os")
    assert compile_[at:at + 5] == ["-Os", "-fno-gcse", "-fno-tree-pre", "-fno-code-hoisting",
                                   "-fno-schedule-insns2"]
    # a library of plain -Os is another file, built again
    monkeypatch.setattr(build, "LEVEL_FLAGS", {})
    commands.clear()
    plain = build.build_library(files, ("sq.c",), opt="-Os", name="libsq", strict=False)
    assert plain != lib and any("-c" in c for c in commands)
    assert "-fno-gcse" not in next(c for c in commands if "-c" in c)


def test_the_recipe_key_names_the_levels_flags(monkeypatch):
    recipe = paper_loop_recipe(2)

    def key():
        return recall.recall_key(recipe, "continuous", None, (), "qlsim_paper_continuous",
                                 "-Os", False)

    with_flags = key()
    monkeypatch.setattr(build, "LEVEL_FLAGS", {})
    plain = key()
    monkeypatch.setattr(build, "LEVEL_FLAGS", {"-Os": ("-Os", "-fno-gcse")})
    assert len({with_flags, plain, key()}) == 3
    # -O2 has no flags of its own: its key is the one it had
    monkeypatch.setattr(build, "LEVEL_FLAGS", {})
    o2 = recall.recall_key(recipe, "continuous", None, (), "qlsim_paper_continuous", "-O2",
                           False)
    monkeypatch.undo()
    assert recall.recall_key(recipe, "continuous", None, (), "qlsim_paper_continuous", "-O2",
                             False) == o2
