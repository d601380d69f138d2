"""The simulated world: the road network (``network``, ``roadmap``), the scenario's actors as
SUMO demand (``demand``), the per-step state (``snapshot``) and the SUMO adapter (``sumo``, the
only module that imports libsumo; import it explicitly, this package does not)."""
