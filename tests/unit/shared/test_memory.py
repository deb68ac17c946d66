"""What keeps the services lean: no OpenSSL and no pydantic in a service, no other command's code in the
router, one read-noise bank for a simulator's cameras."""

from __future__ import annotations

import hashlib
import hmac
import os
import subprocess
import sys
from pathlib import Path

import msgspec
import numpy as np
import pytest

REPO_ROOT = Path(__file__).resolve().parents[3]
#: Every service that runs in the main environment (ros2_dds needs rclpy, from ``make ros2``).
SERVICES = sorted(
    p.parent.name for p in (REPO_ROOT / "services").glob("*/__main__.py") if p.parent.name != "ros2_dds"
)


def _run(code: str) -> str:
    env = {k: v for k, v in os.environ.items() if k != "OPENBLAS_NUM_THREADS"}
    done = subprocess.run(
        [sys.executable, "-c", code], cwd=REPO_ROOT, env=env, capture_output=True, text=True, timeout=60
    )
    assert done.returncode == 0, done.stderr
    return done.stdout.strip()


def _openssl_loaded() -> str:
    """Code that prints whether hashlib reached OpenSSL (``_hashlib`` imported, not kept out)."""
    return "print(sys.modules.get('_hashlib') is not None)\n"


def test_without_openssl_the_hashes_are_python_s_own_and_the_same() -> None:
    out = _run(
        "import sys\n"
        "from shared.memory import keep_openssl_out\n"
        "assert keep_openssl_out()\n"
        "import hashlib, hmac, secrets\n"
        "print(hashlib.sha256(b'abc').hexdigest(), hmac.new(b'k', b'm', 'sha256').hexdigest())\n"
        + _openssl_loaded()
    )
    digests, loaded = out.splitlines()
    assert digests.split() == [hashlib.sha256(b"abc").hexdigest(), hmac.new(b"k", b"m", "sha256").hexdigest()]
    assert loaded == "False"


def test_once_hashlib_has_openssl_it_keeps_it() -> None:
    out = _run("import hashlib\nfrom shared.memory import keep_openssl_out\nprint(keep_openssl_out())")
    assert out == "False"


@pytest.mark.parametrize("service", SERVICES)
def test_a_service_starts_without_openssl(service: str) -> None:
    """``python -m services.NAME`` keeps OpenSSL out, and loads no pydantic: its parameters and worlds are
    msgspec records (``--help`` comes after every import of the service)."""
    out = _run(
        "import contextlib, io, os, runpy, sys\n"
        "os.environ.pop('OPENBLAS_NUM_THREADS', None)\n"
        f"sys.argv = ['services.{service}', '--help']\n"
        "with contextlib.redirect_stdout(io.StringIO()):\n"
        "    try:\n"
        f"        runpy.run_module('services.{service}', run_name='__main__', alter_sys=True)\n"
        "    except SystemExit:\n        pass\n"
        "print('pydantic' in sys.modules, os.environ.get('OPENBLAS_NUM_THREADS'))\n" + _openssl_loaded()
    )
    assert out.split() == ["False", "1", "False"], (
        f"services.{service}: expected neither pydantic nor OpenSSL loaded, and OpenBLAS on one thread"
    )


def test_openblas_keeps_to_one_thread_unless_numpy_came_first_or_the_user_chose() -> None:
    code = (
        "import os, sys\n"
        "from shared.memory import keep_blas_single_threaded\n"
        "os.environ.pop('OPENBLAS_NUM_THREADS', None)\n"
    )
    assert _run(code + "print(keep_blas_single_threaded(), os.environ['OPENBLAS_NUM_THREADS'])") == "True 1"
    assert _run(code + "import numpy\nprint(keep_blas_single_threaded())") == "False"
    chosen = "os.environ['OPENBLAS_NUM_THREADS'] = '2'\n"
    out = _run(code + chosen + "print(keep_blas_single_threaded(), os.environ['OPENBLAS_NUM_THREADS'])")
    assert out == "False 2"


@pytest.mark.parametrize("command", ["router", "container"])
def test_a_lean_command_loads_only_its_own_code(command: str) -> None:
    out = _run(
        "import io, contextlib, sys\n"
        "from deploy.cli import main\n"
        "with contextlib.redirect_stdout(io.StringIO()):\n"
        "    try:\n"
        f"        main(['{command}', '--help'])\n"
        "    except SystemExit:\n        pass\n"
        "others = sorted(m for m in sys.modules if m.startswith('deploy.commands.'))\n"
        "print(others, 'deploy.launcher' in sys.modules)\n"
        + _openssl_loaded()
        + "import os\nprint(os.environ.get('OPENBLAS_NUM_THREADS'))\n"
    )
    assert out.split("\n") == [f"['deploy.commands.{command}'] False", "False", "1"]


def test_the_router_loads_no_pydantic() -> None:
    out = _run(
        "import io, contextlib, sys\n"
        "from deploy.cli import main\n"
        "with contextlib.redirect_stdout(io.StringIO()):\n"
        "    try:\n        main(['router', '--help'])\n"
        "    except SystemExit:\n        pass\n"
        "print('pydantic' in sys.modules)\n"
    )
    assert out == "False"


def test_a_simulator_s_cameras_share_one_noise_bank_and_draw_their_own_windows() -> None:
    from services.simulator.camera import CameraParams, CameraRenderer, ReadNoise, build_scene
    from shared.geometry import Pose2D
    from shared.world import load_world

    world = load_world(REPO_ROOT / "deploy/worlds/seed_room.yaml")
    scene, params = build_scene(world), CameraParams()
    bank = ReadNoise(np.random.default_rng(1))
    first = CameraRenderer(scene, params, np.random.default_rng(2), bank)
    second = CameraRenderer(scene, params, np.random.default_rng(3), bank)
    pose = Pose2D(1.0, 1.0, 0.3)
    a, b = first.render(pose), second.render(pose)
    assert first.noise is second.noise
    assert np.abs(a.astype(int) - b.astype(int)).mean() > 1.0  # independent noise, same scene
    noiseless = CameraRenderer(scene, msgspec.structs.replace(params, noise_sigma=0.0)).render(pose)
    residual = a.astype(float) - noiseless
    assert abs(residual[(noiseless > 10) & (noiseless < 245)].std() - params.noise_sigma) < 0.3
    again = CameraRenderer(
        scene, params, np.random.default_rng(2), ReadNoise(np.random.default_rng(1))
    ).render(pose)
    assert np.array_equal(a, again)  # the same seeds, the same frame
