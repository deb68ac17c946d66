"""``zendock bench record``'s report: a recording's own per-key account, robots' keys under one name."""

from __future__ import annotations

from pathlib import Path

import pytest

from deploy.bench.recording import RecordingTap
from deploy.recording.mcap_log import SUMMARY_METADATA, McapLog, RecordedSample
from deploy.recording.summary import KeySummary, summary_metadata


def _row(key: str, received: int, gaps: tuple[tuple[int, int], ...] = ()) -> KeySummary:
    lost = sum(b - a + 1 for a, b in gaps)
    return KeySummary(
        key=key,
        type_name="",
        received=received,
        lost=lost,
        gaps=gaps,
        publishers=1,
        unnumbered=0,
        duplicates=0,
    )


def test_report_adds_up_each_robots_keys_and_the_images(tmp_path: Path) -> None:
    path = tmp_path / "campaign.mcap"
    log = McapLog(path)
    log.write_sample(RecordedSample("r0/clock", "application/msgpack;rosgraph_msgs/msg/Clock", b"\x80", 1, 1))
    rows = [
        _row("r0/clock", 100, ((5, 6),)),
        _row("r1/clock", 90, ((9, 9),)),
        _row("r0/camera/image_raw", 30, ((3, 3),)),
        _row("r1/aruco/debug_image", 20),
        _row("map", 2),
    ]
    log.add_metadata(SUMMARY_METADATA, summary_metadata(rows, 10.0))
    log.finish()
    tap = RecordingTap(output=path, world=tmp_path / "w.yaml", robots=["r0", "r1"], cpu_s=2.0, wall_s=4.0)
    report = tap.report()
    assert report["keys"]["clock"] == {"recorded": 190, "lost": 3, "gaps": 2}
    assert (report["recorded"], report["lost"], report["gaps"]) == (242, 4, 3)
    assert (report["images_recorded"], report["images_lost"]) == (50, 1)
    assert report["recorder_cpu_fraction"] == 0.5
    assert list(report["keys"])[0] == "clock"  # the most lost first


def test_no_file_says_what_the_recorder_printed(tmp_path: Path) -> None:
    tap = RecordingTap(
        output=tmp_path / "missing.mcap", world=tmp_path / "w.yaml", recorder_output="no router"
    )
    with pytest.raises(RuntimeError, match="no router"):
        tap.report()
