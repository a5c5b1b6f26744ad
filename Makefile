# meshletlab: two-command quick start is `make demo` and `make test`.
CARGO ?= cargo

.PHONY: setup demo test lint bench build bench-robustness python-test

# A CI build starts clean: incremental caches there only cost time to write.
ifdef CI
export CARGO_INCREMENTAL := 0
endif

# pyo3 builds for the virtual environment's interpreter in every step (a different value would
# rebuild it), as an extension module (not linked to libpython, which Debian ships only in -dev).
VENV := .venv
export PYO3_PYTHON := $(CURDIR)/$(VENV)/bin/python
export PYO3_BUILD_EXTENSION_MODULE := 1

# Idempotent: installs only what is missing (Debian 12, as root); silent when all is present.
# Set SKIP_SETUP=1 on systems you provision by hand (see README, "Other systems").
setup:
	@if [ -z "$(SKIP_SETUP)" ]; then bash scripts/setup.sh; fi

build: setup
	$(CARGO) build --release

# The whole pipeline on generated meshes (no input files needed): strategies, GPU parity, a render.
demo: setup
	$(CARGO) run --release --quiet -- demo

lint:
	$(CARGO) fmt --check
	$(CARGO) clippy --all-targets --quiet -- -D warnings
	$(CARGO) clippy --lib --no-default-features --quiet -- -D warnings
	RUSTDOCFLAGS="-D warnings" $(CARGO) doc --no-deps --lib --quiet
	RUSTDOCFLAGS="-D warnings" $(CARGO) doc --no-deps --lib --quiet --no-default-features

# Unit, integration, property and doc tests; the heavy ones run in the optimised test profile.
# The core alone too: what an engine gets with `default-features = false` builds and passes, and
# the examples run. Every step that shares a build takes the whole workspace, so cargo resolves
# the dependencies' features once with the Python module (pyo3 adds features to shared crates:
# resolved apart, nearly every crate would build twice), and the module's library is built here
# with the tests; the examples are built the same way and run from their binaries (`cargo run`
# resolves the root alone; the test step builds them as test harnesses). `required-features` says what each example needs.
test: setup lint $(VENV)/.deps
	$(CARGO) test --workspace --all-targets --features meshletlab-python/gpu
	$(CARGO) test --workspace --doc --features meshletlab-python/gpu
	$(CARGO) test --lib --no-default-features
	$(CARGO) build --workspace --examples --profile test --quiet --features meshletlab-python/gpu
	for e in build_meshlets lod_cut laced_wires gpu_kmedoids gpu_draw; do \
	  target/debug/examples/$$e || exit 1; done
	$(MAKE) python-test

# The Python module (python/) in a virtual environment (Debian's Python refuses system-wide pip):
# built by cargo in the test profile and target directory the steps above filled, so only pyo3,
# numpy and the module itself compile anew; maturin cannot, as its `cargo rustc --profile test`
# builds a test harness. The library is put beside the package and imported from python/; the
# command-line round trips run target/debug/meshletlab. The example runs headless.
PYTHON ?= python3
PYTHON_DEPS := numpy pytest matplotlib

# Re-checked when this file changes (PYTHON_DEPS may have).
$(VENV)/.deps: Makefile
	@test -x $(VENV)/bin/python || $(PYTHON) -m venv $(VENV)
	$(VENV)/bin/pip install -q $(PYTHON_DEPS)
	@touch $@

python-test: $(VENV)/.deps
	CARGO_TARGET_DIR=$(CURDIR)/target \
	  $(CARGO) build --profile test --quiet --workspace --all-targets --features meshletlab-python/gpu
	cp target/debug/lib_meshletlab.so \
	  python/meshletlab/_meshletlab$$($(VENV)/bin/python -c 'import sysconfig; print(sysconfig.get_config_var("EXT_SUFFIX"))')
	PYTHONPATH=python $(VENV)/bin/python -m pytest -q python/tests
	d=$$(mktemp -d) && PYTHONPATH=python MPLBACKEND=Agg $(VENV)/bin/python python/examples/compare.py gen:noisy-sphere --out $$d \
	  && test -s $$d/compare.png && rm -r $$d

# Regenerates every table and plot in results/ from the shared real meshes.
bench: setup
	$(CARGO) run --release --quiet -- bench build
	$(CARGO) run --release --quiet -- bench fidelity
	$(CARGO) run --release --quiet -- bench kmedoids
	$(CARGO) run --release --quiet -- bench gpu
	$(CARGO) run --release --quiet -- bench stability
	$(CARGO) run --release --quiet -- bench render
	$(CARGO) run --release --quiet -- bench lod
	$(CARGO) run --release --quiet -- bench compress
	$(CARGO) run --release --quiet -- bench compress-render
	$(MAKE) bench-robustness

# The fuzzer runs in the `fuzz` profile (optimised, overflow checks on): >= 1 M cases, results/robustness.md.
bench-robustness: setup
	$(CARGO) run --profile fuzz --quiet -- bench robustness
