"""``convexguid validate``: every paper case solved and set beside its published table (:mod:`.run`), the
cross-method tables (:mod:`.comparisons`), the timings file (:mod:`.timings`) and the comparison of a fresh report
with the committed one (:mod:`.reproduction`)."""
