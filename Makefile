# Thin wrapper over CMake. Every target first installs missing Debian packages.
BUILD      ?= build
BUILD_ASAN ?= build-asan
JOBS       ?= $(shell nproc)
SCENE      ?= scenes/foggy-dof.pbrt
# Output: out/NAME.exr and out/NAME.png, NAME the scene file's name.
OUT        ?= out/$(basename $(notdir $(SCENE)))

.PHONY: all deps configure render test test-asan update-refs clean fuzz bench bench-mpi

all: deps configure
	cmake --build $(BUILD) -j $(JOBS)

deps:
	@bash tools/deps.sh

configure:
	@test -f $(BUILD)/CMakeCache.txt || cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release

render: all
	@mkdir -p out
	$(BUILD)/haze render $(SCENE) -o $(OUT).exr --preview $(OUT).png

test: all
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS)

test-asan: deps
	@test -f $(BUILD_ASAN)/CMakeCache.txt || cmake -S . -B $(BUILD_ASAN) -DCMAKE_BUILD_TYPE=Debug -DHAZE_SANITIZE=ON
	cmake --build $(BUILD_ASAN) -j $(JOBS)
	cd $(BUILD_ASAN) && ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 ctest --output-on-failure -j $(JOBS)

# Re-render the regression references (REF_SPP=4096 by default) and print how
# each one changed; review, then commit them. NAMES="smoke motion" limits it.
update-refs: all
	sh tests/regression/update-refs.sh $(BUILD)/haze $(NAMES)

# libFuzzer: builds build-fuzz with clang (HAZE_FUZZ=ON) and runs each target for
# FUZZ_SECONDS on a scratch copy of fuzz/corpus; fails on any crash (docs/fuzzing.md).
FUZZ_SECONDS ?= 60
fuzz: deps
	@test -f build-fuzz/CMakeCache.txt || CC=clang CXX=clang++ cmake -S . -B build-fuzz -DCMAKE_BUILD_TYPE=RelWithDebInfo -DHAZE_FUZZ=ON -DHAZE_TESTS=OFF
	cmake --build build-fuzz -j $(JOBS) --target fuzz_scene fuzz_exr fuzz_nvdb fuzz_bsdf
	sh fuzz/run.sh build-fuzz $(FUZZ_SECONDS)

# Speed against accuracy (bench/README.md): the peer, target and yardstick parts
# took 25 min on two cores with the references cached in bench/cache/ (a first
# run renders them too: the peer's anti-aliased ones ~5 min, the smoke target's
# 7 min, ...); BENCH_QUICK=1 is a ~4 min smoke run into
# bench/cache/quick-results/. Writes bench/results/trade.md and trade.png.
bench: all
	BENCH_QUICK=$(BENCH_QUICK) sh bench/run.sh $(BUILD)/haze

# MPI scaling (bench/results/mpi.md): 1, 2 and 4 ranks on one machine.
bench-mpi: all
	sh bench/mpi_scaling.sh $(BUILD)/haze

clean:
	rm -rf $(BUILD) $(BUILD_ASAN)
