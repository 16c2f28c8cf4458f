# Thin wrapper over CMake: `make demo` and `make test` do the whole set-up.
BUILD      ?= build
ASAN_BUILD ?= build-asan
FUZZ_BUILD ?= build-fuzz
FUZZ_TIME  ?= 300
JOBS       ?= $(shell nproc)
DEMO_OUT   ?= out/demo

.PHONY: deps build demo test test-asan test-slurm fuzz-build fuzz fuzz-smoke bench clean

deps:
	@bash scripts/install_deps.sh

$(BUILD)/CMakeCache.txt: | deps
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release

build: deps $(BUILD)/CMakeCache.txt
	cmake --build $(BUILD) -j $(JOBS)

demo: build
	@bash scripts/demo.sh $(BUILD)/apps/rovermap $(DEMO_OUT)

test: build
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS) -LE slurm

# The campaign on a real single-node Slurm cluster, started for the test and stopped after it.
test-slurm: build
	@bash scripts/slurm/test.sh $(BUILD)

# The same suite under AddressSanitizer + UndefinedBehaviorSanitizer (-O2; -g1: the line tables
# that a report's stack needs, with objects far smaller than full debug information's). Left out
# there: the documentation's examples (label docs) and the outside project built against an
# installed tree (label install), which check text and packaging that `make test` checks.
test-asan: deps
	cmake -S . -B $(ASAN_BUILD) -DCMAKE_BUILD_TYPE=RelWithDebInfo -DROVERMAP_SANITIZE=ON -DROVERMAP_BUILD_BENCH=OFF \
	  "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O2 -g1 -DNDEBUG"
	cmake --build $(ASAN_BUILD) -j $(JOBS)
	cd $(ASAN_BUILD) && ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 ctest --output-on-failure -j $(JOBS) -LE 'slurm|docs|install'

# libFuzzer targets (tests/fuzz) with ASan + UBSan, built with clang in their own folder.
fuzz-build: deps
	cmake -S . -B $(FUZZ_BUILD) -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=RelWithDebInfo \
	  -DROVERMAP_FUZZ=ON -DROVERMAP_BUILD_TESTS=OFF -DROVERMAP_BUILD_BENCH=OFF
	cmake --build $(FUZZ_BUILD) -j $(JOBS) --target fuzz_targets

# Each target FUZZ_TIME seconds, one after the other (FUZZ_TARGETS="ply tum" for a few).
fuzz: fuzz-build
	@bash scripts/fuzz.sh $(FUZZ_BUILD) $(FUZZ_TIME) $(FUZZ_TARGETS)

# CI: every target briefly on its seed corpus, so that a parser regression shows up.
fuzz-smoke: fuzz-build
	@bash scripts/fuzz.sh $(FUZZ_BUILD) 20

bench: build
	@bash bench/run_bench.sh $(BUILD)

clean:
	rm -rf $(BUILD) $(ASAN_BUILD) $(FUZZ_BUILD)
