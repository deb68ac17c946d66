"""The stack a campaign runs: one simulator for every robot, each robot's own services (a :class:`Scenario`)."""

from __future__ import annotations

from pathlib import Path

from deploy.launcher.stack_file import Stack
from deploy.scenario import GLASS_MEMORY_FILE, Scenario, scenario_stack
from deploy.trials.records import TrialOptions

__all__ = ["GLASS_MEMORY_FILE", "trials_stack"]


def trials_stack(
    options: TrialOptions, endpoint: str, robots: list[str], state_dir: Path | None = None
) -> Stack:
    """Each robot alone in its copy of the room, on one simulator.

    ``state_dir``: where each robot's planner keeps its glass memory and its battery its charge across
    restarts (``--chaos``), and the campaign's own map (other stacks in this checkout never read it).
    """
    return scenario_stack(
        Scenario(
            project="trials",
            world=options.world,
            robots=tuple(robots),
            endpoint=endpoint,
            rtf=options.rtf,
            seed=options.seed,
            controller=options.controller,
            detector=options.detector,
            state_dir=state_dir,
            map_file=str(state_dir / "map.yaml") if state_dir else ".zendock/maps/map.yaml",
            simulator_params={"localisation.error": options.localisation_error},
            compose=options.compose,
            replacements=options.replacements,
        )
    )
