"""`pip install .` from the checkout, offline, with Debian's packages only (docs/python.md).

The build reuses the configured build folder (STEREODET_CMAKE_BUILD_DIR), so this checks the
packaging (setup.py, pyproject.toml, the files that go into the wheel), not a second compilation.
"""

import os
import subprocess
import sys
from pathlib import Path

from conftest import REPO, build_dir


def test_pip_installs_an_importable_package(tmp_path):
    target = tmp_path / "site"
    env = dict(os.environ, STEREODET_CMAKE_BUILD_DIR=str(build_dir()), PIP_NO_CACHE_DIR="1",
               PYTHONDONTWRITEBYTECODE="1")
    env.pop("PYTHONPATH", None)
    subprocess.run([sys.executable, "-m", "pip", "install", "--quiet", "--no-build-isolation",
                    "--no-index", "--no-deps", "--target", str(target), str(REPO)],
                   check=True, env=env, cwd=tmp_path)
    installed = sorted(p.name for p in (target / "stereodet").iterdir())
    assert "__init__.py" in installed and "py.typed" in installed and "_core.pyi" in installed
    assert any(name.startswith("_core.") and name.endswith(".so") for name in installed)
    assert any(name.startswith("_stereo.") and name.endswith(".so") for name in installed)
    # A fresh interpreter that sees only the installed copy (and Debian's numpy).
    out = subprocess.run([sys.executable, "-c",
                          "import stereodet, stereodet._stereo; print(stereodet.__file__)"],
                         check=True, capture_output=True, text=True, cwd=tmp_path,
                         env=dict(env, PYTHONPATH=str(target))).stdout
    assert Path(out.strip()).resolve() == (target / "stereodet" / "__init__.py").resolve()
    # The executables travel with the package: stereodet.scale finds them there, and the console
    # script (stereodet._cli) runs the CLI itself.
    for name in ("stereodet", "stereodet-vision"):
        assert os.access(target / "stereodet" / "bin" / name, os.X_OK), name
    env_installed = {k: v for k, v in env.items() if k not in ("STEREODET_BIN", "STEREODET_BUILD_DIR")}
    env_installed["PYTHONPATH"] = str(target)
    found = subprocess.run([sys.executable, "-c",
                            "from stereodet import scale; print(scale.find_bin_dir())"],
                           check=True, capture_output=True, text=True, cwd=tmp_path,
                           env=env_installed).stdout
    assert Path(found.strip()) == (target / "stereodet" / "bin").resolve()
    version = subprocess.run([sys.executable, "-m", "stereodet._cli", "--version"], check=True,
                             capture_output=True, text=True, cwd=tmp_path,
                             env=env_installed).stdout
    assert version.startswith("stereodet ")
    # pip's own console script for it (with --target, in TARGET/bin).
    assert (target / "bin" / "stereodet").exists()
