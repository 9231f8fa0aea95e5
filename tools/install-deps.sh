#!/bin/sh
# Installs the Debian 12 packages Sluice needs, only when some are missing.
# Idempotent; uses sudo when not run as root.
#   --bench   also the benchmarks' optional peers (libembree-dev, for
#             bench_raytrace's Embree comparison; povray, for
#             bench/bench_error.py's POV-Ray photon mapping)
set -eu
BENCH=0
for arg in "$@"; do
    case "$arg" in
    --bench) BENCH=1 ;;
    *) echo "usage: $0 [--bench]" >&2; exit 2 ;;
    esac
done
PKGS="build-essential pkg-config meson ninja-build cmake python3
ocl-icd-opencl-dev opencl-headers pocl-opencl-icd clinfo
libopenimageio-dev openimageio-tools libassimp-dev libcjson-dev libflann-dev
glmark2-data"
if [ "$BENCH" = 1 ]; then
    PKGS="$PKGS libembree-dev povray"
fi
missing=""
for p in $PKGS; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing="$missing $p"
done
[ -z "$missing" ] && exit 0
echo "installing:$missing"
SUDO=""
if [ "$(id -u)" != 0 ]; then
    command -v sudo >/dev/null 2>&1 || { echo "error: need root or sudo to install:$missing" >&2; exit 1; }
    SUDO=sudo
fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -q
# shellcheck disable=SC2086
$SUDO apt-get install -y -q --no-install-recommends $missing
