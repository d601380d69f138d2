"""User-facing errors: one line that names the source, the field and the fix.

The CLI prints ``str(error)`` and exits with status 2 for any :class:`UserError`;
nothing else in the project prints tracebacks to users for bad input.
"""

from __future__ import annotations


class UserError(Exception):
    """Bad input from the user: a file, a field or a command-line argument.

    Rendered as ``"<source>: <field>: <problem> -- <fix>"`` on one line.
    """

    def __init__(self, source: str, field: str, problem: str, fix: str = "") -> None:
        self.source = str(source)
        self.field = field
        self.problem = problem
        self.fix = fix
        super().__init__(self.one_line())

    def one_line(self) -> str:
        parts = [p for p in (self.source, self.field) if p]
        text = ": ".join([*parts, self.problem])
        if self.fix:
            text += f" -- {self.fix}"
        return " ".join(text.split())


class SimulationError(Exception):
    """A failure inside SUMO or the co-simulation loop, naming the scenario."""

    def __init__(self, scenario: str, problem: str) -> None:
        self.scenario = scenario
        self.problem = problem
        super().__init__(" ".join(f"{scenario}: simulation failed: {problem}".split()))


class AssumptionBroken(SimulationError):
    """The simulated world broke an assumption of the estimator that the scenario does not
    list in ``breaks_assumptions``: the run stops before any set is checked against a truth
    that left the model. Rendered as one line naming the scenario, what happened and the fix.
    """

    def __init__(self, scenario: str, assumption: str, problem: str, fix: str) -> None:
        super().__init__(scenario, problem)
        self.assumption = assumption
        self.fix = fix
        line = (f"{scenario}: the simulated world broke an assumption of the estimator "
                f"({assumption}): {problem} -- {fix}")
        self.args = (" ".join(line.split()),)

    def __str__(self) -> str:
        return str(self.args[0])
