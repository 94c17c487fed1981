#!/usr/bin/env bash
# Installs everything skillbus needs on a fresh Debian 12 machine, idempotently:
# apt packages (only those missing, so a second run is quick and needs no network),
# Debian's source of DART (deploy/dart-source.sh, once), then a Python virtual environment
# at .venv with the package installed editable (pip runs only when pyproject.toml changed
# since the last install).
set -euo pipefail
cd "$(dirname "$0")/.."

APT_PACKAGES=(
  build-essential cmake ninja-build ccache pkg-config
  libgtest-dev libssl-dev libglib2.0-0 valgrind
  libserd-dev libraptor2-dev librasqal3-dev libeigen3-dev zlib1g-dev
  libdart-dev libdart-collision-bullet-dev libdart-utils-urdf-dev nlohmann-json3-dev libcli11-dev libceres-dev
  libode-dev  # (for DART rebuilt with the features of Debian's build: cmake/DartSameFeatures.cmake)
  libgoogle-perftools-dev
  liboctomap-dev libompl-dev
  cyclonedds-dev cyclonedds-tools
  xvfb imagemagick
  chromium libjs-three
  default-jdk-headless
  python3-venv python3-dev
  iproute2 util-linux procps
)

missing=()
for p in "${APT_PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing apt packages: ${missing[*]}"
  SUDO=""; [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

# Debian's source of its DART, built again without assertions by the CMake build
# (cmake/DartWithoutAssertions.cmake); fetched once, and a warning only if it cannot be.
deploy/dart-source.sh

PY=${PYTHON:-python3}
if [ ! -x .venv/bin/python ]; then
  echo "setup: creating .venv"
  "$PY" -m venv .venv
fi
stamp=.venv/.skillbus-installed
want=$(sha256sum pyproject.toml | cut -d' ' -f1)
if [ ! -f "$stamp" ] || [ "$(cat "$stamp")" != "$want" ]; then
  echo "setup: installing the Python package and its dependencies into .venv"
  .venv/bin/pip install -q --upgrade pip
  .venv/bin/pip install -q -e '.[test,bench]'
  echo "$want" > "$stamp"
fi
