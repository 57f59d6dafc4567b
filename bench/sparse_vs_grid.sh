#!/usr/bin/env bash
# Sparse bricks against uniform grids (issue 14): for each layout, probes,
# file bytes and bake wall time against the image error of probe-lit renders
# compared with path-traced references (render --mode diff:
# relative_rmse_surfaces and p95_relative_error, averaged over the views;
# for sparse layouts also the same two where its levels meet and elsewhere,
# render's seam metrics, each the mean over views weighted by the view's
# pixels in that class, and the fraction of surface pixels on a seam; and
# the peer grid's error on those same seam pixels, render --seams-of, so a
# seam's error is told from a region that is hard for any layout).
# Grids at several spacings, sparse layouts at several refinement errors, all
# in the same run; ratios are against the finest grid (the peer). Prints a
# table, writes CSV and JSON.
#
#   bench/sparse_vs_grid.sh [--probebake P] [--out DIR] [--size WxH] [--spp N]
#                           [--grid "S1 S2 ..."] [--finest F] [--sparse "E1 E2 ..."] [--max-level L]
#                           [--sparse-args "BAKE ARGS"] [--view "RENDER ARGS"]... [--ref-spp N]
#                           SCENE [bake options...]
#
# Defaults: grids at 1, 0.5 and 0.25 m; sparse with the finest spacing
# --finest (default the smallest grid spacing) at errors 0.3, 0.1 and 0.03;
# --sparse-args: bake options for the sparse rows only (e.g. "--refine-seams 1
# --seam-error 1.6"); 160x120, probe images at 64 spp; the view "--camera 0"; bake options
# --rays 256 --passes 4; into bench/results/sparse_vs_grid/.
#
# The reference of each view is path traced once at --ref-spp (default 4096)
# and every layout is compared with that same image (render --reference), so
# the reference's own noise is small and equal for all rows. --ref-spp 0:
# each diff traces its own 16x-spp reference instead (the old, noisier way).
# References are kept in $out/references/ (keyed by scene, view, size and
# spp; not committed) and reused by later runs.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
pb=$root/build/probebake
out=$root/bench/results/sparse_vs_grid
size=160x120
spp=64
ref_spp=4096
grids="1 0.5 0.25"
finest=""
errors="0.3 0.1 0.03"
max_level=2
sparse_args=""
views=()
while [ $# -gt 0 ]; do
    case $1 in
        --probebake) pb=$2; shift 2 ;;
        --out) out=$2; shift 2 ;;
        --size) size=$2; shift 2 ;;
        --spp) spp=$2; shift 2 ;;
        --ref-spp) ref_spp=$2; shift 2 ;;
        --grid) grids=$2; shift 2 ;;
        --finest) finest=$2; shift 2 ;;
        --sparse) errors=$2; shift 2 ;;
        --max-level) max_level=$2; shift 2 ;;
        --sparse-args) sparse_args=$2; shift 2 ;;
        --view) views+=("$2"); shift 2 ;;
        *) break ;;
    esac
