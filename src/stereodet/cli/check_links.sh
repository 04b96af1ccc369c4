#!/bin/sh
# check_links.sh EXE absent|present REGEX
#   Checks the shared libraries the dynamic loader would load for EXE (ldd: direct and indirect):
#   `absent` fails if any matches the extended regular expression REGEX, `present` fails if none
#   does (the control that shows the check can see a library). Used by the cli.links.* tests.
exe=$1 want=$2 pattern=$3
if [ $# -ne 3 ] || [ ! -x "$exe" ]; then
  echo "usage: check_links.sh EXE absent|present REGEX (EXE must be an executable: '$exe')" >&2
  exit 2
fi
libs=$(ldd "$exe") || { echo "FAIL: ldd $exe failed" >&2; exit 1; }
found=$(printf '%s\n' "$libs" | grep -E "$pattern")
count=$(printf '%s\n' "$libs" | grep -c .)
case $want in
  absent)
    if [ -n "$found" ]; then
      echo "FAIL: $exe loads libraries matching '$pattern' (it must not):" >&2
      printf '%s\n' "$found" >&2
      exit 1
    fi
    echo "ok: $exe loads $count shared libraries, none matching '$pattern'" ;;
  present)
    if [ -z "$found" ]; then
      echo "FAIL: $exe loads no library matching '$pattern' ($count libraries)" >&2
      exit 1
    fi
    echo "ok: $exe loads $(printf '%s\n' "$found" | grep -c .) libraries matching '$pattern'" ;;
  *)
    echo "check_links.sh: second argument must be absent or present, not '$want'" >&2
    exit 2 ;;
esac
