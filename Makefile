# lanemap: the two commands of the README, and what they are made of.
#   make demo   installs missing Debian packages, builds, simulates a drive and maps it
#   make test   installs missing Debian packages, builds, runs every test
#   make fuzz   builds the fuzz harnesses (clang, ASan + UBSan) and runs each FUZZ_SECONDS (60)
#   make replay-update  rewrites the process replay references (tests/replay) and shows the diff
BUILD_DIR ?= build
JOBS ?= $(shell nproc)
DEMO_OUT ?= demo-out

.PHONY: all deps configure build test demo bench fuzz replay-update clean

all: build

deps:
	@scripts/install-deps.sh

configure: deps
	@cmake -S . -B $(BUILD_DIR) -DCMAKE_BUILD_TYPE=Release > $(BUILD_DIR).configure.log 2>&1 || (cat $(BUILD_DIR).configure.log; exit 1)

build: configure
	@cmake --build $(BUILD_DIR) -j$(JOBS)

test: build
	@cd $(BUILD_DIR) && ctest --output-on-failure -j$(JOBS) --timeout 900

demo: build
	@scripts/demo.sh $(BUILD_DIR) $(DEMO_OUT)

bench: build
	@tools/bench/run_all.sh $(BUILD_DIR)

# After an intended change of a process's output: new references, then review them in the diff.
replay-update: build
	@$(BUILD_DIR)/bin/lanemap-replay --update
	@git --no-pager diff --stat -- tests/replay

FUZZ_SECONDS ?= 60
fuzz: deps
	@FUZZ_SECONDS=$(FUZZ_SECONDS) fuzz/run.sh $(FUZZ_HARNESSES)

clean:
	rm -rf $(BUILD_DIR) $(BUILD_DIR).configure.log $(DEMO_OUT) build-fuzz build-fuzz.configure.log
