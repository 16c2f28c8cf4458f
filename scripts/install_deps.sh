#!/usr/bin/env bash
# Installs the Debian 12 packages rovermap builds against. Idempotent: quiet and
# quick when everything is already there (checks with dpkg, no network).
set -euo pipefail

packages=(
  build-essential cmake pkg-config
  libeigen3-dev libnanoflann-dev libyaml-cpp-dev libcli11-dev nlohmann-json3-dev
  libopencv-dev liboctomap-dev libgeographiclib-dev libgdal-dev libtbb-dev libspdlog-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  clang libclang-rt-14-dev libomp-dev
)
if [[ "${ROVERMAP_BENCH_PEERS:-OFF}" == "ON" ]]; then
  packages+=(libpcl-dev libopen3d-dev)
fi

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
[[ ${#missing[@]} -eq 0 ]] && exit 0

echo "install_deps: installing ${missing[*]}" >&2
sudo_cmd=()
[[ $(id -u) -ne 0 ]] && sudo_cmd=(sudo)
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -qq
"${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
