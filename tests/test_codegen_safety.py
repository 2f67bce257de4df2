"""quadland codegen touches nothing it did not write, and generated C takes no injected text."""

import subprocess
import sys

import pytest

from quadland.codegen import MANIFEST, generated_files, main, stale
from quadland.exceptions import CodegenError


def _run(*args, cwd):
    return subprocess.run([sys.executable, "-m", "quadland", "codegen", *args], cwd=cwd,
                          capture_output=True, text=True, timeout=300)


def test_a_generation_beside_another_leaves_it_alone(tmp_path, capsys):
    assert main(out=tmp_path / "cg" / "a") == 0
    assert main(out=tmp_path / "cg") == 0          # the parent of an earlier generation
    a = tmp_path / "cg" / "a"
    assert (a / "quadland.h").exists() and (a / MANIFEST).exists()
    assert "removed" not in capsys.readouterr().out


def test_only_files_the_manifest_lists_are_stale(tmp_path):
    files = generated_files()
    main(out=tmp_path)
    (tmp_path / "mine.c").write_text("/* Do not edit: regenerate with `quadland codegen` */\n")
    (tmp_path / "old.c").write_text("/* Do not edit: regenerate with `quadland codegen` */\n")
    (tmp_path / MANIFEST).write_text((tmp_path / MANIFEST).read_text() + "old.c\n../x\n")
    assert stale(tmp_path, files) == ["old.c"]      # not mine.c, not a path outside


def test_out_that_is_a_file_or_cannot_be_made_is_one_line(tmp_path):
    afile = tmp_path / "afile"
    afile.write_text("keep")
    with pytest.raises(CodegenError, match="out: .* exists and is not a folder"):
        main(out=afile)
    with pytest.raises(CodegenError, match="out: cannot write"):
        main(out=afile / "sub")
    assert afile.read_text() == "keep"


def test_overrides_cannot_inject_c(tmp_path):
    proc = _run("--set", 'scenario.description="x */ #error injected /*"', "--set",
                'scenario.name="ok"', "--out", "gen", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    for path in (tmp_path / "gen").rglob("*.[ch]"):
        text = path.read_text()
        assert "#error injected" not in text and '"x */' not in text, path