done
[ $# -ge 1 ] || { echo "usage: $0 [options] SCENE [bake options...]" >&2; exit 2; }
scene=$1
shift
args=("$@")
[ ${#args[@]} -gt 0 ] || args=(--rays 256 --passes 4)
[ ${#views[@]} -gt 0 ] || views=("--camera 0")
if [ -z "$finest" ]; then
    finest=$(for s in $grids; do echo "$s"; done | sort -g | head -n 1)
fi
mkdir -p "$out"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
now_ms() { echo $(($(date +%s%N) / 1000000)); }
# the first "KEY": number in the JSON on stdin: the top-level one (render's
# one-line JSON repeats keys inside "levels"; a greedy sed took the last level's)
# (nothing, and no failure, where the key is absent)
json_num() { { grep -o "\"$1\": [-0-9.eE+]*" || :; } | head -n 1 | sed 's/.*: //'; }

device=$("$pb" devices --json | sed -n 's/.*"index": 0, "name": "\([^"]*\)".*/\1/p' | head -n 1)
echo "sparse_vs_grid: $scene ${args[*]}; grids $grids m; sparse finest $finest m, max level $max_level, errors $errors${sparse_args:+ ($sparse_args)};"
echo "  ${#views[@]} view(s) at $size, probe images $spp spp, references $ref_spp spp; $(nproc) cores; device: $device"

# one converged reference per view (cached: the slow part of the bench)
refs=()
if [ "$ref_spp" != 0 ]; then
    mkdir -p "$out/references"
    for view in "${views[@]}"; do
        key=$( (basename "$scene"; cksum <"$scene"; echo "$view $size $ref_spp") | cksum | cut -d' ' -f1)
        ref=$out/references/$(basename "$scene" | sed 's/\.[^.]*$//')-$key.png
        if [ ! -s "${ref%.png}.pfm" ]; then
            echo "  reference for view '$view': $ref_spp spp ..."
            t=$(now_ms)
            # shellcheck disable=SC2086 # a view is render arguments
            "$pb" render "$scene" --mode reference --spp "$ref_spp" --size "$size" $view --pfm -o "$ref" --quiet \
                >/dev/null
            echo "    $(($(now_ms) - t)) ms"
        fi
        refs+=("${ref%.png}.pfm")
    done
fi

rows=()
measure() { # name param [bake options...]: one layout, baked and rendered
    local name=$1 param=$2
    shift 2
    local vol=$tmp/$name-$param.probes t ms probes bytes rmse=0 p95=0 v=0 seam=(0 0 0 0) px=(0 0 0) k key n
    local peer_seam=(0 0) peer_vol="" g
    t=$(now_ms)
    "$pb" bake "$scene" "${args[@]}" "$@" --quiet -o "$vol" >"$tmp/bake.txt"
    ms=$(($(now_ms) - t))
    probes=$("$pb" inspect "$vol" --json | json_num probes)
    bytes=$(stat -c %s "$vol")
    for i in "${!views[@]}"; do
        view=${views[$i]}
        # shellcheck disable=SC2086 # a view is render arguments
        "$pb" render "$scene" --volume "$vol" --mode diff --json --size "$size" ${spp:+--spp $spp} $view \
            ${refs[$i]:+--reference ${refs[$i]}} -o "$tmp/diff.png" 2>/dev/null >"$tmp/diff.json"
        rmse=$(awk -v a="$rmse" -v b="$(json_num relative_rmse_surfaces <"$tmp/diff.json")" 'BEGIN { print a + b }')
        p95=$(awk -v a="$p95" -v b="$(json_num p95_relative_error <"$tmp/diff.json")" 'BEGIN { print a + b }')
        # seam metrics: weighted by each view's pixels in the class (a view may have none)
        k=0
        for key in relative_rmse_seams p95_relative_error_seams relative_rmse_off_seams p95_relative_error_off_seams; do
            n=$(json_num "$([ $k -lt 2 ] && echo seam_pixels || echo off_seam_pixels)" <"$tmp/diff.json")
            seam[k]=$(awk -v a="${seam[k]}" -v b="$(json_num $key <"$tmp/diff.json")" -v n="${n:-0}" \
                'BEGIN { print a + b * n }')
            k=$((k + 1))
        done
        # the peer grid on this sparse volume's seam pixels
        if [ "$name" = sparse ]; then
            for g in $grids; do
                [ "$(awk -v a="$g" -v b="$finest" 'BEGIN { print (a == b) }')" = 1 ] && peer_vol=$tmp/grid-$g.probes
            done
        fi
        if [ -n "$peer_vol" ] && [ -s "$peer_vol" ]; then
            # shellcheck disable=SC2086 # a view is render arguments
            "$pb" render "$scene" --volume "$peer_vol" --seams-of "$vol" --mode diff --json --size "$size" \
                ${spp:+--spp $spp} $view ${refs[$i]:+--reference ${refs[$i]}} -o "$tmp/diff.png" 2>/dev/null \
                >"$tmp/peer.json"
            n=$(json_num seam_pixels <"$tmp/peer.json")
            k=0
            for key in relative_rmse_seams p95_relative_error_seams; do
                peer_seam[k]=$(awk -v a="${peer_seam[k]}" -v b="$(json_num $key <"$tmp/peer.json")" -v n="${n:-0}" \
                    'BEGIN { print a + b * n }')
                k=$((k + 1))
            done
        fi
        k=0
        for key in seam_pixels off_seam_pixels surface_pixels; do
            n=$(json_num $key <"$tmp/diff.json")
            px[k]=$((px[k] + ${n:-0}))
            k=$((k + 1))
        done
        v=$((v + 1))
    done
    rmse=$(awk -v a="$rmse" -v n="$v" 'BEGIN { printf "%.4f", a / n }')
    p95=$(awk -v a="$p95" -v n="$v" 'BEGIN { printf "%.4f", a / n }')
    local seams="- - - - -"
    if [ "$name" = sparse ]; then
        seams=""
        for k in 0 1 2 3; do
            n=${px[$((k / 2))]}
            seams+="$(awk -v a="${seam[k]}" -v n="$n" 'BEGIN { printf "%.4f", (n > 0 ? a / n : 0) }') "
        done
        seams+="$(awk -v a="${px[0]}" -v n="${px[2]}" 'BEGIN { printf "%.3f", (n > 0 ? a / n : 0) }')"
        if [ -n "$peer_vol" ]; then
            for k in 0 1; do
                seams+=" $(awk -v a="${peer_seam[k]}" -v n="${px[0]}" 'BEGIN { printf "%.4f", (n > 0 ? a / n : 0) }')"
            done
        else
            seams+=" - -"
        fi
    else
        seams+=" - -"
    fi
    rows+=("$name $param $probes $bytes $ms $rmse $p95 $seams")
}

for s in $grids; do
    measure grid "$s" --spacing "$s"
done
for e in $errors; do
    # shellcheck disable=SC2086 # sparse_args is bake arguments
    measure sparse "$e" --spacing "$finest" --layout sparse --max-level "$max_level" --refine-error "$e" $sparse_args
done

# the peer: the finest grid
peer=""
for r in "${rows[@]}"; do
    set -- $r
    [ "$1" = grid ] && [ "$(awk -v a="$2" -v b="$finest" 'BEGIN { print (a == b) }')" = 1 ] && peer=$r
done
peer_is_grid=0
[ -n "$peer" ] && peer_is_grid=1
[ -n "$peer" ] || peer=${rows[0]}
set -- $peer
peer_probes=$3 peer_bytes=$4 peer_ms=$5
ratio() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.3f", (b > 0 ? a / b : 0) }'; }

stem=$out/$(basename "$scene" | sed 's/\.[^.]*$//')
printf '\n%-7s %8s %9s %11s %9s %11s %9s %11s %10s %10s %10s %10s %10s %10s %10s %10s %10s\n' layout param probes \
    "vs grid" bytes "vs grid" "bake ms" "vs grid" rmse_surf p95_rel rmse_seam p95_seam rmse_off p95_off seam_frac \
    peer_rmse_s peer_p95_s
echo "layout,param,probes,probes_ratio,bytes,bytes_ratio,bake_ms,bake_ratio,relative_rmse_surfaces,p95_relative_error,\
relative_rmse_seams,p95_relative_error_seams,relative_rmse_off_seams,p95_relative_error_off_seams,seam_fraction,\
peer_relative_rmse_seams,peer_p95_relative_error_seams" >"$stem.csv"
json="{\"scene\": \"$(basename "$scene")\", \"args\": \"${args[*]}\", \"size\": \"$size\", \"views\": ${#views[@]},"
json+=" \"probe_spp\": $spp, \"reference_spp\": $ref_spp,"
json+=" \"cores\": $(nproc), \"device\": \"$device\", \"peer\": \"grid $finest m\", \"rows\": ["
sep=""
for r in "${rows[@]}"; do
    set -- $r
    printf '%-7s %8s %9s %11s %9s %11s %9s %11s %10s %10s %10s %10s %10s %10s %10s %10s %10s\n' "$1" "$2" "$3" \
        "$(ratio "$3" "$peer_probes")" "$4" "$(ratio "$4" "$peer_bytes")" "$5" "$(ratio "$5" "$peer_ms")" "$6" "$7" \
        "$8" "$9" "${10}" "${11}" "${12}" "${13}" "${14}"
    csv_seams="$8,$9,${10},${11},${12}" json_seams="$8, $9, ${10}, ${11}, ${12}"
    [ "$8" = - ] && csv_seams=",,,," json_seams="null, null, null, null, null"
    csv_peer="${13},${14}" json_peer_r=${13} json_peer_p=${14}
    [ "${13}" = - ] && csv_peer="," json_peer_r=null json_peer_p=null
    echo "$1,$2,$3,$(ratio "$3" "$peer_probes"),$4,$(ratio "$4" "$peer_bytes"),$5,$(ratio "$5" "$peer_ms"),$6,$7,$csv_seams,$csv_peer" \
        >>"$stem.csv"
    IFS=, read -r s1 s2 s3 s4 s5 <<<"${json_seams// /}"
    json+="$sep{\"layout\": \"$1\", \"param\": $2, \"probes\": $3, \"bytes\": $4, \"bake_ms\": $5,"
    json+=" \"relative_rmse_surfaces\": $6, \"p95_relative_error\": $7, \"relative_rmse_seams\": $s1,"
    json+=" \"p95_relative_error_seams\": $s2, \"relative_rmse_off_seams\": $s3, \"p95_relative_error_off_seams\": $s4,"
    json+=" \"seam_fraction\": $s5, \"peer_relative_rmse_seams\": $json_peer_r, \"peer_p95_relative_error_seams\": $json_peer_p}"
    sep=", "
done
echo "$json]}" >"$stem.json"
echo
echo "param: grid spacing (m), or the sparse layout's --refine-error (finest spacing $finest m)"
echo "wrote $stem.csv and $stem.json"
# every row measured: probes and bytes > 0, both errors numbers
for r in "${rows[@]}"; do
    set -- $r
    awk -v p="$3" -v b="$4" -v e="$6" -v q="$7" 'BEGIN { exit !(p > 0 && b > 0 && e ~ /^[0-9.]+$/ && q ~ /^[0-9.]+$/) }' ||
        { echo "sparse_vs_grid: row '$r' is incomplete" >&2; exit 1; }
    [ "$1" != sparse ] || awk -v a="$8" -v c="${10}" 'BEGIN { exit !(a ~ /^[0-9.]+$/ && c ~ /^[0-9.]+$/) }' ||
        { echo "sparse_vs_grid: sparse row '$r' has no seam metrics" >&2; exit 1; }
    # with the finest grid among the grids, its error on the sparse seams too
    [ "$1" != sparse ] || [ "$peer_is_grid" != 1 ] || awk -v a="${13}" 'BEGIN { exit !(a ~ /^[0-9.]+$/) }' ||
        { echo "sparse_vs_grid: sparse row '$r' has no peer seam metrics" >&2; exit 1; }
done
