#!/usr/bin/env bash
# Alternating bakes, the build before (A) and after (B): the issue's Crypt bake,
# the Cornell box and the demo, 'resources and pipelines' stage and total wall.
# usage: ab.sh A_BUILD B_BUILD PAIRS > log
set -u
A=$1 B=$2 N=${3:-4}
export VK_DRIVER_FILES=/usr/share/vulkan/icd.d/lvp_icd.json
S=/work/shared/scenes
run() { # build label args...
  local b=$1 label=$2; shift 2
  "$b/probebake" bake "$@" -o /tmp/ab-pipes.probes --verbose 2>&1 |
    awk -v b="$label" '/bake stages/ {match($0, /resources and pipelines [0-9.]+/); r=substr($0, RSTART+24, RLENGTH-24)}
                       /total .* ms wall/ {for (i=1;i<=NF;i++) if ($i=="total") t=$(i+1)}
                       END {printf "%s resources_ms %s total_ms %s\n", b, r, t}'
}
for i in $(seq "$N"); do
  for side in A B; do
    b=$A; [ $side = B ] && b=$B
    echo "crypt16k $(run "$b" $side $S/openarena/oacmpdm1.glb --counts 32,16,32 --rays 256 --passes 1 --bounces 3)"
    echo "cornell2k $(run "$b" $side $S/cornell/cornellBox.gltf --counts 16,8,16 --rays 256 --passes 1 --bounces 3)"
    echo "demo $(run "$b" $side /work/main/tests/scenes/demo.gltf)"
    echo "panel $(run "$b" $side /work/main/tests/scenes/panel.gltf --counts 8,4,8)"
  done
done
