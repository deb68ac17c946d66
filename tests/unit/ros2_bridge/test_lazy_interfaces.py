"""The DDS face's interface packages load each class on first use, and only generated packages do."""

from __future__ import annotations

import subprocess
import sys
import textwrap
from pathlib import Path

from services.ros2_dds.lazy_interfaces import interface_index

REPO_ROOT = Path(__file__).resolve().parents[3]

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
        env={"PYTHONPATH": f"{root}:{REPO_ROOT}", "PYTHONDONTWRITEBYTECODE": "1"},
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


def _stood_in_package(root: Path) -> None:
    package = root / "demo_pkg"
    package.mkdir()
    (package / "__init__.py").write_text("from demo_pkg.sub import Thing\n")
    (package / "sub.py").write_text(
        "import builtins\nbuiltins.SUB_RUNS = getattr(builtins, 'SUB_RUNS', 0) + 1\nclass Thing:\n    pass\n"
    )


def test_a_stand_in_imports_its_module_on_the_first_read_and_only_once(tmp_path: Path) -> None:
    _stood_in_package(tmp_path)
    out = _run(
        tmp_path,
        """
        import builtins, sys, threading
        from services.ros2_dds.lazy_interfaces import load_on_first_use
        print(load_on_first_use("demo_pkg"), load_on_first_use("demo_pkg"), load_on_first_use("no_such_pkg"))
        import demo_pkg
        print(getattr(builtins, "SUB_RUNS", 0))
        sys.setswitchinterval(1e-6)
        errors = []
        def read():
            try:
                demo_pkg.Thing
            except Exception as exc:
                errors.append(exc)
        threads = [threading.Thread(target=read) for _ in range(8)]
        [t.start() for t in threads]
        [t.join() for t in threads]
        print(errors, builtins.SUB_RUNS, demo_pkg.Thing is sys.modules["demo_pkg.sub"].Thing)
        """,
    )
    assert out.splitlines() == ["True False False", "0", "[] 1 True"]


def test_a_submodule_imported_before_the_first_read_runs_once(tmp_path: Path) -> None:
    """``import pkg.sub`` reads the stand-in's ``__path__``, which imports the package, which imports
    ``pkg.sub``: it must not run a second time (two copies of its classes)."""
    _stood_in_package(tmp_path)
    out = _run(
        tmp_path,
        """
        import builtins, sys
        from services.ros2_dds.lazy_interfaces import load_on_first_use
        load_on_first_use("demo_pkg")
        import demo_pkg.sub
        print(builtins.SUB_RUNS, demo_pkg.sub.Thing is sys.modules["demo_pkg"].Thing)
        print(sys.modules["demo_pkg.sub"].__spec__.origin.endswith("sub.py"))
        """,
    )
    assert out.splitlines() == ["1 True", "True"]
