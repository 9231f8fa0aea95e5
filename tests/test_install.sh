#!/bin/sh
# Installs the built library into a temporary staging directory, then builds
# a small Sluice program outside the source tree against the installed
# headers, library and pkg-config file only, runs it and checks its output.
# The program loads its kernel from a file, splits a stream into two
# conditional outputs (one ordered, one unordered) and runs a multipass loop
# stopped by a counter.
#
# usage: test_install.sh BUILD_DIR
# Environment: CC (default cc), and whatever the OpenCL device needs
# (SLUICE_DEVICE, POCL_CACHE_DIR).
set -eu

fail() {
    echo "test_install: FAILED: $*" >&2
    exit 1
}

[ $# -eq 1 ] || fail "usage: test_install.sh BUILD_DIR"
BUILD=$(cd "$1" && pwd) || fail "no build directory $1"
CC=${CC:-cc}
TMP=$(mktemp -d "${TMPDIR:-/tmp}/sluice-install.XXXXXX")
trap 'rm -rf "$TMP"' EXIT INT TERM
DEST=$TMP/dest

# 1. Install into the staging directory (no rebuild: ninja already ran).
meson install -C "$BUILD" --no-rebuild --quiet --destdir "$DEST" >"$TMP/install.log" 2>&1 ||
    { cat "$TMP/install.log" >&2; fail "meson install"; }

PC=$(find "$DEST" -name sluice.pc | head -n 1)
[ -n "$PC" ] || fail "no sluice.pc installed under $DEST"
for f in sluice.h streams.h sluice.cl; do
    [ -n "$(find "$DEST" -path "*/include/sluice/$f")" ] || fail "header $f not installed"
done

# 2. pkg-config on the staged files: the sysroot prefixes every path of the
# .pc file with the staging directory (this also works for multiarch libdirs,
# where --define-prefix guesses the prefix wrong).
export PKG_CONFIG_PATH="$(dirname "$PC")${PKG_CONFIG_PATH:+:$PKG_CONFIG_PATH}"
export PKG_CONFIG_SYSROOT_DIR="$DEST"
CFLAGS=$(pkg-config --cflags sluice) || fail "pkg-config --cflags sluice"
LIBS=$(pkg-config --libs sluice) || fail "pkg-config --libs sluice"
LIBDIR=$(pkg-config --variable=libdir sluice) || fail "pkg-config --variable=libdir sluice"
case "$LIBDIR" in
"$DEST"/*) ;;
*) LIBDIR=$DEST$LIBDIR ;; # older pkg-config does not prefix variables
esac
[ -e "$LIBDIR/libsluice.so" ] || fail "libsluice.so not in $LIBDIR"
echo "pkg-config: $CFLAGS $LIBS"

# 3. A program and its kernel, outside the source tree.
mkdir -p "$TMP/app"
cat >"$TMP/app/thirds.cl" <<'EOF'
#include "sluice.cl"

/* Divides every value by 3: values still above 0 go on (ordered), the
 * others are finished (unordered, their last non-zero value). */
__kernel void thirds(SLUICE_PARAMS, global const uint *in, global uint *next,
                     global uint *finished)
{
    SLUICE_FOR_EACH(i) {
        uint x = in[i];
        uint y = x / 3u;
        SLUICE_EMIT_IF(0, next, y, y > 0u);
        SLUICE_EMIT_IF(1, finished, x, y == 0u);
        SLUICE_COUNT(0, y > 0u);
    }
}
EOF
cat >"$TMP/app/prog.c" <<'EOF'
#include <sluice/sluice.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define N 100000u

typedef struct state {
    sluice_kernel *k;
    sluice_stream *a, *b;
} state;

static sluice_status pass_fn(void *user, unsigned pass, unsigned choice)
{
    (void)pass;
    (void)choice;
    state *s = user;
    sluice_status st = sluice_stream_clear(s->b);
    if (st == SLUICE_OK)
        st = sluice_kernel_launch(s->k);
    if (st == SLUICE_OK)
        st = sluice_stream_swap(s->a, s->b);
    return st;
}

#define TRY(call)                                                              \
    do {                                                                       \
        sluice_status st_ = (call);                                            \
        if (st_ != SLUICE_OK) {                                                \
            fprintf(stderr, "%s: %s\n", #call, sluice_context_error(ctx));     \
            return 1;                                                          \
        }                                                                      \
    } while (0)

int main(int argc, char **argv)
{
    if (argc != 2)
        return 2;
    char err[512];
    sluice_context *ctx = NULL;
    if (sluice_context_create(NULL, &ctx, err, sizeof err) != SLUICE_OK) {
        fprintf(stderr, "context: %s\n", err);
        return 1;
    }
    sluice_program *p = NULL;
    state s = {0};
    sluice_stream *fin = NULL;
    sluice_counters *c = NULL;
    TRY(sluice_program_create_file(ctx, argv[1], NULL, &p));
    TRY(sluice_kernel_create(p, "thirds", &s.k));
    TRY(sluice_stream_create(ctx, 4, N, &s.a));
    TRY(sluice_stream_create(ctx, 4, N, &s.b));
    TRY(sluice_stream_create(ctx, 4, N, &fin));
    TRY(sluice_counters_create(ctx, 1, NULL, &c));
    uint32_t *v = malloc(N * 4), hist[3] = {0, 0, 0}, want[3] = {0, 0, 0};
    unsigned want_passes = 0;
    for (uint32_t i = 0; i < N; ++i) {
        v[i] = i * 2654435761u >> 8;
        uint32_t x = v[i];
        unsigned passes = 1;
        while (x / 3u > 0u) {
            x /= 3u;
            ++passes;
        }
        want[x]++;
        want_passes = passes > want_passes ? passes : want_passes;
    }
    TRY(sluice_stream_upload(s.a, v, N));
    TRY(sluice_kernel_set_input(s.k, 0, s.a));
    TRY(sluice_kernel_set_output(s.k, 1, 0, s.b, SLUICE_ORDERED));
    TRY(sluice_kernel_set_output(s.k, 2, 1, fin, SLUICE_UNORDERED));
    TRY(sluice_kernel_set_counters(s.k, c));
    /* The loop watches only the counter of survivors and goes on while it is
     * non-zero. The counter starts at 0, so the first pass runs before the
     * loop; the loop resets the counter before each of its passes. */
    TRY(pass_fn(&s, 0, 0));
    sluice_loop_desc d = {0};
    d.pass = pass_fn;
    d.user = &s;
    d.counters = c;
    d.reset_counters = 1;
    sluice_loop *loop = NULL;
    TRY(sluice_loop_create(ctx, &d, &loop));
    TRY(sluice_loop_run(loop));
    unsigned passes = 1 + sluice_loop_pass_count(loop);
    size_t n = 0;
    TRY(sluice_stream_download(fin, v, N, &n));
    for (size_t i = 0; i < n; ++i)
        hist[v[i] < 3u ? v[i] : 0]++;
    int ok = n == N && passes == want_passes &&
             memcmp(hist, want, sizeof hist) == 0;
    printf("passes %u (want %u), finished %zu: %u %u %u (want %u %u %u): %s\n",
           passes, want_passes, n, hist[0], hist[1], hist[2], want[0], want[1],
           want[2], ok ? "install-test-ok" : "MISMATCH");
    free(v);
    sluice_loop_destroy(loop);
    sluice_counters_destroy(c);
    sluice_stream_destroy(fin);
    sluice_stream_destroy(s.a);
    sluice_stream_destroy(s.b);
    sluice_kernel_destroy(s.k);
    sluice_program_destroy(p);
    sluice_context_destroy(ctx);
    return ok ? 0 : 1;
}
EOF

# 4. Build with nothing but what pkg-config says, then run against the
# staged library. A sanitized library (make asan) needs the sanitizer runtime
# in the program too.
SANITIZE=$(meson introspect "$BUILD" --buildoptions | python3 -c '
import json, sys
print(next((o["value"] for o in json.load(sys.stdin) if o["name"] == "b_sanitize"), "none"))
') || fail "meson introspect $BUILD"
EXTRA=
if [ "$SANITIZE" != none ] && [ -n "$SANITIZE" ]; then
    EXTRA="-fsanitize=$SANITIZE"
fi
# shellcheck disable=SC2086 # the flags are meant to be split
(cd "$TMP/app" && "$CC" -std=c11 -Wall -Wextra -Werror $EXTRA -o prog prog.c $CFLAGS $LIBS) ||
    fail "compiling against the installed Sluice"
LD_LIBRARY_PATH="$LIBDIR${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
export LD_LIBRARY_PATH
if command -v ldd >/dev/null 2>&1; then
    ldd "$TMP/app/prog" | grep libsluice | grep -q "$DEST" ||
        fail "prog does not load libsluice from the staging directory: $(ldd "$TMP/app/prog" | grep libsluice)"
fi
OUTPUT=$("$TMP/app/prog" "$TMP/app/thirds.cl") || fail "prog exited with $?: $OUTPUT"
echo "$OUTPUT"
case "$OUTPUT" in
*install-test-ok*) ;;
*) fail "unexpected output" ;;
esac
echo "test_install: ok"
