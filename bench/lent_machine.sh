#!/bin/bash
# The figures of issue 14 that need the lent machine (an NVIDIA GPU beside a
# 16-core CPU, Ubuntu, no network), in one call that fits its time limit.
#
#   bench/lent_machine.sh OUTDIR DEADLINE_S PHASE...
#
# Phases, run in the order given, each cut off where it would pass the
# deadline (seconds from the start):
#   gpu-streams   bench_streams on the GPU in the runtime's own layout for it
#                 (interleaved) -> OUTDIR/streams-h100.json
#   gpu-streams-n=N  the same on N records -> streams-h100-nN.json
#   gpu-profile   the same with SLUICE_PROFILE=1 (the kernels' own times on
#                 the device, every launch) -> profile-h100.txt
#   gpu-regs      NVIDIA's build logs with -cl-nv-verbose (registers, spills
#                 and local memory per kernel) -> regs-h100.txt
#   gpu-state-ab=R  bench_streams on the GPU with the work-items' state in
#                 registers (the default) and without (-DSLUICE_NO_UNROLL_STATE),
#                 in turn, R rounds -> state-{on,off}-N.json
#   gpu-block-ab=R  bench_streams on the GPU with compaction's and
#                 partition's blocks of 16 records (the default) and of 4
#                 (-DCOMPACT_BLOCK=4: group order scans once a block), in
#                 turn, R rounds -> block-{on,off}-N.json (off: 4)
#   gpu-scan-ab=R  bench_streams on the GPU with group order's scan as
#                 built there (log2(G) rounds of the whole group) and in 16
#                 work-items' serial segments (-DSLUICE_NO_KS_SCAN), in
#                 turn, R rounds -> ksscan-{on,off}-N.json (off: segments)
#   gpu-rt-ab=R   bench_raytrace on the GPU with the stream tracer's kernels
#                 one ray per work-item (the default there) and in blocks of
#                 16 rays (-DRT_NO_PER_RAY), in turn, R rounds
#                 -> rt-per-ray-{on,off}-N.json
#   gpu-chain-ab  bench_streams_ab on the GPU with SLUICE_GROUP_CHAIN=1:
#                 ordered outputs by three commands against the groups'
#                 chain -> chain-ab-gpu.txt (gpu-tests=..._gpu_chain runs
#                 the stream tests that way)
#   gpu-contig    the same in the CPU's layout -> streams-h100-contiguous.json
#   gpu-chunks=LIST  the same in its own layout with SLUICE_CHUNK (records
#                 per work-item) at each value of LIST -> streams-h100-chunk-N.json
#   gpu-tests     the suite on the GPU (SLUICE_DEVICE=NVIDIA), less what reads
#                 or writes images (OpenImageIO is not carried) or needs
#                 PoCL's own options;
#                 gpu-tests=REGEX only the tests REGEX matches (ctest -R)
#   gpu-raytrace  bench_raytrace on the GPU -> raytrace-h100.json
#   gpu-rt-test   test_raytrace on the GPU, the groups that render first
#                 (its reference images cannot be read) -> raytrace-test-gpu.txt
#   gpu-photonmap bench_photonmap.py on the GPU (its renders write no image,
#                 so the image module is not needed) -> photonmap-h100.json
#   scaling=LIST  bench/bench_scaling.py on PoCL, threads in LIST's order
#                 (1 first) -> scaling-xeon16.json, the runs in scaling-runs.tar
#   overhead=LIST bench_streams on 2^18 records on PoCL at each thread count
#                 of LIST: what a dependent launch, a launch and the wait
#                 for it, and a frame's round trip cost -> overhead-N.json
#   chain-ab=LIST bench_streams_ab on PoCL at each thread count of LIST:
#                 ordered outputs by three commands against the chain (one
#                 launch, decoupled look-back), which waits more with more
#                 threads -> chain-ab-N.txt
#   rt-profile=LIST  bench_raytrace (bunny, bunny-close) on PoCL at each
#                 thread count of LIST with SLUICE_PROFILE=1: the kernels'
#                 own times against the frames' -> rt-profile-N.txt
#   spread-ab=T   on PoCL at T threads, bench_raytrace (three scenes) twice
#                 with and without the spread of the fused tracer's chunks
#                 over the work-groups (SLUICE_NO_SPREAD=1), in turn; and
#                 bench_raytrace at 1 thread for the speedup
#                 -> spread-{on,off}-T-{rt1,rt2}.json, spread-1-rt.json
#   rt-eff=T      on PoCL, bench_raytrace (three scenes) at 1 and T threads
#                 in turn, twice: the speedup from runs side by side
#                 -> eff-{1,T}-N.json
#   rt-chunks=T:LIST  on PoCL at T threads, bench_raytrace (three scenes)
#                 with SLUICE_CHUNK at each value of LIST (0: the runtime's
#                 own choice), in turn: whether smaller chunks (more
#                 work-groups) shorten the last thread's tail
#                 -> rt-chunk-T-N.json
#   libs-probe    which libraries of the image module's closure (the
#                 sonames in .carry/oiio-libs.txt, one a line: `ldd` here) the
#                 machine lacks -> oiio-missing.txt, so that a later call can
#                 carry just those and run the whole suite there
#
# RT_SIZE (default 512) is the image side of the PoCL phases' ray tracer
# runs (spread-ab, rt-eff, rt-chunks): at 16 threads a 512x512 frame is
# short enough that a launch's fixed cost is a tenth of it. RT_SCENES
# (default "cornell bunny bunny-close") and RT_REPS (default 2) narrow them:
# at 1024x1024 one thread took 135 s for the three scenes' two rounds.
# LENT_DEVICE (default NVIDIA) names the device of the gpu phases, so that
# the script can be tried on any machine first (LENT_DEVICE=pthread).
# What it expects: the build in ./build (made on Debian 12, with rpaths
# relative to the binaries), and the Debian libraries the binaries link
# (not the image module's OpenImageIO) in .carry/libs.tar.xz, flat (the
# call carries both). The build's tests name /work/main, so that path is
# linked to this tree.
#
#   bench/lent_machine.sh --pack
#
# makes .carry here, on the machine that built ./build: the libraries (the
# `ldd` closure of every program, less glibc's and the compiler's own, which
# the lent machine has newer), glmark2's bunny and the sonames the image
# module needs (for libs-probe); then
# call the tool with carry ["build", ".carry"].
set -u
if [ "${1:-}" = --pack ]; then
    mkdir -p .carry
    grep -qx '/.carry/' .git/info/exclude 2>/dev/null || echo /.carry/ >>.git/info/exclude
    progs=""
    for b in build/bench/bench_* build/tests/test_* build/apps/sluice-info build/apps/common/sluice-* \
        build/apps/examples/*/sluice-example-* build/apps/raytrace/sluice-raytrace \
        build/apps/photonmap/sluice-photonmap; do
        [ -x "$b" ] && [ -f "$b" ] && progs="$progs $b"
    done
    # No program links OpenImageIO: it sits in the image module, loaded on
    # first use (apps/common/image.h), whose closure is libs-probe's.
    # shellcheck disable=SC2086
    ldd $progs | awk '$3 ~ /^\// {print $3}' | sort -u | grep -v "$(pwd)/build" |
        grep -vE '/(libc|libm|libgcc_s|libstdc\+\+)\.so' >.carry/libs.txt
    # shellcheck disable=SC2046
    tar -chPf - --transform='s,.*/,,' $(cat .carry/libs.txt) | xz -6 -T0 >.carry/libs.tar.xz
    # shellcheck disable=SC2086
    ldd build/apps/common/libsluice-image-oiio.so | awk '$3 ~ /^\// {print $1}' | sort -u |
        grep -v libsluice >.carry/oiio-libs.txt
    cp /usr/share/glmark2/models/bunny.obj .carry/
    du -sh .carry build
    # the tool carries 64 MiB at most; PoCL's caches are no use there
    echo "carry at most 64 MiB: move build/pocl-cache* (and build/tests/pocl-cache*, build/bench/pocl-cache* of older builds) out of build first if it is large"
    exit 0
