#!/usr/bin/env bash
# Installs every build and test dependency of Raybridge from Debian's packages.
# Mesa 25 (lavapipe with ray tracing) and Catch2 3 come from bookworm-backports, which this script adds.
set -euo pipefail
SUDO=""
if [ "$(id -u)" != 0 ]; then SUDO=sudo; fi

if ! grep -rqs "bookworm-backports" /etc/apt/sources.list /etc/apt/sources.list.d/; then
  echo "deb http://deb.debian.org/debian bookworm-backports main" | $SUDO tee /etc/apt/sources.list.d/raybridge-backports.list >/dev/null
fi

PKGS_BASE="build-essential cmake ninja-build pkg-config git
  libvulkan-dev libvulkan-volk-dev vulkan-tools glslang-tools spirv-tools vulkan-validationlayers
  libglfw3-dev libglm-dev libtinygltf-dev nlohmann-json3-dev libstb-dev libopenexr-dev
  libembree-dev libcli11-dev libimgui-dev xvfb python3 clang-format"
PKGS_BACKPORTS="mesa-vulkan-drivers libcatch2-dev"

stamp=/var/tmp/raybridge-setup.stamp
want="$(echo $PKGS_BASE $PKGS_BACKPORTS | md5sum | cut -d' ' -f1)"
if [ -f "$stamp" ] && [ "$(cat $stamp)" = "$want" ] && dpkg -s $PKGS_BASE >/dev/null 2>&1 \
   && dpkg -s $PKGS_BACKPORTS >/dev/null 2>&1; then
  echo "setup: dependencies already installed"
  exit 0
fi

export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -q
$SUDO apt-get install -y -q --no-install-recommends $PKGS_BASE
$SUDO apt-get install -y -q --no-install-recommends -t bookworm-backports $PKGS_BACKPORTS
# The viewer builds Dear ImGui's GLFW and Vulkan backends from the sources libimgui-dev ships under
# /usr/share/doc. Minimal images (Docker's debian:bookworm-slim) tell dpkg to skip /usr/share/doc; then unpack
# the package's copy into /var/tmp/raybridge-imgui, where tools/viewer/CMakeLists.txt looks next.
if [ ! -f /usr/share/doc/libimgui-dev/examples/backends/imgui_impl_vulkan.cpp ]; then
  $SUDO mkdir -p /var/tmp/raybridge-imgui
  (cd /var/tmp/raybridge-imgui && $SUDO apt-get download -q libimgui-dev && $SUDO dpkg-deb -x libimgui-dev_*.deb root)
fi
echo "$want" | $SUDO tee "$stamp" >/dev/null
echo "setup: done"
