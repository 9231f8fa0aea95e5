# Sluice: the two commands of the README's Quick start, and a few more.
#   make demo   install what is missing, build, run the demo
#   make test   install what is missing, build, run the whole suite (ctest)
#   make bench  install the benchmarks' peers (Embree, POV-Ray, Mitsuba 3 and
#               matplotlib in bench/.venv), run the benchmarks (bench/results/
#               streams.json, raytrace.json, knn.json, photonmap.json, error.json)
#   make bench-error  only run time against error (bench/bench_error.py:
#               references, Mitsuba 3, POV-Ray; error.json, error-SCENE.png)
#   make references  converged path-traced references of cornell, glassball
#               and ring (bench/references/, git-ignored; bench/references.py)
#   make mitsuba-agreement  install Mitsuba 3 into bench/.venv, render the
#               same scenes with it and compare (bench/mitsuba_compare.py)
#   make asan   the suite again in an ASan+UBSan build of the host code
#   make sweep  (optional) every CLI over every file of Debian's
#               assimp-testmodels, installed when missing (tools/sweep_models.py)
#   make fuzz   (optional) the libFuzzer harnesses of tests/fuzz/, built with
#               clang (FUZZ_RUNS executions each, default 10^6)
BUILD ?= build
ASAN_BUILD ?= build-asan
MESON_FLAGS ?=
# ctest runs this many tests at once (every core: on a cold PoCL cache most
# of the suite's time is kernel builds, one core each)
TEST_JOBS ?= $(shell nproc 2>/dev/null || echo 2)

.PHONY: all deps build demo test bench bench-error references mitsuba-agreement asan sweep fuzz install clean

all: build

deps:
	@sh tools/install-deps.sh

$(BUILD)/build.ninja: | deps
	meson setup $(BUILD) $(MESON_FLAGS)

build: deps $(BUILD)/build.ninja
	ninja -C $(BUILD)

demo: build
	$(BUILD)/apps/raytrace/sluice-raytrace --scene cornell --mode shadow --size 512x512 --out cornell.png

test: build
	ctest --test-dir $(BUILD) --output-on-failure -j $(TEST_JOBS)

bench:
	sh tools/install-deps.sh --bench
	$(MAKE) build
	@# a build dir configured before Embree was installed must look again
	@grep -q HAVE_EMBREE $(BUILD)/build.ninja || meson setup --reconfigure $(BUILD) $(MESON_FLAGS)
	ninja -C $(BUILD)
	$(BUILD)/bench/bench_streams --out bench/results/streams.json
	$(BUILD)/bench/bench_raytrace --out bench/results/raytrace.json
	$(BUILD)/bench/bench_knn --out bench/results/knn.json
	python3 bench/bench_photonmap.py --exe $(BUILD)/apps/photonmap/sluice-photonmap --out bench/results/photonmap.json
	$(MAKE) bench-error

# Run time against error (issue 13): Sluice's methods, Mitsuba 3 and POV-Ray
# against the references (rendered first when missing: several minutes).
bench-error:
	sh tools/install-deps.sh --bench
	sh tools/install-mitsuba.sh
	$(MAKE) build
	POCL_CACHE_DIR=$${POCL_CACHE_DIR:-$(CURDIR)/$(BUILD)/pocl-cache} nice bench/.venv/bin/python \
	    bench/bench_error.py --build $(BUILD) --out bench/results/error.json

references: build
	POCL_CACHE_DIR=$${POCL_CACHE_DIR:-$(CURDIR)/$(BUILD)/pocl-cache} python3 bench/references.py \
	    --exe $(BUILD)/apps/raytrace/sluice-raytrace

mitsuba-agreement: references
	sh tools/install-mitsuba.sh
	POCL_CACHE_DIR=$${POCL_CACHE_DIR:-$(CURDIR)/$(BUILD)/pocl-cache} bench/.venv/bin/python \
	    bench/mitsuba_compare.py --scene-exe $(BUILD)/apps/common/sluice-scene \
	    --raytrace $(BUILD)/apps/raytrace/sluice-raytrace

# The kernels are the same as the plain build's: its PoCL cache (filled by
# `make test` before, as in CI) spares the sanitizer run their compiles.
$(ASAN_BUILD)/build.ninja: | deps
	meson setup $(ASAN_BUILD) -Dbuildtype=debug -Db_sanitize=address,undefined \
	    -Db_lundef=false -Dpocl_cache_dir=$(CURDIR)/$(BUILD)/pocl-cache $(MESON_FLAGS)

asan: deps $(ASAN_BUILD)/build.ninja
	ninja -C $(ASAN_BUILD)
	@# intercept_tls_get_addr=0: GCC 12's sanitizer runtime (up to GCC 13 and
	@# LLVM 16) can take a dynamic TLS block of PoCL's or TBB's threads for a
	@# pre-2.25 glibc header and read a wild address from it, and the leak
	@# check at exit then dies with "Tracer caught signal 11" though nothing
	@# leaked (google/sanitizers#1322; one such CI run on bench_raytrace_smoke)
	ASAN_OPTIONS=detect_leaks=1:abort_on_error=1:intercept_tls_get_addr=0 \
	LSAN_OPTIONS=suppressions=$(CURDIR)/tools/lsan.supp:print_suppressions=0 \
	UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 \
	    ctest --test-dir $(ASAN_BUILD) --output-on-failure -j $(TEST_JOBS)

# Not part of `make test`: about 600 files, a few minutes with the renderers.
SWEEP_FLAGS ?=
sweep: build
	@dpkg-query -W -f='$${Status}' assimp-testmodels 2>/dev/null | grep -q "install ok installed" || \
	    { if [ "$$(id -u)" = 0 ]; then apt-get install -y -q assimp-testmodels; \
	      else sudo apt-get install -y -q assimp-testmodels; fi; }
	python3 tools/sweep_models.py --build $(BUILD) $(SWEEP_FLAGS)

# Not part of the normal build (CI builds with gcc): clang and libFuzzer.
fuzz:
	sh tests/fuzz/fuzz.sh all

install: build
	meson install -C $(BUILD)

clean:
	rm -rf $(BUILD) $(ASAN_BUILD) build-fuzz
