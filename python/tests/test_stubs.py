"""The hand-written stubs match the compiled module (``mypy.stubtest``), and the
pure-Python code (package, examples, most tests) type-checks against them (``mypy --strict``)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("mypy", reason="mypy is needed to check the stubs (see requirements-test.txt)")

PYTHON_DIR = Path(__file__).resolve().parents[1]
ALLOWLIST = Path(__file__).resolve().parent / "stubtest_allowlist.txt"
# Test files held to `mypy --strict` as well (they exercise the stubs like a user would).
TYPED_TESTS = ("conftest.py", "test_api.py", "test_env.py", "test_errors.py", "test_rust_parity.py", "test_stubs.py")


def run(args: list[str], cwd: Path) -> subprocess.CompletedProcess[str]:
    """Runs ``python -m <args>`` in ``cwd``."""
    return subprocess.run(
        [sys.executable, "-m", *args], cwd=cwd, capture_output=True, text=True, timeout=600, check=False
    )


@pytest.fixture
def empty_config(tmp_path: Path) -> Path:
    path = tmp_path / "mypy.ini"
    path.write_text("[mypy]\n")
    return path


def test_stubtest(tmp_path: Path, empty_config: Path) -> None:
    # Run outside the source tree so that the installed package (with its compiled
    # module) is what gets imported and checked.
    done = run(
        [
            "mypy.stubtest",
            "myoslice._myoslice",
            "--allowlist",
            str(ALLOWLIST),
            "--mypy-config-file",
            str(empty_config),
        ],
        cwd=tmp_path,
    )
    assert done.returncode == 0, f"stubtest failed:\n{done.stdout}\n{done.stderr}"


def test_package_examples_and_tests_type_check(tmp_path: Path, empty_config: Path) -> None:
    done = run(
        [
            "mypy",
            "--strict",
            "--cache-dir",
            str(tmp_path / "cache"),
            "--config-file",
            str(empty_config),
            "myoslice",
            "examples",
            *(f"tests/{name}" for name in TYPED_TESTS),
        ],
        cwd=PYTHON_DIR,
    )
    assert done.returncode == 0, f"mypy failed:\n{done.stdout}\n{done.stderr}"
