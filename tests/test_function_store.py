"""quadland.engine.function_store: a builder's CasADi function kept on disk and read back.

The function read back is the one built (its serialization, its values bit for bit), the
builder is not called again, a key changes with what the function is built from, and a
missing, damaged or unwritable store only costs a build. A landing review's margins are
the same from a filled store as from built functions.
"""

from __future__ import annotations

import hashlib
import json

import casadi as ca
import numpy as np
import pytest

from quadland.engine import function_store
from quadland.engine.function_store import FUNCTIONS, HEADER, function_key, stored_function

CALLS: list = []


def square_builder(n: int, scale: float) -> ca.Function:
    """A small builder: the Jacobian of a scaled sum of squares and sines."""
    CALLS.append((n, scale))
    x = ca.SX.sym("x", n)
    f = scale * ca.sumsqr(x) + ca.sum1(ca.sin(x * 1.1))
    return ca.Function("square", [x], [f, ca.jacobian(f, x)])


@pytest.fixture
def store(tmp_path, monkeypatch):
    monkeypatch.setattr(function_store, "cache_dir", lambda: tmp_path)
    stored_function.cache_clear()
    CALLS.clear()
    yield tmp_path / FUNCTIONS
    stored_function.cache_clear()


def _values(f: ca.Function, n: int) -> list[np.ndarray]:
    x = np.linspace(-1.3, 2.9, n)
    return [np.asarray(v) for v in f(x)]


def test_a_function_is_built_once_and_read_back_the_same(store):
    built = stored_function(square_builder, 3, 0.7)
    assert CALLS == [(3, 0.7)]
    assert stored_function(square_builder, 3, 0.7) is built      # one per process
    files = list(store.iterdir())
    assert len(files) == 1 and files[0].name == function_key(square_builder, (3, 0.7))[:32] \
        + ".casadi"
    stored_function.cache_clear()                                 # as a new process
    read = stored_function(square_builder, 3, 0.7)
    assert CALLS == [(3, 0.7)]                                    # not built again
    assert read.serialize() == built.serialize() == square_builder(3, 0.7).serialize()
    for a, b in zip(_values(read, 3), _values(built, 3), strict=True):
        assert np.array_equal(a, b)


def test_the_key_changes_with_what_the_function_is_built_from(store, monkeypatch):
    key = function_key(square_builder, (3, 0.7))
    assert function_key(square_builder, (3, 0.7)) == key
    assert function_key(square_builder, (4, 0.7)) != key
    assert function_key(square_builder, (3, 0.75)) != key
    assert function_key(_values, (3, 0.7)) != key
    monkeypatch.setattr(function_store, "generator_digest", lambda: "another package")
    assert function_key(square_builder, (3, 0.7)) != key
    monkeypatch.undo()
    monkeypatch.setattr(function_store, "library_versions", lambda: "casadi=0")
    assert function_key(square_builder, (3, 0.7)) != key


def test_nothing_is_stored_by_a_process_whose_sources_changed_under_it(store, monkeypatch):
    """With a source written after the process imported the packages, the function is
    built and returned (the same graph) but not written under a key that hashes the new
    text; once no source is newer, the next process stores it."""
    monkeypatch.setattr(function_store, "sources_edited_since_import",
                        lambda: ["quadland_symbolic/paper_loop.py"])
    built = stored_function(square_builder, 2, 0.3)
    assert built.serialize() == square_builder(2, 0.3).serialize()
    assert not store.exists() or not list(store.iterdir())
    monkeypatch.setattr(function_store, "sources_edited_since_import", lambda: [])
    stored_function.cache_clear()
    stored_function(square_builder, 2, 0.3)
    assert [p.name for p in store.iterdir()] == [
        function_key(square_builder, (2, 0.3))[:32] + ".casadi"]


