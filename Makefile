# SARAS MULTIROBOTS-SURGERY platform — entry points.
#   make demo   install what is missing, build, run the platform headless, write OUT/
#   make test   install what is missing, build, run every test suite
#   make bench  every package benchmark; make bench-platform: the platform at 1 kHz/720p, CPU per process
#   make faults build, run the platform and inject faults one by one, judge them (OUT/faults.md)
#   make faults CLUSTER=1  (root) the faults that need the namespace cluster (console link cut, a machine gone)
#   make cluster           (root) the platform on six machines as network namespaces, report per machine
#   make cluster-impaired  (root) the teleoperation across impaired links: delay/loss x tanks on/bypassed
# Everything runs with Debian's /usr/bin/python3 and ROS Noetic (see scripts/env.sh).
SHELL := /bin/bash
DURATION ?= 30
OUT ?= $(CURDIR)/out/demo
ARGS ?=
CONTROL_RATE ?=
ENDOSCOPE_SIZE ?=
CLUSTER_OUT ?= $(CURDIR)/out/cluster
IMPAIRED_OUT ?= $(CURDIR)/out/cluster_impaired
IMPAIRED_DURATION ?= 40
CASES ?=

.PHONY: all setup build test demo bench bench-platform faults lint run clean cluster cluster-impaired

all: build

setup:
	@bash scripts/setup.sh

build: setup
	@bash scripts/build.sh

test: build
	@bash scripts/run_tests.sh

demo: build
	@CONTROL_RATE="$(CONTROL_RATE)" ENDOSCOPE_SIZE="$(ENDOSCOPE_SIZE)" bash scripts/demo.sh "$(DURATION)" "$(OUT)" $(ARGS)

cluster: build
	@CONTROL_RATE="$(CONTROL_RATE)" ENDOSCOPE_SIZE="$(ENDOSCOPE_SIZE)" bash scripts/cluster.sh "$(DURATION)" "$(CLUSTER_OUT)" $(ARGS); \
	 rc=$$?; if [ $$rc = 77 ]; then echo "make cluster: skipped (needs root)"; fi; exit $$rc

cluster-impaired: build
	@CONTROL_RATE="$(CONTROL_RATE)" ENDOSCOPE_SIZE="$(ENDOSCOPE_SIZE)" bash scripts/cluster_impaired.sh "$(IMPAIRED_DURATION)" "$(IMPAIRED_OUT)" $(CASES)

run: build
	@bash -c 'source scripts/env.sh && roslaunch launch/platform.launch $(ARGS)'

bench: build
	@bash scripts/bench.sh

bench-platform: build
	@bash scripts/bench_platform.sh "$(if $(filter command line,$(origin DURATION)),$(DURATION),60)" "$(if $(filter command line,$(origin OUT)),$(OUT),$(CURDIR)/out/bench_platform)"

faults: build
	@bash scripts/faults/$(if $(CLUSTER),cluster,run).sh \
	  "$(if $(filter command line,$(origin OUT)),$(OUT),$(CURDIR)/out/faults$(if $(CLUSTER),_cluster))"

lint: setup
	@bash -c 'source scripts/env.sh && catkin_lint -W2 --strict src'

clean:
	rm -rf build devel install out
