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
# The renderer and viewer tests draw through wgpu on both of its Linux
# backends, each on Mesa's software driver (llvmpipe): Vulkan
# (mesa-vulkan-drivers) and OpenGL through EGL (libegl1, libgl1-mesa-dri).
# Without them they fail, they do not skip.
need_apt mesa-vulkan-drivers libvulkan1 libegl1 libegl-mesa0 libgl1-mesa-dri
# Mesa's device-select Vulkan layer prints a harmless XDG_RUNTIME_DIR error
# in every test process without a desktop session (the binary quiets it).
export NODEVICE_SELECT=1

step "cargo fmt --check"
cargo fmt --all --check

step "tools/architecture.py --check (arrows one way between floors, no loop between files, no file over 1000 lines)"
python3 tools/architecture.py --check

step "cargo test --release (renderer on Vulkan)"
WGPU_BACKEND=vulkan cargo test --release

step "renderer and viewer tests again on OpenGL (WGPU_BACKEND=gl)"
WGPU_BACKEND=gl cargo test --release --test render --test viewer

step "cargo run --release on a GL-only machine (WGPU_BACKEND=gl): exit 0, preview drawn on GL"
gl_out="$(mktemp -d)"
repo="$PWD"
(cd "$gl_out" && WGPU_BACKEND=gl cargo run --release -q --manifest-path "$repo/Cargo.toml" >/dev/null)
test -s "$gl_out/out/preview.png"
grep -q '"preview_renderer": ".*(Gl)"' "$gl_out/out/report.json"
echo "preview.png drawn on GL"
# The default bake, kept for the runtime's tests from C, C++, C# and Python.
bake="$PWD/target/test-bake"
rm -rf "$bake"
mv "$gl_out/out" "$bake"
rm -rf "$gl_out"

step "the viewer's Carve tool in a real window under Xvfb (a pit carved from outside, steps timed)"
need_apt xvfb xauth
carve_log="$(xvfb-run -a -s "-screen 0 1280x800x24" target/release/organtex view scenes/myoma_cuts.toml \
    --screenshot target/carve-check.png --frames 20 --carve)"
echo "$carve_log"
echo "$carve_log" | grep -Eq '^carving: [1-9][0-9]* steps, [1-9][0-9]* tets removed'
test -s target/carve-check.png

step "tools/fuzz.sh --smoke (every parser's fuzz target and the carving session, 10,000 inputs each)"
command -v g++ >/dev/null 2>&1 || need_apt g++
tools/fuzz.sh --smoke

step "cargo clippy --release --all-targets -- -D warnings (organtex and its C API)"
cargo clippy --release --all-targets -- -D warnings
cargo clippy --release --all-targets -p organtex-capi -- -D warnings

step "C API: the committed header is cbindgen's; installed; C, C++ examples built by CMake against the installed package and run by ctest; again under AddressSanitizer; pkg-config; C# by P/Invoke"
need_apt cmake pkg-config mono-mcs mono-runtime
cargo test --release -p organtex-capi
capi_prefix="$PWD/target/capi-install"
rm -rf "$capi_prefix" target/capi-examples target/capi-examples-asan
capi/install.sh --prefix "$capi_prefix"
for variant in plain asan; do
    dir=target/capi-examples; sanitize=OFF
    [ "$variant" = asan ] && dir=target/capi-examples-asan && sanitize=ON
    cmake -S capi/examples -B "$dir" -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH="$capi_prefix" \
        -DORGANTEX_BAKE="$bake" -DORGANTEX_SANITIZE="$sanitize" >/dev/null
    cmake --build "$dir" -j 2 >/dev/null
    ASAN_OPTIONS=detect_leaks=1 ctest --test-dir "$dir" --output-on-failure
done
PKG_CONFIG_PATH="$capi_prefix/lib/pkgconfig" pkg-config --exists --print-errors "organtex >= 0.1"
# shellcheck disable=SC2046
cc -std=c99 -o target/capi-examples/carve_pkgconfig capi/examples/carve.c \
    $(PKG_CONFIG_PATH="$capi_prefix/lib/pkgconfig" pkg-config --cflags --libs organtex) -lm
LD_LIBRARY_PATH="$capi_prefix/lib" target/capi-examples/carve_pkgconfig "$bake" target/capi-examples/carved_pkgconfig.glb >/dev/null
mcs -out:target/capi-examples/Carve.exe capi/examples/Carve.cs
LD_LIBRARY_PATH="$capi_prefix/lib" mono target/capi-examples/Carve.exe "$bake"

step "tools/crosscheck.py (organtex info vs pymeshlab)"
python3 tools/crosscheck.py --organtex target/release/organtex

step "tools/compare_uv.py --quick (organtex unwrap vs xatlas and pymeshlab)"
python3 tools/compare_uv.py --quick --organtex target/release/organtex

step "tools/check_bakes.py (every scene baked and the C example's carved surface: Khronos glTF validator, trimesh)"
python3 tools/check_bakes.py --organtex target/release/organtex --glb target/capi-examples/carved.glb

step "tools/compare_frames.py --check (the default preview beside real in-vivo frames: highlights in small spots)"
python3 tools/compare_frames.py "$bake/preview.png" --check

step "tools/render_glb.py --check (Blender reads the default scene.glb's camera, scope light and clear coats, and shows highlights)"
python3 tools/render_glb.py "$bake/scene.glb" target/blender-preview.png --size 480x360 --samples 8 --check

step "tools/compare_morph.py --quick --uterus --check (morph vs nearest slice and cross-fading on a brain MRI; the bundled uterus scene's cuts)"
python3 tools/compare_morph.py --quick --uterus --check --organtex target/release/organtex

step "tools/compare_tet.py --quick (organtex tetra vs TetGen and fTetWild, files read by meshio)"
python3 tools/compare_tet.py --quick --organtex target/release/organtex

step "tools/check_stereology.py --large 4 8 12 20 --check (noisy 2048x2048 photographs: the particle class, size distribution TV <= 0.08, volume fraction within 10%)"
python3 tools/check_stereology.py --large 4 8 12 20 --kinds 2 --size 64 --check --organtex target/release/organtex

step "Python package (maturin develop into target/pyorgantex) and pytest: the API, batch bakes on a local two-node Ray cluster"
venv="$PWD/target/pyorgantex"
[ -x "$venv/bin/python" ] || python3 -m venv "$venv"
if [ ! -x "$venv/bin/maturin" ] || ! "$venv/bin/python" -c 'import pytest, numpy, PIL, ray, tqdm' 2>/dev/null; then
    "$venv/bin/pip" install -q maturin pytest numpy pillow ray tqdm
fi
(cd python && VIRTUAL_ENV="$venv" PATH="$venv/bin:$PATH" maturin develop --release -q)
PYO3_PYTHON="$venv/bin/python" cargo clippy --release -p organtex-python -- -D warnings
ORGANTEX_TEST_BAKE="$bake" "$venv/bin/python" -m pytest -q python/tests

step "all checks passed"
