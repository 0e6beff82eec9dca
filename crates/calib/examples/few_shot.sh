#!/usr/bin/env bash
# Re-run issue 11's few-shot measurement end to end (docs/calibration.md):
# part CSVs by frame number, real imports, twins, then for each N and seed
# the few_shot driver, PDenNN training and validation on the real score part.
# Usage: crates/calib/examples/few_shot.sh DATA_DIR WORK_DIR [PART]
#   PART: score (final figures, default) or select (for choosing variants).
# Env: NS="10 30 100 all", SEEDS="1 2 3", RECIPES="A B C".
set -euo pipefail
D=${1:?data dir (targets.csv, frames/)}; W=${2:?work dir}; PART=${3:-score}
NS=${NS:-"10 30 100 all"}; SEEDS=${SEEDS:-"1 2 3"}; RECIPES=${RECIPES:-"A B C"}
ROOT=$(cd "$(dirname "$0")/../../.." && pwd)
cargo build --release --manifest-path "$ROOT/Cargo.toml" -p tactrace -p tactrace-calib --examples >&2
T=$ROOT/target/release/tactrace; E=$ROOT/target/release/examples/few_shot
mkdir -p "$W"; cd "$W"
# Parts of targets.csv: score N%5=0, select 1, fit 2-4 (frame_N_0.png).
for p in score:0 select:1 fit:2,3,4; do
  name=${p%%:*}; mods=${p#*:}
  awk -F, -v mods="$mods" 'NR==1 {print; next}
    { split($1, a, "_"); n = a[2] % 5; if (index("," mods ",", "," n ",")) print }' \
    "$D/targets.csv" > "$name.csv"
done
ref=$D/frames/init_0.png
[ -d real_all ] || $T import --frames "$D/frames" --targets "$D/targets.csv" --reference "$ref" --out real_all
[ -d "real_$PART" ] || $T import --frames "$D/frames" --targets "$PART.csv" --reference "$ref" --out "real_$PART"
[ -d twin ] || $T twin --targets "$D/targets.csv" --reference "$ref" --out twin
for s in 2 3; do
  [ -d "twin_s$s" ] || $T twin --targets "$D/targets.csv" --reference "$ref" --seed $s --out "twin_s$s"
done
common=(--real real_all --real-csv "$D/targets.csv" --twin twin --twin-csv "$D/targets.csv" --pool fit --eval "$PART")
for n in $NS; do
  seeds=$SEEDS; [ "$n" = all ] && seeds=1
  for r in $RECIPES; do
    case $r in
      A) extra=() ;;
      B) extra=(--add-real auto) ;;
      C) extra=(--add-real auto --more-twins twin_s2,twin_s3) ;;
    esac
    # With every fit tap: B adds the real taps once, C is the three twins alone.
    if [ "$n" = all ]; then
      case $r in B) extra=(--add-real 1) ;; C) extra=(--more-twins twin_s2,twin_s3) ;; esac
    fi
    for s in $seeds; do
      rm -rf cor model
      line=$($E "${common[@]}" --samples "$n" --seed "$s" --out cor "${extra[@]}" 2>/dev/null | grep '^taps')
      $T train --model pdennn --train cor --val-fraction 0.15 --out model >/dev/null 2>&1
      res=$($T validate --model model --data "real_$PART" 2>&1 | tail -1)
      echo "N $n recipe $r seed $s | ${line#*seed $s } | $res"
    done
  done
done
