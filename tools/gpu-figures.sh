#!/usr/bin/env bash
# The performance figures that need a real GPU (docs/performance.md), in one run:
# robot.sdf and sphere.sdf at 1080p with every variant `sdfc bench` compares (unrolled
# and loop walks, constant uv, pruning, node bounds, seed data in the buffer or baked,
# the multi-scale atlas pass against the per-pixel walk),
# and the seed sweep with its chart, both walk forms, and once on central differences
# against forward derivatives; and the big scenes of `sdfc bench --scale` (groups
# against the same unions as code, per-tile culling against none). Each bench writes
# its --json next to its log.
#
#   tools/gpu-figures.sh OUT_DIR            # on the GPU machine: everything
#   tools/gpu-figures.sh OUT_DIR robot sweep   # only these parts (robot sphere csg plate sweep scale)
#   SIZE=160x90 FRAMES=3 tools/gpu-figures.sh OUT_DIR   # a quick check of the script
#
# Build first (cargo build --release); the script runs target/release/sdfc, or $SDFC.
#
# Time: on a machine whose driver has never seen these modules, every pipeline is
# compiled cold (on an NVIDIA H200, about 5 s for an unrolled module and 0.4-0.7 s
# for a loop one), and the whole script takes well over 15 minutes; `robot` alone
# took over 110 s. A scene bench prints its table and ratios when it ends (each row
# also goes to standard error as it is measured, into the part's log), so give each
# part its own time limit rather than killing the whole run (docs/performance.md,
# Figures from a GPU, says how the 2026-11-28 figures were taken).
set -euo pipefail
cd "$(dirname "$0")/.."

out=${1:?usage: tools/gpu-figures.sh OUT_DIR [robot sphere csg plate sweep]}
shift
parts=${*:-robot sphere csg plate sweep scale}
want() { [[ " $parts " == *" $1 "* ]]; }
for part in $parts; do
  case $part in
    robot | sphere | csg | plate | sweep | scale) ;;
    *) echo "error: unknown part '$part' (robot sphere csg plate sweep scale)" >&2; exit 2 ;;
  esac
done
size=${SIZE:-1920x1080}
frames=${FRAMES:-30}
sdfc=${SDFC:-${CARGO_TARGET_DIR:-target}/release/sdfc}
mkdir -p "$out"

if [ ! -x "$sdfc" ]; then
  echo "error: $sdfc is not built (cargo build --release)" >&2
  exit 2
fi

{
  echo "date:    $(date -u +%Y-%m-%dT%H:%M:%SZ)"
  echo "commit:  $(git rev-parse --short HEAD 2>/dev/null || echo unknown)"
  if command -v nvidia-smi >/dev/null; then
    nvidia-smi --query-gpu=name,driver_version --format=csv,noheader
  fi
} | tee "$out/machine.txt"

for scene in robot sphere csg plate; do
  want "$scene" || continue
  echo "== bench $scene ($size, $frames frames)"
  "$sdfc" bench "examples/$scene.sdf" --size "$size" --frames "$frames" \
    --json "$out/$scene.json" 2>&1 | tee "$out/$scene.txt"
done

# The sweep's chart needs a font (sdfc looks for DejaVu Sans, Liberation Sans or
# Arial, or SDFC_PLOT_FONT); a machine without one still gets the sweep's tables.
have_font() {
  [ -n "${SDFC_PLOT_FONT:-}" ] && return 0
  local f
  for f in /usr/share/fonts/truetype/dejavu/DejaVuSans.ttf /usr/share/fonts/dejavu/DejaVuSans.ttf \
    /usr/share/fonts/dejavu-sans-fonts/DejaVuSans.ttf /usr/share/fonts/TTF/DejaVuSans.ttf \
    /usr/share/fonts/truetype/liberation/LiberationSans-Regular.ttf \
    /usr/share/fonts/liberation-sans/LiberationSans-Regular.ttf; do
    [ -f "$f" ] && return 0
  done
  return 1
}

for walk in unrolled loop; do
  want sweep || continue
  echo "== seed sweep, $walk walk"
  plot=()
  if have_font; then
    plot=(--plot "$out/sweep-$walk.png")
  else
    echo "note: no font for the chart (set SDFC_PLOT_FONT to a .ttf file); tables only"
  fi
  "$sdfc" bench --seed-sweep --walk "$walk" --size "$size" --frames "$frames" \
    --json "$out/sweep-$walk.json" "${plot[@]}" 2>&1 | tee "$out/sweep-$walk.txt"
done

# The walk's gradients: forward derivatives (a GPU's default) against central
# differences, unrolled walk.
if want sweep; then
  echo "== seed sweep, unrolled walk, central differences"
  "$sdfc" bench --seed-sweep --walk unrolled --gradients differences --size "$size" --frames "$frames" \
    --json "$out/sweep-differences.json" 2>&1 | tee "$out/sweep-differences.txt"
fi


# Big scenes: cities and scattered spheres, groups against unions as code, tiles
# against none (docs/performance.md, Big scenes).
if want scale; then
  echo "== scale ($size, $frames frames)"
  "$sdfc" bench --scale --size "$size" --frames "$frames" \
    --json "$out/scale.json" 2>&1 | tee "$out/scale.txt"
fi

echo "wrote $out"
