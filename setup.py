"""setuptools glue for `pip install .`: the extensions are built by CMake (see pyproject.toml).

Environment:
  STEREODET_CMAKE_BUILD_DIR  an existing, configured build folder to build the Python targets in
                             (e.g. build/: nothing is reconfigured); default build/pip, configured
                             here with tests, benchmarks and the LibTorch models off.
  CMAKE_BUILD_PARALLEL_LEVEL jobs for the build (default: the number of CPUs).
"""

import os
import shutil
import subprocess
import sys
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

SOURCE_DIR = Path(__file__).resolve().parent


class CMakeBuild(build_ext):
    def run(self):
        given = os.environ.get("STEREODET_CMAKE_BUILD_DIR")
        build_dir = Path(given).resolve() if given else SOURCE_DIR / "build" / "pip"
        if not given:
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
        subprocess.check_call(["cmake", "--build", str(build_dir), "--target", "stereodet_python",
                               "-j", jobs])
        built = build_dir / "python" / "stereodet"
        for ext in self.extensions:
            name = ext.name.split(".")[-1]
            candidates = sorted(built.glob(name + ".*.so")) + sorted(built.glob(name + ".so"))
            if not candidates:
                raise RuntimeError(f"CMake built no {name} extension in {built}")
            target = Path(self.get_ext_fullpath(ext.name))
            target.parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(candidates[0], target)


setup(
    ext_modules=[Extension("stereodet._core", sources=[]),
                 Extension("stereodet._stereo", sources=[])],
    cmdclass={"build_ext": CMakeBuild},
    # setuptools' own scratch files next to CMake's, inside the ignored build/ folder.
    options={"build": {"build_base": str(Path("build") / "setuptools")}},
)
