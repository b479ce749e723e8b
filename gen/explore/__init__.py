"""The design-space explorer (:mod:`.explorer`) and the Dask engine its evaluations and
the paper's resource sweep run on (:mod:`.engine`)."""
