"""A contract as a document: JSON (``zendock contract NAME --json``) and Markdown (``docs/contracts/``).

Both are views of :mod:`shared.contracts`, the data zendock's own services are held to while they run,
so a page cannot say something the code does not do. ``python -m deploy.docs_site`` writes the pages and
the JSON Schemas; a test fails when the committed ones differ from what the code renders.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from msgspec.structs import asdict

from shared.contracts import CONTRACTS, Contract, Request, Topic
from shared.contracts.model import ANNOUNCEMENTS, COMMON_FLAGS, DUTIES, ENVIRONMENT, FRAME_RULES, Action
from shared.contracts.wire_schema import WIRE_RULES, json_schema
from shared.schema import Message

CONTRACTS_DIR = Path(__file__).resolve().parents[2] / "docs" / "contracts"


def message_types(contract: Contract) -> list[type[Message]]:
    """Every message type a contract's endpoints carry (requests, responses, goals, results, feedback)."""
    found: dict[str, type[Message]] = {}
    for topic in (*contract.publishes, *contract.subscribes):
        found[topic.type.TYPE_NAME] = topic.type
    for request in (*contract.serves, *contract.calls):
        found[request.type.request.TYPE_NAME] = request.type.request
        found[request.type.response.TYPE_NAME] = request.type.response
    for action in (*contract.serves_actions, *contract.uses_actions):
        for cls in (action.type.goal, action.type.result, action.type.feedback):
            found[cls.TYPE_NAME] = cls
    return [found[name] for name in sorted(found)]


def _topic(topic: Topic) -> dict[str, Any]:
    return {
        "key": topic.name,
        "type": topic.type.TYPE_NAME,
        "qos": asdict(topic.qos),
        "rate_hz": topic.rate_hz,
        **({"max_rate_hz": topic.max_rate_hz} if topic.max_rate_hz else {}),
        "required": topic.required,
        "when": topic.when,
        "about": topic.about,
        **({"fleet_wide": True} if topic.fleet_wide else {}),
        **({"frame_id": topic.frame_id} if topic.frame_id else {}),
        **({"child_frame_id": topic.child_frame_id} if topic.child_frame_id else {}),
    }


def _request(request: Request) -> dict[str, Any]:
    return {
        "key": request.name,
        "type": request.type.type_name,
        "request": request.type.request.TYPE_NAME,
        "response": request.type.response.TYPE_NAME,
        "required": request.required,
        "when": request.when,
        "about": request.about,
    }


def _action(action: Action) -> dict[str, Any]:
    base = f"{action.name}/_action"
    return {
        "name": action.name,
        "type": action.type.type_name,
        "goal": action.type.goal.TYPE_NAME,
        "result": action.type.result.TYPE_NAME,
        "feedback": action.type.feedback.TYPE_NAME,
        "keys": {
            "send_goal": f"{base}/send_goal",
            "cancel_goal": f"{base}/cancel_goal",
            "get_result": f"{base}/get_result",
            "feedback": f"{base}/feedback",
            "status": f"{base}/status",
        },
        "required": action.required,
        "when": action.when,
        "about": action.about,
    }


def contract_json(contract: Contract, with_schemas: bool = True) -> dict[str, Any]:
    """The whole contract as one JSON document (with the JSON Schema of every type it carries)."""
    body: dict[str, Any] = {
        "service": contract.service,
        "version": contract.version,
        "summary": contract.summary,
        "launch": {
            "environment": ENVIRONMENT,
            "flags": [{"flag": f.name, "about": f.about} for f in COMMON_FLAGS],
            "parameters": [{"name": f.name, "about": f.about, "needed": f.needed} for f in contract.flags],
        },
        "announces": list(ANNOUNCEMENTS),
        "publishes": [_topic(t) for t in contract.publishes],
        "subscribes": [_topic(t) for t in contract.subscribes],
        "subscribes_on_demand": contract.subscribes_on_demand,
        "serves": [_request(r) for r in contract.serves],
        "calls": [_request(r) for r in contract.calls],
        "serves_actions": [_action(a) for a in contract.serves_actions],
        "uses_actions": [_action(a) for a in contract.uses_actions],
        "duties": list(DUTIES),
        "behaviour": list(contract.behaviour),
        "conform_runs_beside": list(contract.needs),
        "notes": list(contract.notes),
        "frames": list(FRAME_RULES),
        "wire": list(WIRE_RULES),
    }
    if with_schemas:
        body["types"] = {cls.TYPE_NAME: json_schema(cls) for cls in message_types(contract)}
    return body


def _md_cell(text: object) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


def _qos_words(topic: Topic) -> str:
    q = topic.qos
    words = ["reliable" if q.reliable else "best effort"]
    if q.block:
        words.append("blocking")
    words.append(f"depth {q.depth}")
    return ", ".join(words)


def _rate_words(topic: Topic) -> str:
    if topic.rate_hz:
        return f"{topic.rate_hz:g} Hz"
    return f"on events, at most {topic.max_rate_hz:g}/s" if topic.max_rate_hz else "on events"