fi
OUT=${1:?usage: lent_machine.sh OUTDIR DEADLINE_S PHASE...}
DEADLINE=${2:?deadline in seconds}
shift 2
ROOT=$(pwd)
LOG="$OUT/log.txt"
mkdir -p "$OUT"
exec > >(tee -a "$LOG") 2>&1

say() { echo "[+${SECONDS}s] $*"; }
# run CMD under a limit: the phase's own, or what is left before the deadline
limited() {
    local want=$1
    shift
    local left=$((DEADLINE - SECONDS - 5))
    [ "$left" -lt "$want" ] && want=$left
    if [ "$want" -lt 10 ]; then
        say "skipped (deadline): $*"
        return 124
    fi
    timeout -k 5 "$want" "$@"
    local rc=$?
    [ $rc -ne 0 ] && say "rc $rc: $*"
    return $rc
}
# A benchmark on the GPU as built (SLUICE_BUILD_OPTIONS empty: "on") and
# with OFF_OPTION ("off"), in turn, R rounds, each run within LIMIT seconds,
# writing OUT/NAME-{on,off}-N.json; the lines matching PATTERN printed:
# gpu_ab R OFF_OPTION NAME LIMIT PATTERN CMD...
gpu_ab() {
    local rounds=$1 off=$2 name=$3 lim=$4 pattern=$5 r v opt
    shift 5
    for r in $(seq 1 "$rounds"); do
        for v in on off; do
            opt=""
            [ $v = off ] && opt=$off
            say "$name on the GPU: $v (round $r)"
            SLUICE_DEVICE=$DEV SLUICE_BUILD_OPTIONS=$opt limited "$lim" "$@" \
                --out "$OUT/$name-$v-$r.json" | grep -E "$pattern"
        done
    done
}
# bench_raytrace's three scenes on PoCL at T threads, its rates printed:
# rt_scenes T OUT [VAR=VALUE...]
rt_scenes() {
    local t=$1 out=$2 size=${RT_SIZE:-512} sc scenes=""
    shift 2
    for sc in ${RT_SCENES:-cornell bunny bunny-close}; do scenes="$scenes --scene $sc"; done
    # shellcheck disable=SC2086
    POCL_MAX_PTHREAD_COUNT=$t POCL_CPU_MAX_CU_COUNT=$t \
        limited $((90 * size / 512 * size / 512)) env "$@" \
        taskset -c 0-$((t - 1)) build/bench/bench_raytrace --skip-purcell --reps "${RT_REPS:-2}" \
        --size "$size" $scenes --out "$out" |
        grep -E "^(cornell|bunny|bunny-close) +[0-9]+ +[0-9]"
}

