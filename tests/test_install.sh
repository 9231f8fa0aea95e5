#!/bin/sh
# Installs the built tree and uses it as a user would, with no
# LD_LIBRARY_PATH anywhere:
#  - a --destdir install (staged under $TMP/dest): a small Sluice program is
#    built outside the source tree against the staged headers, library and
#    pkg-config file (PKG_CONFIG_SYSROOT_DIR), and run; the installed example
#    sluice-example-split-sign runs from another folder and must take its
#    kernel from the staged data folder, not from the source tree;
#  - a --prefix install: the staged tree moved to $TMP/prefix with the
#    prefix of its sluice.pc set to match, which is file for file what
#    `meson setup --prefix=$TMP/prefix` would install, without a second
#    configure and build of the whole project. The installed programs were
#    linked for the build's prefix, so that they run there proves that their
#    $ORIGIN rpath and data lookup are relative. The program is built again
#    with plain pkg-config, sluice-example-bounce and sluice-raytrace run
#    (the latter on the installed scene example.json, by its bare name).
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
# Nothing here may lean on LD_LIBRARY_PATH: installed programs find
# libsluice through their rpath, the test's program through -Wl,-rpath.
unset LD_LIBRARY_PATH

# The build's install layout and whether it is sanitized (make asan): a
# sanitized library needs the sanitizer runtime in the program too.
LAYOUT=$(meson introspect "$BUILD" --buildoptions | python3 -c '
import json, sys
o = {x["name"]: x["value"] for x in json.load(sys.stdin)}
print(o["prefix"], o["bindir"], o["libdir"], o["datadir"], o.get("b_sanitize", "none") or "none")
') || fail "meson introspect $BUILD"
# shellcheck disable=SC2086 # five words
set -- $LAYOUT
PREFIX=$1 BINDIR=$2 LIBDIR_REL=$3 DATADIR=$4 SANITIZE=$5
case "$PREFIX$BINDIR$LIBDIR_REL$DATADIR" in
*" "*) fail "install paths with spaces are not supported by this test" ;;
esac
for d in "$BINDIR" "$LIBDIR_REL" "$DATADIR"; do
    case "$d" in
    /*) fail "bindir, libdir and datadir must be relative to the prefix for this test ($d)" ;;
    esac
done
EXTRA=
[ "$SANITIZE" = none ] || EXTRA="-fsanitize=$SANITIZE"

# 1. Install into the staging directory (no rebuild: ninja already ran).
meson install -C "$BUILD" --no-rebuild --quiet --destdir "$DEST" >"$TMP/install.log" 2>&1 ||
    { cat "$TMP/install.log" >&2; fail "meson install"; }
STAGE=$DEST$PREFIX

# 2. The layout: library, headers, pkg-config file, programs, data, docs.
for f in "$LIBDIR_REL/libsluice.so" "$LIBDIR_REL/pkgconfig/sluice.pc" \
    "$LIBDIR_REL/sluice/libsluice-image-oiio.so" \
    include/sluice/sluice.h include/sluice/streams.h include/sluice/sluice.cl \
    "$BINDIR/sluice-raytrace" "$BINDIR/sluice-photonmap" "$BINDIR/sluice-info" \
    "$BINDIR/sluice-scene" "$BINDIR/sluice-imgdiff" \
    "$BINDIR/sluice-example-split-sign" "$BINDIR/sluice-example-bounce" \
    "$DATADIR/sluice/examples/split_sign.cl" "$DATADIR/sluice/examples/bounce.cl" \
    "$DATADIR/sluice/scenes/example.json" "$DATADIR/sluice/scenes/meshes/pyramid.obj" \
    "$DATADIR/doc/sluice/install.md" "$DATADIR/doc/sluice/scenes.md"; do
    [ -e "$STAGE/$f" ] || fail "$PREFIX/$f not installed (under $DEST)"
done
echo "layout: ok under $STAGE"

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


# builds_and_runs LABEL CFLAGS LIBS LIBDIR: compiles prog.c with nothing but
# what pkg-config said (and an rpath to LIBDIR, as a user of a non-system
# prefix would), checks that it loads libsluice from LIBDIR and runs it.
builds_and_runs() {
    label=$1 cflags=$2 libs=$3 libdir=$4
    echo "$label: pkg-config: $cflags $libs"
    [ -e "$libdir/libsluice.so" ] || fail "$label: libsluice.so not in $libdir"
    # shellcheck disable=SC2086 # the flags are meant to be split
    (cd "$TMP/app" && "$CC" -std=c11 -Wall -Wextra -Werror $EXTRA -o prog prog.c $cflags $libs \
        "-Wl,-rpath,$libdir") || fail "$label: compiling against the installed Sluice"
    loads_from "$TMP/app/prog" "$libdir"
    out=$("$TMP/app/prog" "$TMP/app/thirds.cl") || fail "$label: prog exited with $?: $out"
    echo "$label: $out"
    case "$out" in
    *install-test-ok*) ;;
    *) fail "$label: unexpected output" ;;
    esac
}

# loads_from EXE DIR: EXE's libsluice resolves to DIR (when ldd exists).
loads_from() {
    command -v ldd >/dev/null 2>&1 || return 0
    lib=$(ldd "$1" | awk '/libsluice/ { print $3 }')
    { [ -n "$lib" ] && [ -e "$lib" ]; } || fail "$1 finds no libsluice: $(ldd "$1" | grep libsluice)"
    [ "$(cd "$(dirname "$lib")" && pwd -P)" = "$(cd "$2" && pwd -P)" ] ||
        fail "$1 loads libsluice from $lib, not from $2"
}

# runs_installed LABEL EXPECT EXE ARGS...: runs an installed program from a
# folder with nothing in it (not the source or build tree) and checks that
# its output contains EXPECT.
runs_installed() {
    label=$1 expect=$2
    shift 2
    out=$(cd "$TMP/elsewhere" && "$@" 2>&1) || fail "$label: $* exited with $?: $out"
    case "$out" in
    *"$expect"*) ;;
    *) fail "$label: $* did not print [$expect]: $out" ;;
    esac
    echo "$label: $(basename "$1") ok"
}
mkdir -p "$TMP/elsewhere"

# pkg_flags PCDIR SYSROOT: what pkg-config says of the sluice.pc in PCDIR
# (with PKG_CONFIG_SYSROOT_DIR=SYSROOT, none when empty), into $TMP/cflags
# and $TMP/libs.
pkg_flags() {
    (
        export PKG_CONFIG_PATH="$1${PKG_CONFIG_PATH:+:$PKG_CONFIG_PATH}"
        if [ -n "$2" ]; then
            export PKG_CONFIG_SYSROOT_DIR="$2"
        else
            unset PKG_CONFIG_SYSROOT_DIR
        fi
        pkg-config --cflags sluice >"$TMP/cflags" && pkg-config --libs sluice >"$TMP/libs"
    ) || fail "pkg-config on $1/sluice.pc"
}

# 4. The --destdir install: pkg-config on the staged files. The sysroot
# prefixes every path of the .pc file with the staging directory (this also
# works for multiarch libdirs, where --define-prefix guesses the prefix wrong).
pkg_flags "$STAGE/$LIBDIR_REL/pkgconfig" "$DEST"
case "$(cat "$TMP/cflags")" in
*"$DEST"*) ;;
*) fail "pkg-config --cflags does not point into the staging directory: $(cat "$TMP/cflags")" ;;
esac
builds_and_runs destdir "$(cat "$TMP/cflags")" "$(cat "$TMP/libs")" "$STAGE/$LIBDIR_REL"
loads_from "$STAGE/$BINDIR/sluice-example-split-sign" "$STAGE/$LIBDIR_REL"
runs_installed destdir "kernel    $STAGE/$DATADIR/sluice/examples/split_sign.cl" \
    "$STAGE/$BINDIR/sluice-example-split-sign" --count 20000 --repeat 1

# 5. The --prefix install (see the top): the same tree at $TMP/prefix.
PFX=$TMP/prefix
mv "$STAGE" "$PFX" || fail "moving $STAGE to $PFX"
PC=$PFX/$LIBDIR_REL/pkgconfig/sluice.pc
{ sed "s|^prefix=.*|prefix=$PFX|" "$PC" >"$TMP/sluice.pc" && cat "$TMP/sluice.pc" >"$PC"; } ||
    fail "setting the prefix of $PC"
grep -q "^prefix=$PFX\$" "$PC" || fail "$PC has no prefix= line to set"
pkg_flags "$PFX/$LIBDIR_REL/pkgconfig" ""
builds_and_runs prefix "$(cat "$TMP/cflags")" "$(cat "$TMP/libs")" "$PFX/$LIBDIR_REL"
loads_from "$PFX/$BINDIR/sluice-example-bounce" "$PFX/$LIBDIR_REL"
loads_from "$PFX/$BINDIR/sluice-raytrace" "$PFX/$LIBDIR_REL"
runs_installed prefix "kernel $PFX/$DATADIR/sluice/examples/bounce.cl" \
    "$PFX/$BINDIR/sluice-example-bounce" --count 2000 --every 0
runs_installed prefix "rays: eye 1024" "$PFX/$BINDIR/sluice-raytrace" --scene example.json \
    --size 32x32 --spp 1 --out "$TMP/elsewhere/example.png"
[ -s "$TMP/elsewhere/example.png" ] || fail "sluice-raytrace wrote no image"
echo "test_install: ok"
