#!/usr/bin/env bash
# Installs the Debian packages depthfem needs (only those missing), then configures and builds
# in Release. Runs as root without prompts; a non-root user needs sudo for the install step.
# Usage: ./setup.sh            install + build
#        ./setup.sh --test     install + build + run the whole test suite, then the sanitizer
#                              tests and a bounded fuzz pass (tests/fuzz/run.sh)
#        ./setup.sh --demo     install + build the command line + run the demo scene (a slab
#                              folded onto itself by self-contact: HDF5 results, PNG pictures)
set -euo pipefail
cd "$(dirname "$0")"

packages=(build-essential cmake pkg-config libeigen3-dev libtbb-dev libsundials-dev libhdf5-dev
          libgtest-dev libgmock-dev libbenchmark-dev nlohmann-json3-dev libcli11-dev
          libsuitesparse-dev libopenblas-dev petsc-dev clang-format clang libclang-rt-14-dev
          python3-h5py python3-numpy python3-matplotlib)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "setup: installing ${missing[*]}"
  sudo_cmd=()
  [[ $(id -u) -eq 0 ]] || sudo_cmd=(sudo)
  export DEBIAN_FRONTEND=noninteractive
  "${sudo_cmd[@]}" apt-get update -q
  "${sudo_cmd[@]}" apt-get install -y -q --no-install-recommends "${missing[@]}"
fi

jobs=$(nproc 2>/dev/null || echo 2)
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
if [[ ${1:-} == --demo ]]; then
  cmake --build build -j"$jobs" --target depthfem  # the demo needs the command line only
else
  cmake --build build -j"$jobs"
fi

case "${1:-}" in
  --test)
    ctest --test-dir build --output-on-failure -j"$jobs"
    tests/fuzz/run.sh 30
    ;;
  --demo) ./apps/demo.sh ;;
  "") ;;
  *) echo "setup: unknown option '$1' (expected --test or --demo)" >&2; exit 2 ;;
esac
