"""The classics benchmark: published optimal-control problems (COPS 3.0, Betts 2010, Bryson & Ho, the GNC
literature) stated from their papers in ``examples/classics/``, solved by convexguid and by IPOPT on the same
transcription; ``python -m convexguid.classics`` writes validation/CLASSICS.md (:mod:`convexguid.classics.bench`)."""
