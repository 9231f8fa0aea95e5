#!/bin/sh
# Builds the libFuzzer harnesses with clang (ASan + UBSan) and runs each
# (tests/fuzz/README.md). Not part of the normal build or of `make test`:
# CI builds with gcc. Usage, from the repository root:
#   sh tests/fuzz/fuzz.sh [build|run|all] [HARNESS...]
# Environment: FUZZ_DIR (default build-fuzz), FUZZ_RUNS (executions per
# harness, default 1000000), FUZZ_TIME (seconds per harness, default 0: no
# limit), FUZZ_JOBS (parallel workers per harness, default 1),
# FUZZ_KEEP_GOING=1 (fork mode: go on after a crash, timeout or
# out-of-memory in a child, collecting every artifact; for assimp's own
# bugs), FUZZ_SANITIZE (default address,undefined; "undefined" alone runs
# several times faster: Debian's assimp zeroes a 4 MiB buffer per OBJ
# import, which ASan makes slow), CC (clang).
set -eu
ROOT=$(pwd)
OUT=${FUZZ_DIR:-build-fuzz}
RUNS=${FUZZ_RUNS:-1000000}
TIME=${FUZZ_TIME:-0}
JOBS=${FUZZ_JOBS:-1}
SAN=${FUZZ_SANITIZE:-address,undefined}
CC=${CC:-clang}
what=${1:-all}
[ $# -gt 0 ] && shift
harnesses=${*:-"fuzz_scene_json fuzz_mesh"}
mkdir -p "$OUT"

# The scene library's sources, as apps/common/meson.build lists them.
SRC="apps/common/scene.c apps/common/scene_shapes.c apps/common/scene_mesh.c
apps/common/scene_mesh_guard.c apps/common/scene_json.c apps/common/scene_builtin.c
apps/common/app_error.c"
CFLAGS="-std=c11 -D_POSIX_C_SOURCE=200809L -g -O1 -Wall -Wextra -Werror
-fsanitize=fuzzer,$SAN -fno-sanitize-recover=undefined
-Iruntime/include -Iapps/common -DSCENE_SOURCE_ROOT=\"$ROOT\""
# live_scenes.c counts assimp scenes through these
WRAP="-Wl,--wrap=aiImportFileExWithProperties,--wrap=aiImportFileFromMemoryWithProperties
-Wl,--wrap=aiApplyPostProcessing,--wrap=aiReleaseImport"

build() {
    for h in $harnesses; do
        echo "building $OUT/$h"
        # shellcheck disable=SC2086
        $CC $CFLAGS -o "$OUT/$h" "tests/fuzz/$h.c" tests/fuzz/live_scenes.c $SRC $WRAP \
            -lassimp -lcjson -lm
    done
}

# Seeds: the JSON files as they are; a mesh seed is the format's index in
# fuzz_mesh.c's HINTS (one byte) followed by the file.
seed() {
    rm -rf "$OUT/seeds-json" "$OUT/seeds-mesh"
    mkdir -p "$OUT/seeds-json" "$OUT/seeds-mesh" "$OUT/corpus-fuzz_scene_json" \
        "$OUT/corpus-fuzz_mesh"
    cp tests/fuzz/seeds/json/*.json "$OUT/seeds-json/"
    for f in tests/fuzz/seeds/mesh/* scenes/meshes/*.obj; do
        case "$f" in
        *.obj) i=0 ;; *.ply) i=1 ;; *.off) i=2 ;; *.stl) i=3 ;; *.gltf) i=4 ;; *.glb) i=5 ;;
        *) continue ;;
        esac
        { printf "\\$(printf '%03o' "$i")"; cat "$f"; } >"$OUT/seeds-mesh/$(basename "$f")"
    done
}

run() {
    seed
    status=0
    for h in $harnesses; do
        kind=${h#fuzz_}
        kind=${kind#scene_}
        dict=""
        [ -f "tests/fuzz/$kind.dict" ] && dict="-dict=tests/fuzz/$kind.dict"
        par=""
        [ "$JOBS" -gt 1 ] && par="-jobs=$JOBS -workers=$JOBS"
        [ "${FUZZ_KEEP_GOING:-0}" = 1 ] &&
            par="$par -fork=$JOBS -ignore_crashes=1 -ignore_timeouts=1 -ignore_ooms=1"
        mkdir -p "$OUT/artifacts-$h"
        echo "running $h: $RUNS executions, $TIME s at most (0: no limit); log $OUT/$h.log"
        # intercept_tls_get_addr=0: a sanitizer-runtime bug, see the asan target
        # of the Makefile; -timeout: an input taking over 10 s is a hang; -rss_limit_mb and
        # -malloc_limit_mb: one taking over 2 GiB is a missing memory bound
        # shellcheck disable=SC2086
        ASAN_OPTIONS=detect_leaks=1:intercept_tls_get_addr=0 LSAN_OPTIONS=suppressions=$ROOT/tests/fuzz/lsan.supp \
        UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 \
            "$OUT/$h" -runs="$RUNS" -max_total_time="$TIME" -timeout=10 \
            -rss_limit_mb=2048 -malloc_limit_mb=2048 -max_len=65536 -print_final_stats=1 \
            $par $dict -artifact_prefix="$OUT/artifacts-$h/" \
            "$OUT/corpus-$h" "$OUT/seeds-$kind" >"$OUT/$h.log" 2>&1 || status=1
        grep -E '^(stat::|==[0-9]+==ERROR|SUMMARY|artifact_prefix|Done|INFO: Seed|INFO: fuzzed)' \
            "$OUT/$h.log" || true
    done
    return $status
}

case "$what" in
build) build ;;
run) run ;;
all) build && run ;;
*) echo "usage: $0 [build|run|all] [HARNESS...]" >&2; exit 2 ;;
esac
