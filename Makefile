# The two commands of the README:
#   make demo   installs dependencies, builds, renders the demo building
#   make test   installs dependencies, builds, runs every test
BUILD ?= build
JOBS ?= $(shell nproc)

.PHONY: deps build demo test clean

deps:
	bash deploy/install-deps.sh

build: deps
	cmake -S . -B $(BUILD) -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo
	cmake --build $(BUILD) -j $(JOBS)

demo: build
	$(BUILD)/bin/portico scene generate --preset demo out/demo-building
	$(BUILD)/bin/portico render out/demo-building -o out/demo.png
	@echo "demo image: out/demo.png (statistics: out/demo.png.json)"

test: build
	ctest --test-dir $(BUILD) --output-on-failure -j $(JOBS)

clean:
	rm -rf $(BUILD) out
