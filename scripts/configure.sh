#!/usr/bin/env bash
# cmake --preset PRESET [ARGS...], after clearing a build folder's CMake cache
# that was written with another generator: the presets use Ninja (it starts a
# target's compiles before the libraries it links are done, which keeps both
# cores busy), and CMake refuses to change the generator of a configured
# folder. Only CMake's own CMakeCache.txt and CMakeFiles/ there are removed.
set -euo pipefail
cd "$(dirname "$0")/.."
preset=$1
shift
dir=build/$preset
cache=$dir/CMakeCache.txt
if [ -f "$cache" ] && ! grep -qx "CMAKE_GENERATOR:INTERNAL=Ninja" "$cache"; then
  echo "configure: $dir was configured with another generator; clearing its CMake cache for Ninja" >&2
  rm -rf "$cache" "$dir/CMakeFiles"
fi
exec cmake --preset "$preset" "$@"
