#!/bin/bash
# relocation rays vs image error. usage: run.sh NAME SCENE "BAKE ARGS" "VIEW1" ["VIEW2"]
export VK_DRIVER_FILES=/usr/share/vulkan/icd.d/lvp_icd.json
pb=/work/main/build/probebake
name=$1 scene=$2 args=$3; shift 3
views=("$@")
out=/tmp/relo/$name; mkdir -p $out
i=0; refs=()
for v in "${views[@]}"; do
  ref=/tmp/relo/refs/$name-$i.png
  [ -s ${ref%.png}.pfm ] || $pb render $scene --mode reference --spp 2048 --size 160x120 $v --pfm -o $ref --quiet >/dev/null
  refs+=(${ref%.png}.pfm); i=$((i+1))
done
for seed in 1 2; do
 for R in 256 64 32; do
  vol=$out/r$R-s$seed.probes
  $pb bake $scene $args --seed $seed --relocation-rays $R -o $vol --verbose 2>$out/r$R-s$seed.log >/dev/null
  reloc=$(grep -oE 'relocate [0-9.]+ \(GPU [0-9.]+' $out/r$R-s$seed.log | grep -oE '[0-9.]+$')
  counts=$(grep -oE '[0-9]+ valid, [0-9]+ relocated, [0-9]+ invalid' $out/r$R-s$seed.log)
  line="R=$R seed=$seed relocGPU=$reloc [$counts]"
  i=0
  for v in "${views[@]}"; do
    j=$($pb render $scene --volume $vol --mode diff --spp 64 --size 160x120 $v --reference ${refs[$i]} --json -o $out/img-r$R-s$seed-$i.png --quiet 2>/dev/null)
    rm=$(echo "$j" | python3 -c 'import json,sys; r=json.load(sys.stdin); print(r["relative_rmse_surfaces"], r["p95_relative_error"])')
    line="$line | v$i $rm"; i=$((i+1))
  done
  echo "$line"
 done
done
