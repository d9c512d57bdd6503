#!/usr/bin/env bash
# Installs Drapekit's build and test dependencies from Debian's packages.
# Safe to re-run: it only calls apt-get when something is missing.
set -euo pipefail
PKGS=(
  build-essential cmake ninja-build pkg-config
  libeigen3-dev libsuitesparse-dev libopenblas0-pthread
  libopencv-dev libopencv-contrib-dev
  libnlopt-cxx-dev
  libassimp-dev assimp-testmodels
  libsqlite3-dev nlohmann-json3-dev
  qt6-base-dev qt6-declarative-dev qt6-quick3d-dev qt6-shadertools-dev qt6-tools-dev qt6-tools-dev-tools
  qml6-module-qtquick qml6-module-quick3d qml6-module-quick3d-helpers qml6-module-qtquick-window qml6-module-qtqml-workerscript
  qml6-module-qtquick-controls qml6-module-qtquick-layouts qml6-module-qtquick-templates
  libqt6sql6-sqlite libqt6opengl6-dev qt6-qpa-plugins designer-qt6
  xvfb xauth libgl1-mesa-dri mesa-utils
  # scripts/fuzz.sh: clang with libFuzzer and the sanitizer runtimes; jq and
  # python3 write seeds and the bad inputs of scripts/bad-inputs.sh.
  clang-14 libclang-rt-14-dev jq python3
)
missing=()
for p in "${PKGS[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "setup: installing ${#missing[@]} missing packages: ${missing[*]}"
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
