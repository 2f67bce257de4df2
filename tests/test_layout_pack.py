"""``Layout.pack`` writing its blocks in place: the vector of the blocks' concatenation.

The reference is the concatenation ``pack`` computed before (issue 20, seventeenth
session): each real field's block through ``numpy.asarray(v, dtype=float)``, flattened
column-major, nested dicts packed by their layout, then ``numpy.concatenate``. Compared bit
for bit on every vector a landing's set-up packs (``highway`` and ``ship``, their campaigns'
first runs) and on a layout of every kind of field and value.
"""

from __future__ import annotations

import numpy as np
import pytest

from quadland.campaign.dispersed import dispersed
from quadland.campaign.sampling import draws
from quadland.campaign.spec import campaign_spec_of
from quadland.kinds.landing.sensed import sensed_vectors
from quadland.kinds.landing.values import landing_values
from quadland.scenario import load_scenario
from quadland_symbolic.layout import Field, Layout


def concatenated(layout: Layout, values) -> np.ndarray:
    """The slow path: each block converted and flattened, then concatenated."""
    missing = [f.name for f in layout.fields if f.ctype == "real" and f.name not in values]
    if missing:
        raise KeyError(f"{layout.name}: missing {missing}")
    chunks = []
    for f in layout.fields:
        if f.ctype != "real":
            continue
        v = values[f.name]
        if f.layout is not None and isinstance(v, dict):
            v = concatenated(f.layout, v)
        flat = np.asarray(v, dtype=float).reshape(-1, order="F")
        if flat.size != f.size:
            raise ValueError(f"{layout.name}.{f.name}: expected {f.size} values, "
                             f"got {flat.size}")
        chunks.append(flat)
    return np.concatenate(chunks) if chunks else np.zeros(0)


def _same(a: np.ndarray, b: np.ndarray) -> bool:
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


@pytest.mark.parametrize("name", ["highway", "ship"])
def test_every_vector_a_landing_s_set_up_packs_is_the_concatenation(name, monkeypatch):
    packed = []
    fast = Layout.pack

    def recording(self, values):
        out = fast(self, values)
        packed.append((self, dict(values), out))
        return out

    monkeypatch.setattr(Layout, "pack", recording)
    base = load_scenario(name)
    spec = campaign_spec_of(base)
    for draw in draws(spec, range(4)):
        scenario = dispersed(base, draw.values)
        sensed_vectors(scenario, landing_values(scenario))
    assert len(packed) > 40
    for layout, values, out in packed:
        assert _same(out, concatenated(layout, values)), layout.name


INNER = Layout("inner", (Field("a", 1, "m", "a"), Field("b", 2, "m", "b")))
OUTER = Layout("outer", (
    Field("x", 1, "m", "a scalar"),
    Field("n", 1, "-", "an int in C only", ctype="int"),
    Field("m", 6, "m", "a matrix", shape=(2, 3)),
    Field.nested("p", INNER, "a nested layout"),
    Field("v", 3, "m", "a vector"),
    Field("y", 1, "m", "another scalar"),
))


@pytest.mark.parametrize("x, y", [
    (1.5, -0.0), (0, 7), (True, False), (np.float64(2.5), np.int64(-3)), (2**53 + 1, 2**62 + 123),
    (float("nan"), float("inf")), ([4.0], np.array([[5.0]])), (np.float32(0.1), 1e-320),
])
def test_a_layout_of_every_kind_of_field_and_value_packs_the_concatenation(x, y):
    rng = np.random.default_rng(3)
    m = rng.normal(size=(2, 3))
    for p in ({"a": 1, "b": [2.0, -0.0]}, np.array([1.0, 2.0, 3.0])):
        values = {"x": x, "m": m, "p": p, "v": (1, 2.5, np.float64(-1.0)), "y": y, "n": 3}
        got, ref = OUTER.pack(values), concatenated(OUTER, values)
        assert _same(got, ref)
    assert _same(OUTER.pack({**values, "m": np.asfortranarray(m)}), ref)
    assert _same(Layout("empty", ()).pack({}), concatenated(Layout("empty", ()), {}))


def test_the_same_refusals_as_the_concatenation():
    good = {"x": 1.0, "m": np.zeros((2, 3)), "p": np.zeros(3), "v": np.zeros(3), "y": 2.0}
    for bad in ({k: v for k, v in good.items() if k not in ("x", "v")},     # two missing
                {**good, "v": np.zeros(2)},                                  # a wrong size
                {**good, "x": [1.0, 2.0]},                                   # a scalar's
                {**good, "p": {"a": 1.0}},                                   # nested missing
                {k: v for k, v in {**good, "m": np.zeros(5)}.items() if k != "y"}):  # both
        with pytest.raises((KeyError, ValueError)) as ref:
            concatenated(OUTER, bad)
        with pytest.raises(ref.type) as got:
            OUTER.pack(bad)
        assert str(got.value) == str(ref.value)
