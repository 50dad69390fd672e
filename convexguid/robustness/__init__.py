"""The robustness benchmark: does convexguid give the right answer, and the same one on every machine?

Two sections, run on the campaign machinery (a local Dask cluster of single-threaded workers, or in process):

* **round-off**: every problem file solved as written and with its physical inputs moved by 1e-12 relative
  (:func:`convexguid.spec.perturb.perturb_inputs`): the same status, objective and iteration counts expected;
* **random instances** of each planned family (:mod:`convexguid.robustness.instances`), each judged against
  the family's independent optimum (:attr:`convexguid.families.base.Family.independent_optimum`: IPOPT on the
  same NLP from several starts, or the LCvx relaxation): a success is ``converged``, verified and within
  :data:`~convexguid.robustness.trial.GAP_TOLERANCE` of the best reference, or ``infeasible`` where the reference
  proves it.

Run ``python -m convexguid.robustness`` from the repository root; it writes ``validation/ROBUSTNESS.md``.
"""
