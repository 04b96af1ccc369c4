#!/usr/bin/env bash
# Installs, with apt-get, the Debian packages stereodet needs to build, test and benchmark — only those
# that are missing. Idempotent: a second run installs nothing and prints one line.
#
# Works as root; otherwise uses sudo (non-interactively); fails with a clear message if neither works.
# Set STEREODET_DEPS_EXTRA="pkg1 pkg2" to add packages (e.g. clang for `make fuzz`).
set -euo pipefail

packages=(
  build-essential cmake pkg-config
  clang-format-14         # the formatting check of .ci/run (`make format-check`), one pinned version
  libfmt-dev              # util: formatting
  libtbb-dev              # util: parallel-for over frames
  libeigen3-dev           # geometry: small matrices, calibration
  libopencv-dev           # stereo, synth: block matching, image I/O
  libopencv-contrib-dev   # stereo: ximgproc's WLS disparity post-filter (--wls)
  libboost-dev            # eval: boost::geometry (header-only), the KITTI devkit's BEV/3D overlaps
  opencv-doc              # stereo tests: Middlebury "Aloe" pair with ground truth
  libtorch-dev            # models: LibTorch detectors (CPU)
  libgloo-dev             # models: the headers of LibTorch's Gloo process group (train --world-size)
  libopenblas0-openmp     # models: BLAS for LibTorch (alternatives switch it in for the reference
                          # BLAS): a det3d training step 2.5x less CPU (docs/BENCHMARKS.md)
  nlohmann-json3-dev      # report: results.json
  libsimdjson-dev         # eval: COCO results files, parsed 10x faster than with nlohmann
  librsvg2-dev            # report: PNG figures, rasterized from their SVG (librsvg + cairo)
  fonts-dejavu-core       # report: the figures' font, in PNG and in the browser test
  chromium                # tests: the report opened in headless Chromium (cli.report.browser)
  libcli11-dev            # cli: the stereodet command line
  libgtest-dev libgmock-dev  # tests
  libbenchmark-dev        # benchmarks
  pybind11-dev python3-dev   # the stereodet Python module (python/)
  python3-numpy python3-pytest  # ... its arrays and its tests
  python3-pip python3-setuptools python3-wheel python3-venv  # ... `pip install .` (docs/python.md)
  python3-dask python3-distributed  # stereodet.scale: sharded runs on Dask distributed (docs/scale.md)
)
# shellcheck disable=SC2206
extra=(${STEREODET_DEPS_EXTRA:-})
packages+=("${extra[@]}")

missing=()
for p in "${packages[@]}"; do
  # dpkg-query prints "install ok installed" only for a fully installed package.
  status=$(dpkg-query -W -f='${Status}' "$p" 2>/dev/null || true)
  [[ "$status" == "install ok installed" ]] || missing+=("$p")
done

if [[ ${#missing[@]} -eq 0 ]]; then
  echo "install-deps: all ${#packages[@]} packages already installed"
  exit 0
fi

if [[ $(id -u) -eq 0 ]]; then
  as_root=()
elif command -v sudo >/dev/null 2>&1 && sudo -n true 2>/dev/null; then
  as_root=(sudo -n)
else
  echo "install-deps: need root to install: ${missing[*]}" >&2
  echo "install-deps: run as root, or give this user password-less sudo, or install them by hand" >&2
  exit 1
fi

echo "install-deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
"${as_root[@]}" apt-get update -q
"${as_root[@]}" apt-get install -y -q --no-install-recommends "${missing[@]}"
echo "install-deps: done"
