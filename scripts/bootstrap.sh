#!/usr/bin/env bash
# Installs peelcd's build dependencies (Debian 12 packages; idempotent), then configures ./build
# (Release) and builds the command line (`peelcd`): what the README's first command needs.
# --all builds everything (the tests, the Python module, which it then installs for Debian's
# interpreter): the README's second command. Run as root, or with sudo available.
set -euo pipefail
cd "$(dirname "$0")/.."
all=0
for arg in "$@"; do
  case "$arg" in
    --all) all=1 ;;
    *) echo "bootstrap: unknown argument '$arg' (expected --all)" >&2; exit 2 ;;
  esac
done

packages=(
  build-essential cmake pkg-config python3-glad   # toolchain, glad 2 (GL loader generator)
  libosmesa6-dev                                  # OSMesa: the software GL reference backend
  libegl-dev libegl-mesa0 libgl1-mesa-dri         # EGL without a window (Mesa llvmpipe, or a GPU)
  mesa-vulkan-drivers                              # the third GL stack in the tests: zink over lavapipe
  libeigen3-dev libcgal-dev libgmp-dev libmpfr-dev libboost-dev   # geometry, exact predicates
  libassimp-dev nlohmann-json3-dev libcli11-dev    # mesh files, scene JSON, command line
  libopenexr-dev libpng-dev                        # layer dumps and goldens (EXR), previews (PNG)
  chromium                                         # the viewer test (headless)
  libfcl-dev                                       # benchmark peer: FCL 0.7
  libembree-dev libbullet-dev                      # benchmark peers: Embree 3 rtcCollide, Bullet 3 GImpact
  catch2                                           # tests (Catch2 v2)
  python3 python3-jsonschema                       # tests: dump meta.json against its JSON Schema
  python3-matplotlib                               # sweep --plot, scripts/plot_*.py
  python3-dev pybind11-dev python3-numpy python3-pytest   # the Python module (import peelcd) and its tests
  python3-pip python3-venv python3-setuptools python3-wheel  # pip install . (pyproject.toml) and its test
)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  sudo_cmd=""
  [ "$(id -u)" -ne 0 ] && sudo_cmd="sudo"
  echo "bootstrap: installing ${missing[*]}"
  $sudo_cmd apt-get update -q
  DEBIAN_FRONTEND=noninteractive $sudo_cmd apt-get install -y -q --no-install-recommends "${missing[@]}"
fi

cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
if [ "$all" = 0 ]; then
  cmake --build build -j "$(nproc)" --target peelcd
  exit 0
fi
cmake --build build -j "$(nproc)"
# The Python module into Debian's interpreter's path (/usr/local/lib/python3.X/dist-packages):
# /usr/bin/python3 -c "import peelcd" works from anywhere (docs/python.md).
if [ -f build/python/peelcd/__init__.py ]; then
  sudo_cmd=""
  [ "$(id -u)" -ne 0 ] && sudo_cmd="sudo"
  $sudo_cmd cmake --install build --component python --prefix /usr/local
fi
