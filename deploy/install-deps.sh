#!/usr/bin/env bash
# Installs lightfarm's build and test dependencies from Debian 12's packages.
set -euo pipefail
packages=(
  build-essential cmake pkg-config
  libembree-dev libopenexr-dev libtbb-dev libspdlog-dev nlohmann-json3-dev libcli11-dev
  libpng-dev libtinyobjloader-dev libtinygltf-dev libdraco-dev libstb-dev libopenvdb-dev
  libboost-dev  # OpenVDB's io headers include Boost's, which libopenvdb-dev does not depend on
  libgrpc++-dev libprotobuf-dev protobuf-compiler protobuf-compiler-grpc
  libssl-dev libsqlite3-dev libgtest-dev libgmock-dev libbenchmark-dev
  gnuplot-nox
  libcpp-httplib-dev
  iproute2 openssl python3 python3-yaml
  python3-grpcio python3-protobuf
  clang libclang-rt-14-dev
  chromium
  # The Blender add-on's headless test (docs/blender.md): on top of the rest, 166 packages,
  # 171 MB to download, 620 MB installed (Debian 12, --no-install-recommends).
  # Blender's own glTF exporter imports numpy, which Debian's blender package does not pull in.
  blender python3-numpy
)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
# Node.js and npm for the dashboard's browser tests: Debian's, unless a node and npm (from
# NodeSource, say, whose nodejs package conflicts with Debian's npm) are on the PATH already.
if ! command -v node >/dev/null || ! command -v npm >/dev/null; then
  missing+=(nodejs npm)
fi
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi
sudo=""
[ "$(id -u)" -eq 0 ] || sudo="sudo"
echo "install-deps: installing ${missing[*]}"
$sudo apt-get update -qq
DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
