"""Benchmarks of the ocp examples, run from a checkout (they read examples/ and write validation/):
``python -m convexguid.benches.ocp_examples`` (every example against IPOPT on the same NLP) and
``python -m convexguid.benches.openscvx`` (the proximity operation beside OpenSCvx). The classics have their own
package (:mod:`convexguid.classics`), the paper cases theirs (``convexguid bench``, :mod:`convexguid.robustness`)."""
