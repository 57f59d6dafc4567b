#!/usr/bin/env bash
# Command-line behaviour: exit codes, one-line errors naming the file, JSON
# keys. Usage: test_cli.sh PROBEBAKE SOURCE_DIR MAKE_TEST_VOLUME
# (PB_CLI_PART=timed|untimed|all, PB_CLI_GPU=0: the checks without a device,
# PB_CLI_DEVICE_ONLY=1: the checks with one; their set-up still runs)
set -u
pb=$1
src=$2
make_volume=$3
demo=$src/tests/scenes/demo.gltf
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
passed=0
failed=0
# the checks that need no device are skipped until the device's begin, when
# test_cli_nogpu runs them in the same suite (ctest runs test_cli so)
skipping=${PB_CLI_DEVICE_ONLY:-0}

# expect NAME WANT_EXIT REGEX -- command...: exit code and output (stdout+stderr) must match
expect() {
    [ "$skipping" = 1 ] && return 0
    local name=$1 want=$2 regex=$3
    shift 4
    local out rc
    out=$("$@" 2>&1)
    rc=$?
    if [ "$rc" -eq "$want" ] && grep -Eq -- "$regex" <<<"$out"; then
        passed=$((passed + 1))
        echo "[  OK  ] $name"
    else
        failed=$((failed + 1))
        echo "[ FAIL ] $name: exit $rc (want $want), output:"
        sed 's/^/    /' <<<"$out" | head -20
    fi
}

# a failure prints exactly one error line
one_error_line() {
    [ "$skipping" = 1 ] && return 0
    local name=$1
    shift 2
    local n
    n=$("$@" 2>&1 >/dev/null | grep -c 'error:')
    if [ "$n" -eq 1 ]; then
        passed=$((passed + 1))
        echo "[  OK  ] $name"
    else
        failed=$((failed + 1))
        echo "[ FAIL ] $name: $n error lines"
    fi
}

# signal_after SIGNAL SECONDS LOG COMMAND...: runs COMMAND in the background
# (output to LOG), sends SIGNAL SECONDS after it has chosen its device, and
# sets sig_rc (its exit code) and sig_ms (how long it took to exit after the
# signal)
signal_after() {
    local sig=$1 delay=$2 log=$3
    shift 3
    "$@" >"$log" 2>&1 &
    local pid=$! t0
    for _ in $(seq 1 100); do grep -q 'using device' "$log" && break; sleep 0.1; done
    sleep "$delay"
    t0=$(date +%s%N)
    kill -"$sig" "$pid"
    wait "$pid"
    sig_rc=$?
    sig_ms=$(( ($(date +%s%N) - t0) / 1000000 ))
}

# Ctrl-C stops a bake and a render within a second. Timed, so it runs alone
# (PB_CLI_PART=timed: ctest's RUN_SERIAL test_cli_interrupt); the rest of
# this script (PB_CLI_PART=untimed) may run beside other tests.
interrupt_checks() {
    # Ctrl-C during a long bake: exit 130 after 'bake cancelled', and no file
    signal_after INT 2 "$tmp/int.log" "$pb" bake "$demo" --spacing 0.25 --rays 1024 --passes 1000 -o "$tmp/int.probes"
    expect bake-interrupted 0 "^130 absent .*bake cancelled" -- \
        bash -c "echo $sig_rc \$([ -e '$tmp/int.probes' ] && echo present || echo absent) \$(tr '\n' ' ' <'$tmp/int.log')"
    # submissions are kept near 0.25 s, so the cancel lands within a second
    expect bake-interrupt-within-1s 0 "^stopped in [0-9]+ ms: yes" -- \
        bash -c "echo stopped in $sig_ms ms: \$([ $sig_ms -lt 1000 ] && echo yes || echo no)"
    # Ctrl-C during a long render: same promise
    signal_after INT 2 "$tmp/rint.log" "$pb" render "$demo" --size 320x240 --spp 4096 -o "$tmp/int.png"
    expect render-interrupted 0 "^130 absent [0-9]+ .*render cancelled" -- \
        bash -c "echo $sig_rc \$([ -e '$tmp/int.png' ] && echo present || echo absent) $sig_ms \$(tr '\n' ' ' <'$tmp/rint.log')"
    expect render-interrupt-within-1s 0 "^yes" -- bash -c "[ $sig_ms -lt 1000 ] && echo yes || echo no $sig_ms"
}

part=${PB_CLI_PART:-all}
case $part in
all | timed | untimed) ;;
*) echo "PB_CLI_PART is all, timed or untimed, not '$part'"; exit 2 ;;
esac
if [ "$part" = timed ]; then
    interrupt_checks
    echo "$passed passed, $failed failed"
    [ "$failed" -eq 0 ]
    exit
fi

expect help 0 '^usage:' -- "$pb" --help
expect version 0 '^probebake [0-9]+\.[0-9]+\.[0-9]+$' -- "$pb" --version
expect no-command 2 'usage:' -- "$pb"
expect unknown-command 2 "unknown command 'frobnicate'" -- "$pb" frobnicate
expect unknown-option 2 "unknown option '--bogus'" -- "$pb" info "$demo" --bogus
expect info-text 0 'triangles +40 kept of 40' -- "$pb" info "$demo"
expect info-json-triangles 0 '"triangles": 40,' -- "$pb" info "$demo" --json
expect info-json-lights 0 '"lights": \[\{"type": "point"' -- "$pb" info "$demo" --json
expect info-json-bounds 0 '"bounds_min": \[-2, 0, -2.5\]' -- "$pb" info "$demo" --json
expect info-extensions 0 '^extensions  used: KHR_lights_punctual, KHR_materials_emissive_strength; applied: KHR_lights_punctual, KHR_materials_emissive_strength$' -- "$pb" info "$demo"
# names from the file reach the terminal printable: a light named with an escape
# sequence, a line break and a C1 control (U+009B, CSI), its e-acute kept as it is;
# an unsupported required extension's name in the error
sed '0,/"name": "lamp"/s//"name": "lamp\\u001b[2J\\nline\\u009b31m\\u00e9"/' "$demo" >"$tmp/escapes.gltf"
expect info-name-printable 0 "^lights +1: point 'lamp\\\\x1b\\[2J\\\\x0aline\\\\u009b31m[^'\\\\]+' " -- "$pb" info "$tmp/escapes.gltf"
expect info-no-raw-escape 0 '^0$' -- bash -c "'$pb' info '$tmp/escapes.gltf' 2>&1 | tr -dc '\\033' | wc -c"
sed 's/"extensionsUsed": \[/"extensionsRequired": ["EXT_\\u001b[31mred"], "extensionsUsed": ["EXT_\\u001b[31mred", /' \
    "$demo" >"$tmp/escapes-required.gltf"
expect error-name-printable 1 '^probebake: error: .*requires extension EXT_\\x1b\[31mred, which' -- \
    "$pb" info "$tmp/escapes-required.gltf"
one_error_line error-name-one-line -- "$pb" info "$tmp/escapes-required.gltf"
expect info-json-extensions 0 '"extensions_applied": \["KHR_lights_punctual", "KHR_materials_emissive_strength"\],' -- "$pb" info "$demo" --json
expect info-json-bounds-max 0 '"bounds_max": \[2, 3, 2.5\]' -- "$pb" info "$demo" --json
expect info-shading-flat 0 '^shading     0 of 40 triangles smooth' -- "$pb" info "$demo"
expect info-glass 0 '^materials   3 \(0 emissive, 0 alpha-masked, 1 blended, 1 of them thin glass; 0 normal-mapped\)' -- \
    "$pb" info "$src/tests/scenes/skylight.gltf"
expect info-glass-json 0 '"glass_materials": 1,' -- "$pb" info "$src/tests/scenes/skylight.gltf" --json
expect shading-normals-bad 2 "error: --shading-normals takes vertex or face" -- "$pb" info "$demo" --shading-normals x
expect normal-maps-bad 2 "error: --normal-maps takes on or off" -- "$pb" info "$demo" --normal-maps x
helmet=$src/../shared/scenes/samples/DamagedHelmet/DamagedHelmet.gltf
if [ -f "$helmet" ]; then # its occlusion map is counted, not decoded; its normal map too under --normal-maps off
    expect info-textures-unread 0 '^textures    5 \(of the file.s 5, 1 the bake never reads, not decoded' -- \
        "$pb" info "$helmet"
    expect info-normal-mapped 0 '^materials   2 .*; 1 normal-mapped\)' -- "$pb" info "$helmet"
    expect info-json-textures-in 0 '"textures_in": 5,' -- "$pb" info "$helmet" --json
    expect info-json-textures-unread 0 '"textures_unread": 1,' -- "$pb" info "$helmet" --json
    expect info-json-normal-maps-off 0 '"normal_mapped_materials": 0,' -- "$pb" info "$helmet" --json --normal-maps off
    expect info-json-normal-maps-off-unread 0 '"textures_unread": 2,' -- "$pb" info "$helmet" --json --normal-maps off
else
    echo "skip info-textures-unread: $helmet absent"
fi
# the bundled normal-mapped scene (scripts/make_normal_map_scene.py)
expect info-bumps 0 '^materials   2 .*; 1 normal-mapped\)' -- "$pb" info "$src/tests/scenes/bumps.gltf"
alphablend=$src/../shared/scenes/samples/AlphaBlendModeTest/AlphaBlendModeTest.gltf
if [ -f "$alphablend" ]; then # its normal-mapped box has TANGENT: read, counted; not under --normal-maps off
    expect info-tangents 0 '^shading     0 of 61 triangles smooth .*, 30 with the file.s tangents' -- \
        "$pb" info "$alphablend"
    expect info-json-tangents-off 0 '"tangent_triangles": 0,' -- "$pb" info "$alphablend" --json --normal-maps off
else
    echo "skip info-tangents: $alphablend absent"
fi
duck=$src/../shared/scenes/samples/Duck/Duck.gltf
if [ -f "$duck" ]; then # vertex normals shade smooth, unless --shading-normals face
    expect info-shading-duck 0 '^shading     4183 of 4212 triangles smooth' -- "$pb" info "$duck"
    expect info-shading-duck-face 0 '"smooth_triangles": 0,' -- "$pb" info "$duck" --json --shading-normals face
else
    echo "skip info-shading-duck: $duck absent"
