#!/usr/bin/env bash
# Regenerate the committed sample set (deterministic: fixed seeds).
set -euo pipefail
cd "$(dirname "$0")"
gen() { name=$1; shift; rm -rf "$name"; motiondetect synth "$name" --frames 60 --seed 1 "$@"; }
gen static_walker      --camera static      --mover smooth
gen uniform_mixed      --camera uniform     --mover smooth --mover animate
gen pan_blindspot      --camera pan         --mover on-ray --mover animate
gen forward_crossing   --camera forward     --mover smooth
gen oblique_crossing   --camera oblique     --mover smooth
gen forwardyaw_waving  --camera forward-yaw --mover animate
gen fixation_waving    --camera fixation    --mover animate
gen handheld_emerging  --camera jitter      --mover animate --mover emerging
gen uniform_rigid      --camera uniform
