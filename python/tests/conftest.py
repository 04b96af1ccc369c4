"""Shared fixtures of the Python tests.

ctest runs each file as `python3 -m pytest FILE` from the checkout with PYTHONPATH=build/python and
STEREODET_BUILD_DIR set (python/CMakeLists.txt); by hand:
    PYTHONPATH=build/python /usr/bin/python3 -m pytest python/tests
"""

import os
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
DATA = REPO / "tests" / "data"


def build_dir() -> Path:
    return Path(os.environ.get("STEREODET_BUILD_DIR", REPO / "build")).resolve()


@pytest.fixture(scope="session")
def build() -> Path:
    return build_dir()


@pytest.fixture(scope="session")
def cli(build):
    """Runs build/bin/stereodet with the given arguments; returns the CompletedProcess."""
    binary = build / "bin" / "stereodet"
    if not binary.exists():
        pytest.fail(f"{binary} is not built (cmake --build build)")

    def run(*args, check=True):
        result = subprocess.run([str(binary), *map(str, args)], capture_output=True, text=True)
        if check and result.returncode != 0:
            raise AssertionError(f"stereodet {' '.join(map(str, args))} failed:\n{result.stderr}")
        return result

    return run


@pytest.fixture(scope="session")
def data() -> Path:
    return DATA