def _frame_words(topic: Topic) -> str:
    """``header.frame_id`` (and ``child_frame_id``) every message carries, or a dash when free."""
    if not topic.frame_id:
        return "-"
    child = f", child `{topic.child_frame_id}`" if topic.child_frame_id else ""
    return f"`{topic.frame_id}`{child}"


def _schema_link(type_name: str) -> str:
    return f"[`{type_name}`](schemas/{schema_file_name(type_name)})"


def contract_markdown(contract: Contract) -> str:
    """The contract as a documentation page (``docs/contracts/<service>.md``)."""
    out = [
        f"# {contract.service}",
        "",
        "<!-- Generated from shared/contracts by `python -m deploy.docs_site`. Do not edit. -->",
        "",
        contract.summary,
        "",
        f"Contract version **{contract.version}** ([what changed](changelog.md)).",
        "",
        f"Check a program against it: `zendock conform {contract.service} -- COMMAND ...`. "
        f"Run it in a stack: `zendock demo --service {contract.service}=COMMAND`. "
        "Keys are relative to the robot's namespace; the rules every service follows are on "
        "[the contracts page](index.md).",
        "",
    ]

    def topics_table(title: str, rows: tuple[Topic, ...]) -> None:
        if not rows:
            return
        framed = any(t.frame_id for t in rows)
        out.extend(
            [
                f"## {title}",
                "",
                "| key | type | delivery | rate (sim) |" + (" frame |" if framed else "") + " when | about |",
                "|---|---|---|---|" + ("---|" if framed else "") + "---|---|",
            ]
        )
        for t in rows:
            rate = _rate_words(t)
            key = f"`*/{t.name}` (every robot)" if t.fleet_wide else f"`{t.name}`"
            frame = f" {_frame_words(t)} |" if framed else ""
            out.append(
                f"| {key} | {_schema_link(t.type.TYPE_NAME)} | {_qos_words(t)} | {rate} |{frame} "
                f"{_md_cell(t.when or 'always')} | {_md_cell(t.about)} |"
            )
        out.append("")

    def requests_table(title: str, rows: tuple[Request, ...]) -> None:
        if not rows:
            return
        out.extend(
            [
                f"## {title}",
                "",
                "| key | type | request | response | when | about |",
                "|---|---|---|---|---|---|",
            ]
        )
        for r in rows:
            out.append(
                f"| `{r.name}` | `{r.type.type_name}` | {_schema_link(r.type.request.TYPE_NAME)} | "
                f"{_schema_link(r.type.response.TYPE_NAME)} | {_md_cell(r.when or 'always')} | {_md_cell(r.about)} |"
            )
        out.append("")

    def actions_table(title: str, rows: tuple[Action, ...]) -> None:
        if not rows:
            return
        out.extend(
            [
                f"## {title}",
                "",
                "| action | type | goal | result | feedback | about |",
                "|---|---|---|---|---|---|",
            ]
        )
        for a in rows:
            out.append(
                f"| `{a.name}` | `{a.type.type_name}` | {_schema_link(a.type.goal.TYPE_NAME)} | "
                f"{_schema_link(a.type.result.TYPE_NAME)} | {_schema_link(a.type.feedback.TYPE_NAME)} | "
                f"{_md_cell(a.about)} |"
            )
        out.extend(
            [
                "",
                "Keys: `<action>/_action/send_goal`, `cancel_goal` and `get_result` (requests), "
                "`feedback` and `status` (topics), as the [contracts page](index.md#actions) describes.",
                "",
            ]
        )

    topics_table("Publishes", contract.publishes)
    topics_table(
        "Subscribes (what it may read: zendock's own reads these, a replacement what it needs)",
        contract.subscribes,
    )
    if contract.subscribes_on_demand:
        out.extend(["It also subscribes on demand to whatever a client of its own asks for.", ""])
    requests_table("Serves", contract.serves)
    requests_table("Calls", contract.calls)
    actions_table("Serves actions", contract.serves_actions)
    actions_table("Uses actions", contract.uses_actions)
    out.extend(["## Parameters the launcher may pass", "", "| `-p` name | needed | about |", "|---|---|---|"])
    out += [
        f"| `{f.name}` | {'yes' if f.needed else 'may be ignored'} | {_md_cell(f.about)} |"
        for f in contract.flags
    ]
    out.append("")
    if contract.behaviour:
        beside = ", ".join(contract.needs) or "the router alone"
        out.extend(["## What `zendock conform` checks of its behaviour", "", f"Beside: {beside}.", ""])
        out += [f"- {line}" for line in contract.behaviour]
        out.append("")
    if contract.notes:
        out.extend(["## Notes", ""])
        out += [f"- {line}" for line in contract.notes]
        out.append("")
    return "\n".join(out)


