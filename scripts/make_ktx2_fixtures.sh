#!/usr/bin/env bash
# Regenerates tests/data/ktx2/ (scripts/make_ktx2_fixtures.mjs): installs the
# pinned Basis Universal encoder from npm into a temporary folder and decodes
# with three.js's transcoder from runtime/node_modules (scripts/install-runtime.sh
# or the runtime test installs it).
set -euo pipefail
cd "$(dirname "$0")/.."
transcoder=runtime/node_modules/three/examples/jsm/libs/basis/basis_transcoder.js
[ -f "$transcoder" ] || { echo "make_ktx2_fixtures: $transcoder missing: install the runtime's packages first (bash scripts/install-deps.sh)" >&2; exit 1; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
npm install --silent --no-audit --no-fund --prefix "$tmp" ktx2-encoder@0.6.0 pngjs@7.0.0 >/dev/null
node scripts/make_ktx2_fixtures.mjs "$tmp" "$PWD/$transcoder" tests/data/ktx2
