"""The simulator bench runs a fleet world's robots together, each with every sensor."""

from __future__ import annotations

from pathlib import Path

from services.simulator.bench import bench_simulation

WORLDS = Path(__file__).resolve().parents[3] / "deploy" / "worlds"


def test_a_fleet_world_is_benched_with_all_its_robots_in_one_room() -> None:
    fleet = bench_simulation(WORLDS / "fleet" / "depot.yaml", 0.3)
    alone = bench_simulation(WORLDS / "seed_room.yaml", 0.3)
    assert fleet["robots"] == 6.0 and alone["robots"] == 1.0
    assert fleet["sim_seconds"] == alone["sim_seconds"] == 0.3
    for result in (fleet, alone):
        assert result["lidar_us_per_call"] > 0 and result["render_ms_per_frame"] > 0
        assert result["ms_per_sim_s_without_camera"] > 0
