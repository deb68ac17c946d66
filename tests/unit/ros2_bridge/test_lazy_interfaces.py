"""The DDS face's interface packages load each class on first use, and only generated packages do."""

from __future__ import annotations

import subprocess
import sys
import textwrap
from pathlib import Path

from services.ros2_dds.lazy_interfaces import interface_index

GENERATED = "from demo_msgs.msg._first import First  # noqa: F401\nfrom demo_msgs.msg._second_one import SecondOne  # noqa: F401\n"


def test_a_generated_init_gives_each_name_its_module() -> None:
    assert interface_index(GENERATED, "demo_msgs.msg") == {
        "First": "demo_msgs.msg._first",
        "SecondOne": "demo_msgs.msg._second_one",
    }


def test_anything_else_in_the_init_keeps_the_ordinary_import() -> None:
    assert interface_index('"""doc"""\n' + GENERATED, "demo_msgs.msg") is None
    assert interface_index(GENERATED + "x = 1\n", "demo_msgs.msg") is None
    assert interface_index("from demo_msgs.msg._first import First as F\n", "demo_msgs.msg") is None
    assert interface_index("from other.msg._first import First\n", "demo_msgs.msg") is None
    assert interface_index("from demo_msgs.msg._a import A, B\n", "demo_msgs.msg") is None
    assert interface_index("from . import _first\n", "demo_msgs.msg") is None
    assert interface_index("", "demo_msgs.msg") is None
    assert interface_index("from (\n", "demo_msgs.msg") is None


def _package(root: Path, init: str) -> None:
    msg = root / "demo_msgs" / "msg"
    msg.mkdir(parents=True)
    (root / "demo_msgs" / "__init__.py").write_text("")
    (msg / "__init__.py").write_text(init)
    (msg / "_first.py").write_text("class First:\n    pass\n")
    (msg / "_second_one.py").write_text("class SecondOne:\n    pass\n")


def _run(root: Path, body: str) -> str:
    script = (
        "from services.ros2_dds.lazy_interfaces import load_interfaces_on_use\nload_interfaces_on_use()\n"
    )
    result = subprocess.run(
        [sys.executable, "-c", script + textwrap.dedent(body)],
        env={"PYTHONPATH": f"{root}:{Path.cwd()}", "PYTHONDONTWRITEBYTECODE": "1"},
        capture_output=True,
        text=True,
        timeout=30,
    )
    assert result.returncode == 0, result.stderr
    return result.stdout


def test_a_class_is_imported_when_first_read_and_is_the_modules_own(tmp_path: Path) -> None:
    _package(tmp_path, GENERATED)
    out = _run(
        tmp_path,
        """
        import sys
        import demo_msgs.msg
        print(sorted(m for m in sys.modules if m.startswith("demo_msgs.msg.")))
        from demo_msgs.msg import First
        print(sorted(m for m in sys.modules if m.startswith("demo_msgs.msg.")))
        print(First is sys.modules["demo_msgs.msg._first"].First, "SecondOne" in dir(demo_msgs.msg))
        try:
            from demo_msgs.msg import Third
        except ImportError as exc:
            print("ImportError", "Third" in str(exc))
        """,
    )
    assert out.splitlines() == ["[]", "['demo_msgs.msg._first']", "True True", "ImportError True"]


def test_a_package_that_is_not_generated_loads_the_ordinary_way(tmp_path: Path) -> None:
    _package(tmp_path, GENERATED + "LOADED = True\n")
    out = _run(
        tmp_path,
        """
        import sys
        import demo_msgs.msg
        print(demo_msgs.msg.LOADED, sorted(m for m in sys.modules if m.startswith("demo_msgs.msg.")))
        """,
    )
    assert out.strip() == "True ['demo_msgs.msg._first', 'demo_msgs.msg._second_one']"