say "setup in $ROOT"
if [ -f .carry/bunny.obj ] && [ ! -e /usr/share/glmark2/models/bunny.obj ]; then
    mkdir -p /usr/share/glmark2/models && cp .carry/bunny.obj /usr/share/glmark2/models/
fi
if [ "$ROOT" != /work/main ] && [ ! -e /work/main ]; then
    mkdir -p /work && ln -s "$ROOT" /work/main
fi
mkdir -p /tmp/sluice-libs
tar -xJf .carry/libs.tar.xz -C /tmp/sluice-libs
export LD_LIBRARY_PATH=/tmp/sluice-libs
# NVIDIA's OpenCL library is there but not registered with the ICD loader
DEV=${LENT_DEVICE:-NVIDIA}
if [ "$DEV" = NVIDIA ]; then
    mkdir -p /etc/OpenCL/vendors
    echo libnvidia-opencl.so.1 >/etc/OpenCL/vendors/nvidia.icd
fi
ls /etc/OpenCL/vendors
export POCL_CACHE_DIR=$ROOT/build/pocl-cache
nvidia-smi --query-gpu=name,driver_version,memory.total,clocks.max.sm,clocks.max.mem --format=csv
lscpu | grep -E "Model name|^CPU\(s\)|Flags" | cut -c1-200
build/apps/sluice-info 2>&1 | head -30

