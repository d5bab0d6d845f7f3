#!/usr/bin/env bash
# Every test of myoslice, from a fresh machine: system packages (software Vulkan for the
# off-screen viewer capture, Xvfb for the window's smoke test), Rust format/lint/tests,
# then the Python package built as a wheel into a fresh virtual environment and its
# pytest suite (bindings, Gymnasium env, stubs, scenario runs and their ParaView/Blender
# outputs, sweeps on a local two-node Ray cluster, fits with Ray Tune), the viewer's web
# page in headless Chromium, and RLlib's PPO on the env in an environment of its own.
# Usage: scripts/test.sh
set -euo pipefail
cd "$(dirname "$0")/.."
root=$(pwd)
start=$(date +%s)

# A run from scratch gains nothing from incremental builds, which would add ~11 GB.
export CARGO_INCREMENTAL=0

step() { printf '\n==> %s (%ss)\n' "$*" "$(( $(date +%s) - start ))"; }

# --- system packages -------------------------------------------------------------------
need_pkgs=()
dpkg -s mesa-vulkan-drivers >/dev/null 2>&1 || need_pkgs+=(mesa-vulkan-drivers)
dpkg -s libvulkan1 >/dev/null 2>&1 || need_pkgs+=(libvulkan1)
# A virtual X display for the interactive window's smoke test.
dpkg -s xvfb >/dev/null 2>&1 || need_pkgs+=(xvfb)
dpkg -s xauth >/dev/null 2>&1 || need_pkgs+=(xauth)
# A real browser for the web page's tests (WebGL2 and WebGPU on SwiftShader).
dpkg -s chromium >/dev/null 2>&1 || need_pkgs+=(chromium)
if [ ${#need_pkgs[@]} -gt 0 ]; then
  step "installing ${need_pkgs[*]} (software Vulkan, virtual display, browser)"
  sudo_cmd=""
  [ "$(id -u)" = 0 ] || sudo_cmd="sudo"
  $sudo_cmd apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo_cmd apt-get install -y -qq "${need_pkgs[@]}"
fi

# --- Rust ------------------------------------------------------------------------------
step "cargo fmt --check"
cargo fmt --all -- --check
step "cargo clippy (warnings are errors)"
cargo clippy --workspace --all-targets -- -D warnings
step "cargo test (core, CLI, viewer incl. off-screen capture and the window on Xvfb, software adapter)"
# The Python crate is tested through its wheel below (its test binary would embed Python).
cargo test --workspace --exclude myoslice-py
step "release CLI (reference for the Python parity tests, scenario runs)"
cargo build --release -p myoslice-cli
step "the web page (scripts/web.sh: the viewer for wasm32, wasm-bindgen) and its lints"
scripts/web.sh target/web
cargo clippy --target wasm32-unknown-unknown -p myoslice-viewer --lib -- -D warnings

# --- Python ----------------------------------------------------------------------------
step "fresh virtual environment with the test requirements"
rm -rf .venv-test
python3 -m venv .venv-test
.venv-test/bin/python -m pip install -q --upgrade pip
.venv-test/bin/python -m pip install -q "maturin>=1.9.4,<2" -r python/requirements-test.txt
step "building and installing the wheel"
rm -rf target/wheels
.venv-test/bin/maturin build --release -m python/Cargo.toml -o target/wheels 2>&1 | tee target/maturin-build.log
# The wheel must link the core the CLI was built with (crates/workspace-hack): a second
# build of it means the dependency features diverged, and the Python parity figures with it.
if grep -q "Compiling myoslice v" target/maturin-build.log; then
    echo "the wheel compiled its own build of the core: align crates/workspace-hack (cargo tree -e features)" >&2
    exit 1
fi
.venv-test/bin/python -m pip install -q --force-reinstall --no-deps target/wheels/myoslice-*.whl
step "pytest"
# From the repository root, so that the installed wheel (not python/myoslice/) is imported.
.venv-test/bin/python -m pytest -q python/tests

step "the web page in headless Chromium (WebGL2 and WebGPU, against the native run)"
.venv-test/bin/python -m pytest -q tests/web

step "RLlib (its own environment: RLlib pins an older gymnasium)"
rm -rf .venv-rllib
python3 -m venv .venv-rllib
.venv-rllib/bin/python -m pip install -q --upgrade pip
.venv-rllib/bin/python -m pip install -q -r python/requirements-rllib.txt
.venv-rllib/bin/python -m pip install -q --no-deps target/wheels/myoslice-*.whl
MYOSLICE_REQUIRE_RLLIB=1 .venv-rllib/bin/python -m pytest -q python/tests/test_rllib.py
rm -rf .venv-rllib

step "all tests passed"
