#!/usr/bin/env bash
# Per-pass GPU ms per eye of the stereo reuse, the second depth layer and the footprint,
# each against the default in one run, on a machine with a GPU:
#   scripts/gpu-budget-sweep.sh VRAO SCENES OUT [vrao budget options, e.g. --width 64 --height 72]
# Writes OUT/NAME.json (one `vrao budget --measure occlusion` report per row), OUT/sweep.log
# and OUT/info.txt (the adapter). The Vulkan loader must be installed (scripts/gpu-table.sh
# unpacks .gl/*.deb where it is not).
# The rows alternate their settings inside each scene and resolution, and the whole sweep
# runs twice (SWEEP_ROUNDS), so clocks that drift show as a difference between the rounds.
# Each report's `ao_chain.right_eye_added_share` is what the right eye adds to the chain.
set -uo pipefail
[ $# -ge 3 ] || { echo "usage: $0 VRAO SCENES OUT [vrao budget options]" >&2; exit 2; }
bin=$(realpath "$1") scenes=$(realpath "$2") out=$3
shift 3
repo=$(cd "$(dirname "$0")/.." && pwd)
mkdir -p "$out"; out=$(realpath "$out")
cd "$repo"
export VRAO_SCENES="$scenes"
# The NVIDIA driver's Vulkan ICD, where the loader does not find it by itself.
icd=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
if [ -z "${VK_DRIVER_FILES:-}" ] && [ -f "$icd" ]; then export VK_DRIVER_FILES="$icd"; fi
# Twice a fresh device machine's first Vulkan start never returned, in every later call
# too (the next machine answered at once): give up early rather than time out every row.
if ! timeout 30 "$bin" info --backend vulkan >"$out/info.txt" 2>&1; then
  echo "$bin info: no Vulkan adapter opened within 30 s; see $out/info.txt (try another machine)" >&2
  exit 1
fi
# Scene files (SWEEP_SCENES to choose others): the scenes' own poses and 30 cm from a wall.
scene_files=${SWEEP_SCENES:-assets/scenes/sibenik.toml assets/scenes/furnished.toml assets/scenes/sibenik-wall.toml assets/scenes/furnished-wall.toml}
rounds=${SWEEP_ROUNDS:-2}
case $rounds in [1-9]) ;; *) echo "SWEEP_ROUNDS must be 1..9, not '$rounds'" >&2; exit 2 ;; esac
declare -A settings=(
  [default]=""
  [independent]="--independent-eyes"
  [fold]="--fold-right-eye"
  [layers2]="--layers 2"
  [footprint0]="--footprint 0 --thickness 0.75"
  [foveated]="--foveation high"
)
for round in $(seq "$rounds"); do
  for scene in $scene_files; do
    name=$(basename "$scene" .toml)
    case $name in *-wall) rows="default independent fold" ;; *) rows="default independent fold layers2 footprint0 foveated" ;; esac
    for res in full half; do
      half=""; [ $res = half ] && half="--half-res"
      for row in $rows; do
        tag="$name.$res.$row.r$round"
        echo "== $tag" >>"$out/sweep.log"
        # shellcheck disable=SC2086
        timeout 120 "$bin" budget --scene "$scene" --measure occlusion $half ${settings[$row]} \
          --out "$out/$tag.json" "$@" >>"$out/sweep.log" 2>&1
        # Exit 3: measured and written, but over the frame budget (every row on lavapipe).
        rc=$?; [ $rc = 0 ] || [ $rc = 3 ] || echo "!! $tag failed ($rc)" >>"$out/sweep.log"
      done
    done
  done
done
