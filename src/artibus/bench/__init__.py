"""A bench and what it is made of: SSP reading and packing (``ssp``), parameter
sets, their checks and ``--set`` (``parameters``), array names such as
``Bus.mu[*]`` (``names``), units (``units``), the vehicle check (``check``),
roads (``roads``) and a bench's own KPIs and figures, its ``bench.py``
(``script``)."""
