"""Studies of many runs: sweeps on Dask (``sweep``), KPIs (``kpi``), frequency
responses by sine tests (``bode``), the complementary gain Kc(v) (``kc``) and
seed 001's articulation damping study (``damping``)."""
