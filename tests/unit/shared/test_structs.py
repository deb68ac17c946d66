"""Validating user-written values into records: each mistake is one line naming the source, the field's
dotted place and the reason in plain words."""

from __future__ import annotations

from typing import Annotated, Literal

import msgspec
import pytest
from msgspec import Meta

from shared.config_errors import ConfigError
from shared.structs import field_spec, fields, non_finite, plain, validate


class Lidar(msgspec.Struct, forbid_unknown_fields=True, frozen=True, kw_only=True):
    noise_m: Annotated[float, Meta(ge=0.0, description="range noise")] = 0.01
    rate_hz: Annotated[float, Meta(gt=0.0, le=50.0)] = 10.0
    mount: tuple[float, float, float] = (0.1, 0.0, 0.0)


class Pane(msgspec.Struct, forbid_unknown_fields=True, kw_only=True):
    ends: tuple[tuple[float, float], tuple[float, float]]
    name: Annotated[str, Meta(min_length=1)] = "pane"


class Settings(msgspec.Struct, forbid_unknown_fields=True, kw_only=True):
    world: str
    mode: Literal["fast", "careful"] = "careful"
    lidar: Lidar = msgspec.field(default_factory=Lidar)
    panes: list[Pane] = msgspec.field(default_factory=list)
    low: float = 0.2
    high: Annotated[float, Meta(extra={"dynamic": True})] = 0.9

    def __post_init__(self) -> None:
        if self.high <= self.low:
            raise ValueError(f"high: {self.high} must be above low ({self.low})")


def _message(data: dict) -> str:
    with pytest.raises(ConfigError) as info:
        validate(Settings, {"world": "w.yaml", **data}, "s.yaml")
    return str(info.value)


@pytest.mark.parametrize(
    ("data", "expected"),
    [
        ({"lidar": {"noise_m": -1}}, "s.yaml: lidar.noise_m: must be at least 0.0"),
        ({"lidar": {"rate_hz": 0}}, "s.yaml: lidar.rate_hz: must be greater than 0.0"),
        ({"lidar": {"rate_hz": 80}}, "s.yaml: lidar.rate_hz: must be at most 50.0"),
        ({"lidar": {"noise_m": "loud"}}, "s.yaml: lidar.noise_m: expected float, got text"),
        ({"lidar": {"mount": [1, 2]}}, "s.yaml: lidar.mount: must have 3 items, got 2"),
        ({"lidar": {"noies_m": 0.1}}, "s.yaml: lidar.noies_m: unknown key (did you mean noise_m?)"),
        ({"wrold": "x"}, "s.yaml: wrold: unknown key (did you mean world?)"),
        ({"colour": "red"}, "s.yaml: colour: unknown key"),
        (
            {"panes": [{"ends": [[0, 0], [1, 0]]}, {"ends": [[0, 0], [1, 0]], "name": ""}]},
            "s.yaml: panes.1.name: must not be empty",
        ),
        ({"panes": [{"name": "p"}]}, "s.yaml: panes.0.ends: missing (required)"),
        ({"mode": "reckless"}, "s.yaml: mode: invalid enum value 'reckless' (choose from 'fast', 'careful')"),
        ({"high": 0.1}, "s.yaml: high: 0.1 must be above low (0.2)"),
    ],
)
def test_each_mistake_names_its_place_and_reason(data: dict, expected: str) -> None:
    assert _message(data) == expected


def test_a_missing_top_level_field_is_named() -> None:
    with pytest.raises(ConfigError, match=r"^s.yaml: world: missing \(required\)$"):
        validate(Settings, {}, "s.yaml")


def test_the_root_prefixes_the_place() -> None:
    with pytest.raises(ConfigError, match=r"^docks.yaml: docks.3.lidar.noise_m: must be at least 0.0$"):
        validate(Settings, {"world": "w", "lidar": {"noise_m": -1}}, "docks.yaml", root="docks.3")


class Fleet(msgspec.Struct, forbid_unknown_fields=True, kw_only=True):
    lidars: dict[str, Lidar] = msgspec.field(default_factory=dict)