fi
expect info-needs-scene 2 'needs a SCENE' -- "$pb" info
expect info-missing 1 "error: $tmp/missing.gltf: cannot open" -- "$pb" info "$tmp/missing.gltf"
printf '{"asset": {"version": "2.0"}, "meshes": [' >"$tmp/broken.gltf"
expect info-malformed 1 "error: $tmp/broken.gltf: " -- "$pb" info "$tmp/broken.gltf"
one_error_line info-malformed-one-line -- "$pb" info "$tmp/broken.gltf"
expect rays-zero 2 "--rays '0' is not an integer in \[1, 65536\]" -- "$pb" trace "$demo" --rays 0
expect probes-negative 2 "--probes '-5'" -- "$pb" trace "$demo" --probes -5
expect probes-garbage 2 "--probes 'lots'" -- "$pb" trace "$demo" --probes lots
expect device-missing-value 2 '--device needs a value' -- "$pb" trace "$demo" --device
expect trace-needs-scene 2 'trace needs a SCENE file' -- "$pb" trace
expect shard-out-of-range 2 "--shard '3/3' is not I/N with 0 <= I < N" -- "$pb" bake "$demo" --shard 3/3 -o "$tmp/x.probes"
expect shard-garbage 2 "--shard 'half' is not I/N" -- "$pb" bake "$demo" --shard half -o "$tmp/x.probes"
expect merge-needs-parts 2 'merge needs OUT.probes and the parts' -- "$pb" merge "$tmp/m.probes"
expect merge-missing-part-file 1 "error: $tmp/nope.probes: " -- "$pb" merge "$tmp/m.probes" "$tmp/nope.probes"
expect devices-and-device 2 '--devices splits the bake by device: drop --device' -- \
    "$pb" bake "$demo" --devices 0,0 --device 0 -o "$tmp/x.probes"
expect layout-garbage 2 "--layout 'octree' is not grid or sparse" -- "$pb" bake "$demo" --layout octree -o "$tmp/x.probes"
expect max-level-range 2 "--max-level '3' is not an integer in \[0, 2\]" -- "$pb" bake "$demo" --max-level 3 -o "$tmp/x.probes"
expect refine-error-garbage 2 "--refine-error '-1' is not a relative error" -- "$pb" bake "$demo" --refine-error -1 -o "$tmp/x.probes"
expect target-error-range 2 "--target-error '1' is not a relative error in \(0, 1\)" -- "$pb" bake "$demo" --target-error 1 -o "$tmp/x.probes"
expect max-level-needs-sparse 2 '--max-level, --refine-error, --refine-test, --refine-seams and --seam-error shape a sparse layout: add --layout sparse' -- \
    "$pb" bake "$demo" --max-level 1 -o "$tmp/x.probes"
expect refine-test-garbage 2 "--refine-test 'pixel' is not surface or probe" -- \
    "$pb" bake "$demo" --layout sparse --refine-test pixel -o "$tmp/x.probes"
expect refine-seams-range 2 "--refine-seams '9' is not a number of rounds from 0 to 8" -- \
    "$pb" bake "$demo" --layout sparse --refine-seams 9 -o "$tmp/x.probes"
expect seam-error-garbage 2 "--seam-error '0' is not a relative error in \(0, 100\)" -- \
    "$pb" bake "$demo" --layout sparse --refine-seams 1 --seam-error 0 -o "$tmp/x.probes"
expect seam-error-needs-seams 2 '--seam-error sets the seam test.s threshold: add --refine-seams N' -- \
    "$pb" bake "$demo" --layout sparse --seam-error 0.5 -o "$tmp/x.probes"
expect seam-error-needs-seams-no-file 0 '' -- test ! -e "$tmp/x.probes"
# option combinations are refused before any file is read: the scene here does not exist
expect combination-before-scene 2 'add --layout sparse' -- "$pb" bake "$tmp/missing.gltf" --refine-seams 1 -o "$tmp/x.probes"
expect devices-and-shard 2 '--devices splits the bake by device: drop --shard' -- \
    "$pb" bake "$tmp/missing.gltf" --devices 0,0 --shard 0/2 -o "$tmp/x.probes"
expect sparse-and-points 2 '--layout sparse places its own probes: not with --points' -- \
    "$pb" bake "$tmp/missing.gltf" --layout sparse --points "$tmp/missing.json" -o "$tmp/x.probes"

# inspect: a fixture volume (tests/make_test_volume.c)
"$make_volume" "$tmp/v.probes"
expect inspect-text 0 'probes +6 = 3 x 2 x 1' -- "$pb" inspect "$tmp/v.probes"
expect inspect-flags 0 '5 valid, 1 relocated, 1 dilated' -- "$pb" inspect "$tmp/v.probes"
expect inspect-json-count 0 '"probes": 6,' -- "$pb" inspect "$tmp/v.probes" --json
expect inspect-json-probe 0 '"index": 1, "position": \[1000001, 2.25, -5\], "offset": \[0, 0.25, 0\], "flags": \["valid", "relocated"\], "paths": 2048, "std_error": 0.125, "sh": \[1, 1.00999999' -- \
    "$pb" inspect "$tmp/v.probes" --json --probe 1
expect inspect-json-last 0 '"index": 5, .*"sh": \[5, .*5.26000023\]\}$' -- "$pb" inspect "$tmp/v.probes" --json
expect inspect-probe-text 0 'probe 4 at .*\["dilated"\]' -- "$pb" inspect "$tmp/v.probes" --probe 4
expect inspect-probe-error 0 '^5120 paths, relative standard error of its irradiance 1.56 %$' -- "$pb" inspect "$tmp/v.probes" --probe 4
expect inspect-probe-error-unknown 0 '^6144 paths, standard error unknown' -- "$pb" inspect "$tmp/v.probes" --probe 5
expect inspect-json-unknown-null 0 '"index": 5, .*"paths": 6144, "std_error": null,' -- "$pb" inspect "$tmp/v.probes" --json
# of 5 probes' errors the p95 by nearest rank is the worst (the 4th, 12.5 %, was printed before)
expect inspect-error-summary 0 'median 6.25 %, p95 25 %, worst 25 % \(5 probes\)' -- "$pb" inspect "$tmp/v.probes"
expect inspect-probe-missing 1 "probe 6 does not exist \(6 probes\)" -- "$pb" inspect "$tmp/v.probes" --probe 6
expect inspect-atlas 0 "wrote $tmp/atlas.png: 34x23, depth atlas of 6 probes" -- \
    "$pb" inspect "$tmp/v.probes" --atlas "$tmp/atlas.png"
expect inspect-sh-view 0 "wrote $tmp/sh.png: 52x35, SH irradiance view of 6 probes" -- \
    "$pb" inspect "$tmp/v.probes" --sh-view "$tmp/sh.png"
expect inspect-atlas-unwritable 1 "error: $tmp/no/such/dir/a.png: cannot write in $tmp/no/such/dir: No such file or directory" -- \
    "$pb" inspect "$tmp/v.probes" --atlas "$tmp/no/such/dir/a.png"
# the two debug images together or not at all: the SH view's folder is missing,
# so the depth atlas (made first) is not left behind either
expect inspect-views-neither 1 "error: $tmp/no/such/dir/s.png: cannot write in" -- \
    "$pb" inspect "$tmp/v.probes" --atlas "$tmp/both-a.png" --sh-view "$tmp/no/such/dir/s.png"
expect inspect-views-neither-left 0 '^absent$' -- bash -c "[ -e '$tmp/both-a.png' ] && echo present || echo absent"
expect export-textures 0 "wrote $tmp/tex/manifest.json, probes.ktx2, sh.ktx2, depth.ktx2: 6 probes \(3 x 2 x 1\)" -- \
    "$pb" export "$tmp/v.probes" --textures "$tmp/tex"
expect export-manifest 0 '"pb_tex_width": 42,' -- cat "$tmp/tex/manifest.json"
expect export-no-dir 2 'export needs --textures DIR' -- "$pb" export "$tmp/v.probes"
expect export-into-file 1 "error: $tmp/v.probes: exists and is not a directory" -- \
    "$pb" export "$tmp/v.probes" --textures "$tmp/v.probes"
head -c 700 "$tmp/v.probes" >"$tmp/cut.probes"
expect inspect-truncated 1 "error: $tmp/cut.probes: file is 700 bytes" -- "$pb" inspect "$tmp/cut.probes"
expect inspect-not-volume 1 "error: $demo: not a probebake volume" -- "$pb" inspect "$demo"

# points files: parsed before any device work
printf '{"points": [[0, 1, 0], [1, 2]]}' >"$tmp/bad1.json"
expect points-short-vector 1 "error: $tmp/bad1.json: expected ','" -- "$pb" bake "$demo" --points "$tmp/bad1.json" -o "$tmp/x.probes"
printf '{"points": [{"id": 3, "position": [0,1,0]}, {"id": 3, "position": [1,1,0]}]}' >"$tmp/bad2.json"
expect points-duplicate-id 1 "two points share id 3" -- "$pb" bake "$demo" --points "$tmp/bad2.json" -o "$tmp/x.probes"
printf '{"points": []}' >"$tmp/bad3.json"
expect points-empty 1 "$tmp/bad3.json: no points" -- "$pb" bake "$demo" --points "$tmp/bad3.json" -o "$tmp/x.probes"
printf '{"pointz": []}' >"$tmp/bad4.json"
expect points-unknown-key 1 'unknown key "pointz"' -- "$pb" bake "$demo" --points "$tmp/bad4.json" -o "$tmp/x.probes"
# each malformed point names the file and the point; nothing is written
points_bad() { # name, file contents, the error expected
    printf '%s' "$2" >"$tmp/$1.json"
    expect "points-$1" 1 "^probebake: error: $tmp/$1.json: $3" -- "$pb" bake "$demo" --points "$tmp/$1.json" -o "$tmp/$1.probes"
    expect "points-$1-wrote-nothing" 0 '^absent$' -- bash -c "[ -e '$tmp/$1.probes' ] && echo present || echo absent"
}
points_bad not-a-number '{"points": [[0, x, 0]]}' 'expected a finite number near "x, 0\]\]\}"'
points_bad out-of-range '{"points": [[0, 1e999, 0]]}' 'expected a finite number near "1e999'
points_bad negative-id '{"points": [[0, 0, 0], {"id": -1, "position": [0, 1, 0]}]}' 'point 1: id must be a non-negative integer'
points_bad fractional-id '{"points": [{"id": 1.5, "position": [0, 1, 0]}]}' 'point 0: id must be a non-negative integer'
points_bad point-key '{"points": [{"id": 1, "pos": [0, 1, 0]}]}' 'point 0: unknown key "pos"'
points_bad no-position '{"points": [[0, 0, 0], {"id": 4}]}' 'point 1 has no position'
points_bad negative-spacing '{"spacing": -0.5, "points": [[0, 0, 0]]}' 'spacing must be >= 0'