def test_a_process_whose_sources_changed_under_it_reads_no_stored_function(store,
                                                                           monkeypatch):
    """A function stored by a process of the code before is not read back by a process
    during which a source was written (its key may hash the new text while the code it
    runs is the module of before): the builder is called again; once no source is newer
    than the import, the stored file is read (no call)."""
    stored_function(square_builder, 4, 0.2)
    assert CALLS == [(4, 0.2)]
    stored_function.cache_clear()
    monkeypatch.setattr(function_store, "sources_edited_since_import",
                        lambda: ["quadland_symbolic/paper_loop.py"])
    stored_function(square_builder, 4, 0.2)
    assert CALLS == [(4, 0.2)] * 2
    monkeypatch.setattr(function_store, "sources_edited_since_import", lambda: [])
    stored_function.cache_clear()
    read = stored_function(square_builder, 4, 0.2)
    assert CALLS == [(4, 0.2)] * 2
    assert read.serialize() == square_builder(4, 0.2).serialize()


def test_a_source_written_during_the_build_stores_nothing(store, monkeypatch):
    """No source newer than the import before the build, one written during it: the
    function is returned, not stored."""
    answers = iter([[], ["quadland_symbolic/paper_loop.py"]])
    monkeypatch.setattr(function_store, "sources_edited_since_import", lambda: next(answers))
    stored_function(square_builder, 5, 0.4)
    assert CALLS == [(5, 0.4)]
    assert not store.exists() or not list(store.iterdir())


def _stored(function: ca.Function) -> str:
    """The file the store writes for ``function``: its header line, then its text."""
    text = function.serialize()
    return f"{HEADER} {hashlib.sha256(text.encode()).hexdigest()}\n{text}"


def test_a_damaged_file_is_built_again_and_replaced(store):
    built = stored_function(square_builder, 2, 1.5)
    (path,) = store.iterdir()
    assert path.read_text() == _stored(built)
    path.write_text(path.read_text()[:1000])                      # cut short
    stored_function.cache_clear()
    again = stored_function(square_builder, 2, 1.5)
    assert CALLS == [(2, 1.5), (2, 1.5)]
    assert again.serialize() == built.serialize() and path.read_text() == _stored(built)
    path.write_bytes(b"\xff\xfe not a function")
    stored_function.cache_clear()
    assert stored_function(square_builder, 2, 1.5).serialize() == built.serialize()
    assert len(CALLS) == 3


@pytest.mark.parametrize("damage", ["empty", "one character", "no header", "foreign header"])
def test_a_file_casadi_would_read_is_built_again_unless_intact(store, damage):
    """Damage CasADi's reader may take without an error (an empty text reads as a null
    function; a changed operation code crashes the call later) is caught by the digest."""
    built = stored_function(square_builder, 2, 1.5)
    (path,) = store.iterdir()
    head, _, text = path.read_text().partition("\n")
    i = len(text) * 3 // 4
    damaged = {"empty": "",
               "one character": f"{head}\n{text[:i]}{'b' if text[i] == 'a' else 'a'}{text[i + 1:]}",
               "no header": text,
               "foreign header": f"{HEADER} {'0' * 64}\n{text}"}[damage]
    path.write_text(damaged)
    stored_function.cache_clear()
    again = stored_function(square_builder, 2, 1.5)
    assert len(CALLS) == 2                                         # built again
    assert again.serialize() == built.serialize() and path.read_text() == _stored(built)


def test_an_unwritable_store_only_costs_the_build(store):
    store.write_text("a file where the folder would be")
    f = stored_function(square_builder, 2, 0.5)
    assert CALLS == [(2, 0.5)]
    assert np.array_equal(_values(f, 2)[0], _values(square_builder(2, 0.5), 2)[0])


def test_a_landing_review_is_the_same_from_a_filled_store(store, monkeypatch):
    """highway's review with the hover's functions built (and stored), then with them read
    back from the store: the same report, number for number."""
    import quadland
    from quadland.margins import margin_report

    read = []
    deserialize = ca.Function.deserialize

    def spy(text):
        read.append(len(text))
        return deserialize(text)

    monkeypatch.setattr(ca.Function, "deserialize", staticmethod(spy))
    sc = quadland.load_scenario("highway")
    built = margin_report(sc).to_dict()
    assert read == [] and len(list(store.iterdir())) == 4
    stored_function.cache_clear()
    again = margin_report(sc).to_dict()
    assert len(read) == 4
    for d in (built, again):
        d.pop("runtime_s", None)
    assert json.dumps(again, sort_keys=True) == json.dumps(built, sort_keys=True)
