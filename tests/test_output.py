"""Output folders, whole files and deterministic PNGs."""

import re

import pytest
from matplotlib.figure import Figure

from quadland.exceptions import QuadlandError
from quadland.output import MARKER, OutputFolder, figure_png, output_folder, write_files


def _figure():
    fig = Figure(figsize=(3, 2))
    fig.subplots().plot([0, 1, 2], [1, 0, 1])
    return fig


def test_default_folder_is_named_and_unique(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    first = output_folder(None, "paper", "margins")
    assert first.path.parent == tmp_path
    assert re.fullmatch(r"paper-margins-\d{8}-\d{6}", first.path.name)
    assert not first.path.exists()                 # named, not created
    write_files(first, {})
    second = output_folder(None, "paper", "margins")
    assert second.path != first.path and not second.path.exists()
    assert re.fullmatch(r"paper-margins-\d{8}-\d{6}(-2)?", second.path.name)
    assert re.fullmatch(r"paper-\d{8}-\d{6}", output_folder(None, "paper").path.name)


def test_folder_given_is_checked_before_any_work(tmp_path):
    assert output_folder(tmp_path / "new", "paper").path == tmp_path / "new"
    assert not (tmp_path / "new").exists()
    afile = tmp_path / "file"
    afile.write_text("keep")
    with pytest.raises(QuadlandError, match=r"^out: .*file exists and is not a folder$"):
        output_folder(afile, "paper")
    with pytest.raises(QuadlandError, match="exists and is not a folder"):
        write_files(afile, {"a.txt": b"x"})
    assert afile.read_text() == "keep"


def test_a_set_replaces_the_earlier_set_whole(tmp_path):
    folder = tmp_path / "a" / "b"
    assert write_files(folder, {"x.json": b"{}\n", "y.png": b"\x89PNG"}) == folder
    assert (folder / "x.json").read_bytes() == b"{}\n"
    write_files(folder, {"x.json": b"[]\n"})
    assert (folder / "x.json").read_bytes() == b"[]\n"
    assert sorted(p.name for p in folder.iterdir()) == [MARKER, "x.json"]
    assert sorted(p.name for p in folder.parent.iterdir()) == ["b"]   # nothing stray


def test_a_folder_of_other_files_is_refused(tmp_path):
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / "thesis.tex").write_text("mine")
    with pytest.raises(QuadlandError, match="not a quadland output"):
        write_files(tmp_path / "out", {"x.json": b"{}"})
    assert [p.name for p in (tmp_path / "out").iterdir()] == ["thesis.tex"]


def test_a_claimed_folder_refuses_a_second_run(tmp_path):
    with OutputFolder(tmp_path / "out"):
        with pytest.raises(QuadlandError, match="in use by another quadland run"):
            OutputFolder(tmp_path / "out").claim()
    OutputFolder(tmp_path / "out").claim().release()       # free again
    assert list(tmp_path.iterdir()) == []


def test_leftovers_of_a_killed_run_are_cleaned_and_never_results(tmp_path):
    stale = tmp_path / ".out.tmp-abc123"
    stale.mkdir()
    (stale / "trajectory.csv").write_text("half")
    write_files(tmp_path / "out", {"x.json": b"{}"})
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]


def test_swap_without_an_atomic_exchange(tmp_path, monkeypatch):
    """Where renameat2 is missing the old set is kept aside until the new one is in."""
    import quadland.output as output

    class NoRenameat2:
        def __getattr__(self, name):
            raise AttributeError(name)

    write_files(tmp_path / "out", {"old.txt": b"1"})
    monkeypatch.setattr(output.ctypes, "CDLL", lambda *a, **k: NoRenameat2())
    write_files(tmp_path / "out", {"new.txt": b"2"})
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == [MARKER, "new.txt"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]


@pytest.mark.parametrize("name", ["../x", "sub/x", "", ".."])
def test_write_files_takes_plain_names_only(tmp_path, name):
    with pytest.raises(ValueError):
        write_files(tmp_path / "out", {name: b""})
    assert not (tmp_path / "out").exists()


def test_figure_png_is_deterministic():
    one, two = figure_png(_figure()), figure_png(_figure())
    assert one[:8] == b"\x89PNG\r\n\x1a\n"
    assert one == two
    assert b"Software" not in one and b"matplotlib" not in one
    # 3 x 2 in at 110 dpi
    assert int.from_bytes(one[16:20], "big") == 330 and int.from_bytes(one[20:24], "big") == 220


