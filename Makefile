# isokit — the commands a newcomer types (README). Each target installs missing Debian
# packages, configures and builds (Release, all cores), then runs.
BUILD      ?= build
ASAN_BUILD ?= build-asan
FUZZ_BUILD ?= build-fuzz
FUZZ_SECONDS ?= 300
FUZZ_TARGETS ?= glb gltf fbx dae setup spec npy
FUZZ_ISOLATE ?= 0
DEMO_OUT   ?= out/demo
EVAL_OUT   ?= out/eval
EVAL_ARGS  ?=
JOBS       ?= $(shell nproc)
CMAKE_ARGS ?=

.PHONY: all deps configure build demo eval test test-release test-asan bench bench-studio bench-view fuzz blender-addon clean

all: build

deps:
	@scripts/install-deps.sh

configure: deps
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release $(CMAKE_ARGS)

build: configure
	cmake --build $(BUILD) -j $(JOBS)

# The skinning demo: the procedural humanoid's elbow and knee bent to 150° and back with all
# six methods (lbs, dqs, ddm, cor, implicit2013, tracking2014); writes $(DEMO_OUT)/ (contact sheet, metrics JSON, the default method's .glb: implicit2013.glb).
demo: build
	$(BUILD)/apps/skinning/isokit-skin demo --out $(DEMO_OUT)

# The real-rig evaluation: every clip of every rig in ../shared/data/rigs (and Fox), plus an
# elbow/knee bend-and-return, with dqs, ddm, cor, implicit2013 and tracking2014; writes
# $(EVAL_OUT)/ (eval.json, eval.md, per-rig metrics and contact sheets), then scores the implicit
# methods against the best geometric method of each row (bench/eval/score_vs_geometric.py, when
# ../shared/tools is there; $(EVAL_OUT)/score_vs_geometric.json). Quick run:
# EVAL_ARGS="--max-frames 10"; docs/skinning-real-rigs.md.
eval: build
	$(BUILD)/bench/isokit-eval --out $(EVAL_OUT) --commit "$$(git rev-parse --short HEAD 2>/dev/null)" $(EVAL_ARGS)
	@if [ -f ../shared/tools/judge_vs_dqs.py ]; then \
	  python3 bench/eval/score_vs_geometric.py $(EVAL_OUT) --tools ../shared/tools --json $(EVAL_OUT)/score_vs_geometric.json; fi

# All tests of the Release build (unit, slow, gpu — skipped without a device — and the
# find_package consumer), then the unit tests again under ASan + UBSan.
test: test-release test-asan

test-release: build
	ctest --test-dir $(BUILD) --output-on-failure -j $(JOBS)

test-asan: deps
	cmake -S . -B $(ASAN_BUILD) -DCMAKE_BUILD_TYPE=RelWithDebInfo -DISOKIT_SANITIZE=ON \
	  -DISOKIT_CUDA=OFF -DISOKIT_APPS=OFF -DISOKIT_BENCH=OFF -DISOKIT_PYTHON=OFF $(CMAKE_ARGS)
	cmake --build $(ASAN_BUILD) -j $(JOBS)
	ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1 \
	  ctest --test-dir $(ASAN_BUILD) --output-on-failure -j $(JOBS) -L unit

# Benchmarks: 5 repetitions each, JSON in $(BUILD)/bench-results, ratio tables on stdout.
bench: build
	@mkdir -p $(BUILD)/bench-results
	$(BUILD)/bench/bench_fields --benchmark_repetitions=5 \
	  --benchmark_out=$(BUILD)/bench-results/fields.json --benchmark_out_format=json
	$(BUILD)/bench/isokit-bench-report $(BUILD)/bench-results/fields.json --baseline BM_CapsuleEval
	$(BUILD)/bench/bench_operators --benchmark_repetitions=5 \
	  --benchmark_out=$(BUILD)/bench-results/operators.json --benchmark_out_format=json
	$(BUILD)/bench/isokit-bench-report $(BUILD)/bench-results/operators.json --baseline BM_Slice/0/0/0/128
	$(BUILD)/bench/bench_track --benchmark_repetitions=5 \
	  --benchmark_out=$(BUILD)/bench-results/track.json --benchmark_out_format=json
	$(BUILD)/bench/isokit-bench-report $(BUILD)/bench-results/track.json --baseline BM_TrackIterations/0/0/real_time
	$(BUILD)/bench/bench_implicit --benchmark_repetitions=5 \
	  --benchmark_out=$(BUILD)/bench-results/implicit.json --benchmark_out_format=json
	$(BUILD)/bench/isokit-bench-report $(BUILD)/bench-results/implicit.json --baseline BM_TreeEval/0/real_time
	$(BUILD)/bench/bench_skinning --benchmark_repetitions=3 \
	  --benchmark_out=$(BUILD)/bench-results/skinning.json --benchmark_out_format=json
	$(BUILD)/bench/isokit-bench-report $(BUILD)/bench-results/skinning.json \
	  --baseline BM_SkinFrame/1/13000/50/iterations:1/manual_time

# The design studio under Xvfb: a recorded drag in a 1280x800 window, 5 runs, with BM_EditSlice
# from the same session (re-solve ms, input-to-redraw latency in frames, fps; docs/performance.md).
bench-studio: build
	bench/studio/studio-bench.py $(BUILD) --runs 5

# The skinning viewer under Xvfb: a recorded elbow drag on CesiumMan with tracking2014, 3 runs
# (redraw rate and the lag of the skin shown behind the slider; docs/performance.md).
bench-view: build
	bench/viewer/view-bench.sh $(BUILD) 3

# libFuzzer targets (clang, ASan + UBSan; docs/fuzzing.md): builds them in $(FUZZ_BUILD), writes
# the seed corpora with the project's own writers, runs each target for $(FUZZ_SECONDS) s, one at a
# time; crashes, hangs and out-of-memory inputs go to $(FUZZ_BUILD)/findings/<target>/.
fuzz: deps
	@command -v clang++ >/dev/null || { echo "make fuzz needs clang (libFuzzer): apt-get install clang"; exit 1; }
	CC=clang CXX=clang++ cmake -S . -B $(FUZZ_BUILD) -DCMAKE_BUILD_TYPE=RelWithDebInfo -DISOKIT_FUZZ=ON \
	  -DISOKIT_APPS=ON -DISOKIT_CUDA=OFF -DISOKIT_BENCH=OFF -DISOKIT_TESTS=OFF -DISOKIT_WERROR=OFF \
	  -DISOKIT_PYTHON=OFF $(CMAKE_ARGS)
	cmake --build $(FUZZ_BUILD) -j $(JOBS) --target isokit_fuzz_all
	rm -rf $(FUZZ_BUILD)/seeds && $(FUZZ_BUILD)/fuzz/isokit_fuzz_seeds $(FUZZ_BUILD)/seeds
	ISOKIT_FUZZ_ISOLATE=$(FUZZ_ISOLATE) scripts/run-fuzz.sh $(FUZZ_BUILD) $(FUZZ_SECONDS) $(FUZZ_TARGETS)

# The Blender add-on as a zip for Edit > Preferences > Add-ons > Install (docs/blender.md).
blender-addon:
	@mkdir -p $(BUILD)
	cd apps/blender && python3 -m zipfile -c ../../$(BUILD)/isokit_blender.zip isokit_blender
	@echo "wrote $(BUILD)/isokit_blender.zip"

clean:
	rm -rf $(BUILD) $(ASAN_BUILD) $(FUZZ_BUILD) out demo-out