# environment maps: read and checked before any device work. A 4x2 flat
# Radiance file: radiance 1 (RGBE 128,128,128,129) everywhere.
{
    printf '#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 2 +X 4\n'
    for _ in 1 2 3 4 5 6 7 8; do printf '\x80\x80\x80\x81'; done
} >"$tmp/sky.hdr"
head -c 40 "$tmp/sky.hdr" >"$tmp/cut.hdr"
expect env-missing 1 "error: $tmp/none.hdr: cannot open: No such file or directory" -- \
    "$pb" bake "$demo" --env "$tmp/none.hdr" -o "$tmp/x.probes"
expect env-not-hdr 1 "error: $demo: neither a Radiance .hdr nor an OpenEXR file" -- \
    "$pb" bake "$demo" --env "$demo" -o "$tmp/x.probes"
# an EXR cut short: the OpenEXR magic number, then the start of a header
printf '\x76\x2f\x31\x01\x02\x00\x00\x00channels' >"$tmp/cut.exr"
expect env-truncated-exr 1 "error: $tmp/cut.exr: cannot decode the EXR file" -- \
    "$pb" bake "$demo" --env "$tmp/cut.exr" -o "$tmp/x.probes"
expect env-truncated 1 "error: $tmp/cut.hdr: cannot decode the .hdr file" -- \
    "$pb" bake "$demo" --env "$tmp/cut.hdr" -o "$tmp/x.probes"
expect env-and-sky 1 '--sky and --env both give the environment: choose one' -- \
    "$pb" bake "$demo" --env "$tmp/sky.hdr" --sky 1,1,1 -o "$tmp/x.probes"
expect env-bad-intensity 2 "--env-intensity '-1' is not a finite scale >= 0" -- \
    "$pb" bake "$demo" --env "$tmp/sky.hdr" --env-intensity -1 -o "$tmp/x.probes"
expect env-bad-rotation 2 "--env-rotation 'nan' is not an angle in degrees" -- \
    "$pb" bake "$demo" --env "$tmp/sky.hdr" --env-rotation nan -o "$tmp/x.probes"
expect sh-window-bad 2 "--sh-window 'gauss': use none, hanning" -- "$pb" bake "$demo" --sh-window gauss -o "$tmp/x.probes"
expect sh-window-bad-width 2 "--sh-window 'lanczos:0'" -- "$pb" bake "$demo" --sh-window lanczos:0 -o "$tmp/x.probes"
expect max-lights-bad 2 "--max-lights-per-hit '0' is not an integer in \[1, 1048576\]" -- \
    "$pb" bake "$demo" --max-lights-per-hit 0 -o "$tmp/x.probes"
expect relocation-rays-bad 2 "--relocation-rays '0' is not an integer in \[1, 65536\]" -- \
    "$pb" bake "$demo" --relocation-rays 0 -o "$tmp/x.probes"
expect clamp-bad 2 "--clamp-indirect '-3' is not a positive radiance" -- "$pb" bake "$demo" --clamp-indirect -3 -o "$tmp/x.probes"
expect indirect-bad 2 '--indirect takes path or volume' -- "$pb" bake "$demo" --indirect photons -o "$tmp/x.probes"
expect skip-inside-bad 2 '--skip-inside takes on or off' -- "$pb" bake "$demo" --skip-inside maybe -o "$tmp/x.probes"
expect scene-loads-bad 2 '--scene-loads takes auto, address or texel' -- "$pb" trace "$demo" --scene-loads words

# settings that need no scene are refused before the scene is read (a large
# scene's load can take minutes) and before any device is made: here the
# scene would not load at all, and test_cli_nogpu has no device
printf '{"asset": {"version": "2.0"}, "buffers": [{"byteLength": 1e30}' >"$tmp/unloadable.gltf"
expect settings-before-load-relocation 1 "^probebake: error: 16 relocation rays per probe: at most the 8 rays per probe of a pass$" -- \
    "$pb" bake "$tmp/unloadable.gltf" --rays 8 --relocation-rays 16 -o "$tmp/x.probes"
expect settings-before-load-volume-shard 1 "^probebake: error: --indirect volume samples the whole previous bounce's volume: a part \\(--shard, --devices\\) cannot bake it alone" -- \
    "$pb" bake "$tmp/unloadable.gltf" --indirect volume --shard 0/2 -o "$tmp/x.probes"
expect settings-before-load-surface-error 1 "^probebake: error: --refine-error 5: the surface test's error is relative" -- \
    "$pb" bake "$tmp/unloadable.gltf" --layout sparse --refine-error 5 -o "$tmp/x.probes"
expect settings-before-load-sparse-target 1 "^probebake: error: --target-error in a sparse bake depends on every probe" -- \
    "$pb" bake "$tmp/unloadable.gltf" --layout sparse --target-error 0.1 --shard 1/2 -o "$tmp/x.probes"
printf '{"points": [[0, 0, 0]]}' >"$tmp/one-point.json"
expect settings-before-load-volume-points 1 "^probebake: error: --indirect volume samples the previous bounce's grid: it needs a grid" -- \
    "$pb" bake "$tmp/unloadable.gltf" --indirect volume --points "$tmp/one-point.json" -o "$tmp/x.probes"
expect settings-before-load-devices 1 "^probebake: error: --target-error in a sparse bake depends on every probe of each level: its parts \(--shard, --devices\)" -- \
    "$pb" bake "$tmp/unloadable.gltf" --layout sparse --target-error 0.1 --devices 0,0 -o "$tmp/x.probes"
# the same scene with good settings: its own error, naming it
expect settings-then-load 1 "^probebake: error: $tmp/unloadable.gltf: " -- \
    "$pb" bake "$tmp/unloadable.gltf" --rays 8 --relocation-rays 8 -o "$tmp/x.probes"

# non-finite or overflowing light and positions: refused before any device work (issue 9)
sed 's/"intensity": 15.0/"intensity": 1e38/' "$demo" >"$tmp/hot-light.gltf"
expect light-overflow 1 "error: $tmp/hot-light.gltf: light 0 'lamp' has intensity 1e\+38 .*at most 1e\+20" -- \
    "$pb" bake "$tmp/hot-light.gltf" -o "$tmp/x.probes"
expect light-overflow-render 1 "light 0 'lamp' has intensity 1e\+38" -- "$pb" render "$tmp/hot-light.gltf" -o "$tmp/x.png"
sed 's/"emissiveStrength": 8.0/"emissiveStrength": 1e38/' "$demo" >"$tmp/hot-panel.gltf"
expect emission-overflow 1 "error: $tmp/hot-panel.gltf: material [0-9]+ '[^']*' emits 1e\+38 \(emissive factor x strength\)" -- \
    "$pb" bake "$tmp/hot-panel.gltf" -o "$tmp/x.probes"
sed 's/"emissiveStrength": 8.0/"emissiveStrength": 1e39/' "$demo" >"$tmp/inf-panel.gltf"
expect emission-infinite 1 "emits inf" -- "$pb" bake "$tmp/inf-panel.gltf" -o "$tmp/x.probes"
expect sky-infinite 2 "--sky needs 3 comma-separated finite numbers, got 'inf,0,0'" -- \
    "$pb" bake "$demo" --sky inf,0,0 -o "$tmp/x.probes"
expect sky-overflow 1 'error: sky radiance \(1e\+38, 1e\+38, 1e\+38\): each must be finite, >= 0 and at most 1e\+20' -- \
    "$pb" bake "$demo" --sky 1e38,1e38,1e38 -o "$tmp/x.probes"
printf '{"points": [[0, 1, 0], [1e39, 0, 0]]}' >"$tmp/far.json"
expect points-overflow 1 "error: $tmp/far.json: point 1 at \(1e\+39, 0, 0\): coordinates must be within \+-1e\+15 m" -- \
    "$pb" bake "$demo" --points "$tmp/far.json" -o "$tmp/x.probes"
expect refusals-left-no-file 0 '^absent$' -- bash -c "[ -e '$tmp/x.probes' ] && echo present || echo absent"
# a file holding NaN (written by hand: the writer refuses them) is refused by the reader too
cp "$tmp/v.probes" "$tmp/nan.probes"
printf '\x00\x00\xc0\x7f' | dd of="$tmp/nan.probes" bs=1 seek=704 conv=notrunc status=none # SH[0] of probe 0
expect inspect-nan-refused 1 "error: $tmp/nan.probes: probe 0 has a NaN or infinite value in an SH coefficient" -- \
    "$pb" inspect "$tmp/nan.probes" --json
expect inspect-json-no-nan 0 '^clean$' -- \
    bash -c "'$pb' inspect '$tmp/nan.probes' --json | grep -Eqi '(: |\\[|, )-?(nan|inf)' && echo dirty || echo clean"
expect inspect-json-depth-unit 0 '"depth_unit": 0.25,' -- "$pb" inspect "$tmp/v.probes" --json

# inputs that are not regular files, outputs that must not be replaced (issue 10); checked before any device work
mkdir "$tmp/adir"
expect info-directory 1 "error: $tmp/adir: is a directory" -- "$pb" info "$tmp/adir"
expect bake-directory-scene 1 "error: $tmp/adir: is a directory" -- "$pb" bake "$tmp/adir" -o "$tmp/x.probes"
mkfifo "$tmp/scene.fifo"
expect info-fifo-no-hang 1 "error: $tmp/scene.fifo: is not a regular file \(a FIFO\)" -- timeout 20 "$pb" info "$tmp/scene.fifo"
expect inspect-fifo-no-hang 1 "is not a regular file \(a FIFO\)" -- timeout 20 "$pb" inspect "$tmp/scene.fifo"
expect points-fifo-no-hang 1 "error: $tmp/scene.fifo: is not a regular file \(a FIFO\)" -- \
    timeout 20 "$pb" bake "$demo" --points "$tmp/scene.fifo" -o "$tmp/x.probes"
cp "$demo" "$tmp/mine.gltf"
ln "$tmp/mine.gltf" "$tmp/mine-hard.gltf"
ln -s mine.gltf "$tmp/mine-link.gltf"
for out in mine.gltf mine-hard.gltf mine-link.gltf; do
    expect "bake-over-input-$out" 1 "error: $tmp/$out: is the same file as the input $tmp/mine.gltf" -- \
        "$pb" bake "$tmp/mine.gltf" -o "$tmp/$out"
