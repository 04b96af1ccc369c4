#!/usr/bin/env python3
"""Checks every `--help` of the CLI, so that none can lose a description or repeat itself.

    help_test.py STEREODET

Walks `stereodet --help` and, through each "Subcommands:" list, every command's and subcommand's
`--help` (those of the sibling executables included: the front end hands them over). Fails,
listing each, on
  - an option or positional without a description (CLI11 writes descriptions from column 30, or on
    the next line, indented, after a long name);
  - an exclusion listed on both of its options ("Excludes:" belongs to one side: the one that names
    the most options);
  - a subcommand without a description.
Prints "help: N pages, M options, all described" when it passes.
"""
import re
import subprocess
import sys

DESCRIPTION_COLUMN = 30  # CLI11's default column width


def help_text(binary, path):
    done = subprocess.run([binary, *path, "--help"], capture_output=True, text=True, check=False)
    if done.returncode != 0:
        raise SystemExit(f"FAILED: `{' '.join(['stereodet', *path, '--help'])}` exited "
                         f"{done.returncode}: {done.stderr.strip()}")
    return done.stdout


def sections(text):
    """{"Options": [lines], "Subcommands": [lines], ...} of one help page."""
    out, current = {}, None
    for line in text.splitlines():
        heading = re.match(r"^([A-Z]\w*):\s*$", line)
        if heading:
            current = out.setdefault(heading.group(1), [])
        elif current is not None:
            current.append(line)
    return out


def entries(lines):
    """(first line, next line) of each entry: an entry starts two spaces in."""
    for i, line in enumerate(lines):
        if re.match(r"^  \S", line):
            yield line, lines[i + 1] if i + 1 < len(lines) else ""


def described(line, following):
    if len(line) > DESCRIPTION_COLUMN and line[DESCRIPTION_COLUMN - 1] == " " and \
            line[DESCRIPTION_COLUMN] != " ":
        return True
    return re.match(r"^ {%d}\S" % DESCRIPTION_COLUMN, following) is not None


def main():
    binary = sys.argv[1]
    problems, pages, options = [], 0, 0
    pending = [[]]
    while pending:
        path = pending.pop()
        name = " ".join(["stereodet", *path])
        page = sections(help_text(binary, path))
        pages += 1
        excludes = {}  # option -> the options its "Excludes:" names
        for heading in ("Options", "Positionals"):
            for line, following in entries(page.get(heading, [])):
                options += 1
                option = line.split()[0].split(",")[-1]
                if not described(line, following):
                    problems.append(f"{name}: {option} has no description")
                listed = re.search(r"Excludes:((?: --?[\w-]+)+)", line)
                if listed:
                    excludes[option] = set(listed.group(1).split())
        for option, others in excludes.items():
            for other in others:
                if option in excludes.get(other, ()):
                    problems.append(f"{name}: {option} and {other} both list their exclusion")
        for line, following in entries(page.get("Subcommands", [])):
            if not described(line, following):
                problems.append(f"{name}: subcommand {line.split()[0]} has no description")
            pending.append([*path, line.split()[0]])
    if problems:
        print("FAILED:\n" + "\n".join(problems))
        return 1
    print(f"help: {pages} pages, {options} options, all described")
    return 0


if __name__ == "__main__":
    sys.exit(main())
