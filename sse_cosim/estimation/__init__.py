"""Set-membership estimation of pedestrians, per node and at the bus (paper Section III).

- :mod:`.motion`: the motion models by name (p = s + e): their sets, reach and arrivals.
- :mod:`.observer`: every node's local observer (first fusion level), whose correction step
  (Proposition 1, inconsistent sensors left out) is :mod:`.correction`.
- :mod:`.vote`: the consistency vote and probation both levels use.
- :mod:`.v2x`: messages between nodes and the bus, late or never.
- :mod:`.fusion_centre`: the bus's step -- :mod:`.bus_screen`, :mod:`.bus_fusion`
  (Proposition 2), :mod:`.flags`.
- :mod:`.occupancy`: negative information, as polygons; :mod:`.kalman`: a baseline.
"""
