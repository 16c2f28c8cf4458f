#!/usr/bin/env bash
# `make test-slurm`: starts a throw-away single-node Slurm cluster, runs the tests labelled
# "slurm" (the campaign through sbatch) against it, and stops it whatever happened.
set -euo pipefail
build=$(realpath "${1:-build}")
here=$(dirname "$(realpath "$0")")
cluster=$(mktemp -d "${TMPDIR:-/tmp}/rovermap-slurm.XXXXXX")
trap 'bash "$here/cluster.sh" stop "$cluster"; rm -rf "$cluster"' EXIT
eval "$(bash "$here/cluster.sh" start "$cluster")"
echo "test-slurm: cluster up (SLURM_CONF=$SLURM_CONF)" >&2
cd "$build"
ctest --output-on-failure -L slurm
