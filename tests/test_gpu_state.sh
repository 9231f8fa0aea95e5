#!/bin/sh
# The stream kernels, built as the runtime builds them for a GPU (group
# emission, SLUICE_UNROLL_STATE_: kernels/sluice.cl), keep each work-item's
# state in registers: clang's NVPTX back end (the clang PoCL depends on)
# must give them no stack frame (a `.local` depot in the PTX). NVIDIA's own
# OpenCL compiler showed a 176-byte frame, the size of sluice_state_, in
# every stream kernel before they were unrolled; clang shows the same frame
# without SLUICE_UNROLL_STATE_. No GPU is needed.
#
# The ray tracer's stream kernels, built as for a GPU (RT_PER_RAY:
# kernels/render/rt_stream.cl), the same; its fused kernel is left out (its
# packet's arrays are per work-item by design: 80 bytes).
#
# Usage: test_gpu_state.sh KERNELS_DIR EXAMPLES_DIR CLANG
# Exits 77 (skipped) where CLANG cannot build for NVPTX.
set -u
kernels=$1
examples=$2
clang=$3
tmp=$(mktemp -d) || exit 1
trap 'rm -rf "$tmp"' EXIT

build() { # build() SOURCE PTX [OPTION...]: OpenCL C 1.2 to PTX
    src=$1
    out=$2
    shift 2
    "$clang" -x cl -cl-std=CL1.2 -target nvptx64-nvidia-nvcl -O3 -I"$kernels" "$@" \
        -S "$src" -o "$out" 2>"$tmp/err"
}

# the method's own check: a private array indexed at run time must show up
cat >"$tmp/control.cl" <<'EOF'
__kernel void control(global uint *out, uint i)
{
    uint a[16];
    for (uint k = 0; k < 16u; ++k)
        a[k] = out[k];
    out[0] = a[i & 15u];
}
EOF
if ! build "$tmp/control.cl" "$tmp/control.ptx"; then
    echo "SKIP: $clang cannot build OpenCL C for nvptx64-nvidia-nvcl:"
    head -5 "$tmp/err"
    exit 77
fi
if ! grep -q '__local_depot' "$tmp/control.ptx"; then
    echo "FAIL: the control kernel's stack frame was not found in its PTX"
    exit 1
fi

# every loop form, emission and counter a user kernel can use
cat >"$tmp/forms.cl" <<'EOF'
#include "sluice.cl"
__kernel void copy(SLUICE_PARAMS, global const uint *in, global uint *out)
{
    SLUICE_FOR_EACH (i)
        out[i] = in[i];
}
__kernel void emit_count(SLUICE_PARAMS, global const float *in, global float *neg,
                         global float *pos)
{
    SLUICE_FOR_EACH (i) {
        float x = in[i];
        SLUICE_EMIT_IF(0, neg, x, x < 0.0f);
        SLUICE_EMIT_IF(1, pos, x, x >= 0.0f);
        SLUICE_COUNT(0, x == 0.0f);
    }
}
__kernel void ranges(SLUICE_PARAMS, global const uint *in, global uint *out)
{
    SLUICE_FOR_EACH_RANGE (b, e) {
        for (uint i = b; i < e; ++i)
            SLUICE_EMIT_IF(0, out, in[i], in[i] & 1u);
        SLUICE_COUNT(1, e - b);
    }
}
__kernel void blocks(SLUICE_PARAMS, global const uint *in, global uint *out)
{
    SLUICE_FOR_EACH_BLOCK(b, e)
    {
        for (uint i = b; i < e; ++i)
            SLUICE_EMIT_IF(0, out, in[i], in[i] > 7u);
    }
}
EOF

failed=0
checked=0
# check NAME: every entry of $tmp/NAME.ptx but those matching $skip, without
# a stack frame
check() {
    awk -v file="$1" '
        /^\.entry/ { if (entry != "") print file, entry, depot; entry = $2; sub(/\(.*/, "", entry); depot = 0 }
        /__local_depot[0-9]*\[/ { d = $0; sub(/.*\[/, "", d); sub(/\].*/, "", d); depot = d }
        END { if (entry != "") print file, entry, depot }' "$tmp/$1.ptx" >"$tmp/$1.frames"
    while read -r file entry depot; do
        if [ -n "$skip" ] && echo "$entry" | grep -qE "$skip"; then
            continue
        fi
        checked=$((checked + 1))
        if [ "$depot" != 0 ]; then
            echo "FAIL: $file: $entry has a $depot-byte stack frame on NVPTX"
            failed=1
        fi
    done <"$tmp/$1.frames"
}
gpu="-DSLUICE_GROUP_EMIT_ -DSLUICE_UNROLL_STATE_"
skip=""
# sort_radix.cl is left out: its kernels are the CPU's, a work-item walking
# a whole chunk with private histograms by design
for src in "$tmp/forms.cl" "$kernels"/compact.cl "$kernels"/scan.cl "$kernels"/reduce.cl \
    "$kernels"/route.cl "$kernels"/cell_index.cl "$kernels"/sort_bitonic.cl \
    "$kernels"/runtime.cl "$examples"/split_sign/split_sign.cl "$examples"/bounce/bounce.cl; do
    name=$(basename "$src" .cl)
    # shellcheck disable=SC2086
    if ! build "$src" "$tmp/$name.ptx" $gpu; then
        echo "FAIL: $src does not build for NVPTX:"
        head -20 "$tmp/err"
        failed=1
        continue
    fi
    check "$name"
done
# the ray tracer's program as apps/render/tracer.c puts it together
render=$kernels/render
for f in rt_types.h triangle.cl rt_trace.cl rt_lanes.cl rt_stream.cl rt_fused.cl; do
    cat "$render/$f"
    echo
done >"$tmp/tracer.cl"
# shellcheck disable=SC2086
if build "$tmp/tracer.cl" "$tmp/tracer.ptx" $gpu -I"$render" -D__OPENCL_VERSION__=120 \
    -DRT_UNROLL_STEPS=8 -DRT_UNROLL_TESTS=256 -DRT_PER_RAY; then
    skip='^rt_trace_fused$'
    check tracer
else
    echo "FAIL: the ray tracer's kernels do not build for NVPTX:"
    head -20 "$tmp/err"
    failed=1
fi
if [ "$checked" -lt 60 ]; then
    echo "FAIL: only $checked kernels found in the PTX"
    exit 1
fi
[ "$failed" = 0 ] && echo "OK: $checked stream kernels without a stack frame on NVPTX"
exit "$failed"
