#!/usr/bin/env bash
# CTest Install.AnOutsideProjectBuildsAgainstTheInstalledTree: installs the build into a fresh
# prefix, checks the layout, builds this folder's project against it with find_package(rovermap)
# and main.cpp again through pkg-config, and runs both (each must recover a known motion); with
# the Python module, imports it from the installed tree and registers two curves.
#
#   check.sh BUILD_DIR WORK_DIR CXX [EXTRA_FLAGS]
# EXTRA_FLAGS go to every compile and link (the sanitizers, when the libraries have them).
set -euo pipefail

build=$1
work=$2
cxx=$3
extra=${4:-}
here=$(cd "$(dirname "$0")" && pwd)

fail() {
  echo "FAIL: $*" >&2
  exit 1
}
step() { echo "== $*"; }

rm -rf "$work"
mkdir -p "$work"
work=$(cd "$work" && pwd)  # absolute: CMake would read a relative prefix from elsewhere
prefix=$work/prefix

step "cmake --install $build --prefix $prefix"
cmake --install "$build" --prefix "$prefix" >"$work/install.log" ||
  { cat "$work/install.log"; fail "cmake --install"; }

step "installed layout"
modules=(config campaign mosaic service mapper sim eval stereo io dem registration)
for m in "${modules[@]}"; do
  [[ -f $prefix/lib/librovermap_$m.a ]] || fail "no lib/librovermap_$m.a"
  compgen -G "$prefix/include/rovermap/$m/*.hpp" >/dev/null || fail "no include/rovermap/$m/*.hpp"
done
for f in bin/rovermap libexec/rovermap/rovermap-full include/rovermap/registration/Icp.hpp lib/pkgconfig/rovermap.pc \
  lib/cmake/rovermap/rovermapConfig.cmake lib/cmake/rovermap/rovermapConfigVersion.cmake \
  lib/cmake/rovermap/rovermapTargets.cmake share/rovermap/default.yaml \
  share/rovermap/presets/fast.yaml; do
  [[ -e $prefix/$f ]] || fail "no $f"
done
[[ ! -e $prefix/include/rovermap/io/detail ]] || fail "io/detail (private) was installed"
# --help runs in rovermap-full (found in libexec/), a plain register in the launcher itself.
"$prefix/bin/rovermap" --help >/dev/null || fail "the installed rovermap --help"
bunny=$(cd "$here/../../datasets/stanford_bunny" && pwd)
"$prefix/bin/rovermap" register "$bunny/bun045.ply" "$bunny/bun000.ply" >/dev/null ||
  fail "the installed rovermap register"

# The export must name neither the build-only warnings target nor the source or build tree.
source_dir=$(cd "$here/../.." && pwd)
build_dir=$(cd "$build" && pwd)
for pattern in rovermap_warnings "$source_dir" "$build_dir"; do
  if grep -l -F "$pattern" "$prefix"/lib/cmake/rovermap/*.cmake "$prefix/lib/pkgconfig/rovermap.pc"; then
    fail "the installed package files above name $pattern"
  fi
done

step "find_package(rovermap) from an outside project"
# No build type: the consumer's configuration is not the archives' (imported targets fall back).
cmake -S "$here" -B "$work/consumer" -DCMAKE_PREFIX_PATH="$prefix" \
  -DCMAKE_CXX_COMPILER="$cxx" -DCMAKE_CXX_FLAGS="$extra" -DCMAKE_EXE_LINKER_FLAGS="$extra" \
  >"$work/consumer-configure.log" || { cat "$work/consumer-configure.log"; fail "configure"; }
grep -q -x -F "rovermap_DIR:PATH=$prefix/lib/cmake/rovermap" "$work/consumer/CMakeCache.txt" ||
  fail "rovermap was not found in $prefix: $(grep '^rovermap_DIR' "$work/consumer/CMakeCache.txt")"
cmake --build "$work/consumer" -j 2 >"$work/consumer-build.log" ||
  { cat "$work/consumer-build.log"; fail "build"; }
"$work/consumer/consumer" || fail "the CMake-built consumer did not recover the motion"

step "pkg-config --cflags --libs rovermap"
export PKG_CONFIG_PATH=$prefix/lib/pkgconfig
read -r -a cflags <<<"$(pkg-config --cflags rovermap)"
read -r -a libs <<<"$(pkg-config --libs rovermap)"
read -r -a extras <<<"$extra"
"$cxx" "${extras[@]}" "${cflags[@]}" "$here/main.cpp" -o "$work/consumer_pc" "${libs[@]}" ||
  fail "compile and link main.cpp with pkg-config's flags"
"$work/consumer_pc" || fail "the pkg-config-built consumer did not recover the motion"
# Every archive whole: the Libs line must cover what any object file of any module needs.
echo 'int main() { return 0; }' >"$work/empty_main.cpp"
"$cxx" "${extras[@]}" "$work/empty_main.cpp" -o "$work/consumer_pc_whole" \
  -Wl,--whole-archive "${libs[@]}" -Wl,--no-whole-archive ||
  fail "link every installed archive whole with pkg-config's Libs"

# The Python module, when the build has it (ROVERMAP_PYTHON): installed beside the libraries and
# importable from there alone, outside the source and build trees.
if compgen -G "$build/python/rovermap/_rovermap*.so" >/dev/null; then
  step "import rovermap from the installed tree"
  package=$(compgen -G "$prefix/lib/python3*/dist-packages/rovermap" | head -n 1) ||
    fail "no lib/python3*/dist-packages/rovermap"
  [[ -f $package/__init__.py ]] || fail "no $package/__init__.py"
  (cd "$work" && PYTHONPATH=$(dirname "$package") /usr/bin/python3 -c '
import numpy as np, rovermap, sys
assert rovermap.__file__.startswith(sys.argv[1]), rovermap.__file__
t = np.linspace(0, 6, 300)
target = np.column_stack([np.cos(t), np.sin(2 * t), 0.3 * t])
source = target + [0.01, -0.02, 0.005]
r = rovermap.register(source, target, geometry="curve")
assert r.usable and np.allclose(r.T[:3, 3], [-0.01, 0.02, -0.005], atol=1e-4), r.T
' "$package") || fail "import rovermap from $package did not recover the motion"
fi

echo "PASS"
