"""Output folders, whole files and deterministic PNGs."""

import re

import pytest
from matplotlib.figure import Figure

from quadland.exceptions import QuadlandError
from quadland.output import figure_png, output_folder, write_files


def _figure():
    fig = Figure(figsize=(3, 2))
    fig.subplots().plot([0, 1, 2], [1, 0, 1])
    return fig


def test_default_folder_is_named_and_unique(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    first = output_folder(None, "paper", "margins")
    assert first.parent == tmp_path
    assert re.fullmatch(r"paper-margins-\d{8}-\d{6}", first.name)
    assert not first.exists()                      # named, not created
    write_files(first, {})
    second = output_folder(None, "paper", "margins")
    assert second != first and not second.exists()
    assert re.fullmatch(r"paper-margins-\d{8}-\d{6}(-2)?", second.name)
    assert re.fullmatch(r"paper-\d{8}-\d{6}", output_folder(None, "paper").name)


def test_folder_given_is_checked_before_any_work(tmp_path):
    assert output_folder(tmp_path / "new", "paper") == tmp_path / "new"
    assert not (tmp_path / "new").exists()
    afile = tmp_path / "file"
    afile.write_text("keep")
    with pytest.raises(QuadlandError, match=r"^out: .*file exists and is not a folder$"):
        output_folder(afile, "paper")
    with pytest.raises(QuadlandError, match="exists and is not a folder"):
        write_files(afile, {"a.txt": b"x"})
    assert afile.read_text() == "keep"


def test_write_files_creates_and_replaces_whole_files(tmp_path):
    folder = tmp_path / "a" / "b"
    assert write_files(folder, {"x.json": b"{}\n", "y.png": b"\x89PNG"}) == folder
    assert (folder / "x.json").read_bytes() == b"{}\n"
    (folder / "other.txt").write_text("left alone")
    write_files(folder, {"x.json": b"[]\n"})
    assert (folder / "x.json").read_bytes() == b"[]\n"
    assert sorted(p.name for p in folder.iterdir()) == ["other.txt", "x.json", "y.png"]


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