def index_markdown() -> str:
    """``docs/contracts/index.md``: what every service gets, announces and must survive; the wire; the list."""
    out = [
        "# Contracts",
        "",
        "<!-- Generated from shared/contracts by `python -m deploy.docs_site`. Do not edit. -->",
        "",
        "Each zendock service has a contract, defined once in code (`shared/contracts/`): the keys it publishes "
        "and subscribes, the requests and actions it serves and uses, what the launcher hands it and what it "
        "must survive. zendock's own services are held to theirs while they run; these pages are rendered from "
        "the same data. Write a replacement in any language from them, check it with "
        "`zendock conform SERVICE -- COMMAND`, and run it with `--service SERVICE=COMMAND` on `zendock up`, "
        "`demo`, `trials` and `fleet`.",
        "",
        "| service | what it does |",
        "|---|---|",
    ]
    out += [f"| [{c.service}]({c.service}.md) | {_md_cell(c.summary)} |" for c in CONTRACTS.values()]
    out.extend(["", "## What the launcher hands every service", "", "| environment | meaning |", "|---|---|"])
    out += [f"| `{name}` | {_md_cell(about)} |" for name, about in ENVIRONMENT.items()]
    out.extend(["", "| flag | meaning |", "|---|---|"])
    out += [f"| `{f.name}` | {_md_cell(f.about)} |" for f in COMMON_FLAGS]
    out.extend(["", "## What every service announces", ""])
    out += [f"- {line}" for line in ANNOUNCEMENTS]
    out.extend(["", "## What every service must survive", ""])
    out += [f"- {line}" for line in DUTIES]
    out.extend(["", "## Frames and units", ""])
    out += [f"- {line}" for line in FRAME_RULES]
    out.extend(["", "## The wire", ""])
    out += [f"- {line}" for line in WIRE_RULES]
    out.extend(
        [
            "",
            "Each message type's JSON Schema is under [`schemas/`](schemas/index.md).",
            "",
            "## Actions",
            "",
            "An action `<name>` is five keys: the requests `<name>/_action/send_goal` "
            "(`{goal_id: {uuid: uint8[16]}, goal}` -> `{accepted, stamp}`), `<name>/_action/cancel_goal` "
            "(`action_msgs/srv/CancelGoal`) and `<name>/_action/get_result` (`{goal_id}` -> `{status, result}`, "
            "answered when the goal ends), and the topics `<name>/_action/feedback` (`{goal_id, feedback}`) and "
            "`<name>/_action/status` (`action_msgs/msg/GoalStatusArray`). Status codes are action_msgs': "
            "1 accepted, 2 executing, 3 canceling, 4 succeeded, 5 canceled, 6 aborted.",
            "",
        ]
    )
    return "\n".join(out)


def schema_file_name(type_name: str) -> str:
    return type_name.replace("/", ".") + ".json"


def all_message_types() -> list[type[Message]]:
    found: dict[str, type[Message]] = {}
    for contract in CONTRACTS.values():
        for cls in message_types(contract):
            found[cls.TYPE_NAME] = cls
    return [found[name] for name in sorted(found)]


def schemas_index() -> str:
    out = [
        "# Message schemas",
        "",
        "<!-- Generated from shared/contracts by `python -m deploy.docs_site`. Do not edit. -->",
        "",
        "JSON Schema (2020-12) of each message type's payload once msgpack-decoded; the "
        "[wire rules](../index.md#the-wire) say what a schema cannot.",
        "",
    ]
    out += [f"- [`{cls.TYPE_NAME}`]({schema_file_name(cls.TYPE_NAME)})" for cls in all_message_types()]
    return "\n".join(out) + "\n"


#: Written by hand beside the generated files: kept by :func:`write_files`, not judged by :func:`stale_files`.
HAND_WRITTEN = frozenset({"changelog.md"})


def rendered_files(directory: Path = CONTRACTS_DIR) -> dict[str, str]:
    """Every generated file under ``docs/contracts/`` (relative path -> text)."""
    from deploy.contracts.versions import VERSIONS_FILE, versions_json  # noqa: PLC0415 - it imports this module

    files = {"index.md": index_markdown(), VERSIONS_FILE: versions_json(directory)}
    files.update({f"{c.service}.md": contract_markdown(c) for c in CONTRACTS.values()})
    files["schemas/index.md"] = schemas_index()
    for cls in all_message_types():
        files[f"schemas/{schema_file_name(cls.TYPE_NAME)}"] = json.dumps(json_schema(cls), indent=2) + "\n"
    return files


def stale_files(directory: Path = CONTRACTS_DIR) -> list[str]:
    """Generated files that are missing, differ, or should not be there."""
    wanted = rendered_files(directory)
    problems = [
        name
        for name, text in wanted.items()
        if not (directory / name).is_file() or (directory / name).read_text(encoding="utf-8") != text
    ]
    present = (
        {str(p.relative_to(directory)) for p in directory.rglob("*") if p.is_file()}
        if directory.is_dir()
        else set()
    )
    return sorted(problems + [name for name in present - set(wanted) - HAND_WRITTEN])


def write_files(directory: Path = CONTRACTS_DIR) -> None:
    wanted = rendered_files(directory)
    if directory.is_dir():
        for path in directory.rglob("*"):
            name = str(path.relative_to(directory))
            if path.is_file() and name not in wanted and name not in HAND_WRITTEN:
                path.unlink()
    for name, text in wanted.items():
        target = directory / name
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_text(text, encoding="utf-8")
