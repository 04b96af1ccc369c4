#!/usr/bin/env python3
"""Runs the README's shell examples, so that a command, flag or output folder they name cannot rot.

    readme_examples_test.py README BIN_DIR

A block is tested when the line before its opening ```sh is a marker comment,
    <!-- test: OLD=NEW OLD=NEW ... -->
whose pairs rewrite paths that only exist on the reader's machine (/path/to/kitti) into the
outputs of earlier lines. Each line of the block then runs in order, in a fresh temporary folder
(its working directory, and /tmp/ becomes that folder), with build/bin/ the tested binaries and
the sizes shrunk so the whole block takes seconds: --frames N becomes --frames 4 at 160x48 px,
and train gets 1 epoch at 128x40. Every line must exit 0; the first that does not fails the test,
with its output. The blocks are counted, so a README without a marked block fails too.
"""
import os
import re
import shlex
import subprocess
import sys
import tempfile

# Extra flags per command, to keep every example fast; only flags the line does not set itself.
SHRINK = {
    "synth": ["--width", "160", "--height", "48", "--threads", "2"],
    "train": ["--epochs", "1", "--width", "128", "--height", "40", "--batch-size", "2",
              "--threads", "2", "--quiet"],
    "detect": ["--threads", "2", "--quiet"],
    "stereo": ["--threads", "2", "--quiet"],
}


def marked_blocks(text):
    """(substitutions, [lines]) for each ```sh block after a <!-- test: ... --> line."""
    blocks, lines = [], text.splitlines()
    i = 0
    while i < len(lines):
        m = re.match(r"^<!-- test:(.*)-->\s*$", lines[i])
        if m and i + 1 < len(lines) and lines[i + 1].strip() == "```sh":
            subs = [pair.split("=", 1) for pair in m.group(1).split()]
            body, j = [], i + 2
            while j < len(lines) and lines[j].strip() != "```":
                body.append(lines[j])
                j += 1
            blocks.append((subs, body))
            i = j
        i += 1
    return blocks


def shrink(args):
    """args with the sizes made tiny (see SHRINK)."""
    out = list(args)
    if "--frames" in out:
        out[out.index("--frames") + 1] = "4"
    command = out[1] if len(out) > 1 else ""
    for flag, value in zip(SHRINK.get(command, [])[::2], SHRINK.get(command, [])[1::2]):
        if flag not in out and (flag != "--quiet" or "--quiet" not in out):
            out += [flag] if flag == "--quiet" else [flag, value]
    return out


def main():
    readme, bin_dir = sys.argv[1], os.path.abspath(sys.argv[2])
    with open(readme, encoding="utf-8") as f:
        blocks = marked_blocks(f.read())
    if not blocks:
        print(f"FAILED: no block of {readme} is marked <!-- test: ... -->")
        return 1
    ran = 0
    for subs, body in blocks:
        with tempfile.TemporaryDirectory(prefix="stereodet-readme-") as work:
            for line in body:
                line = line.split("#", 1)[0].strip()  # the examples' comments
                if not line:
                    continue
                for old, new in subs:
                    line = line.replace(old, new)
                line = line.replace("/tmp/", work + "/")
                args = shlex.split(line)
                if not args[0].startswith("build/bin/"):
                    print(f"FAILED: not a build/bin/ command: {line}")
                    return 1
                args[0] = os.path.join(bin_dir, args[0][len("build/bin/"):])
                args = shrink(args)
                result = subprocess.run(args, cwd=work, stdout=subprocess.PIPE,
                                        stderr=subprocess.STDOUT, text=True, timeout=300)
                print(f"$ {shlex.join(args)}\n  exit {result.returncode}")
                if result.returncode != 0:
                    print(result.stdout)
                    print(f"FAILED: the README line `{line}` exited {result.returncode}")
                    return 1
                ran += 1
    print(f"README examples: {ran} commands in {len(blocks)} block(s), all exit 0")
    return 0


if __name__ == "__main__":
    sys.exit(main())
