"""Monte Carlo campaigns: dispersed runs of a scenario, on every core or a Dask cluster.

A scenario's ``[campaign]`` table (:mod:`quadland.campaign.spec`, validated by
:func:`campaign_spec_of` when a campaign runs) names the
dispersed keys; :mod:`~quadland.campaign.sampling` gives run ``i`` its seed
and values from the campaign seed and ``i`` alone; :mod:`~quadland.campaign.fly`
flies one run; :mod:`~quadland.campaign.journal` records each finished run
durably in the campaign folder; :mod:`~quadland.campaign.statistics` holds the
Clopper-Pearson interval, the order statistics and the separation of failures;
:mod:`~quadland.campaign.execute` runs a campaign (``quadland campaign``), with
:mod:`~quadland.campaign.local`, :mod:`~quadland.campaign.cluster`,
:mod:`~quadland.campaign.resume` and :mod:`~quadland.campaign.summary`.
:mod:`~quadland.campaign.grid` flies an envelope (``quadland envelope``): a grid
of two keys (:mod:`~quadland.campaign.axes`), each cell a small campaign,
counted by :mod:`~quadland.campaign.cells`. See docs/campaign.md and docs/cli.md.
"""

__all__ = ["CampaignSpec", "Dispersion", "campaign_spec", "campaign_spec_of", "RunDraw",
           "draws", "run_seed", "RunOutcome", "fly", "clopper_pearson", "order_statistic",
           "separation",
           "CampaignResult", "run_campaign", "summarize_campaign", "EnvelopeResult",
           "run_envelope", "cell_statistics"]

# The submodules import NumPy, SciPy and the simulator: load them on first use.
_LAZY = {"CampaignSpec": "spec", "Dispersion": "spec", "campaign_spec": "spec",
         "campaign_spec_of": "spec",
         "RunDraw": "sampling", "draws": "sampling", "run_seed": "sampling",
         "RunOutcome": "fly", "fly": "fly",
         "clopper_pearson": "statistics", "order_statistic": "statistics",
         "separation": "statistics",
         "CampaignResult": "execute", "run_campaign": "execute",
         "summarize_campaign": "summary", "EnvelopeResult": "grid", "run_envelope": "grid",
         "cell_statistics": "cells"}


def __getattr__(name):
    if name in _LAZY:
        import importlib

        return getattr(importlib.import_module(f"quadland.campaign.{_LAZY[name]}"), name)
    raise AttributeError(f"module 'quadland.campaign' has no attribute {name!r}")