def test_figure_png_closes_a_pyplot_figure():
    plt = pytest.importorskip("matplotlib.pyplot")
    fig, ax = plt.subplots()
    ax.plot([0, 1])
    figure_png(fig)
    assert fig.number not in plt.get_fignums()


def test_user_files_beside_an_earlier_set_are_never_deleted(tmp_path):
    folder = tmp_path / "r2"
    write_files(folder, {"x.json": b"{}"})
    (folder / "notes.txt").write_text("mine")
    (folder / "analysis").mkdir()
    with pytest.raises(QuadlandError, match="not a quadland output"):
        write_files(folder, {"x.json": b"[]"})
    assert (folder / "notes.txt").read_text() == "mine" and (folder / "analysis").is_dir()


def test_a_nested_output_is_not_replaced_by_its_parent(tmp_path):
    write_files(tmp_path / "r2" / "inner", {"a.txt": b"1"})
    with pytest.raises(QuadlandError, match="not a quadland output"):
        write_files(tmp_path / "r2", {"b.txt": b"2"})
    assert (tmp_path / "r2" / "inner" / "a.txt").read_bytes() == b"1"


def test_files_that_appear_during_the_run_stay(tmp_path):
    folder = OutputFolder(tmp_path / "e2")
    with folder:
        (tmp_path / "e2").mkdir()
        (tmp_path / "e2" / "thesis.tex").write_text("written meanwhile")
        with pytest.raises(QuadlandError, match="gained files .* nothing was replaced"):
            folder.write({"x.json": b"{}"})
    assert (tmp_path / "e2" / "thesis.tex").read_text() == "written meanwhile"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["e2"]


def test_symlinks_and_the_current_folder_are_refused(tmp_path, monkeypatch):
    write_files(tmp_path / "real", {"x.json": b"{}"})
    (tmp_path / "lnk").symlink_to(tmp_path / "real")
    with pytest.raises(QuadlandError, match="symbolic link"):
        write_files(tmp_path / "lnk", {"x.json": b"[]"})
    monkeypatch.chdir(tmp_path / "real")
    for target in (".", str(tmp_path / "real"), str(tmp_path)):
        with pytest.raises(QuadlandError, match="current folder or holds it"):
            OutputFolder(target).claim()


def test_two_default_names_in_one_second_differ(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    first = output_folder(None, "paper")          # claimed: a second run takes another name
    second = output_folder(None, "paper")
    assert first.path != second.path
    first.release()
    second.release()


def test_glob_characters_in_a_name_touch_no_other_run(tmp_path):
    other = tmp_path / ".run1.tmp-abc"
    other.mkdir()
    write_files(tmp_path / "run[1]", {"x.json": b"{}"})
    assert other.is_dir()                         # '[1]' is not a pattern


# --- work folders held while in use, removed once abandoned --------------------------

def test_remove_abandoned_takes_only_old_unheld_folders(tmp_path):
    import os
    import subprocess
    import sys
    import time
    from pathlib import Path

    from quadland.output import WorkFolder, remove_abandoned

    old = time.time() - 3600
    abandoned, young = tmp_path / ".w-abandoned", tmp_path / ".w-young"
    for p in (abandoned, young):
        p.mkdir()
        (p / "x").write_text("x")
    link = tmp_path / ".w-link"
    link.symlink_to(abandoned)
    # held by another live process: its flock, not this process's
    code = ("import sys, time; from quadland.output import WorkFolder; "
            f"w = WorkFolder({str(tmp_path)!r}, '.w-other-'); print(w.path, flush=True); "
            "sys.stdin.read()")
    other = subprocess.Popen([sys.executable, "-c", code], stdin=subprocess.PIPE,
                             stdout=subprocess.PIPE, text=True)
    try:
        held_elsewhere = Path(other.stdout.readline().strip())
        with WorkFolder(tmp_path, ".w-") as held:
            for p in (abandoned, held.path, held_elsewhere, link):
                os.utime(p, (old, old), follow_symlinks=False)
            assert remove_abandoned(tmp_path, ".w-*", 60) == 1
            assert not abandoned.exists() and link.is_symlink()        # a link is left alone
            assert held.path.exists() and held_elsewhere.exists() and young.exists()
        assert not held.path.exists()                     # leaving removes it
    finally:
        other.stdin.close()
        other.wait(timeout=60)
    # the holder is gone (as after SIGKILL, its lock went with it)
    os.utime(held_elsewhere, (old, old))
    assert held_elsewhere.exists() and remove_abandoned(tmp_path, ".w-*", 60) == 1
    assert not held_elsewhere.exists()
