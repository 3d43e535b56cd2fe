#!/usr/bin/env bash
# The CTest Package.InstallAndConsume (tests/CMakeLists.txt): installs the
# build tree into a prefix inside it, builds examples/consumer against that
# prefix (find_package(pumasim)), runs it, and compares the end of its scene
# run with `pumasim run` on the same installed scene. Writes only under
# BUILD_DIR/package_test/ (replaced at every run).
#
#   scripts/test_package.sh SOURCE_DIR BUILD_DIR PUMASIM_BINARY CXX_COMPILER NATIVE_FLAG
set -euo pipefail
[[ $# -eq 5 ]] || { echo "usage: $0 SOURCE_DIR BUILD_DIR PUMASIM_BINARY CXX_COMPILER NATIVE_FLAG" >&2; exit 2; }
src=$1 build=$2 pumasim=$3 cxx=$4 native=$5
work=$build/package_test
prefix=$work/prefix
fail() { echo "test_package: $*" >&2; exit 1; }

rm -rf "$work"
mkdir -p "$work"

# 1. Install, as docs/user-guide/cpp.md says (cmake --install <build> --prefix <dir>).
cmake --install "$build" --prefix "$prefix" >"$work/install.log"
for f in lib/cmake/pumasim/pumasim-config.cmake lib/cmake/pumasim/pumasim-config-version.cmake \
         lib/cmake/pumasim/pumasim-targets.cmake include/pumasim/models/plant/plant.hpp \
         include/pumasim/simulation/scene_run.hpp share/pumasim/robots/puma560.toml \
         share/pumasim/scenes/paper_slow_6dof_hybrid.toml; do
  [[ -f $prefix/$f ]] || fail "not installed: $f"
done
# Every project include in an installed header resolves inside the installed tree.
while IFS= read -r inc; do
  [[ -f $prefix/include/pumasim/$inc ]] || fail "an installed header includes $inc, which is not installed"
done < <(grep -rhoE '^\s*#\s*include\s+"(models|integrators|experiments)/[^"]+"' "$prefix/include/pumasim" |
         sed -E 's/.*"(.*)"/\1/' | sort -u)

# 2. Configure and build the consumer against the prefix only (no build type:
# one file, compiled quickly; the simulation runs in the installed libraries).
cmake -S "$src/examples/consumer" -B "$work/consumer" -DCMAKE_PREFIX_PATH="$prefix" \
      -DCMAKE_CXX_COMPILER="$cxx" -DCMAKE_EXPORT_COMPILE_COMMANDS=ON >"$work/configure.log" ||
  { cat "$work/configure.log" >&2; fail "the consumer does not configure"; }
cmake --build "$work/consumer" >"$work/build.log" 2>&1 || { cat "$work/build.log" >&2; fail "the consumer does not build"; }
# The ABI flag reached the consumer's compile line (pumasim_NATIVE).
if [[ -n $native ]]; then
  grep -q -- "$native" "$work/consumer/compile_commands.json" ||
    fail "the consumer is not compiled with $native, which the libraries were built with"
fi

# 3. Run it, with nothing from the environment pointing at the source tree.
env -u PUMASIM_ROBOTS_DIR "$work/consumer/consumer" >"$work/consumer.out" ||
  { cat "$work/consumer.out" >&2; fail "the consumer failed"; }
cat "$work/consumer.out"
grep -qF "robot from $prefix/share/pumasim/robots/puma560.toml" "$work/consumer.out" ||
  fail "the consumer's scene did not load the installed robot file"

# 4. The same scene and span through the command line: the same last row.
PUMASIM_ROBOTS_DIR=$prefix/share/pumasim/robots "$pumasim" run "$prefix/share/pumasim/scenes/paper_slow_6dof_hybrid.toml" \
  --t-end 0.5 --out "$work/run" >/dev/null 2>"$work/run.log" || { cat "$work/run.log" >&2; fail "pumasim run failed"; }
expected=$(tail -n 1 "$work/run/trajectory.csv")
got=$(sed -n 's/^final row //p' "$work/consumer.out")
[[ "$got" == "$expected" ]] || fail "the consumer's last row differs from pumasim run's:
  consumer: $got
  pumasim:  $expected"
echo "test_package: installed into $prefix, consumer built and run; its last row equals pumasim run's"
