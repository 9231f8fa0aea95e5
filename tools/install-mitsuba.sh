#!/bin/sh
# Installs Mitsuba 3 (PyPI "mitsuba", CPU variant scalar_rgb) and numpy into
# a virtual environment, bench/.venv by default (git-ignored), for
# bench/mitsuba_compare.py. Only the benchmarks need it: the build and the
# test suite (make test) never do.
#   sh tools/install-mitsuba.sh [VENV]
set -eu
ROOT=$(cd "$(dirname "$0")/.." && pwd)
VENV=${1:-$ROOT/bench/.venv}
if [ -x "$VENV/bin/python" ] && "$VENV/bin/python" -c "import mitsuba, numpy" 2>/dev/null; then
    echo "Mitsuba 3 already in $VENV: $("$VENV/bin/python" -c 'import mitsuba; print(mitsuba.__version__)')"
    exit 0
fi
if ! python3 -c "import venv, ensurepip" 2>/dev/null; then
    echo "python3 venv/ensurepip missing: installing python3-venv" >&2
    apt-get install -y python3-venv
fi
python3 -m venv "$VENV"
"$VENV/bin/pip" install --quiet --upgrade pip
"$VENV/bin/pip" install --quiet "mitsuba>=3.5" numpy
"$VENV/bin/python" -c "import mitsuba as mi; mi.set_variant('scalar_rgb'); print('Mitsuba', mi.__version__, 'in $VENV')"
