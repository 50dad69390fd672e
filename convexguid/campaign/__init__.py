"""Campaigns: parameter sweeps and Monte Carlo over any problem file, run on Dask.

A campaign file (:mod:`~convexguid.campaign.definition`) names a problem file, a grid over its keys and random
dispersions; :mod:`~convexguid.campaign.plan` expands it into runs with their exact ``--set`` overrides and
seeds; :mod:`~convexguid.campaign.execute` runs them on a ``dask.distributed`` cluster (a local one by default)
or in process; :mod:`~convexguid.campaign.table` appends each result to a Parquet table as it arrives, so an
interrupted campaign resumes; :mod:`~convexguid.campaign.document` writes the markdown page and
:mod:`~convexguid.campaign.plots` its plots. :func:`run_campaign` (:mod:`~convexguid.campaign.run`) does all of
it, and ``convexguid campaign`` calls it.
"""

from convexguid.campaign.run import CampaignResult, run_campaign

__all__ = ["CampaignResult", "run_campaign"]
