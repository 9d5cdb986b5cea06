#!/usr/bin/env bash
# Reproduces the parameter studies behind docs/validation.md (about 5 minutes on 2 cores).
# Outputs: out/studies/<name>/study.csv, study.png, contour_*.png; the PNGs are copied to
# docs/figures/.
set -euo pipefail
cd "$(dirname "$0")/.."
PY=/usr/bin/python3
S="$PY tools/study.py"
G="Model/G=0,0.001,0.003,0.01,0.03,0.1,0.3,1"
H="Discretization/Horizon Factor=1.015,2.015,3.015"
$S --scene xml/hydrostatic.xml --probe "right middle" --component 0 --metric e_u --sweep "$G" --series "$H" \
   --out out/studies/hydrostatic_G
FEM='--reference-label FEM(CalculiX)'
$S --scene xml/clamped_beam.xml --probe midspan --component 1 --normalise -5.08 --sweep "$G" --series "$H" \
   --reference 0.615605 $FEM --contours 0,0.1 --out out/studies/clamped_G
$S --scene xml/clamped_beam.xml --probe midspan --component 1 --normalise -5.08 --sweep "$G" --series "$H" \
   --reference 0.615605 $FEM --set "Discretization/Particles={125,5}" --out out/studies/clamped_G_5x125
$S --scene xml/simply_supported_beam.xml --probe midspan --component 1 --normalise -5.08 --sweep "$G" --series "$H" \
   --reference 1.004269 $FEM --contours 0,0.1 --out out/studies/simply_supported_G
$S --scene xml/cantilever.xml --probe tip --component 1 --normalise -10 --sweep "$G" --series "$H" \
   --reference 0.8263748 $FEM --set "Model/Stabilization=Silling" --contours 0,0.1 --out out/studies/cantilever_G
for d in hydrostatic_G clamped_G clamped_G_5x125 simply_supported_G cantilever_G; do
  cp out/studies/$d/study.png docs/figures/$d.png
  for c in out/studies/$d/contour_*.png; do [ -e "$c" ] && cp "$c" "docs/figures/${d}_$(basename "$c")"; done
done
echo "studies done"
