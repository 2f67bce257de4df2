"""quadland codegen touches nothing it did not write, and generated C takes no injected text."""

import errno
import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

from quadland.codegen import MANIFEST, generated_files, main, stale
from quadland.exceptions import CodegenError


def _run(*args, cwd):
    return subprocess.run([sys.executable, "-m", "quadland", "codegen", *args], cwd=cwd,
                          capture_output=True, text=True, timeout=300)


@pytest.mark.slow
def test_a_generation_beside_another_leaves_it_alone(tmp_path, capsys):
    assert main(out=tmp_path / "cg") == 0
    assert main(out=tmp_path / "cg" / "a") == 0    # inside an earlier generation
    assert main(out=tmp_path / "cg") == 0          # the parent of an earlier generation
    a = tmp_path / "cg" / "a"
    assert (a / "quadland.h").exists() and (a / MANIFEST).exists()
    assert "removed" not in capsys.readouterr().out


@pytest.mark.slow
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


@pytest.mark.slow
def test_overrides_cannot_inject_c(tmp_path):
    proc = _run("--set", 'scenario.description="x */ #error injected /*"', "--set",
                'scenario.name="ok"', "--out", "gen", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    for path in (tmp_path / "gen").rglob("*.[ch]"):
        text = path.read_text()
        assert "#error injected" not in text and '"x */' not in text, path


# --- nothing of the user's replaced, nothing half-written (the V8, V9) -------

def _snapshot(folder):
    return {str(p.relative_to(folder)): (p.is_symlink(), p.read_bytes() if p.is_file()
                                         and not p.is_symlink() else None)
            for p in sorted(folder.rglob("*"))}


def _one_line(proc, expected):
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.startswith(f"quadland: error: --out: {expected}"), proc.stderr
    assert len(proc.stderr.splitlines()) == 1 and proc.stdout == ""


@pytest.mark.slow
def test_a_file_where_a_folder_goes_is_refused_before_anything_is_written(tmp_path):
    """``mkdir -p out && touch out/float && quadland codegen --scenario turning --out out``
    wrote 15 entries, then failed."""
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / "float").touch()
    proc = _run("--scenario", "turning", "--out", "out", cwd=tmp_path)
    _one_line(proc, "out/float is in the way (the generated tree needs a folder there)")
    assert [p.name for p in (tmp_path / "out").iterdir()] == ["float"]


@pytest.mark.slow
@pytest.mark.parametrize("rel", [".gitignore", "example/Makefile", "vehicle.c"])
def test_a_file_the_manifest_does_not_list_is_never_replaced(tmp_path, rel):
    out = tmp_path / "out"
    (out / rel).parent.mkdir(parents=True)
    (out / rel).write_text("the user's\n")
    before = _snapshot(out)
    proc = _run("--out", "out", cwd=tmp_path)
    _one_line(proc, f"out/{rel} was not written by quadland codegen")
    assert _snapshot(out) == before


def test_a_file_that_is_already_the_generated_text_is_taken_over(tmp_path):
    """An unlisted file identical to what would be written is not replaced, only listed."""
    files = generated_files()
    (tmp_path / "quadland.h").write_text(files["quadland.h"])
    assert main(out=tmp_path) == 0
    assert "quadland.h" in (tmp_path / MANIFEST).read_text().splitlines()


@pytest.mark.slow
def test_a_listed_file_is_replaced_and_the_user_s_files_beside_it_stay(tmp_path):
    files = generated_files()
    main(out=tmp_path)
    (tmp_path / "quadland.h").write_text("edited\n")
    (tmp_path / "example" / "notes.txt").write_text("mine\n")
    (tmp_path / "example" / "fly.c").unlink()
    assert main(out=tmp_path) == 0
    assert (tmp_path / "quadland.h").read_text() == files["quadland.h"]
    assert (tmp_path / "example" / "fly.c").read_text() == files["example/fly.c"]
    assert (tmp_path / "example" / "notes.txt").read_text() == "mine\n"
    assert not [p for p in tmp_path.rglob("*tmp-*")]


@pytest.mark.slow
@pytest.mark.parametrize("link", ["file", "folder", "out"])
def test_nothing_is_written_through_a_symbolic_link(tmp_path, link):
    target = tmp_path / "target"
    target.mkdir()
    (target / "keep").write_text("keep\n")
    out = tmp_path / "out"
    if link == "out":
        out.symlink_to(target)
        expected = "out is a symbolic link"
    else:
        out.mkdir()
        if link == "file":
            (out / "quadland.h").symlink_to(target / "keep")
            expected = "out/quadland.h is a symbolic link"
        else:
            (out / "example").symlink_to(target)
            expected = "out/example is a symbolic link"
    before = _snapshot(tmp_path)
    proc = _run("--out", "out", cwd=tmp_path)
    _one_line(proc, expected)
    assert _snapshot(tmp_path) == before


