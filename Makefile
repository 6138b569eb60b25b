# geocull: `make demo` renders the demo scene to demo.png; `make test` runs every test.
# Both do all set-up on a fresh Debian machine (Rust toolchain and Python 3.11 present):
# the Vulkan software driver (lavapipe) when no Vulkan driver is installed, the GL one (EGL +
# llvmpipe) when missing, a .venv with the Python dependencies, and a release build of the
# extension. Re-running is fast.

PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
SUDO   := $(shell [ "$$(id -u)" = 0 ] || echo sudo)
export VTK_DEFAULT_OPENGL_WINDOW ?= vtkEGLRenderWindow

.PHONY: setup vulkan gl build demo test test-rust test-python test-gl browser test-browser lint bench bench-quick bench-scale bench-distributed wheel device-bundle examples-quick notebooks clean

setup: vulkan gl build

# Mesa's lavapipe renders Vulkan on the CPU; install it only when no Vulkan driver is present.
vulkan:
	@if ls /usr/share/vulkan/icd.d/*.json /etc/vulkan/icd.d/*.json 2>/dev/null | grep -q . && ldconfig -p | grep -q libvulkan.so.1; then \
	  echo "vulkan: driver present"; \
	else \
	  echo "vulkan: installing libvulkan1 mesa-vulkan-drivers"; \
	  $(SUDO) apt-get update -qq && DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y -qq libvulkan1 mesa-vulkan-drivers >/dev/null; \
	fi

# Mesa's EGL + llvmpipe render GL on the CPU: machines without Vulkan have only GL, and `make
# test-gl` renders on it. Installed only when missing.
gl:
	@if ldconfig -p | grep -q libEGL.so.1 && ldconfig -p | grep -q libEGL_mesa.so.0 && ls /usr/lib/*/dri/swrast_dri.so >/dev/null 2>&1; then \
	  echo "gl: EGL + llvmpipe present"; \
	else \
	  echo "gl: installing libegl1 libegl-mesa0 libgl1-mesa-dri"; \
	  $(SUDO) apt-get update -qq && DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y -qq libegl1 libegl-mesa0 libgl1-mesa-dri >/dev/null; \
	fi

$(VENV)/.deps: requirements-dev.txt
	@test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip
	$(PY) -m pip install -q -r requirements-dev.txt
	@touch $@

# Release build of the Rust extension, installed into the venv in editable mode.
# The extension is an abi3 module (one build for CPython >= 3.11); a version-specific build left by an
# older checkout would shadow it on import, so it is removed first.
build: $(VENV)/.deps
	rm -f python/geocull/_geocull.cpython-*.so
	$(VENV)/bin/maturin develop --release -q 2>&1 | grep -v "^📦\|^🔗\|^🐍\|^✏️\|Installed\|Built wheel" || true
	@$(PY) -c "import geocull._geocull" || (echo "build failed" && exit 1)

demo: setup
	$(PY) -m geocull demo --out demo.png

test-rust: vulkan
	cargo test --release

test-python: setup
	$(PY) -m pytest -q

# The render tests again on GL (EGL + llvmpipe), chosen for every renderer through the variable
# that backend="auto" honours: every backend the Renderer accepts must render the same image.
test-gl: setup
	GEOCULL_BACKEND=gl $(PY) -m pytest -q tests/test_render.py tests/test_three_pass.py tests/test_hard_cases.py \
	  tests/test_iso.py tests/test_cull_frustum.py tests/test_horizon.py tests/test_interrupt.py tests/test_color.py tests/test_slices.py tests/test_grid.py \
	  tests/test_lod.py tests/test_cull_temporal.py tests/test_pass_triangles.py tests/test_slab_culling.py tests/test_wells.py tests/test_grid_cells.py tests/test_priority.py \
	  tests/test_implicit.py

test: setup test-rust test-python test-gl

