"""quadland.plots.text_cache.font_paths: the font files matplotlib finds for font properties,
kept per what they are found from.

The reference is matplotlib's own ``fontManager._find_fonts_by_props``, called afresh after
each change of the properties, of the rc parameters and of the font list.
"""

from __future__ import annotations

import matplotlib as mpl
from matplotlib.font_manager import FontProperties, fontManager

from quadland.plots import text_cache


def _theirs(prop):
    return tuple(fontManager._find_fonts_by_props(prop))


def test_the_files_are_matplotlibs_for_each_font():
    for kw in ({}, {"family": "serif"}, {"family": "monospace", "weight": "bold"},
               {"family": ["DejaVu Serif", "DejaVu Sans"]}, {"style": "italic", "size": 7},
               {"family": "sans-serif", "stretch": "condensed", "variant": "small-caps"}):
        prop = FontProperties(**kw)
        assert text_cache.font_paths(prop) == _theirs(prop)
        assert text_cache.font_paths(prop) == _theirs(prop)       # from the kept entry


def test_changed_properties_and_rc_parameters_are_found_again():
    prop = FontProperties(family=["sans-serif"])
    first = text_cache.font_paths(prop)
    prop.set_family("serif")
    assert text_cache.font_paths(prop) == _theirs(prop) != first
    prop.set_family("sans-serif")
    with mpl.rc_context({"font.sans-serif": ["DejaVu Serif"]}):
        assert text_cache.font_paths(prop) == _theirs(prop) != first
    assert text_cache.font_paths(prop) == first


def test_a_font_list_grown_starts_a_new_entry(monkeypatch):
    calls = []
    find = fontManager._find_fonts_by_props

    def counted(prop, *args, **kwargs):
        calls.append(prop)
        return find(prop, *args, **kwargs)

    monkeypatch.setattr(fontManager, "_find_fonts_by_props", counted)
    prop = FontProperties(family="monospace", size=13.25)
    text_cache.font_paths(prop)
    text_cache.font_paths(prop)
    assert len(calls) == 1
    monkeypatch.setattr(fontManager, "ttflist", [*fontManager.ttflist, fontManager.ttflist[0]])
    text_cache.font_paths(prop)
    assert len(calls) == 2


def test_a_changed_default_family_is_found_again(monkeypatch, caplog):
    """A family not installed falls back to the font manager's default family, read by
    ``_find_fonts_by_props`` on every call: changed, the files are matplotlib's new ones."""
    import logging

    caplog.set_level(logging.ERROR)
    prop = FontProperties(family="No Such Family Anywhere")
    first = text_cache.font_paths(prop)
    assert first == _theirs(prop)
    monkeypatch.setitem(fontManager.defaultFamily, "ttf", "DejaVu Serif")
    assert text_cache.font_paths(prop) == _theirs(prop) != first
