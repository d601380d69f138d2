"""sse-cosim: set-membership estimation in shared situational awareness, co-simulated with SUMO.

Folders, one concern each, in the order data flows through a simulation step:

- ``scenario``   -- validated scenario files (pydantic), ``extends`` inheritance
- ``world``      -- the SUMO adapter (the only module importing ``libsumo``) and snapshot types
- ``sensors``    -- fields of view, occlusion ray-casting, bounded-noise strips (pure geometry)
- ``sets``       -- zonotopes, strips, Propositions 1 and 2 (pure math)
- ``estimation`` -- per-node observers, V2X sharing, the bus's fused estimate
- ``control``    -- situational picture and speed levels
- ``pipeline``   -- the stages of one simulation step, wired one way, and the step's record
- ``runner``     -- one simulation run (``simulate``), batches and sweeps; uses ``reporting``
- ``reporting``  -- traces, summaries, tables and plots; reads run folders, never ``runner``
- ``cli``        -- the ``sse-cosim`` command
"""

__version__ = "0.1.0"
