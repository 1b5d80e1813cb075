#!/bin/bash
# The surface issue's figures: `fires demo` sessions (default scenario, 60 s) over SEEDS, each network
# reconstructed with both methods, from the tracked and from the true strokes, against the true object; plus the
# thin-plate-spline baseline (scripts/tps_baseline.py; PYTHON must have numpy and scipy). One JSON line per
# (seed, input, method) on standard output.
# usage: scripts/surface_figures.sh OUT_DIR [SEEDS...]   (default seeds 1 2 3 4 5)
set -euo pipefail
out=${1:?usage: surface_figures.sh OUT_DIR [SEEDS...]}; shift
seeds=${*:-1 2 3 4 5}
here=$(cd "$(dirname "$0")/.." && pwd)
fires=${FIRES:-$here/target/release/fires}
python=${PYTHON:-python3}
mkdir -p "$out"
for seed in $seeds; do
  d=$out/seed-$seed
  rm -rf "$d"
  "$fires" demo --out "$d" --seed "$seed" --duration 60 > "$d.txt"
  for input in tracked truth; do
    net=$d/replay/network.json; [ $input = truth ] && net=$d/replay/network_truth.json
    for m in v1 v2; do
      line=$("$fires" recon "$net" -o "$d/$input-$m.obj" --method $m --truth "$d/recording" 2>&1) || line="{\"error\": \"$(echo "$line" | tr -d '"')\"}"
      echo "{\"seed\": $seed, \"input\": \"$input\", \"recon\": $line}"
    done
  done
  if "$python" "$here/scripts/tps_baseline.py" "$d/recording" "$d/tps.obj" > /dev/null; then
    echo "{\"seed\": $seed, \"input\": \"truth\", \"baseline\": $("$fires" mesh compare "$d/tps.obj" --truth "$d/recording" --method tps)}"
  fi
done
