"""sse-cosim: set-membership estimation in shared situational awareness, co-simulated with SUMO.

Folders, one concern each, in the order data flows through a simulation step:

- ``scenario``   -- validated scenario files (pydantic), ``extends`` inheritance
- ``world``      -- the SUMO adapter (the only module importing ``libsumo``) and snapshot types
- ``sensors``    -- fields of view, occlusion ray-casting, bounded-noise strips (pure geometry)
- ``sets``       -- zonotopes, strips, Propositions 1 and 2 (pure math)
- ``estimation`` -- per-node observers, V2X sharing, the bus's fused estimate
- ``control``    -- situational picture and speed levels
- ``runner``     -- one simulation run, batches and sweeps
- ``reporting``  -- traces, summaries, tables and plots
- ``cli``        -- the ``sse-cosim`` command
"""

__version__ = "0.1.0"
