#!/bin/sh
# Installs Mitsuba 3 (PyPI "mitsuba"), numpy and matplotlib into a virtual
# environment, bench/.venv by default (git-ignored), for
# bench/mitsuba_compare.py and bench/bench_error.py (its plots), and a
# recent libLLVM (Debian's libllvm19) for Mitsuba's fastest CPU variant,
# llvm_ad_rgb: Dr.Jit compiles its kernels with the libLLVM it finds, and
# with LLVM 14 and 15 (what Debian 12 has for PoCL) it aborted on the path
# tracer ("Cannot select: fminimum"). bench/bench_error.py points Dr.Jit at
# the newest libLLVM (DRJIT_LIBLLVM_PATH) and falls back to scalar_rgb when
# the llvm variant does not work. Only the benchmarks need any of this: the
# build and the test suite (make test) never do.
#   sh tools/install-mitsuba.sh [VENV]
set -eu
ROOT=$(cd "$(dirname "$0")/.." && pwd)
VENV=${1:-$ROOT/bench/.venv}
SUDO=""
[ "$(id -u)" = 0 ] || SUDO=sudo
export DEBIAN_FRONTEND=noninteractive
if command -v dpkg-query >/dev/null 2>&1 &&
    ! dpkg-query -W -f='${Status}' libllvm19 2>/dev/null | grep -q "install ok installed"; then
    echo "installing libllvm19 (for Mitsuba's llvm_ad_rgb variant)"
    $SUDO apt-get install -y -q --no-install-recommends libllvm19 ||
        { $SUDO apt-get update -q && $SUDO apt-get install -y -q --no-install-recommends libllvm19; } ||
        echo "warning: no libllvm19: Mitsuba will fall back to scalar_rgb" >&2
fi
if [ -x "$VENV/bin/python" ] && "$VENV/bin/python" -c "import mitsuba, numpy, matplotlib" 2>/dev/null; then
    echo "Mitsuba 3 already in $VENV: $("$VENV/bin/python" -c 'import mitsuba; print(mitsuba.__version__)')"
    exit 0
fi
if ! python3 -c "import venv, ensurepip" 2>/dev/null; then
    echo "python3 venv/ensurepip missing: installing python3-venv" >&2
    $SUDO apt-get install -y python3-venv
fi
python3 -m venv "$VENV"
"$VENV/bin/pip" install --quiet --upgrade pip
"$VENV/bin/pip" install --quiet "mitsuba>=3.5" numpy matplotlib
"$VENV/bin/python" -c "import mitsuba as mi, matplotlib; mi.set_variant('scalar_rgb'); print('Mitsuba', mi.__version__, 'and matplotlib', matplotlib.__version__, 'in $VENV')"
