#!/usr/bin/env bash
# Installs every Debian 12 package Nephele needs to build, test and run.
# Idempotent and non-interactive: when everything is present it does nothing.
set -euo pipefail

packages=(
  build-essential cmake pkg-config ccache clang-format
  clang libclang-rt-14-dev
  libosmesa6-dev libegl-dev libegl-mesa0 libgl1-mesa-dri libgles-dev libgbm-dev
  libglm-dev libopenimageio-dev openimageio-tools
  libtomlplusplus-dev nlohmann-json3-dev libcli11-dev libspdlog-dev libfmt-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  libxxhash-dev libasio-dev
  libavcodec-dev libavformat-dev libavutil-dev libswscale-dev  # streamed views (H.264)
  ffmpeg  # ffplay and ffmpeg: the stream tests decode what the daemon sends
  libmodbus-dev python3-pymodbus python3-serial-asyncio python3-numpy mbpoll
  python3-venv python3-setuptools python3-wheel python3-pil  # clients/python: offline pip install
  libsystemd-dev  # sd_notify: readiness and the watchdog under systemd
  tshark  # Wireshark's CIGI dissector checks every CIGI packet in the tests
  glslang-tools  # glslangValidator checks every GLSL stage (the glsl_stages test)
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#packages[@]} packages present"
  exit 0
fi

sudo=""
[ "$(id -u)" -eq 0 ] || sudo="sudo"
echo "setup: installing ${#missing[@]} packages: ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -q
$sudo apt-get install -y -q --no-install-recommends "${missing[@]}"
echo "setup: done"
