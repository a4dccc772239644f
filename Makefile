# The two commands of the README:
#   make demo   installs dependencies, builds the programs it runs, renders the demo building
#   make test   installs dependencies, builds everything (tests too), runs every test
BUILD ?= build
JOBS ?= $(shell nproc)
# What the demo runs: the portico command and the services `portico render`
# starts (coordinator/cli/local_services.cpp); the image module they load
# comes with them. Not the tests: building those is most of a full build.
PROGRAMS = portico portico-coordinator portico-worker

.PHONY: deps configure programs build demo test clean

deps:
	bash deploy/install-deps.sh

configure: deps
	cmake -S . -B $(BUILD) -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo

programs: configure
	cmake --build $(BUILD) -j $(JOBS) --target $(PROGRAMS)

build: configure
	cmake --build $(BUILD) -j $(JOBS)

demo: programs
	$(BUILD)/bin/portico scene generate --preset demo out/demo-building
	$(BUILD)/bin/portico render out/demo-building -o out/demo.png
	@echo "demo image: out/demo.png (statistics: out/demo.png.json)"

test: build
	ctest --test-dir $(BUILD) --output-on-failure -j $(JOBS)

clean:
	rm -rf $(BUILD) out
