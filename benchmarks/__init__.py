"""Benchmarks and validation of sse-cosim (``sse-cosim bench``, ``make bench``).

One module per item: :mod:`.loop_cost` (cost per step against bare SUMO), :mod:`.gain_methods`,
:mod:`.scaling`, :mod:`.throughput`, :mod:`.tightness` (against the exact filter),
:mod:`.soundness` (the campaign), :mod:`.baseline` (Kalman filter); :mod:`.run` runs them all
and :mod:`.report` writes ``benchmarks.md``. Run from the repository root.
"""
