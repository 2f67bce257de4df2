"""The ``[disturbance]`` section's force and moment, sampled and held."""

from __future__ import annotations

import numpy as np

from quadland.scenario import Scenario

__all__ = ["disturbance_samples"]


def disturbance_samples(scenario: Scenario, times: np.ndarray) -> np.ndarray:
    """Disturbance ``[d_F, d_M]`` held from each of ``times`` to the next.

    ``bias + amplitude sin(frequency t) + noise_std n`` per axis, where ``n``
    is standard normal, drawn from a generator seeded with
    ``simulation.seed`` (Section 4 of the paper). The draws do not depend on
    ``disturbance.noise``, which only zeroes them.

    Returns
    -------
    ndarray, shape (6, len(times))
    """
    d = scenario.data["disturbance"]
    rng = np.random.default_rng(scenario.data["simulation"]["seed"])
    # one row of six draws per sample: sample k gets the same draws whatever the duration
    noise = rng.standard_normal((len(times), 6)).T * float(d["noise"])
    t = np.asarray(times)[None, :]
    d_F = (np.asarray(d["force_bias"])[:, None] + d["force_amplitude"]
           * np.sin(d["force_frequency"] * t) + d["force_noise_std"] * noise[0:3])
    d_M = (np.asarray(d["moment_bias"])[:, None] + d["moment_amplitude"]
           * np.sin(d["moment_frequency"] * t) + d["moment_noise_std"] * noise[3:6])
    return np.vstack([d_F, d_M])