@pytest.mark.slow
def test_a_stale_file_behind_a_symbolic_link_is_not_removed(tmp_path):
    out, elsewhere = tmp_path / "out", tmp_path / "elsewhere"
    main(out=out)
    elsewhere.mkdir()
    victim = elsewhere / "old.c"
    victim.write_text("/* Do not edit: regenerate with `quadland codegen` */\n")
    (out / "linked").symlink_to(elsewhere)
    (out / MANIFEST).write_text((out / MANIFEST).read_text() + "linked/old.c\n")
    assert stale(out, generated_files()) == []
    main(out=out)
    assert victim.exists()


@pytest.mark.parametrize("where", [".", "..", "quadland", "quadland/scenarios", "symbolic",
                                   "checkout", "above"])
@pytest.mark.slow
def test_out_may_not_be_the_current_folder_a_package_or_the_checkout(tmp_path, where):
    import quadland

    checkout = Path(quadland.__file__).resolve().parents[1]
    target = {"quadland": checkout / "quadland", "quadland/scenarios":
              checkout / "quadland" / "scenarios", "symbolic": checkout / "symbolic",
              "checkout": checkout, "above": checkout.parent}.get(where, where)
    expected = {".": ". is the current folder", "..": ".. is the current folder or holds it",
                "quadland": f"{target} is the package folder",
                "quadland/scenarios": f"{target} lies in the package folder",
                "symbolic": f"{target} is the package folder",
                "checkout": f"{target} is the source checkout's root",
                "above": f"{target} "}[where]     # holds the package (or the current folder)
    (tmp_path / "cwd").mkdir()
    proc = _run("--out", str(target), cwd=tmp_path / "cwd")
    _one_line(proc, expected)
    assert where != "above" or " holds " in proc.stderr
    assert list((tmp_path / "cwd").iterdir()) == []


def test_the_checkout_s_generated_folder_stays_allowed():
    from quadland.codegen import check_target, generated_dir

    check_target(generated_dir())                        # no error


@pytest.mark.slow
def test_a_failure_while_writing_changes_nothing(tmp_path, monkeypatch):
    """A disk that fills up while the files are staged: the earlier tree stays as it was,
    a new folder does not appear, and no staging folder is left."""
    from quadland import codegen

    main(out=tmp_path / "old")
    for path in sorted((tmp_path / "old").glob("*.c"))[:10]:      # so that there is work
        path.write_text("edited\n")
    before = _snapshot(tmp_path)
    real, count = os.fsync, [0]

    def failing(fd):
        count[0] += 1
        if count[0] > 5:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return real(fd)

    monkeypatch.setattr(codegen.os, "fsync", failing)
    for out in ("old", "new"):
        count[0] = 0
        with pytest.raises(CodegenError, match="No space left on device"):
            main(out=tmp_path / out)
    assert _snapshot(tmp_path) == before


def test_a_killed_generation_s_staging_folder_is_removed_by_the_next(tmp_path):
    main(out=tmp_path)
    left = tmp_path / f"{MANIFEST}.tmp-killed"
    left.mkdir()
    (left / "quadland.h").write_text("half")
    old = time.time() - 3600
    os.utime(left, (old, old))
    (tmp_path / "quadland.h").write_text("edited\n")
    assert main(out=tmp_path) == 0
    assert not left.exists()


@pytest.mark.parametrize("rel, named", [("notes.txt", "notes.txt"),
                                        ("example/notes.txt", "example/notes.txt"),
                                        ("src/main.c", "src")])    # a folder not the tree's
@pytest.mark.slow
def test_a_folder_of_the_user_s_without_a_manifest_is_refused(tmp_path, rel, named):
    """D11: ``codegen --out DIR`` mixed the generated tree into a folder of other files
    (81 files written beside ``notes.txt``)."""
    out = tmp_path / "out"
    (out / rel).parent.mkdir(parents=True)
    (out / rel).write_text("the user's\n")
    before = _snapshot(out)
    proc = _run("--out", "out", cwd=tmp_path)
    _one_line(proc, f"out holds {named}, which quadland codegen did not write (there is no "
                    f"{MANIFEST}); choose a new or empty folder")
    assert _snapshot(out) == before


@pytest.mark.slow
def test_an_empty_folder_or_one_with_the_manifest_is_written(tmp_path):
    (tmp_path / "empty").mkdir()
    assert _run("--out", "empty", cwd=tmp_path).returncode == 0
    assert (tmp_path / "empty" / MANIFEST).is_file()
    (tmp_path / "empty" / "notes.txt").write_text("mine\n")      # beside a generation
    proc = _run("--out", "empty", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert (tmp_path / "empty" / "notes.txt").read_text() == "mine\n"
