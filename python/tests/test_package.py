"""The package itself: where it is imported from, its version, its docstrings, what it loads."""

import os
import re
import subprocess
import sys
from pathlib import Path

import stereodet
from conftest import REPO, build_dir


def test_imported_from_the_build_tree():
    assert Path(stereodet.__file__).resolve().parent == build_dir() / "python" / "stereodet"


def test_version_is_the_projects():
    cmake = (REPO / "CMakeLists.txt").read_text()
    version = re.search(r"project\(stereodet VERSION ([0-9.]+)", cmake).group(1)
    assert stereodet.__version__ == version
    pyproject = (REPO / "pyproject.toml").read_text()
    assert f'version = "{version}"' in pyproject


def test_help_shows_the_docstrings():
    text = subprocess.run([sys.executable, "-c", "import stereodet; help(stereodet)"],
                          capture_output=True, text=True, check=True,
                          env=dict(os.environ, PAGER="cat", TERM="dumb")).stdout
    assert "KITTI I/O, KITTI evaluation and stereo features" in text
    assert "ParseError" in text


def test_parse_error_is_a_value_error():
    assert issubclass(stereodet.ParseError, ValueError)


def loaded_libraries(code: str) -> str:
    """The shared objects mapped into a fresh interpreter after running `code`."""
    script = code + "\nprint(open('/proc/self/maps').read())"
    return subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          check=True).stdout


def test_import_loads_neither_opencv_nor_libtorch():
    maps = loaded_libraries("import stereodet")
    assert "_core" in maps
    assert "libopencv" not in maps
    assert "libtorch" not in maps and "libc10" not in maps


def test_stereo_loads_opencv_on_first_use_but_never_libtorch():
    maps = loaded_libraries("import stereodet; stereodet.stereo.disparity")
    assert "libopencv_core" in maps and "_stereo" in maps
    assert "libtorch" not in maps and "libc10" not in maps