done
expect render-over-input 1 "is the same file as the input" -- "$pb" render "$tmp/mine.gltf" -o "$tmp/mine-link.gltf"
expect inputs-intact 0 '^same$' -- bash -c "cmp -s '$demo' '$tmp/mine.gltf' && echo same || echo changed"
expect bake-output-directory 1 "error: $tmp/adir: is a directory: not an output" -- "$pb" bake "$demo" -o "$tmp/adir"
expect bake-output-missing-dir 1 "error: $tmp/nodir/v.probes: cannot write in $tmp/nodir: No such file or directory" -- \
    "$pb" bake "$demo" -o "$tmp/nodir/v.probes"
expect render-pfm-stdout 2 '--pfm writes beside -o FILE' -- "$pb" render "$demo" --pfm -o -
expect inspect-atlas-stdout 0 '^PNG$' -- bash -c "'$pb' inspect '$tmp/v.probes' --atlas - | head -c 4 | tail -c 3"
if [ "$(id -u)" = 0 ]; then # device nodes of our own in $tmp, never the machine's /dev
    mknod "$tmp/zero" c 1 5 && mknod "$tmp/null" c 1 3 && mknod "$tmp/full" c 1 7
    expect info-char-device 1 "error: $tmp/zero: is not a regular file \(a character device\)" -- "$pb" info "$tmp/zero"
    expect atlas-to-null 0 "wrote $tmp/null" -- "$pb" inspect "$tmp/v.probes" --atlas "$tmp/null"
    expect atlas-to-full 1 "error: $tmp/full: write failed: No space left on device" -- \
        "$pb" inspect "$tmp/v.probes" --atlas "$tmp/full"
    expect devices-still-devices 0 '^character special file character special file$' -- \
        bash -c "echo \$(stat -c %F '$tmp/null') \$(stat -c %F '$tmp/full')"
fi

# render: parameters checked before any device work
expect render-no-output 2 'render needs -o IMG.png' -- "$pb" render "$demo"
expect render-bad-size 2 "--size '0x10' is not WxH" -- "$pb" render "$demo" --size 0x10 -o "$tmp/r.png"
expect render-bad-fov 2 "--fov '200' is not a vertical field of view" -- "$pb" render "$demo" --fov 200 -o "$tmp/r.png"
expect render-bad-mode 2 "--mode 'pretty': use probes, reference" -- "$pb" render "$demo" --mode pretty -o "$tmp/r.png"
expect render-probes-needs-volume 2 '--mode probes needs --volume' -- "$pb" render "$demo" --mode probes -o "$tmp/r.png"
expect render-missing-volume 1 "error: $tmp/none.probes: cannot open" -- \
    "$pb" render "$demo" --volume "$tmp/none.probes" -o "$tmp/r.png"
expect render-no-such-camera 1 "camera 5 does not exist \(1 camera\)" -- "$pb" render "$demo" --camera 5 -o "$tmp/r.png"
expect render-eye-without-target 2 '--eye and --target go together' -- "$pb" render "$demo" --eye 0,1,2 -o "$tmp/r.png"
expect render-needs-scene 2 'render needs a SCENE' -- "$pb" render -o "$tmp/r.png"
expect render-camera-and-eye 2 'give --camera or --eye/--target, not both' -- \
    "$pb" render "$demo" --camera 0 --eye 0,1,2 --target 0,0,0 -o "$tmp/r.png"
expect render-scene-without-cameras 1 "^probebake: error: $src/tests/scenes/doorway.gltf: the scene has no cameras" -- \
    "$pb" render "$src/tests/scenes/doorway.gltf" --camera 0 -o "$tmp/r.png"
expect render-up-parallel 1 'up vector is parallel' -- \
    "$pb" render "$demo" --eye 0,1,0 --target 0,2,0 --up 0,-1,0 -o "$tmp/r.png"
expect render-eye-is-target 1 '^probebake: error: --eye and --target are the same point' -- \
    "$pb" render "$demo" --eye 0,1,0 --target 0,1,0 -o "$tmp/r.png"
expect render-bad-eye 2 "--eye '1,2' is not three" -- "$pb" render "$demo" --eye 1,2 --target 0,0,0 -o "$tmp/r.png"
expect render-spheres-need-volume 2 '--show-probes needs --volume' -- "$pb" render "$demo" --show-probes -o "$tmp/r.png"
expect render-no-partial-file 0 '^absent$' -- bash -c "[ -e '$tmp/r.png' ] && echo present || echo absent"
expect render-bad-emitter-sampling 2 '--emitter-sampling takes solid-angle or area' -- \
    "$pb" render "$demo" --emitter-sampling cosine -o "$tmp/r.png"

# no Vulkan driver at all: one clear line, exit 1, nothing else
expect no-driver-devices 1 'error: no Vulkan 1.2 driver found .*mesa-vulkan-drivers' -- \
    env VK_DRIVER_FILES=/nonexistent.json VK_ICD_FILENAMES=/nonexistent.json "$pb" devices
expect no-driver-trace 1 'error: no Vulkan 1.2 driver found' -- \
    env VK_DRIVER_FILES=/nonexistent.json VK_ICD_FILENAMES=/nonexistent.json "$pb" trace "$demo"
one_error_line no-driver-one-line -- env VK_DRIVER_FILES=/nonexistent.json VK_ICD_FILENAMES=/nonexistent.json "$pb" trace "$demo"

skipping=0
if [ "${PB_CLI_GPU:-1}" = 1 ]; then
    expect devices 0 'llvmpipe|GPU|CPU' -- "$pb" devices
    expect render-emitters-by-area 0 'wrote .*direct, 1 spp' -- \
        "$pb" render "$demo" --mode direct --size 32x24 --emitter-sampling area -o "$tmp/ea.png"
    # world coordinates on the command line keep double precision: the demo
    # moved 1e7 m away (float steps are 1 m there) takes --bounds and --eye
    # to the centimetre
    python3 -c 'import json, sys
d = json.load(open(sys.argv[1]))
scene = d["scenes"][d.get("scene", 0)]
d["nodes"].append({"name": "far", "translation": [1e7, 0, 1e7], "children": scene["nodes"]})
scene["nodes"] = [len(d["nodes"]) - 1]
json.dump(d, open(sys.argv[2], "w"))' "$demo" "$tmp/far.gltf"
    expect info-far-bounds 0 '^bounds      \(9999998, 0, 9999997\.5\) \.\. \(10000002, 3, 10000002\.5\) m$' -- \
        "$pb" info "$tmp/far.gltf"
    "$pb" bake "$tmp/far.gltf" --bounds 9999998.3,0.5,9999997.8,10000001.7,2.5,10000002.2 --counts 2,2,2 --rays 16 \
        --passes 1 --octmap-res 4 --quiet -o "$tmp/far.probes" >/dev/null
    expect bake-far-bounds 0 '"origin": \[9999999\.1[45][0-9]*, 1, 9999998\.(89|90)[0-9]*\],  *"spacing": \[1\.7[0-9]*, 1, 2\.2[0-9]*\]' -- \
        bash -c "'$pb' inspect '$tmp/far.probes' --json | tr -d '\n'"
    "$pb" render "$demo" --mode direct --size 32x24 --eye 0.3,1.5,2.3 --target 0.3,1.2,0 --pfm --quiet \
        -o "$tmp/near-eye.png" >/dev/null
    "$pb" render "$tmp/far.gltf" --mode direct --size 32x24 --eye 10000000.3,1.5,10000002.3 --target 10000000.3,1.2,1e7 \
        --pfm --quiet -o "$tmp/far-eye.png" >/dev/null
    expect render-far-eye 0 '^same view$' -- python3 -c 'import struct, sys
