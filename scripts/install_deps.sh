#!/usr/bin/env bash
# Installs the Debian 12 packages rovermap builds against. Idempotent: quiet and
# quick when everything is already there (checks with dpkg, no network).
set -euo pipefail

# libnanoflann-dev is for bench/bench_kdtree only; the build leaves that benchmark out without it.
# liblz4-dev, libzstd-dev, libsqlite3-dev and zlib1g-dev read ROS 2 bags (MCAP chunks, their
# CRC32, the SQLite storage); the ROS 1 packages only ROS 1 bags (ROVERMAP_WITH_ROSBAG);
# libceres-dev solves the pose graph (graph/).
packages=(
  build-essential cmake pkg-config
  libeigen3-dev libnanoflann-dev libyaml-cpp-dev libcli11-dev nlohmann-json3-dev
  libopencv-dev liboctomap-dev libgeographiclib-dev libgdal-dev libtbb-dev libspdlog-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  liblz4-dev libzstd-dev libsqlite3-dev zlib1g-dev
  libceres-dev
  librosbag-storage-dev libsensor-msgs-dev libnav-msgs-dev libgeometry-msgs-dev libtf2-msgs-dev
  clang libclang-rt-14-dev libomp-dev
  slurmctld slurmd slurm-client munge
  pybind11-dev python3-dev python3-numpy python3-pytest
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

# Another apt or dpkg run holding the package manager's locks (unattended-upgrades on a freshly
# booted machine) is waited for, at most ROVERMAP_APT_LOCK_WAIT_S seconds, instead of failing
# at once. apt-get waits for dpkg's lock itself (DPkg::Lock::Timeout) but not for the lists
# lock `apt-get update` takes (apt 2.6, measured): a failure naming a lock is retried every
# ROVERMAP_APT_LOCK_POLL_S seconds until the deadline.
lock_wait_s="${ROVERMAP_APT_LOCK_WAIT_S:-600}"
lock_poll_s="${ROVERMAP_APT_LOCK_POLL_S:-5}"
# In microseconds of the wall clock: bash's SECONDS counts whole seconds of it, so a deadline of
# SECONDS + 1 could pass a few milliseconds after the start, before a single retry.
lock_deadline_us=$((${EPOCHREALTIME/[.,]/} + lock_wait_s * 1000000))

apt_get() {
  local errors timeout=0 waiting=""
  errors=$(mktemp)
  while true; do
    if "${sudo_cmd[@]}" apt-get -o DPkg::Lock::Timeout="$timeout" "$@" 2>"$errors"; then
      cat "$errors" >&2
      rm -f "$errors"
      return 0
    fi
    if ! grep -q "Could not get lock" "$errors" || ((${EPOCHREALTIME/[.,]/} >= lock_deadline_us)); then
      [[ -n $waiting ]] && echo "install_deps: gave up waiting for the package manager's lock" \
        "after ${lock_wait_s} s (ROVERMAP_APT_LOCK_WAIT_S)" >&2
      cat "$errors" >&2
      rm -f "$errors"
      return 1
    fi
    if [[ -z $waiting ]]; then
      echo "install_deps: another package manager run holds its lock" \
        "($(grep -m1 "Could not get lock" "$errors" | sed 's/^E: //'));" \
        "waiting for it, at most ${lock_wait_s} s (ROVERMAP_APT_LOCK_WAIT_S)" >&2
      waiting=yes
    fi
    sleep "$lock_poll_s"
    timeout=$(((lock_deadline_us - ${EPOCHREALTIME/[.,]/}) / 1000000))
    ((timeout > 0)) || timeout=0
  done
}

apt_get update -qq
apt_get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
