#!/usr/bin/env bash
# The whole test suite, as CI runs it: format, lints, the Rust tests (release
# build: the geometry tests are heavy), and the cross-checks against other
# tools. Installs what it needs when it is missing.
set -euo pipefail
cd "$(dirname "$0")/.."

step() { printf '\n== %s\n' "$*"; }

need_apt() {
    # Install Debian packages that are missing (CI machines start bare).
    local missing=()
    for pkg in "$@"; do
        dpkg -s "$pkg" >/dev/null 2>&1 || missing+=("$pkg")
    done
    if [ ${#missing[@]} -gt 0 ]; then
        step "installing ${missing[*]}"
        local sudo=""
        [ "$(id -u)" -ne 0 ] && sudo="sudo"
        $sudo apt-get update -qq
        DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq "${missing[@]}"
    fi
}

rustup component list --installed 2>/dev/null | grep -q '^rustfmt' || rustup component add rustfmt
rustup component list --installed 2>/dev/null | grep -q '^clippy' || rustup component add clippy
python3 -c 'import venv, ensurepip' 2>/dev/null || need_apt python3-venv
command -v npm >/dev/null 2>&1 || need_apt nodejs npm
# The renderer and viewer tests draw on a software Vulkan driver (llvmpipe);
# without it they fail, they do not skip.
need_apt mesa-vulkan-drivers libvulkan1

step "cargo fmt --check"
cargo fmt --check

step "cargo test --release"
cargo test --release

step "cargo clippy --release --all-targets -- -D warnings"
cargo clippy --release --all-targets -- -D warnings

step "tools/crosscheck.py (organtex info vs pymeshlab)"
python3 tools/crosscheck.py --organtex target/release/organtex

step "tools/compare_uv.py --quick (organtex unwrap vs xatlas and pymeshlab)"
python3 tools/compare_uv.py --quick --organtex target/release/organtex

step "tools/check_bakes.py (every scene baked, Khronos glTF validator, trimesh)"
python3 tools/check_bakes.py --organtex target/release/organtex

step "all checks passed"
