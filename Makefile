# SARAS MULTIROBOTS-SURGERY platform — entry points.
#   make demo   install what is missing, build, run the platform headless, write OUT/
#   make test   install what is missing, build, run every test suite
#   make faults build, run the platform and inject faults one by one, judge them (OUT/faults.md)
# Everything runs with Debian's /usr/bin/python3 and ROS Noetic (see scripts/env.sh).
SHELL := /bin/bash
DURATION ?= 30
OUT ?= $(CURDIR)/out/demo
ARGS ?=
CONTROL_RATE ?=
ENDOSCOPE_SIZE ?=

.PHONY: all setup build test demo bench faults lint run clean

all: build

setup:
	@bash scripts/setup.sh

build: setup
	@bash scripts/build.sh

test: build
	@bash scripts/run_tests.sh

demo: build
	@CONTROL_RATE="$(CONTROL_RATE)" ENDOSCOPE_SIZE="$(ENDOSCOPE_SIZE)" bash scripts/demo.sh "$(DURATION)" "$(OUT)" $(ARGS)

run: build
	@bash -c 'source scripts/env.sh && roslaunch launch/platform.launch $(ARGS)'

bench: build
	@bash scripts/bench.sh

faults: build
	@bash scripts/faults/run.sh "$(if $(filter command line,$(origin OUT)),$(OUT),$(CURDIR)/out/faults)"

lint: setup
	@bash -c 'source scripts/env.sh && catkin_lint -W2 --strict src'

clean:
	rm -rf build devel install out