for phase in "$@"; do
    case "$phase" in
    gpu-streams)
        say "bench_streams on the GPU, its own layout"
        SLUICE_DEVICE=$DEV limited 150 build/bench/bench_streams --out "$OUT/streams-h100.json"
        ;;
    gpu-streams-n=*)
        nrec=${phase#gpu-streams-n=}
        say "bench_streams on the GPU, $nrec records"
        SLUICE_DEVICE=$DEV limited 150 build/bench/bench_streams --n "$nrec" --skip-bitonic \
            --out "$OUT/streams-h100-n$nrec.json"
        ;;
    gpu-profile)
        say "bench_streams on the GPU with SLUICE_PROFILE=1"
        SLUICE_DEVICE=$DEV SLUICE_PROFILE=1 limited 90 build/bench/bench_streams --reps 3 \
            --skip-bitonic >"$OUT/profile-h100.txt" 2>&1
        head -32 "$OUT/profile-h100.txt"
        ;;
    gpu-regs)
        say "NVIDIA's build logs (-cl-nv-verbose)"
        SLUICE_DEVICE=$DEV SLUICE_BUILD_OPTIONS=-cl-nv-verbose SLUICE_VERBOSE=1 limited 90 \
            build/bench/bench_streams --n 65536 --reps 1 --skip-bitonic >"$OUT/regs-h100.txt" 2>&1
        # one line a kernel: its name, stack frame and spills, registers
        awk "/Compiling entry function/ {n = \$7} /stack frame/ {f = \$0; sub(/.*\\. +/, \"\", f)}
            /Used [0-9]+ registers/ {print n, f, \$5, \"registers\"}" "$OUT/regs-h100.txt" |
            sort -u | head -120
        ;;
    gpu-state-ab=*)
        # the work-items' state in registers (kernels/sluice.cl,
        # SLUICE_UNROLL_STATE_) against it in memory
        gpu_ab "${phase#gpu-state-ab=}" -DSLUICE_NO_UNROLL_STATE state 90 \
            "^ *(copy|scan|reduce|split|compact|sort_radix|partition)" \
            build/bench/bench_streams --skip-bitonic
        ;;
    gpu-block-ab=*)
        # blocks of 16 records (COMPACT_BLOCK, kernels/compact.cl) against 4
        gpu_ab "${phase#gpu-block-ab=}" -DCOMPACT_BLOCK=4 block 90 \
            "^ *(copy|scan|split|compact|partition)" \
            build/bench/bench_streams --skip-bitonic
        ;;
    gpu-scan-ab=*)
        # group order's scan (sluice_group_place_, kernels/sluice.cl):
        # Kogge and Stone's rounds against 16 serial segments
        gpu_ab "${phase#gpu-scan-ab=}" -DSLUICE_NO_KS_SCAN ksscan 90 \
            "^ *(copy|scan|split|compact|partition)" \
            build/bench/bench_streams --skip-bitonic
        ;;
    gpu-rt-ab=*)
        # the stream tracer's kernels one ray per work-item (RT_PER_RAY, the
        # default on GPUs) against blocks of 16 rays
        gpu_ab "${phase#gpu-rt-ab=}" -DRT_NO_PER_RAY rt-per-ray 150 \
            "^(cornell|bunny|bunny-close) +[0-9]+ +[0-9]" \
            build/bench/bench_raytrace --skip-purcell --reps 2
        ;;
    gpu-chain-ab)
        # ordered outputs: count launch, scan and write launch against each
        # group placing its tile by the chain (SLUICE_GROUP_CHAIN=1), pairs
        # of calls; then the GPU's stream tests with the chain on
        say "bench_streams_ab on the GPU, SLUICE_GROUP_CHAIN=1"
        SLUICE_DEVICE=$DEV SLUICE_GROUP_CHAIN=1 limited 90 build/bench/bench_streams_ab \
            --pairs 20 >"$OUT/chain-ab-gpu.txt" 2>&1
        cat "$OUT/chain-ab-gpu.txt"
        ;;
    gpu-contig)
        say "bench_streams on the GPU, SLUICE_LAYOUT=contiguous"
        SLUICE_DEVICE=$DEV SLUICE_LAYOUT=contiguous limited 120 build/bench/bench_streams \
            --skip-bitonic --out "$OUT/streams-h100-contiguous.json"
        ;;
    gpu-chunks=*)
        for c in $(echo "${phase#gpu-chunks=}" | tr , ' '); do
            say "bench_streams on the GPU, SLUICE_CHUNK=$c"
            SLUICE_DEVICE=$DEV SLUICE_CHUNK=$c limited 60 build/bench/bench_streams --skip-bitonic \
                --out "$OUT/streams-h100-chunk-$c.json"
        done
        ;;
    gpu-tests | gpu-tests=*)
        only=""
        [ "$phase" != gpu-tests ] && only=${phase#gpu-tests=}
        say "the suite on the GPU${only:+, tests matching $only}"
        mkdir -p /tmp/gpu-tests
        sed -e "s/SLUICE_DEVICE=;/SLUICE_DEVICE=$DEV;/g" -e "s/SLUICE_DEVICE=\")/SLUICE_DEVICE=$DEV\")/g" \
            build/CTestTestfile.cmake >/tmp/gpu-tests/CTestTestfile.cmake
        CTEST=$(command -v ctest || ls /opt/torch/.venv/bin/ctest /usr/local/bin/ctest 2>/dev/null | head -1)
        # what reads or writes images (the image module is not carried):
        # photonmap and adaptive write none since OpenImageIO is loaded lazily
        excl='avx2|portable|^image$|imgdiff|^raytrace|photonmap_cli|^stress$|^install$|bench_error_selftest'
        if [ -n "$CTEST" ]; then
            limited 200 "$CTEST" --test-dir /tmp/gpu-tests -j 8 --timeout 180 -E "$excl" \
                ${only:+-R "$only"} --output-on-failure >"$OUT/gpu-tests.txt" 2>&1
            tail -60 "$OUT/gpu-tests.txt"
        else
            say "no ctest on this machine"
        fi
        ;;
    gpu-rt-test)
        # the ray tracer's test on the GPU, its groups that render first
        # (stream against fused bit for bit), then the rest; the reference
        # images cannot be read there (no image module), so those fail
        say "test_raytrace on the GPU"
        (cd build/tests && SLUICE_DEVICE=$DEV limited 150 ./test_raytrace \
            --only determinism,auto_grid,camera_inside,near_area_light;
            SLUICE_DEVICE=$DEV limited 150 ./test_raytrace \
                --only random_rays,one_triangle,watertight,reference_images) \
            >"$OUT/raytrace-test-gpu.txt" 2>&1
        grep -E "failed|passed|checked|cannot" "$OUT/raytrace-test-gpu.txt" | head -40
        ;;
    gpu-photonmap)
        say "bench_photonmap on the GPU"
        limited 200 python3 bench/bench_photonmap.py --device "$DEV" \
            --out "$OUT/photonmap-h100.json" | tail -30
        ;;
    gpu-raytrace)
        say "bench_raytrace on the GPU"
        SLUICE_DEVICE=$DEV limited 150 build/bench/bench_raytrace --skip-purcell --reps 3 \
            --out "$OUT/raytrace-h100.json"
        ;;
    scaling=*)
        list=${phase#scaling=}
        say "scaling on PoCL, threads $list"
        limited 400 python3 bench/bench_scaling.py --threads "$list" --keep /tmp/scaling \
            --out "$OUT/scaling-xeon16.json"
        (cd /tmp && tar -cf "$OUT/scaling-runs.tar" scaling)
        ;;
    overhead=*)
        for t in $(echo "${phase#overhead=}" | tr , ' '); do
            say "launch overhead on PoCL, $t threads"
            POCL_MAX_PTHREAD_COUNT=$t POCL_CPU_MAX_CU_COUNT=$t limited 60 taskset -c 0-$((t - 1)) \
                build/bench/bench_streams --n 262144 --reps 5 --skip-bitonic \
                --out "$OUT/overhead-$t.json" | grep -E "device:|chain|wait"
        done
        ;;
    chain-ab=*)
        for t in $(echo "${phase#chain-ab=}" | tr , ' '); do
            say "ordered outputs, three commands against the chain, on PoCL, $t threads"
            POCL_MAX_PTHREAD_COUNT=$t POCL_CPU_MAX_CU_COUNT=$t limited 90 taskset -c 0-$((t - 1)) \
                build/bench/bench_streams_ab --pairs 20 >"$OUT/chain-ab-$t.txt" 2>&1
            cat "$OUT/chain-ab-$t.txt"
        done
        ;;
    rt-profile=*)
        for t in $(echo "${phase#rt-profile=}" | tr , ' '); do
            say "bench_raytrace on PoCL with SLUICE_PROFILE=1, $t threads"
            POCL_MAX_PTHREAD_COUNT=$t POCL_CPU_MAX_CU_COUNT=$t SLUICE_PROFILE=1 limited 120 \
                taskset -c 0-$((t - 1)) build/bench/bench_raytrace --skip-purcell --reps 2 \
                --scene bunny --scene bunny-close >"$OUT/rt-profile-$t.txt" 2>&1
            grep -E "^bunny|rt_trace_fused|total" "$OUT/rt-profile-$t.txt"
        done
        ;;
    spread-ab=*)
        t=${phase#spread-ab=}
        for r in 1 2; do
            for sp in 1 0; do
                say "bench_raytrace, $t threads, spread $sp, round $r"
                rt_scenes "$t" "$OUT/spread-$([ $sp = 1 ] && echo on || echo off)-$t-rt$r.json" \
                    SLUICE_NO_SPREAD=$((1 - sp))
            done
        done
        say "bench_raytrace, 1 thread"
        rt_scenes 1 "$OUT/spread-1-rt.json"
        ;;
    rt-eff=*)
        t=${phase#rt-eff=}
        for r in 1 2; do
            for n in 1 "$t"; do
                say "bench_raytrace, $n threads, round $r"
                rt_scenes "$n" "$OUT/eff-$n-$r.json"
            done
        done
        ;;
    rt-chunks=*)
        spec=${phase#rt-chunks=}
        t=${spec%%:*}
        for c in $(echo "${spec#*:}" | tr , ' '); do
            say "bench_raytrace, $t threads, SLUICE_CHUNK=$c"
            rt_scenes "$t" "$OUT/rt-chunk-$t-$c.json" $([ "$c" != 0 ] && echo SLUICE_CHUNK="$c")
        done
        ;;
    libs-probe)
        say "libraries of the OpenImageIO programs the machine lacks"
        while read -r lib; do
            ldconfig -p | grep -q "^[[:space:]]*$lib " || echo "$lib"
        done <.carry/oiio-libs.txt >"$OUT/oiio-missing.txt"
        echo "$(wc -l <"$OUT/oiio-missing.txt") of $(wc -l <.carry/oiio-libs.txt) missing"
        ;;
    *)
        say "unknown phase $phase"
        ;;
    esac
done
say "done"
