"""The fleet run's picture: every robot's track over the room, with the docks, holding poses and the
places where two robots touched."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import matplotlib.pyplot as plt

from deploy.fleet.monitor import RobotTally
from deploy.plotting import draw_world  # chooses matplotlib's file-only backend first
from shared.world import World


def plot_fleet(
    world: World,
    robots: Sequence[RobotTally],
    contacts: Sequence[tuple[float, float, float, str, str]],
    output: Path,
    staging_offset_m: float = 0.7,
    dpi: int = 120,
) -> Path:
    fig, ax = plt.subplots(figsize=(11, 8))
    try:
        draw_world(ax, world, staging_offset_m)
        colours = plt.get_cmap("tab10")
        for i, robot in enumerate(robots):
            if robot.track:
                xs, ys = zip(*robot.track)
                ax.plot(
                    xs,
                    ys,
                    color=colours(i % 10),
                    linewidth=0.8,
                    alpha=0.6,
                    label=f"{robot.name}: {robot.distance_m:.0f} m, {robot.dockings} docking(s)",
                    zorder=2,
                )
                ax.plot([xs[-1]], [ys[-1]], marker="o", color=colours(i % 10), markersize=8, zorder=6)
        if world.holding:
            ax.plot(
                [h[0] for h in world.holding],
                [h[1] for h in world.holding],
                marker="s",
                linestyle="none",
                color="tab:gray",
                markersize=8,
                label="holding pose",
                zorder=5,
            )
        if contacts:
            ax.plot(
                [c[1] for c in contacts],
                [c[2] for c in contacts],
                marker="x",
                linestyle="none",
                color="red",
                markersize=10,
                markeredgewidth=2,
                label="robot-robot contact",
                zorder=7,
            )
        xmin, ymin, xmax, ymax = world.bounds
        ax.set_xlim(xmin - 0.3, xmax + 0.3)
        ax.set_ylim(ymin - 0.3, ymax + 0.3)
        ax.set_aspect("equal")
        ax.set_title(f"fleet: {len(robots)} robots, {len(world.docks)} docks in {world.name}")
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, frameon=False)
        fig.tight_layout()
        output.parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(output, dpi=dpi)
    finally:
        plt.close(fig)
    return output
