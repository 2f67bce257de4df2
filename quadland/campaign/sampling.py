"""Each run's seed and dispersed values, from the campaign seed and the run's index.

Run ``i``'s seed is drawn from ``numpy.random.SeedSequence(campaign_seed,
spawn_key=(i,))``, which is the ``i``-th child of
``SeedSequence(campaign_seed).spawn(n)`` for any ``n > i``: it depends on the
campaign seed and ``i`` alone, so run ``i`` is the same whatever the worker
count, the order of the runs or the machine. The dispersions map a point
``u`` of the unit cube to values through each distribution's inverse CDF;
``u`` comes from the run's own generator (``random``) or from a scrambled
Sobol' sequence or a Latin hypercube over the campaign (``sobol``, ``lhs``,
``scipy.stats.qmc``, seeded by the campaign seed).
"""

from __future__ import annotations

import dataclasses
import inspect
import math
from collections.abc import Iterable, Iterator, Mapping
from typing import Any

import numpy as np

from quadland.campaign.draws import U_EDGE, apply_mode
from quadland.campaign.spec import CampaignSpec, Dispersion

__all__ = ["RunDraw", "run_seed", "unit_samples", "draws", "iter_draws", "format_value",
           "U_EDGE"]


@dataclasses.dataclass(frozen=True)
class RunDraw:
    """One run's seed and dispersed values.

    Attributes
    ----------
    index : int
    seed : int
        The run's seed (63 bits).
    values : mapping
        ``section.key`` -> value, as :meth:`quadland.Scenario.replace` takes it.
    columns : mapping
        runs.csv column -> text of the value.
    """

    index: int
    seed: int
    values: Mapping[str, Any]
    columns: Mapping[str, str]

    def overrides(self) -> list[str]:
        """The values as ``--set`` texts (exact: floats as their shortest round trip)."""
        from quadland.scenario import toml_value

        return [f"{k}={toml_value(v)}" for k, v in self.values.items()]


def run_seed(campaign_seed: int, index: int) -> int:
    """Run ``index``'s seed: 63 bits of ``SeedSequence(campaign_seed, spawn_key=(index,))``."""
    child = np.random.SeedSequence(campaign_seed, spawn_key=(index,))
    return int(child.generate_state(1, np.uint64)[0] >> np.uint64(1))


def _qmc(kind, d: int, campaign_seed: int):
    """A ``scipy.stats.qmc`` engine seeded by the campaign (``rng=``, or ``seed=`` before 1.15)."""
    rng = np.random.default_rng(np.random.SeedSequence(campaign_seed, spawn_key=(2 ** 32,)))
    keyword = "rng" if "rng" in inspect.signature(kind).parameters else "seed"
    return kind(d, scramble=True, **{keyword: rng})


def unit_samples(spec: CampaignSpec, indices: Iterable[int], runs: int | None = None
                 ) -> np.ndarray:
    """Points of the unit cube for the runs ``indices``, one row each.

    ``random``: run ``i``'s row is ``default_rng(run_seed(seed, i)).random(d)``.
    ``sobol``: row ``i`` of the scrambled Sobol' sequence (its first rows do
    not depend on how many follow). ``lhs``: row ``i`` of a Latin hypercube
    of ``runs`` points (default ``spec.runs``), which depends on ``runs``.
    """
    idx = np.asarray(list(indices), dtype=np.int64)
    d = spec.dims
    if d == 0 or idx.size == 0:
        return np.zeros((idx.size, d))
    if spec.sampling == "random":
        u = np.array([np.random.default_rng(run_seed(spec.seed, int(i))).random(d) for i in idx])
        return np.clip(u, U_EDGE, 1.0 - U_EDGE)
    # scipy.stats takes a second to import: only the space-filling samplings need it
    from scipy.stats import qmc

    if spec.sampling == "sobol":
        m = max(0, math.ceil(math.log2(int(idx.max()) + 1)))
        u = _qmc(qmc.Sobol, d, spec.seed).random_base2(m)[idx]
    else:
        u = _qmc(qmc.LatinHypercube, d, spec.seed).random(runs or spec.runs)[idx]
    return np.clip(u, U_EDGE, 1.0 - U_EDGE)


