"""setuptools glue for `pip install .`: the extensions are built by CMake (see pyproject.toml).

What goes into the wheel: the package (python/stereodet), its two extensions (_core, _stereo) and
the command-line executables in stereodet/bin/ (`stereodet`, `stereodet-vision`, and
`stereodet-models` when the build folder has the LibTorch models), so that `python3 -m
stereodet.scale` and the `stereodet` console script work from the installed package alone.

Which build folder:
  STEREODET_CMAKE_BUILD_DIR  an existing, configured build folder to build in (nothing is
                             reconfigured);
  otherwise build/, when it is a configured build of this checkout for this interpreter (`make
  build` made it: only what changed is compiled again);
  otherwise build/pip, configured here with tests, benchmarks and the LibTorch models off.
  CMAKE_BUILD_PARALLEL_LEVEL jobs for the build (default: the number of CPUs).

pip hides a build backend's output unless `pip install -v`; the CMake build's progress (its
percentage) is also written to the terminal (/dev/tty) when there is one, on one line.
"""

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

SOURCE_DIR = Path(__file__).resolve().parent
EXECUTABLES = ("stereodet", "stereodet-vision", "stereodet-models")


def cache_value(build_dir, name):
    """A variable of build_dir/CMakeCache.txt, or None."""
    try:
        text = (build_dir / "CMakeCache.txt").read_text(errors="replace")
    except OSError:
        return None
    m = re.search(r"^" + re.escape(name) + r":[A-Z]+=(.*)$", text, re.M)
    return m.group(1) if m else None


def reusable(build_dir):
    """build_dir is a configured build of this checkout, with the Python module, for this
    interpreter."""
    home = cache_value(build_dir, "CMAKE_HOME_DIRECTORY")
    python = cache_value(build_dir, "Python3_EXECUTABLE")
    return (home is not None and Path(home).resolve() == SOURCE_DIR and
            cache_value(build_dir, "STEREODET_BUILD_PYTHON") not in ("OFF", "0", "FALSE") and
            python is not None and Path(python).resolve() == Path(sys.executable).resolve())


class Terminal:
    """Progress lines on the user's terminal, which pip's captured output does not reach."""

    def __init__(self):
        try:
            self.tty = open("/dev/tty", "w")
        except OSError:
            self.tty = None

    def line(self, text, end="\n"):
        if self.tty is not None:
            self.tty.write("\r\033[K" + text + end)
            self.tty.flush()


def run_build(command, terminal):
    """Runs the CMake build, its output to pip's log and its percentage to the terminal."""
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                               text=True, errors="replace")
    for line in process.stdout:
        sys.stdout.write(line)
        m = re.match(r"^\[\s*(\d+)%\]", line)
        if m:
            terminal.line(f"stereodet: building with CMake, {m.group(1)}%", end="")
    if process.wait() != 0:
        terminal.line("stereodet: the CMake build failed; `pip install -v .` shows its output")
        raise subprocess.CalledProcessError(process.returncode, command)
    terminal.line("stereodet: CMake build done")


class CMakeBuild(build_ext):
    def run(self):
        terminal = Terminal()
        given = os.environ.get("STEREODET_CMAKE_BUILD_DIR")
        if given:
            build_dir = Path(given).resolve()
        elif reusable(SOURCE_DIR / "build"):
            build_dir = SOURCE_DIR / "build"
        else:
            build_dir = SOURCE_DIR / "build" / "pip"
            subprocess.check_call([
                "cmake", "-S", str(SOURCE_DIR), "-B", str(build_dir),
                "-DCMAKE_BUILD_TYPE=Release",
                "-DSTEREODET_BUILD_PYTHON=ON",
                "-DSTEREODET_BUILD_TESTS=OFF",
                "-DSTEREODET_BUILD_BENCHMARKS=OFF",
                "-DSTEREODET_BUILD_MODELS=OFF",
                f"-DPython3_EXECUTABLE={sys.executable}",
            ])
        jobs = os.environ.get("CMAKE_BUILD_PARALLEL_LEVEL", str(os.cpu_count() or 1))
        terminal.line(f"stereodet: building in {build_dir} with {jobs} jobs")
        # The front end's target builds its siblings too (stereodet-vision, and stereodet-models
        # where the models are configured).
        run_build(["cmake", "--build", str(build_dir), "--target", "stereodet_python",
                   "stereodet", "-j", jobs], terminal)
        built = build_dir / "python" / "stereodet"
        for ext in self.extensions:
            name = ext.name.split(".")[-1]
            candidates = sorted(built.glob(name + ".*.so")) + sorted(built.glob(name + ".so"))
            if not candidates:
                raise RuntimeError(f"CMake built no {name} extension in {built}")
            target = Path(self.get_ext_fullpath(ext.name))
            target.parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(candidates[0], target)
        # The executables, beside the extensions: stereodet/bin/ (stereodet.scale finds them).
        package_dir = Path(self.get_ext_fullpath("stereodet._core")).parent
        (package_dir / "bin").mkdir(parents=True, exist_ok=True)
        copied = 0
        for name in EXECUTABLES:
            source = build_dir / "bin" / name
            if source.exists():
                shutil.copy2(source, package_dir / "bin" / name)
                copied += 1
        if copied < 2:
            raise RuntimeError(f"CMake built no stereodet executables in {build_dir / 'bin'}")


setup(
    ext_modules=[Extension("stereodet._core", sources=[]),
                 Extension("stereodet._stereo", sources=[])],
    cmdclass={"build_ext": CMakeBuild},
    # setuptools' own scratch files next to CMake's, inside the ignored build/ folder.
    options={"build": {"build_base": str(Path("build") / "setuptools")}},
)
