#!/usr/bin/env bash
# Installs everything csgvox needs to build, test and benchmark on Debian 12.
# Run as root (or with sudo). Safe to run again.
set -euo pipefail
SUDO=""
if [[ $(id -u) -ne 0 ]]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -q
$SUDO apt-get install -y -q --no-install-recommends \
  build-essential cmake ccache pkg-config \
  libcgal-dev libopenvdb-dev libboost-iostreams-dev libceres-dev \
  libeigen3-dev libtbb-dev libgmp-dev libmpfr-dev \
  nlohmann-json3-dev libcli11-dev libnanoflann-dev \
  libgtest-dev libgmock-dev libbenchmark-dev \
  openscad \
  libocct-foundation-dev libocct-modeling-data-dev libocct-modeling-algorithms-dev \
  libocct-data-exchange-dev libstb-dev freecad-python3 \
  python3-dev pybind11-dev python3-numpy python3-pytest python3-setuptools python3-wheel \
  python3-pip python3-venv parallel
