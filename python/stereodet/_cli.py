"""The `stereodet` console script of a pip install: the stereodet executable the wheel carries.

`pip install .` puts the command-line executables in stereodet/bin/ (setup.py); this replaces the
Python process with stereodet/bin/stereodet and the same arguments, so `stereodet eval ...` after a
pip install is the CLI itself (its messages, exit codes and sibling executables).
"""
import os
import sys
from pathlib import Path


def main() -> None:
    executable = Path(__file__).resolve().parent / "bin" / "stereodet"
    if not executable.exists():
        sys.exit(f"stereodet: {executable} is not there: this copy of the package was not "
                 "installed with `pip install .` (from a build tree, run build/bin/stereodet)")
    os.execv(str(executable), ["stereodet", *sys.argv[1:]])


if __name__ == "__main__":
    main()