def test_a_mapping_key_is_named() -> None:
    """msgspec writes a mapping's key as ``[...]``; the place names the key whose value was refused."""
    with pytest.raises(ConfigError, match=r"^f.yaml: lidars.rear.noise_m: must be at least 0.0$"):
        validate(Fleet, {"lidars": {"front": {}, "rear": {"noise_m": -1}}}, "f.yaml")
    with pytest.raises(
        ConfigError, match=r"^f.yaml: lidars.rear.nois_m: unknown key \(did you mean noise_m\?\)$"
    ):
        validate(Fleet, {"lidars": {"front": {}, "rear": {"nois_m": 1}}}, "f.yaml")


def test_values_a_user_writes_are_accepted_as_meant() -> None:
    settings = validate(Settings, {"world": "w", "lidar": {"rate_hz": "5", "noise_m": 0}, "high": 1}, "s")
    assert settings.lidar.rate_hz == 5.0 and isinstance(settings.lidar.noise_m, float)
    assert settings.high == 1.0 and settings.lidar.mount == (0.1, 0.0, 0.0)


def test_fields_read_the_meta_and_find_groups() -> None:
    names = [spec.name for spec in fields(Settings)]
    assert names == ["world", "mode", "lidar", "panes", "low", "high"]
    assert field_spec(Settings, "lidar") is not None and field_spec(Settings, "lidar").group is Lidar
    assert field_spec(Settings, "panes").group is None
    assert field_spec(Lidar, "noise_m").description == "range noise"
    assert field_spec(Settings, "high").extra == {"dynamic": True}
    assert field_spec(Settings, "nope") is None


def test_plain_gives_json_ready_values() -> None:
    settings = validate(Settings, {"world": "w", "panes": [{"ends": [[0, 0], [1, 0]]}]}, "s")
    assert plain(settings)["lidar"]["mount"] == [0.1, 0.0, 0.0]
    assert plain(settings)["panes"] == [{"ends": [[0.0, 0.0], [1.0, 0.0]], "name": "pane"}]


def test_non_finite_names_the_fields() -> None:
    assert list(non_finite(Lidar(noise_m=float("nan"), mount=(0.0, float("inf"), 0.0)))) == [
        "noise_m",
        "mount",
    ]
    assert list(non_finite(Lidar())) == []


def test_several_mistakes_are_listed_at_once_one_line_each() -> None:
    message = _message({"wrold": "x", "lidar": {"noise_m": -1, "rate_hz": 0}, "mode": "reckless"})
    assert message.splitlines() == [  # in the order the file gives them
        "s.yaml: wrold: unknown key (did you mean world?)",
        "s.yaml: lidar.noise_m: must be at least 0.0",
        "s.yaml: lidar.rate_hz: must be greater than 0.0",
        "s.yaml: mode: invalid enum value 'reckless' (choose from 'fast', 'careful')",
    ]


def test_listing_stops_at_a_list_item_and_never_blames_a_key_for_its_own_absence() -> None:
    # a list item left out would renumber the rest: what follows it waits for the next run
    panes = [{"ends": [[0, 0], [1, 0]], "name": ""}, {"ends": [[0, 0]]}]
    assert _message({"colour": "red", "panes": panes, "mode": "x"}).splitlines() == [
        "s.yaml: colour: unknown key",
        "s.yaml: panes.0.name: must not be empty",
    ]
    # world is required: leaving out its bad value must not add "world: missing (required)"
    with pytest.raises(ConfigError) as info:
        validate(Settings, {"world": 3, "low": "x"}, "s.yaml")
    assert str(info.value).splitlines() == [
        "s.yaml: world: expected text, got int",
        "s.yaml: low: expected float, got text",
    ]


def test_a_record_s_own_check_waits_until_the_keys_before_it_are_mended() -> None:
    # high 0.1 would be refused (below low), but low is left out for its bad type: with its default (0.2)
    # in its place, the check would blame a value the user never wrote
    assert _message({"low": "x", "high": 0.1}).splitlines() == ["s.yaml: low: expected float, got text"]
