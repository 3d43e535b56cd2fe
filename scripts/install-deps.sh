#!/usr/bin/env bash
# Installs what pumasim needs from Debian 12's archive, and only what is missing.
# Idempotent: a second run finds everything and does nothing. Uses sudo when not root.
set -euo pipefail

PACKAGES=(
  build-essential cmake git            # toolchain (g++ 12, CMake 3.25)
  ninja-build                          # the presets' generator
  ccache                               # compiler cache (build/ccache): the extension check recompiles only its edit
  clang libclang-rt-14-dev llvm-14     # clang 14 with its sanitizer and libFuzzer runtimes (preset asan), llvm-symbolizer for reports
  libeigen3-dev                        # Eigen 3.4
  libsundials-dev                      # SUNDIALS 6.4.1: CVODES (CVODE with sensitivities), ARKODE
  libboost-dev                         # Boost 1.74 headers: Odeint
  libtomlplusplus-dev                  # toml++: robot and scene files
  liburdfdom-dev                       # urdfdom 3.0: URDF robot files
  libtinyxml-dev                       # TinyXML 2.6.2 (urdfdom's parser): a URDF's <transmission> elements
  nlohmann-json3-dev                   # nlohmann-json: the JSON the programs write
  libcli11-dev                         # CLI11: the pumasim command line
  libgtest-dev libbenchmark-dev        # GoogleTest, Google Benchmark
  python3 python3-matplotlib python3-sympy   # plots, tables, symbolic generation
  python3-pytest                       # tests of the Python scripts' module (tests/test_pumasim_io.py)
  strace                               # tests/test_input_files.py: every file a run opens is hashed
  parallel                             # GNU parallel: tests/check_ensemble_shards.sh runs an ensemble's shards under it
  clang-format                         # clang-format 14: the lines a change touches follow .clang-format (scripts/check_format.sh)
  pybind11-dev python3-pybind11 python3-dev  # the Python module `import pumasim` (python/)
  python3-numpy python3-scipy          # its arrays, and its tests against scipy's solve_ivp
  python3-hypothesis                   # its property-based test with hostile arguments (tests/test_python_hostile.py)
)

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
[ ${#missing[@]} -eq 0 ] && exit 0

echo "install-deps: installing ${missing[*]}" >&2
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
$SUDO apt-get update -qq
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
