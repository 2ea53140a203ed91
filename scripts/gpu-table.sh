#!/usr/bin/env bash
# The GPU table on a machine with a GPU: scripts/gpu-table.sh VRAO SCENES OUT [vrao table options]
#   VRAO    the release binary (cargo build --release: target/release/vrao)
#   SCENES  the public scenes folder ($VRAO_SCENES: sibenik/, envmaps/)
#   OUT     folder for gpu-table.md, gpu-table.log and info.txt (the adapter)
# Needs nothing installed but a Vulkan driver: where the system has no Vulkan loader, the
# loader's .deb files in the repository's .gl/ (see the device machine's README) are
# unpacked first. Extra options go to `vrao table` (e.g. --width 48 --height 54 --frames 1).
set -euo pipefail
[ $# -ge 3 ] || { echo "usage: $0 VRAO SCENES OUT [vrao table options]" >&2; exit 2; }
bin=$(realpath "$1") scenes=$(realpath "$2") out=$3
shift 3
repo=$(cd "$(dirname "$0")/.." && pwd)
# (grep reads the whole list: with pipefail, a grep -q that stops early fails ldconfig.)
if ! { ldconfig -p 2>/dev/null || /sbin/ldconfig -p; } | grep libvulkan.so.1 >/dev/null; then
  for f in "$repo"/.gl/*.deb; do
    [ -f "$f" ] || { echo "no Vulkan loader and no $repo/.gl/*.deb to unpack" >&2; exit 2; }
    dpkg -x "$f" /
  done
  ldconfig
fi
# The NVIDIA driver's Vulkan ICD, where the loader does not find it by itself.
icd=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
if [ -z "${VK_DRIVER_FILES:-}" ] && [ -f "$icd" ]; then export VK_DRIVER_FILES="$icd"; fi
mkdir -p "$out"
out=$(realpath "$out")
# Bounded: on one fresh device machine the first Vulkan start never returned (the next
# machine answered in under a second), and a table run would have waited on it for good.
if ! timeout 120 "$bin" info > "$out/info.txt"; then
  echo "$bin info: no Vulkan adapter opened within 120 s (or it failed); see $out/info.txt and run again" >&2
  exit 1
fi
cat "$out/info.txt"
# From the repository root: the default scenes name assets/scenes/sibenik.toml.
cd "$repo"
VRAO_SCENES="$scenes" "$bin" table --out "$out/gpu-table.md" "$@" 2>&1 | tee "$out/gpu-table.log"
