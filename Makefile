# The two commands a new user needs are `make demo` and `make test`; both install what is
# missing first (deploy/setup.sh is idempotent and quick when everything is there).
VENV   := .venv
PY     := $(VENV)/bin/python
BUILD  := build
JOBS   ?= 2
# pytest's worker processes (pytest-xdist). The multi-process tests spend much of their
# time waiting (processes starting, timeouts that must pass, lockstep round trips), so two
# workers on two cores halve `make test` (docs/testing.md); 0 runs in one process.
PYTEST_WORKERS ?= 2
PYTEST_PAR := -n $(PYTEST_WORKERS) --dist worksteal

.PHONY: setup build test test-cpp test-py test-dds faults fuzz fuzz-asan demo bench clean

setup:
	@deploy/setup.sh

build: setup
	@if [ ! -f $(BUILD)/build.ninja ]; then \
	  cmake -S . -B $(BUILD) -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
	        -DPython3_EXECUTABLE=$(abspath $(PY)) ; fi
	@cmake --build $(BUILD) -j $(JOBS)
	@# The generated Python bindings live in the build tree; put them on the venv's path.
	@$(PY) -c "import site,sys; open(site.getsitepackages()[0] + '/skillbus_msgs.pth','w').write(sys.argv[1] + '\n')" $(abspath $(BUILD))/gen/python

# pytest: the examples in the package's docstrings (--doctest-modules over py_skills/skillbus),
# then the tests. A test that cannot run fails; SKILLBUS_ALLOW_SKIP=1 lets it be skipped
# (docs/testing.md).
test: build
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS)
	$(PY) -m pytest -q -rs --doctest-modules py_skills/skillbus
	$(PY) -m pytest -q -rs $(PYTEST_PAR) --durations=30 tests

test-cpp: build
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS)

test-py: build
	$(PY) -m pytest -q -rs --doctest-modules py_skills/skillbus
	$(PY) -m pytest -q -rs $(PYTEST_PAR) tests

# Every multi-process test on Cyclone DDS instead of LCM (the `sandbox` fixture's
# transport; `make test` runs the transport tests on both). Tests about LCM itself (its
# wire, lcm-spy, lcm-logger) are skipped, saying so. About 10 minutes.
test-dds: build
	SKILLBUS_TEST_TRANSPORT=dds $(PY) -m pytest -q -rs $(PYTEST_PAR) tests/integration

# The long fault runs: the world model's journal under simulated power loss at 1,000
# random points of a write sequence (`make test` runs 50; docs/world_model.md), then
# kill -9 of every process of the pick-and-place system at a random moment of ClearTable,
# under lockstep and on the wall clock, 10 times each (`make test` runs each process
# once; docs/faults.md). About two hours.
faults: build
	SKILLBUS_FAULT_POINTS=$${SKILLBUS_FAULT_POINTS:-1000} $(PY) -m pytest -q -rs -s tests/integration/test_journal_faults.py -k power_loss
	SKILLBUS_FAULT_TRIALS=$${SKILLBUS_FAULT_TRIALS:-10} $(PY) -m pytest -q -rs -s tests/integration/test_fault_suite.py

# Every process of the system flooded with 1,000,000 messages on every channel it hears
# (random, truncated, bit flips, absurd values, valid; unsigned, forged, stale, replayed):
# alive, answering, a normal end (`make test` sends 20,000 each; docs/security.md).
fuzz: build
	SKILLBUS_FUZZ_MESSAGES=$${SKILLBUS_FUZZ_MESSAGES:-1000000} $(PY) -m pytest -q -rs -s tests/integration/test_fuzz.py

# The fuzz run of the world model and the skill manager built with AddressSanitizer (in
# build-asan/): memory errors that a release build survives by luck. It found two in the
# skill manager (docs/security.md). (Not the programs that link DART: its library and an
# ASan build of Eigen's headers disagree on how aligned memory is freed.)
ASAN_BUILD := build-asan
fuzz-asan: build
	@if [ ! -f $(ASAN_BUILD)/build.ninja ]; then \
	  cmake -S . -B $(ASAN_BUILD) -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
	        -DPython3_EXECUTABLE=$(abspath $(PY)) -DCMAKE_CXX_FLAGS="-fsanitize=address -fno-omit-frame-pointer" \
	        -DCMAKE_EXE_LINKER_FLAGS=-fsanitize=address ; fi
	@cmake --build $(ASAN_BUILD) -j $(JOBS) --target wm_server skill_mgr
	SKILLBUS_BUILD_DIR=$(abspath $(ASAN_BUILD)) ASAN_OPTIONS=detect_leaks=0 \
	  SKILLBUS_FUZZ_MESSAGES=$${SKILLBUS_FUZZ_MESSAGES:-1000000} \
	  $(PY) -m pytest -q -rs -s tests/integration/test_fuzz.py -k "test_wm_server or test_skill_mgr"

demo: build
	$(VENV)/bin/skillbus demo $(if $(BUS),--bus $(BUS)) $(if $(ROBOTS),--robots $(ROBOTS),$(if $(filter 0,$(PERCEPTION)),,--perception) $(if $(filter none,$(SEED)),,--seed $(or $(SEED),1)))

bench: build
	$(PY) bench/lockstep_overhead.py
	$(PY) bench/wm_query.py
	$(PY) bench/wm_resolve.py
	$(PY) bench/wm_scale.py
	$(PY) bench/sparql.py
	$(PY) bench/skill_ticks.py
	$(PY) bench/frame_codecs.py
	$(PY) bench/sim_physics.py
	$(PY) bench/can_latency.py
	$(PY) bench/pick_and_place.py
	$(PY) bench/demo_obstacle.py
	$(PY) bench/planning_bench.py
	$(PY) bench/dds_transport.py
	$(PY) bench/console_overhead.py
	$(PY) bench/generate_scaling.py
	$(BUILD)/bench/perception_bench
	$(BUILD)/bench/motion_bench

clean:
	rm -rf $(BUILD)
