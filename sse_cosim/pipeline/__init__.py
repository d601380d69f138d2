"""The stages of one co-simulation step, in the order data flows through them (paper Fig. 3).

snapshot (:mod:`sse_cosim.world`) -> observe (:func:`stages.sense`; every node's observer,
:class:`~sse_cosim.estimation.observer.LocalObservers`, by id or anonymous:
:func:`stages.first_level`) -> every node's message, built once
(:func:`stages.outgoing`), sent to each automated vehicle over V2X (:class:`stages.Sharing`)
-> screen, fuse, flag
(:class:`~sse_cosim.estimation.fusion_centre.FusionCentre`; anonymous tracks:
:class:`~sse_cosim.estimation.anonymous_fusion.AnonymousFusionCentre`, both behind
:func:`stages.second_level`) -> refined regions
(:func:`stages.known_regions`) and the unobserved area -> picture
(:func:`~sse_cosim.control.picture.assess`) -> decide (:mod:`sse_cosim.control.speed`) ->
actuate (the world) -> record (:class:`result.StepResult`).

:func:`sse_cosim.runner.simulation.simulate` runs them against SUMO; nothing here touches
SUMO, and nothing here depends on the runner or on reporting.
"""