def _numeric(disp: Dispersion, u: np.ndarray) -> np.ndarray:
    """The draws ``X`` of a numeric dispersion at ``u`` (one per dimension; a row per run
    for ``u`` of shape ``(runs, dims)``: each element as alone, the same bits)."""
    if disp.distribution == "uniform":
        lo, hi = np.array(disp.low), np.array(disp.high)
        return lo + u * (hi - lo)
    mean, std = np.array(disp.mean), np.array(disp.std)
    if disp.distribution == "normal":
        from scipy.special import ndtri

        return mean + std * ndtri(u)
    from scipy import stats

    lo, hi = np.array(disp.low), np.array(disp.high)
    # std = 0, or a spread so small against the distance to [low, high] that
    # all the mass sits at the nearest bound (the standardized bounds overflow)
    out = np.broadcast_to(np.clip(mean, lo, hi), np.shape(u)).copy()
    spread = std > 0
    if spread.any():
        with np.errstate(all="ignore"):
            a = (lo[spread] - mean[spread]) / std[spread]
            b = (hi[spread] - mean[spread]) / std[spread]
            x = mean[spread] + std[spread] * stats.truncnorm.ppf(u[..., spread], a, b)
        out[..., spread] = np.where(np.isfinite(x), x, out[..., spread])
    return np.clip(out, lo, hi)                 # never outside its bounds, even by rounding


def _choose(disp: Dispersion, u: float):
    weights = np.ones(len(disp.values)) if disp.weights is None else np.array(disp.weights)
    with np.errstate(over="ignore"):
        total = weights.sum()
    if not np.isfinite(total):                  # weights near 1e308 overflow their sum
        weights = weights / weights.max()
    edges = np.cumsum(weights) / weights.sum()
    k = min(int(np.searchsorted(edges, u, side="right")), len(disp.values) - 1)
    while weights[k] == 0:                          # never pick a zero-weight value
        k -= 1
    return disp.values[k]


def format_value(value) -> str:
    """A value as runs.csv holds it: numbers as their shortest round trip, else TOML."""
    if isinstance(value, float):
        return repr(value)
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    from quadland.scenario import toml_value

    return toml_value(value)


def draws(spec: CampaignSpec, indices: Iterable[int], runs: int | None = None
          ) -> list[RunDraw]:
    """Each run's :class:`RunDraw`, in the order of ``indices``."""
    return list(iter_draws(spec, indices, runs))


def iter_draws(spec: CampaignSpec, indices: Iterable[int], runs: int | None = None,
               chunk: int = 1024) -> Iterator[RunDraw]:
    """:func:`draws`, computed ``chunk`` runs at a time (a campaign may have a million)."""
    idx = list(indices)
    whole = None
    if spec.sampling != "random" and idx:          # one matrix for the whole campaign
        whole = unit_samples(spec, range(max(idx) + 1), runs)
    for start in range(0, len(idx), chunk):
        part = idx[start:start + chunk]
        U = whole[part] if whole is not None else unit_samples(spec, part, runs)
        # each numeric dispersion's inverse CDF once for the chunk's runs (per run, the
        # truncated normal's was 1 ms of a landing's 46), element for element the same
        X, col = [], 0
        for disp in spec.dispersions:
            numeric = disp.distribution not in ("seed", "choice")
            X.append(_numeric(disp, U[:, col:col + disp.dims]) if numeric else None)
            col += disp.dims
        for row, i in enumerate(part):
            yield _draw(spec, i, U[row], [None if x is None else x[row] for x in X])


def _draw(spec: CampaignSpec, i: int, u_row: np.ndarray, xs: list) -> RunDraw:
    """Run ``i``'s draw from its point ``u_row`` and its numeric dispersions' values
    ``xs`` (None for the others)."""
    seed = run_seed(spec.seed, i)
    values, columns, col = {}, {}, 0
    for disp, x in zip(spec.dispersions, xs, strict=True):
        u = u_row[col:col + disp.dims]
        col += disp.dims
        if disp.distribution == "seed":
            values[disp.key] = seed
            columns[disp.key] = str(seed)
            continue
        if disp.distribution == "choice":
            value = _choose(disp, float(u[0]))
            values[disp.key] = list(value) if isinstance(value, tuple) else value
            columns[disp.key] = format_value(value)
            continue
        for t, target in enumerate(disp.targets):
            per = [apply_mode(disp.mode, nom, float(x[0 if (t or len(x) == 1) else e]))
                   for e, nom in enumerate(target.nominal)]
            values[target.key] = per[0] if target.scalar else per
            columns.update(zip(target.columns(), map(format_value, per), strict=True))
    return RunDraw(i, seed, values, columns)
