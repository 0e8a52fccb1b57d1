#!/usr/bin/env bash
# The learning check of issue 17, as measured for the README: 40 scripted demonstrations of
# citrus_plate_loading on UR5+RH5DG2 rendered under policy_tiny, ACT tiny trained 8,000 steps on one CPU
# core (about 29 minutes), then 10 closed-loop episodes per channel anchored on the training scenes.
#   bash scripts/learning_check.sh [OUT_DIR] [POLICY] [STEPS]     (defaults: data/learning_check act 8000)
set -euo pipefail
cd "$(dirname "$0")/.."
OUT="${1:-data/learning_check}"; POLICY="${2:-act}"; STEPS="${3:-8000}"
B=.venv/bin
export MUJOCO_GL="${MUJOCO_GL:-egl}" LP_NUM_THREADS=0
SETTING=citrus_plate_loading__ur5_rh5dg2
$B/b2d record --task citrus_plate_loading --embodiment ur5_rh5dg2 --episodes 40 --out "$OUT/raw"
$B/b2d replay "$OUT"/raw/*.raw.h5 --profile policy_tiny --out "$OUT/episodes"
$B/b2d train --setting $SETTING --policy "$POLICY" --config tiny --steps "$STEPS" --episodes "$OUT/episodes" \
  --out "$OUT/checkpoint_$POLICY"
$B/b2d eval --checkpoint "$OUT/checkpoint_$POLICY" --episodes 10 --out "$OUT/records_$POLICY.parquet"
$B/b2d tables --records "$OUT/records_$POLICY.parquet" --out "$OUT/tables_$POLICY"
