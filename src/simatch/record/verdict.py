"""The verdict of a reproduction check (`simatch.record.reproduce.verify`): whether the re-simulation
reproduced the recording and, where it did not, the first step and component that differ, the first states
that differ with both values, and what differs in the environment, in one line (docs/reliability.md,
"Reading a verify verdict")."""

from __future__ import annotations

from dataclasses import dataclass, field

from .divergence import ComponentDifference


@dataclass
class Difference:
    t: float
    step: int
    model: str
    field: str
    recorded: float | str
    simulated: float | str
    differing_values: int

    def describe(self) -> str:
        """What differs, and both values: ``magenta/2 x 3.0 recorded, 2.9 here (2 value(s) of that step differ)``."""
        return (
            f"{self.model} {self.field} {self.recorded!r} recorded, {self.simulated!r} here "
            f"({self.differing_values} value(s) of that step differ)"
        )


@dataclass
class Verdict:
    identical: bool
    compared: int  # model-state samples compared
    until: float  # simulated time of the last one [s]
    first_difference: Difference | None = None
    operator_commands: int = 0
    problems: list[str] = field(default_factory=list)
    complete: bool = True  # the whole run was recorded and compared (file intact, finalised)
    mode: str = "strategies"  # how it was re-simulated: "inputs" (the world from its recorded inputs) or "strategies"
    inputs: int = 0  # world inputs carried out again (mode "inputs")
    #: what differs between the recording's environment and this one (`environment.differences`)
    environment: list[str] = field(default_factory=list)
    #: the first step and component whose fingerprint differs (`divergence`), None if none does
    component: ComponentDifference | None = None
    #: the recording's format version, and whether it holds component fingerprints (format 3 on)
    format_version: str = ""
    components: bool = False

    def describe(self) -> str:
        if self.identical:
            how = (
                f"from {self.inputs} recorded world input(s)"
                if self.mode == "inputs"
                else f"from the strategies, {self.operator_commands} operator command(s) re-applied"
            )
            head = (
                f"reproduced bit for bit: {self.compared} model-state samples (0 to {self.until:.3f} s), "
                f"re-simulated {how}"
            )
            if not self.complete:
                head += "; the recording is incomplete, so only what it holds was checked"
        else:
            head = f"NOT reproduced: {self.where()}"
            if self.environment:
                head += f"; made in another environment: {', '.join(self.environment)}"
        return "\n".join([head] + [f"note: {p}" for p in self.problems])

    def where(self) -> str:
        """The first divergent step, its component (where the recording holds them) and the first values
        that differ, in one line."""
        diff, comp = self.first_difference, self.component
        if comp is not None:
            if diff is None:
                return (
                    f"{comp.describe()} — the model states and the exact states' fingerprints agree to the end "
                    f"({self.compared} samples)"
                )
            return f"{comp.describe()} — then at step {diff.step} (t={diff.t:.3f} s): {diff.describe()}"
        if diff is None:
            return "no difference found"
        head = f"differs from step {diff.step} (t={diff.t:.3f} s)"
        if not self.components:
            head += (
                f": the recording (format {self.format_version or '?'}) predates component fingerprints, "
                "so no component is named"
            )
        else:
            head += ": no component fingerprint recorded up to there differs"
        return f"{head} — {diff.describe()}"

    def as_dict(self) -> dict:
        out = {
            "identical": self.identical,
            "mode": self.mode,
            "inputs": self.inputs,
            "compared": self.compared,
            "until": self.until,
            "operator_commands": self.operator_commands,
            "complete": self.complete,
            "problems": self.problems,
            "environment": self.environment,
            "first_difference": None,
            "format_version": self.format_version,
            "components": self.components,
            "first_component": dict(self.component.__dict__) if self.component is not None else None,
            "verdict": self.describe().splitlines()[0],
        }
        if self.first_difference:
            out["first_difference"] = dict(self.first_difference.__dict__)
        return out