def pfm(path):
    b = open(path, "rb").read()
    head = b.split(b"\n", 3)
    return struct.unpack("<%df" % ((len(head[3])) // 4), head[3])
a, b = pfm(sys.argv[1]), pfm(sys.argv[2])
worst = max(abs(x - y) / max(1.0, abs(y)) for x, y in zip(a, b))
print("same view" if len(a) == len(b) and worst < 1e-3 else "differs by %g" % worst)' "$tmp/near-eye.pfm" "$tmp/far-eye.pfm"
    # straight down without --up: a plan view, -Z at the top of the image (as --up 0,0,-1 gives)
    expect render-plan-view 0 '^same$' -- bash -c "'$pb' render '$demo' --mode direct --size 32x24 --eye 0,2.9,0 \
        --target 0,0,0 --pfm --quiet -o '$tmp/plan.png' >/dev/null && '$pb' render '$demo' --mode direct --size 32x24 \
        --eye 0,2.9,0 --target 0,0,0 --up 0,0,-1 --pfm --quiet -o '$tmp/plan-up.png' >/dev/null &&
        cmp -s '$tmp/plan.pfm' '$tmp/plan-up.pfm' && echo same"
    expect devices-json 0 '"subgroup_size": [0-9]+.*"kernels": "(native64|portable)"' -- "$pb" devices --json
    expect trace-verify 0 'verify +GPU vs CPU reference: 0 mismatches' -- \
        "$pb" trace "$demo" --verify --validation --probes 64 --rays 128
    # the kernels for devices without 64-bit types, asked for on any device: the same hits
    expect trace-portable-kernels 0 'kernels: portable \(asked for\)' -- \
        "$pb" trace "$demo" --portable-kernels --verbose --validation --probes 64 --rays 32
    expect trace-portable-verify 0 'verify +GPU vs CPU reference: 0 mismatches' -- \
        "$pb" trace "$demo" --portable-kernels --verify --validation --probes 64 --rays 128
    # the BVH read through either load, asked for: the same hits
    for loads in address texel; do
        expect trace-loads-$loads 0 "scene loads: ${loads}[a-z]* \\(asked for\\)" -- \
            "$pb" trace "$demo" --scene-loads $loads --verbose --validation --probes 64 --rays 32
        expect trace-loads-$loads-verify 0 'verify +GPU vs CPU reference: 0 mismatches' -- \
            "$pb" trace "$demo" --scene-loads $loads --verify --validation --probes 64 --rays 128
    done
    expect trace-too-many-rays 1 "^probebake: error: $demo: [0-9]+ rays requested; at most 2\\^28 per trace" -- \
        "$pb" trace "$demo" --probes 10000 --rays 65536
    expect bake-tiny 0 "wrote $tmp/a.probes: 8 probes" -- \
        "$pb" bake "$demo" --counts 2,2,2 --rays 32 --passes 1 --octmap-res 4 --validation -o "$tmp/a.probes"
    expect bake-inspect 0 '"probes": 8,' -- "$pb" inspect "$tmp/a.probes" --json
    # every timing the file holds is filled: the upload (the CLI's) and the
    # relocation's GPU time (a part of trace and sh) were written as 0 before
    t='[0-9.e+-]+' pos='(0\.0*[1-9]|[1-9])[0-9.e+-]*' # a time, a time above 0
    expect bake-inspect-timings 0 "^time +load $t ms, bvh $t ms, upload $pos ms; GPU trace $pos ms, sh $t ms, depth $t ms \\(relocation: $pos ms of trace and sh\\); $pos ms total\$" -- \
        "$pb" inspect "$tmp/a.probes"
    expect bake-sparse 0 '^sparse: 2 levels, bricks 1 [0-9]+ .*; [0-9]+ bakes, [1-9][0-9]* test probes thrown away; [0-9]+ probes inside geometry dropped' -- \
        "$pb" bake "$demo" --layout sparse --max-level 1 --spacing 1 --rays 32 --passes 2 --octmap-res 4 --validation \
        -o "$tmp/s.probes"
    # the probe test (one probe inside each cell) is still there; the surface test's error is below 1
    expect bake-sparse-probe-test 0 '^sparse: 2 levels, bricks 1 [0-9]+ .*, 0 test probes thrown away' -- \
        "$pb" bake "$demo" --layout sparse --max-level 1 --spacing 1 --rays 16 --passes 1 --octmap-res 4 \
        --refine-test probe --refine-error 1 -o "$tmp/sp.probes"
    rm -f "$tmp/x.probes"
    expect refine-error-surface-below-1 1 "--refine-error 1: the surface test's error is relative to the larger of prediction and bake, so at most 1" -- \
        "$pb" bake "$demo" --layout sparse --spacing 1 --refine-error 1 -o "$tmp/x.probes"
    expect refine-error-surface-no-file 0 '' -- test ! -e "$tmp/x.probes"
    expect export-sparse 0 'sparse.ktx2: [0-9]+ probes in [0-9]+ bricks \(2 levels\)' -- \
        "$pb" export "$tmp/s.probes" --textures "$tmp/s-textures"
    expect inspect-sparse 0 '^level 1     spacing 1 m: [0-9]+ bricks' -- "$pb" inspect "$tmp/s.probes"
    expect inspect-sparse-refined 0 '^refined     where off by more than 0.1: surface test, its probes at 4x the passes; seam test 0 rounds' -- \
        "$pb" inspect "$tmp/s.probes"
    expect inspect-sparse-refined-json 0 '"refine_error": 0.1, "refine_test": "surface", "test_pass_scale": 4, "seam_rounds": 0' -- \
        "$pb" inspect "$tmp/s.probes" --json
    # the seam test: cells refined because a finer brick's hanging probe saw them err, recorded in the file
    expect bake-sparse-seams 0 '^sparse: 3 levels, .*refined [0-9]+ \([1-9][0-9]* at seams\)' -- \
        "$pb" bake "$demo" --layout sparse --spacing 0.5 --rays 32 --passes 1 --octmap-res 4 --refine-seams 2 \
        -o "$tmp/seams.probes"
    expect inspect-sparse-seams 0 'seam test 2 rounds, where missed by more than 0.1$' -- "$pb" inspect "$tmp/seams.probes"
    expect inspect-sparse-seams-json 0 '"seam_rounds": 2, "seam_error": 0.1}' -- "$pb" inspect "$tmp/seams.probes" --json
    # a seam threshold no miss reaches refines no seam cell, and is recorded
    expect bake-sparse-seam-error 0 '^sparse: 3 levels, .*refined [0-9]+ \(0 at seams\)' -- \
        "$pb" bake "$demo" --layout sparse --spacing 0.5 --rays 32 --passes 1 --octmap-res 4 --refine-seams 2 \
        --seam-error 50 -o "$tmp/seams100.probes"
    expect inspect-sparse-seam-error 0 'seam test 2 rounds, where missed by more than 50$' -- \
        "$pb" inspect "$tmp/seams100.probes"
    expect inspect-sparse-probe-test 0 '^refined     where off by more than 1: probe test' -- "$pb" inspect "$tmp/sp.probes"
    # the debug views of a sparse file: one tile per probe, in layout order
    sparse_probes=$("$pb" inspect "$tmp/s.probes" --json | sed -n 's/.*"probes": \([0-9]*\),.*/\1/p' | head -n 1)
    expect inspect-sparse-atlas 0 "depth atlas of $sparse_probes probes; tile frames by finest level" -- \
        "$pb" inspect "$tmp/s.probes" --atlas "$tmp/s-atlas.png"
    expect inspect-sparse-sh-view 0 "wrote $tmp/s-sh.png: [0-9]+x[0-9]+, .*$sparse_probes probes" -- \
        "$pb" inspect "$tmp/s.probes" --sh-view "$tmp/s-sh.png"
    expect render-sparse 0 "wrote $tmp/s.png: 32x24, probes" -- \
        "$pb" render "$demo" --volume "$tmp/s.probes" --size 32x24 --validation -o "$tmp/s.png"
    # a sparse volume's diff also reports the error where its levels meet and elsewhere
    # levels meeting in view: at 1 m every 3 m cell of the demo is refined, at 0.3 m some 0.9 m cells are not
    "$pb" bake "$demo" --layout sparse --max-level 1 --spacing 0.3 --rays 16 --passes 1 --octmap-res 4 \
        -o "$tmp/seams.probes" --quiet >/dev/null
    expect render-sparse-seams 0 '"seam_pixels": [1-9][0-9]*, "relative_rmse_seams": [0-9.]+, .*"p95_relative_error_off_seams": [0-9.]+, "unserved_pixels": 0, "levels": \[\{"level": 0, "pixels": [1-9][0-9]*, .*\{"level": 1, "pixels": [1-9][0-9]*, "relative_rmse": [0-9.]+, "p95_relative_error": [0-9.]+\}\]' -- \
        "$pb" render "$demo" --volume "$tmp/seams.probes" --mode diff --json --size 64x48 --spp 2 --eye 0,1.5,2.3 \
        --target 0,1.2,0 -o "$tmp/s-diff.png"
    # --indirect volume on a sparse layout: each bounce places its own bricks
    expect bake-sparse-indirect-volume 0 '^sparse: 2 levels, bricks 1 [0-9]+ .*; [0-9]+ bakes' -- \
        "$pb" bake "$demo" --layout sparse --max-level 1 --spacing 1 --rays 16 --passes 1 --octmap-res 4 --bounces 1 \
        --indirect volume --validation -o "$tmp/siv.probes"
    expect inspect-sparse-indirect-volume 0 'indirect volume' -- "$pb" inspect "$tmp/siv.probes"
    # one level: no two levels meet, so no pixel is on a seam
    "$pb" bake "$demo" --layout sparse --max-level 0 --spacing 1 --rays 16 --passes 1 --octmap-res 4 -o "$tmp/s0.probes" \
        --quiet >/dev/null
    expect render-sparse-one-level 0 '"seam_pixels": 0, .*"off_seam_pixels": [1-9][0-9]*, ' -- \
        "$pb" render "$demo" --volume "$tmp/s0.probes" --mode diff --json --size 64x48 --spp 2 --eye 0,1.5,2.3 \
        --target 0,1.2,0 -o "$tmp/s0-diff.png"
    "$pb" bake "$demo" --counts 2,2,2 --rays 32 --passes 1 --octmap-res 4 -o "$tmp/b.probes" --quiet >/dev/null
    "$pb" bake "$demo" --counts 2,2,2 --rays 32 --passes 1 --octmap-res 4 --seed 9 -o "$tmp/c.probes" --quiet >/dev/null
    # same seed: identical bytes except the timings block (offsets 184..247, docs/format.md)
    same=$(cmp -l "$tmp/a.probes" "$tmp/b.probes" | awk '$1 < 185 || $1 > 248' | wc -l)
    differ=$(cmp -l "$tmp/a.probes" "$tmp/c.probes" | awk '$1 < 185 || $1 > 248' | wc -l)
    expect bake-same-seed-same-bytes 0 '^0 [1-9]' -- echo "$same $differ"
    expect bake-zero-bounces 0 ', 0 bounces,' -- \
        "$pb" bake "$demo" --counts 2,2,2 --rays 32 --passes 1 --octmap-res 4 --bounces 0 -o "$tmp/z.probes"
    # quality presets and probe NEE: printed at the start, recorded in the file
    expect bake-quality-preview 0 'at quality preview: .* 128 rays x 2 passes, .*probe NEE on, guiding off' -- \
        "$pb" bake "$demo" --counts 2,2,2 --octmap-res 4 --quality preview --validation -o "$tmp/q.probes"
    expect bake-quality-inspect 0 '"techniques": \["probe-nee", "light-cells", "solid-angle"\],' -- "$pb" inspect "$tmp/q.probes" --json
    expect bake-quality-override 0 'at quality production: .* 32 rays x up to 4 passes \(until converged\)' -- \
        "$pb" bake "$demo" --counts 2,2,2 --octmap-res 4 --quality production --rays 32 --passes 4 -o "$tmp/q.probes"
    expect bake-guide-on 0 'guiding on' -- \
        "$pb" bake "$demo" --counts 2,2,2 --rays 32 --passes 1 --octmap-res 4 --guide on --validation -o "$tmp/g.probes"
    expect bake-guide-inspect 0 '"techniques": \["probe-nee", "guiding", "light-cells", "solid-angle"\],' -- "$pb" inspect "$tmp/g.probes" --json
    expect bake-light-cells-off 0 'light cells off' -- \
        "$pb" bake "$demo" --counts 2,2,2 --rays 32 --passes 1 --octmap-res 4 --light-cells off -o "$tmp/l.probes"
    expect bake-light-cells-off-inspect 0 'probe NEE on, guiding off, light cells off' -- "$pb" inspect "$tmp/l.probes"
    expect bake-bad-light-cells 2 '--light-cells takes on or off' -- "$pb" bake "$demo" --light-cells yes -o "$tmp/x.probes"
    # emitter samples by solid angle (the default) or by area: printed, recorded
    expect bake-emitters-by-area 0 'light cells on, emitters by area' -- \
        "$pb" bake "$demo" --counts 2,2,2 --rays 32 --passes 1 --octmap-res 4 --emitter-sampling area -o "$tmp/ea.probes"
    expect bake-emitters-by-area-inspect 0 'light cells on, emitters by area' -- "$pb" inspect "$tmp/ea.probes"
    expect bake-emitters-by-solid-angle-inspect 0 'light cells off, emitters by solid angle' -- "$pb" inspect "$tmp/l.probes"
    expect bake-bad-emitter-sampling 2 '--emitter-sampling takes solid-angle or area' -- \
        "$pb" bake "$demo" --emitter-sampling uniform -o "$tmp/x.probes"
    expect bake-bad-guide 2 '--guide takes on or off' -- "$pb" bake "$demo" --guide 7 -o "$tmp/x.probes"
    # --schedule wavefront: the default's volume byte for byte (bytes 185-248 are timings), validation silent
    expect bake-schedule-wavefront 0 "wrote $tmp/w.probes" -- "$pb" bake "$demo" --counts 2,2,2 --rays 32 --passes 1 \
        --octmap-res 4 --bounces 3 --schedule wavefront --validation -o "$tmp/w.probes"
    "$pb" bake "$demo" --counts 2,2,2 --rays 32 --passes 1 --octmap-res 4 --bounces 3 -o "$tmp/m.probes" >/dev/null 2>&1
    expect bake-schedule-same-bytes 0 '^0$' -- \
        bash -c "test -s '$tmp/w.probes' && cmp -l '$tmp/m.probes' '$tmp/w.probes' | awk '\$1 < 185 || \$1 > 248' | wc -l"
    # --schedule restart:K: the same bytes too (3 paths per lane: the last workgroup partly past the paths)
    expect bake-schedule-restart 0 "schedule restart:3 " -- "$pb" bake "$demo" --counts 2,2,2 --rays 32 --passes 1 \
        --octmap-res 4 --bounces 3 --schedule restart:3 --validation -o "$tmp/r.probes"
    expect bake-schedule-restart-same-bytes 0 '^0$' -- \
        bash -c "test -s '$tmp/r.probes' && cmp -l '$tmp/m.probes' '$tmp/r.probes' | awk '\$1 < 185 || \$1 > 248' | wc -l"
    expect bake-bad-schedule 2 '--schedule takes megakernel, wavefront or restart\[:K\]' -- \
        "$pb" bake "$demo" --schedule fast -o "$tmp/x.probes"
    for k in 0 65 x 8x; do
        expect bake-bad-restart-$k 2 '--schedule restart:K takes K from 1 to 64 paths per lane' -- \
            "$pb" bake "$demo" --schedule restart:$k -o "$tmp/x.probes"
    done
    expect bake-probe-nee-off 0 'probe NEE off' -- \
        "$pb" bake "$demo" --counts 2,2,2 --rays 32 --passes 1 --octmap-res 4 --probe-nee off -o "$tmp/q.probes"
    expect bake-probe-nee-off-inspect 0 'probe NEE off' -- "$pb" inspect "$tmp/q.probes"
    expect bake-bad-quality 2 '--quality takes preview, production or reference' -- \
        "$pb" bake "$demo" --quality best -o "$tmp/x.probes"
    expect bake-bad-probe-nee 2 '--probe-nee takes on or off' -- "$pb" bake "$demo" --probe-nee yes -o "$tmp/x.probes"
    expect bake-bounces-range 2 "--bounces '65' is not an integer in \[0, 64\]" -- \
        "$pb" bake "$demo" --bounces 65 -o "$tmp/x.probes"
    expect bake-bad-spacing 2 "--spacing '-1' is not a positive length" -- "$pb" bake "$demo" --spacing -1 -o "$tmp/x.probes"
    expect bake-no-output 2 'needs -o OUT.probes' -- "$pb" bake "$demo"
    expect bake-both-grids 2 'give --spacing or --counts, not both' -- \
        "$pb" bake "$demo" --spacing 1 --counts 2,2,2 -o "$tmp/x.probes"
    expect bake-bad-counts 2 "--counts needs 3 comma-separated finite numbers" -- "$pb" bake "$demo" --counts 2,2 -o "$tmp/x.probes"
    expect bake-missing-scene 1 "error: $tmp/none.gltf: cannot open" -- "$pb" bake "$tmp/none.gltf" -o "$tmp/x.probes"
    expect bake-no-partial-file 0 '^absent$' -- bash -c "[ -e '$tmp/x.probes' ] && echo present || echo absent"
    printf '{"spacing": 0.5, "points": [[0, 1.5, 0], {"id": 7, "position": [1, 1, -1]}, [-1.2, 2.5, 2]]}' >"$tmp/p.json"
    expect bake-points 0 "wrote $tmp/p.probes: 3 probes" -- \
        "$pb" bake "$demo" --points "$tmp/p.json" --rays 32 --passes 1 --octmap-res 4 -o "$tmp/p.probes" --validation
    expect bake-points-inspect 0 '"index": 1, "position": \[1, 1, -1\]' -- "$pb" inspect "$tmp/p.probes" --json --probe 1
    expect bake-points-grid-false 0 '"grid": false' -- "$pb" inspect "$tmp/p.probes" --json
    # the error summary's quantiles are in order, even over two probes (where the p95 was once the
    # smaller error and the median the larger)
    printf '{"points": [[0, 1.5, 0], [1, 1, -1]]}' >"$tmp/two.json"
    expect bake-two-points-quantiles 0 '^ordered$' -- bash -c "'$pb' bake '$demo' --points '$tmp/two.json' --rays 32 \
        --passes 2 --octmap-res 4 -o '$tmp/two.probes' 2>&1 | awk '/std error/ { m = \$0; sub(/.*median /, \"\", m);
        p = \$0; sub(/.*p95 /, \"\", p); w = \$0; sub(/.*worst /, \"\", w);
        print (m + 0 <= p + 0 && p + 0 == w + 0) ? \"ordered\" : \"not ordered: \" \$0 }'"
    expect bake-target-error-few-passes 0 'warning: --target-error stops a probe after 4 passes at the earliest; with --passes 3 every probe takes all 3' -- \
        "$pb" bake "$demo" --counts 2,2,2 --rays 16 --passes 3 --target-error 0.05 --octmap-res 4 -o "$tmp/x.probes"
    expect points-with-grid 2 '--points replaces the grid' -- "$pb" bake "$demo" --points "$tmp/p.json" --spacing 1 -o "$tmp/x.probes"
    expect bake-env 0 "environment $tmp/sky.hdr \(4x2, x2, turned 30 deg\)" -- \
        "$pb" bake "$demo" --counts 2,2,2 --rays 32 --passes 1 --octmap-res 4 --env "$tmp/sky.hdr" --env-intensity 2 \
        --env-rotation 30 --validation -o "$tmp/e.probes"
    # a DWAB-compressed EXR (shared scenes): its near-black negatives read as 0, with a warning
    exr=$src/../shared/scenes/env/courtyard.exr
    if [ -f "$exr" ]; then
        expect bake-env-exr 0 "warning: $exr: 1818 channel values below 0 \(down to -0.00318527; lossy compression\) read as 0" -- \
            "$pb" bake "$demo" --counts 2,2,2 --rays 32 --passes 1 --octmap-res 4 --env "$exr" --validation -o "$tmp/e.probes"
    else
        echo "skip bake-env-exr: $exr absent"
    fi
    # outputs: a device is written into, "-" is standard output, a symlink is written through
    if [ "$(id -u)" = 0 ]; then
        expect bake-to-null 0 "wrote $tmp/null: 8 probes" -- \
            "$pb" bake "$demo" --counts 2,2,2 --rays 32 --passes 1 --octmap-res 4 --quiet -o "$tmp/null"
        expect bake-to-full 1 "error: $tmp/full: write failed: No space left on device" -- \
            "$pb" bake "$demo" --counts 2,2,2 --rays 32 --passes 1 --octmap-res 4 --quiet -o "$tmp/full"
    fi
    expect bake-to-stdout 0 '^PBVOLUME$' -- \
        bash -c "'$pb' bake '$demo' --counts 2,2,2 --rays 32 --passes 1 --octmap-res 4 --quiet -o - 2>/dev/null | head -c 8"
    expect bake-to-full-stdout 1 'error: standard output: write failed: No space left on device' -- \
        bash -c "'$pb' bake '$demo' --counts 2,2,2 --rays 32 --passes 1 --octmap-res 4 --quiet -o - >/dev/full"
    ln -s later/through.probes "$tmp/through-link.probes"
    mkdir "$tmp/later"
    expect bake-through-symlink 0 '^symbolic link regular file 6[0-9][0-9]$' -- \
        bash -c "'$pb' bake '$demo' --counts 2,2,2 --rays 32 --passes 1 --octmap-res 4 --quiet -o '$tmp/through-link.probes' >/dev/null &&
                 echo \$(stat -c %F '$tmp/through-link.probes') \$(stat -c '%F %a' '$tmp/later/through.probes')"
    # SIGTERM during a bake: exit 143, the previous output untouched, no temporary left
    printf 'previous' >"$tmp/term.probes"
    signal_after TERM 1 "$tmp/term.log" "$pb" bake "$demo" --spacing 0.25 --rays 1024 --passes 1000 -o "$tmp/term.probes"
    expect bake-sigterm 0 '^143 previous none$' -- \
        bash -c "echo $sig_rc \$(cat '$tmp/term.probes') \$(ls '$tmp' | grep -c 'term.probes.tmp' | sed 's/^0\$/none/')"
    [ "$part" = untimed ] || interrupt_checks
    expect bake-sh-window-clamp 0 "biased on request: reflected light clamped per path to radiance 5 SH Lanczos window" -- \
        "$pb" bake "$demo" --counts 2,2,2 --rays 32 --passes 1 --octmap-res 4 --sh-window lanczos:3 --clamp-indirect 5 \
        -o "$tmp/w.probes"
    expect bake-window-recorded 0 'biased +SH window lanczos \(W 3\), indirect clamp 5' -- "$pb" inspect "$tmp/w.probes"
    expect bake-window-json 0 '"sh_window": "lanczos",' -- "$pb" inspect "$tmp/w.probes" --json
    expect bake-indirect-volume 0 "wrote $tmp/iv.probes: 8 probes" -- \
        "$pb" bake "$demo" --counts 2,2,2 --rays 32 --passes 1 --octmap-res 4 --indirect volume --validation -o "$tmp/iv.probes"
    expect bake-indirect-volume-recorded 0 'indirect volume' -- "$pb" inspect "$tmp/iv.probes"
    expect bake-indirect-volume-points 1 '--indirect volume .* needs a grid, not points' -- \
        "$pb" bake "$demo" --points "$tmp/p.json" --indirect volume -o "$tmp/x.probes"
    expect render-probes 0 "wrote $tmp/r.png: 32x24, probes, 1 spp" -- \
        "$pb" render "$demo" --volume "$tmp/a.probes" --size 32x24 --pfm --validation -o "$tmp/r.png"
    expect render-png-pfm 0 '^PNG PF$' -- bash -c "printf '%s %s\n' \$(head -c 4 '$tmp/r.png' | tail -c 3) \$(head -c 2 '$tmp/r.pfm')"
    # a volume of another scene lights it, with a warning; a scene without
    # cameras is seen from in front of its bounds, above
    expect render-no-camera-view 0 "info: $src/tests/scenes/doorway.gltf has no camera: seen from \\([-0-9.e]+, [-0-9.e]+, [-0-9.e]+\\) towards" -- \
        "$pb" render "$src/tests/scenes/doorway.gltf" --mode direct --size 16x12 -o "$tmp/nocam.png"
    expect render-volume-of-another-scene 0 "warning: $tmp/a.probes was baked from a different scene than .*doorway.gltf" -- \
        "$pb" render "$src/tests/scenes/doorway.gltf" --volume "$tmp/a.probes" --size 16x12 -o "$tmp/other.png"
    expect render-diff-json 0 '"relative_rmse": [0-9.]+, "relative_rmse_indirect": [0-9.]+' -- \
        "$pb" render "$demo" --volume "$tmp/a.probes" --mode diff --size 16x12 --spp 1 --json -o "$tmp/d.png"
    # a diff against a given reference (bench/sparse_vs_grid.sh): the same image
    # as the one a diff traces itself gives the same metrics
    expect render-reference-pfm 0 "wrote $tmp/ref16.png: 16x12, reference, 16 spp" -- \
        "$pb" render "$demo" --mode reference --size 16x12 --spp 16 --bounces 3 --pfm -o "$tmp/ref16.png"
    diff_metrics() { "$pb" render "$demo" --volume "$tmp/a.probes" --mode diff --size 16x12 --spp 1 --bounces 3 --json \
        -o "$tmp/d2.png" "$@" | sed 's/.*"relative_rmse_surfaces": \([0-9.]*\), "p95_relative_error": \([0-9.]*\).*/\1 \2/'; }
    m_own=$(diff_metrics)
    m_given=$(diff_metrics --reference "$tmp/ref16.pfm")
    expect render-diff-given-reference 0 '^same [0-9.]+ [0-9.]+$' -- \
        bash -c "[ '$m_own' = '$m_given' ] && echo same $m_own || echo 'different: $m_own / $m_given'"
    expect render-diff-reference-json 0 '"reference": ".*ref16.pfm", "relative_rmse": [0-9.]+, "relative_rmse_indirect": null' -- \
        "$pb" render "$demo" --volume "$tmp/a.probes" --mode diff --size 16x12 --spp 1 --json --reference "$tmp/ref16.pfm" \
        -o "$tmp/d3.png"
    expect render-reference-size 1 "ref16.pfm: the reference is 16x12, the render 32x24 \(--size\)" -- \
        "$pb" render "$demo" --volume "$tmp/a.probes" --mode diff --size 32x24 --reference "$tmp/ref16.pfm" -o "$tmp/d4.png"
    expect render-reference-not-pfm 1 "ref16.png: not a colour PFM image" -- \
        "$pb" render "$demo" --volume "$tmp/a.probes" --mode diff --size 16x12 --reference "$tmp/ref16.png" -o "$tmp/d4.png"
    head -c 100 "$tmp/ref16.pfm" >"$tmp/short.pfm"
    expect render-reference-truncated 1 "short.pfm: PFM of 16x12 needs [0-9]+ bytes, has 100" -- \
        "$pb" render "$demo" --volume "$tmp/a.probes" --mode diff --size 16x12 --reference "$tmp/short.pfm" -o "$tmp/d4.png"
    expect render-reference-not-diff 2 "--reference REF.pfm is for --mode diff" -- \
        "$pb" render "$demo" --volume "$tmp/a.probes" --reference "$tmp/ref16.pfm" -o "$tmp/d4.png"
    expect render-reference-no-partial 0 '^absent$' -- bash -c "[ -e '$tmp/d4.png' ] && echo present || echo absent"
    # a grid's error where a sparse volume's levels meet (bench/sparse_vs_grid.sh compares the two there)
    expect render-seams-of 0 'where levels meet \([0-9]+ pixels\): relative RMSE [0-9.]+' -- \
        "$pb" render "$demo" --volume "$tmp/a.probes" --seams-of "$tmp/s.probes" --mode diff --size 16x12 --spp 1 \
        --reference "$tmp/ref16.pfm" -o "$tmp/d5.png"
    expect render-seams-of-grid 1 "a.probes: not a sparse volume: it has no seams \(--seams-of\)" -- \
        "$pb" render "$demo" --volume "$tmp/s.probes" --seams-of "$tmp/a.probes" --mode diff --size 16x12 --spp 1 \
        --reference "$tmp/ref16.pfm" -o "$tmp/d6.png"
    expect render-seams-of-not-diff 2 "--seams-of SPARSE.probes is for --mode diff" -- \
        "$pb" render "$demo" --volume "$tmp/a.probes" --seams-of "$tmp/s.probes" -o "$tmp/d6.png"
    expect render-seams-of-no-partial 0 '^absent$' -- bash -c "[ -e '$tmp/d6.png' ] && echo present || echo absent"
    expect render-reference-eye 0 "wrote $tmp/ref.png: 16x12, reference, 4 spp" -- \
        "$pb" render "$demo" --eye 0,1.5,2 --target 0,1,0 --fov 60 --size 16x12 --spp 4 --exposure 1 -o "$tmp/ref.png"
    # (2^24 probes of 64x64 texels: 512 GiB of depth sums; at 16x16 the H100 fits them in 32 GiB)
    expect bake-too-large 1 'need [0-9.]+ MiB of (device|host) memory; the budget is half of .* MiB \([0-9.]+ MiB\)' -- \
        "$pb" bake "$demo" --counts 4096,4096,1 --rays 65536 --octmap-res 64 -o "$tmp/huge.probes"
    # faults mid-bake (injected as drivers report them): a clear error, and the
    # previous output file untouched
    printf 'previous' >"$tmp/keep.probes"
    expect bake-device-lost 1 'device lost during vkQueueSubmit' -- \
        env PB_INJECT_FAULT=submission:3 "$pb" bake "$demo" --counts 2,2,2 --rays 32 --passes 2 -o "$tmp/keep.probes"
    expect bake-out-of-device-memory 1 'out of device memory during allocation of .* MiB for' -- \
        env PB_INJECT_FAULT=allocation:6 "$pb" bake "$demo" --counts 2,2,2 --rays 32 --passes 2 -o "$tmp/keep.probes"
    expect bake-pipeline-fault 1 'out of host memory during vkCreateComputePipelines \(injected fault\) \(kernel bake_sh\)' -- \
        env PB_INJECT_FAULT=pipeline:2 "$pb" bake "$demo" --counts 2,2,2 --rays 32 --passes 2 -o "$tmp/keep.probes"
    expect render-device-lost 1 'device lost' -- \
        env PB_INJECT_FAULT=submission:1 "$pb" render "$demo" --size 16x12 --spp 2 -o "$tmp/keep.png"
    expect faults-left-files-alone 0 '^previous absent$' -- \
        bash -c "echo \$(cat '$tmp/keep.probes') \$([ -e '$tmp/keep.png' ] && echo present || echo absent)"
    # the demo room in millimetres (5 km of numbers): every value finite, or the write would refuse
    sed 's/"name": "room",/"name": "room", "scale": [1000, 1000, 1000],/' "$demo" >"$tmp/demo-mm.gltf"
    expect bake-millimetres 0 "wrote $tmp/mm.probes: 27 probes" -- \
        "$pb" bake "$tmp/demo-mm.gltf" --counts 3,3,3 --rays 64 --passes 1 --octmap-res 4 -o "$tmp/mm.probes"
    expect bake-millimetres-unit 0 '"depth_unit": 64,' -- "$pb" inspect "$tmp/mm.probes" --json
    expect trace-bad-device 1 "--device: no Vulkan device matches 'no-such-gpu'" -- \
        "$pb" trace "$demo" --device no-such-gpu
    expect bake-bad-devices-entry 1 "^probebake: error: --devices '0,no-such-gpu': no Vulkan device matches 'no-such-gpu'" -- \
        "$pb" bake "$demo" --counts 2,2,2 --devices 0,no-such-gpu --quiet -o "$tmp/x.probes"
    # a device that matches nothing is said before the scene (or a volume) is read, so
    # before a missing scene's error (and a large scene's user waits for no load, no BVH)
    expect bake-bad-device-first 1 "^probebake: error: --device: no Vulkan device matches 'no-such-gpu'" -- \
        "$pb" bake "$tmp/absent.gltf" --counts 2,2,2 --device no-such-gpu -o "$tmp/x.probes"
    expect bake-bad-devices-first 1 "^probebake: error: --devices '0,no-such-gpu': no Vulkan device matches" -- \
        "$pb" bake "$tmp/absent.gltf" --counts 2,2,2 --devices 0,no-such-gpu --quiet -o "$tmp/x.probes"
    expect render-bad-device-first 1 "^probebake: error: --device: no Vulkan device matches 'no-such-gpu'" -- \
        "$pb" render "$tmp/absent.gltf" --volume "$tmp/absent.probes" --device no-such-gpu -o "$tmp/x.png"
    expect trace-bad-device-first 1 "^probebake: error: --device: no Vulkan device matches 'no-such-gpu'" -- \
        "$pb" trace "$tmp/absent.gltf" --device no-such-gpu
    expect bake-devices-all-in-list 1 "^probebake: error: --devices 'all,0': 'all' stands alone, not in a list" -- \
        "$pb" bake "$demo" --counts 2,2,2 --devices all,0 --quiet -o "$tmp/x.probes"
    # sharded bakes (issue 16): 3 parts, merged in any order, are the whole
    # bake's file outside the timings block (header bytes 184..247); so is a
    # bake on two logical devices of the one driver
    shard_args=(--counts 6,5,7 --rays 32 --passes 6 --target-error 0.05 --octmap-res 4 --quiet)
    "$pb" bake "$demo" "${shard_args[@]}" -o "$tmp/whole.probes" >/dev/null
    for i in 0 1 2; do
        expect "bake-shard-$i" 0 "wrote $tmp/part$i.probes: part $i of 3, 70 of 210 probes, undilated" -- \
            "$pb" bake "$demo" "${shard_args[@]}" --shard "$i/3" -o "$tmp/part$i.probes"
    done
    same_but_timings() { cmp -s <(head -c 184 "$1") <(head -c 184 "$2") && cmp -s <(tail -c +249 "$1") <(tail -c +249 "$2") && echo same || echo different; }
    expect inspect-shard 0 '^part        1 of 3: probes 1, 4, ... every 3 of 210, undilated' -- "$pb" inspect "$tmp/part1.probes"
    expect inspect-shard-json 0 '"shard": \{"index": 1, "count": 3, "first": 1, "step": 3, "total": 210\}' -- \
        "$pb" inspect "$tmp/part1.probes" --json
    expect render-refuses-shard 1 'part 1 of 3 of a sharded bake: probebake merge joins the parts first' -- \
        "$pb" render "$demo" --volume "$tmp/part1.probes" --size 16x12 -o "$tmp/s.png"
    expect merge-parts 0 "wrote $tmp/merged.probes: 3 parts, 210 probes \([0-9]+ dilated across parts\)" -- \
        "$pb" merge "$tmp/merged.probes" "$tmp/part2.probes" "$tmp/part0.probes" "$tmp/part1.probes"
    expect merge-same-bytes 0 '^same$' -- bash -c "$(declare -f same_but_timings); same_but_timings '$tmp/whole.probes' '$tmp/merged.probes'"
    # a room lit only through red thin glass (KHR_materials_transmission) is lit red:
    # its probes' irradiance is more than 3x as red as green (the glass's 0.9 / 0.2;
    # untinted, as transmission was read before, about 1)
    expect glass-tints-room 0 '^red [0-9.]+ x green$' -- bash -c "'$pb' bake '$src/tests/scenes/skylight.gltf' \
        --counts 3,2,3 --rays 64 --passes 2 --octmap-res 4 --quiet --validation -o '$tmp/sky.probes' >/dev/null &&
        '$pb' inspect '$tmp/sky.probes' --json | python3 -c 'import json, sys
p = json.load(sys.stdin)[\"probe_list\"]
r, g = sum(q[\"sh\"][0] for q in p), sum(q[\"sh\"][1] for q in p)
print(\"red %.2f x green\" % (r / g) if r > 3 * g else \"red %g green %g\" % (r, g))'"
    # parts baked with and without a scene's vertex normals are not one bake (the scene hash says so)
    duck=$src/../shared/scenes/samples/Duck/Duck.gltf
    if [ -f "$duck" ]; then
        for n in 0 1; do
            "$pb" bake "$duck" --counts 2,2,2 --rays 32 --passes 1 --octmap-res 4 --sky 1,1,1 --quiet --shard $n/2 \
                --shading-normals "$([ $n = 0 ] && echo vertex || echo face)" -o "$tmp/duck-$n.probes" >/dev/null
        done
        expect merge-shading-mismatch 1 "duck-1.probes: .*scene hash" -- \
            "$pb" merge "$tmp/duck.probes" "$tmp/duck-0.probes" "$tmp/duck-1.probes"
    else
        echo "skip merge-shading-mismatch: $duck absent"
    fi
    expect bake-two-devices 0 "wrote $tmp/dev.probes: 210 probes" -- \
        "$pb" bake "$demo" "${shard_args[@]}" --devices 0,0 --validation -o "$tmp/dev.probes"
    expect two-devices-same-bytes 0 '^same$' -- bash -c "$(declare -f same_but_timings); same_but_timings '$tmp/whole.probes' '$tmp/dev.probes'"
    # a sparse bake splits by coarsest brick (4 of them here): parts, merge, --devices
    sparse_args=(--layout sparse --max-level 1 --spacing 0.3 --rays 16 --passes 1 --octmap-res 4 --quiet)
    "$pb" bake "$demo" "${sparse_args[@]}" -o "$tmp/swhole.probes" >/dev/null
    for i in 0 1; do
        expect "bake-sparse-shard-$i" 0 "wrote $tmp/spart$i.probes: part $i of 2, [0-9]+ probes in [0-9]+ bricks grown from coarsest brick" -- \
            "$pb" bake "$demo" "${sparse_args[@]}" --shard "$i/2" -o "$tmp/spart$i.probes"
    done
    expect inspect-sparse-shard 0 '^part        1 of 2: bricks grown from coarsest brick [0-9]+ on' -- "$pb" inspect "$tmp/spart1.probes"
    expect merge-sparse-parts 0 "wrote $tmp/smerged.probes: 2 parts, [0-9]+ probes in sparse bricks, level seams stitched" -- \
        "$pb" merge "$tmp/smerged.probes" "$tmp/spart1.probes" "$tmp/spart0.probes"
    expect merge-sparse-same-bytes 0 '^same$' -- bash -c "$(declare -f same_but_timings); same_but_timings '$tmp/swhole.probes' '$tmp/smerged.probes'"
    expect bake-sparse-two-devices 0 '^sparse: 2 levels, bricks ' -- \
        "$pb" bake "$demo" "${sparse_args[@]}" --devices 0,0 -o "$tmp/sdev.probes"
    expect sparse-two-devices-same-bytes 0 '^same$' -- bash -c "$(declare -f same_but_timings); same_but_timings '$tmp/swhole.probes' '$tmp/sdev.probes'"
    expect merge-sparse-with-grid 1 "not a part of the same bake as $tmp/spart0.probes" -- \
        "$pb" merge "$tmp/bad.probes" "$tmp/spart0.probes" "$tmp/part1.probes"
    # the parts' headers are checked before any part is read whole: a missing
    # part is named even when the part given has a corrupt layout (which the
    # whole read would find first)
    python3 -c 'import struct, sys
b = bytearray(open(sys.argv[1], "rb").read())
at = struct.unpack_from("<Q", b, 416)[0] + 64  # into the sparse tables, past their 32-byte head
b[at:at + 256] = b"\xff" * 256
open(sys.argv[2], "wb").write(b)' "$tmp/spart0.probes" "$tmp/scorrupt0.probes"
    expect inspect-sparse-corrupt-layout 1 "$tmp/scorrupt0.probes: sparse brick 0 names probe" -- "$pb" inspect "$tmp/scorrupt0.probes"
    expect merge-sparse-missing-before-reading 1 "^probebake: error: part 1/2 is missing" -- \
        "$pb" merge "$tmp/bad.probes" "$tmp/scorrupt0.probes"
    "$pb" bake "$demo" "${shard_args[@]}" --seed 2 --shard 2/3 -o "$tmp/foreign2.probes" >/dev/null
    expect merge-missing 1 "part 1/3 is missing" -- "$pb" merge "$tmp/bad.probes" "$tmp/part0.probes" "$tmp/part2.probes"
    expect merge-duplicated 1 "$tmp/part1.probes: part 1/3 is given twice" -- \
        "$pb" merge "$tmp/bad.probes" "$tmp/part0.probes" "$tmp/part1.probes" "$tmp/part1.probes" "$tmp/part2.probes"
    expect merge-foreign 1 "$tmp/foreign2.probes: not a part of the same bake as $tmp/part0.probes: its seed differs" -- \
        "$pb" merge "$tmp/bad.probes" "$tmp/part0.probes" "$tmp/part1.probes" "$tmp/foreign2.probes"
    # relocation's rays: recorded (shard_args' 32 rays: the default 64 is capped there), at most
    # a pass's, and parts relocated with other counts are not parts of one bake
    expect inspect-relocation-rays 0 '"relocation_rays": 32,' -- "$pb" inspect "$tmp/part0.probes" --json
    # probes relocation finds inside geometry are not traced: the demo's default grid has some
    "$pb" bake "$demo" --rays 64 --passes 1 --quiet -o "$tmp/in.probes" >"$tmp/in.txt"
    expect bake-skips-inside 0 'invalid of which [0-9]+ dilated and [1-9][0-9]* inside geometry, not traced' -- cat "$tmp/in.txt"
    expect inspect-inside 0 '"inside": [1-9][0-9]*,' -- "$pb" inspect "$tmp/in.probes" --json
    "$pb" bake "$demo" --rays 64 --passes 1 --quiet --skip-inside off -o "$tmp/in-off.probes" >"$tmp/in-off.txt"
    expect bake-traces-inside 0 'and 0 inside geometry, not traced' -- cat "$tmp/in-off.txt"
    expect relocation-rays-over-pass 1 "64 relocation rays per probe: at most the 32 rays per probe of a pass" -- \
        "$pb" bake "$demo" "${shard_args[@]}" --relocation-rays 64 --shard 2/3 -o "$tmp/bad.probes"
    "$pb" bake "$demo" "${shard_args[@]}" --relocation-rays 16 --shard 2/3 -o "$tmp/reloc2.probes" >/dev/null
    expect merge-relocation-rays 1 "$tmp/reloc2.probes: not a part of the same bake as $tmp/part0.probes: its relocation ray count" -- \
        "$pb" merge "$tmp/bad.probes" "$tmp/part0.probes" "$tmp/part1.probes" "$tmp/reloc2.probes"
    expect merge-whole-volume 1 "$tmp/whole.probes: not a part of a sharded bake" -- \
        "$pb" merge "$tmp/bad.probes" "$tmp/whole.probes"
    one_error_line merge-one-line -- "$pb" merge "$tmp/bad.probes" "$tmp/part0.probes" "$tmp/part2.probes"
    expect merge-refusals-wrote-nothing 0 '^absent$' -- bash -c "[ -e '$tmp/bad.probes' ] && echo present || echo absent"
    expect merge-output-is-a-part 1 "$tmp/part0.probes" -- \
        "$pb" merge "$tmp/part0.probes" "$tmp/part0.probes" "$tmp/part1.probes" "$tmp/part2.probes"
    # Ctrl-C (SIGINT) in a shard: exit 130, no part file, no temporary
    signal_after INT 1 "$tmp/is.log" "$pb" bake "$demo" --spacing 0.25 --rays 1024 --passes 1000 --shard 1/4 \
        -o "$tmp/intshard.probes"
    expect shard-interrupted 0 '^130 0$' -- bash -c "echo $sig_rc \$(ls '$tmp' | grep -c intshard)"
fi

echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