# The notebook viewer in a real browser: JupyterLab on 127.0.0.1 (no token, a free port, its own
# temporary folders) serves a notebook with a Viewer, which headless Chromium drives through selenium
# (tests/test_browser.py: drags, wheel, every culling mode, the slider, an error in a callback).
# Debian's chromium and chromium-driver are installed when missing, JupyterLab and selenium into the
# venv (requirements-dev.txt) when missing. The run is bounded: jupyter and chromium are always ended.
browser: $(VENV)/.deps
	@if command -v chromium >/dev/null 2>&1 && command -v chromedriver >/dev/null 2>&1; then \
	  echo "browser: chromium and chromedriver present"; \
	else \
	  echo "browser: installing chromium chromium-driver"; \
	  $(SUDO) apt-get update -qq && DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y -qq chromium chromium-driver >/dev/null; \
	fi
	@$(PY) -c "import jupyterlab, selenium" 2>/dev/null || $(PY) -m pip install -q "jupyterlab>=4.0" "selenium>=4.10"

test-browser: setup browser
	GEOCULL_BROWSER_TEST=1 timeout -k 10 240 $(PY) -m pytest -q -p no:cacheprovider tests/test_browser.py

# The gates (CI runs them after the tests): formatting, lints, the public API docs without a broken
# or private link, the type stub against the built extension, and the dependency rule of the code
# (docs/DESIGN.md).
lint: setup
	cargo fmt --check
	cargo clippy --release --all-targets -- -D warnings
	cargo clippy --release --all-targets --features python -- -D warnings
	RUSTDOCFLAGS="-D warnings" cargo doc --release --no-deps --lib
	$(VENV)/bin/ruff check python tests examples scripts
	PYTHONPATH=python $(PY) -m mypy python/geocull
	PYTHONPATH=python $(PY) -m mypy --strict examples
	PYTHONPATH=python $(PY) -m mypy.stubtest geocull._geocull
	$(PY) scripts/check_layers.py

bench: setup
	$(PY) -m geocull bench

bench-quick: setup
	$(PY) -m geocull bench --quick --json out/bench_quick.json
	$(PY) -m geocull bench --scene field --quick --json out/bench_field_quick.json
	$(PY) -m geocull bench --scene big-volume --quick --json out/bench_big_volume_quick.json

# Issue 41's scale benchmark: the Gullfaks-like scene at 3.9 M, 15 M and 61 M triangles, each size in its own
# process (~15 min and ~3 GB on lavapipe); `python -m geocull bench --scene scale --quick` is the seconds-long variant.
bench-scale: setup
	$(PY) -m geocull bench --scene scale --json out/bench_scale.json

# The abi3 wheel (one for every CPython >= 3.11) in dist/, and the bundle that scripts/device_bench.sh runs
# from on a GPU machine without internet (docs/DESIGN.md, "Running on a GPU machine"): out/device_bundle.
wheel: $(VENV)/.deps
	$(VENV)/bin/maturin build --release -o dist

device-bundle: wheel
	scripts/make_device_bundle.sh

# Frames/s of geocull.distributed.render_views on LocalClusters of 1 and 2 worker processes.
bench-distributed: setup
	$(PY) -m geocull bench-distributed --workers 1,2

# Every example in its quick mode (CI runs them so they cannot rot); outputs under out/examples.
examples-quick: setup
	$(PY) examples/seeds_study.py --quick --out out/examples/seeds
	$(PY) examples/iso_table.py --quick --out out/examples/iso_table
	$(PY) examples/horizon_dem.py --width 320 --height 240 --spots 1 --repeat 1 --out out/examples/horizon
	$(PY) examples/geodata_scene.py --quick --out out/examples/geodata
	$(PY) examples/grid_levels.py --quick --out out/examples/grid

# Every example notebook executed in a fresh kernel (nbclient), as CI does; outputs are never
# committed: the executed copies go to out/notebooks.
notebooks: setup
	$(PY) scripts/run_notebooks.py --out out/notebooks

clean:
	rm -rf $(VENV) target demo.png out
