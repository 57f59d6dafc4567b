#!/usr/bin/env bash
# Builds this commit with a kernel change applied (a diff, e.g. one kept in
# bench/results/) and puts its probebake where check.sh's `bakeab` step runs
# it as the "before" build: .dev/probebake-before.xz, unpacked there by check.sh. Run after pack.sh (which
# empties .dev). The build is made in a worktree under /tmp at the paths the
# packed build was made at, so it links the same carried libraries.
# Usage, from the repository root: bash scripts/gpu/variant.sh DIFF
# Then: device run, carry [".gl", ".dev"], `bash scripts/gpu/check.sh bakeab`
# ("before" rows: the variant; "after" rows: this commit).
set -eu
diff=${1:?usage: scripts/gpu/variant.sh DIFF}
[ -f "$diff" ] || { echo "variant.sh: $diff: no such file" >&2; exit 1; }
[ -d .dev ] || { echo "variant.sh: no .dev (run scripts/gpu/pack.sh first)" >&2; exit 1; }
diff=$(cd "$(dirname "$diff")" && pwd)/$(basename "$diff")
wt=$(mktemp -d /tmp/pb-variant.XXXXXX)
trap 'git worktree remove --force "$wt" >/dev/null 2>&1 || rm -rf "$wt"; git worktree prune' EXIT
git worktree add -f --detach "$wt" HEAD >/dev/null
git -C "$wt" apply "$diff"
cmake -S "$wt" -B "$wt/build" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$wt/build" -j"$(nproc)" --target probebake >/dev/null
# compressed: the call carries 64 MiB, working tree included (check.sh unpacks it)
xz -c "$wt/build/probebake" >.dev/probebake-before.xz
echo "variant.sh: .dev/probebake-before.xz is this commit with $(basename "$diff") applied"
