#!/bin/sh
# Rebuild three.bundle.min.js (the three.js subset the HTML viewer inlines) from npm.
# Needs node and npm; run from anywhere. The result is deterministic for the pinned versions.
set -eu
THREE_VERSION=0.187.0
ESBUILD_VERSION=0.28.2
here=$(cd "$(dirname "$0")" && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"
npm init -y >/dev/null
npm install --no-audit --no-fund --silent "three@$THREE_VERSION" "esbuild@$ESBUILD_VERSION"
cp "$here/three-entry.js" entry.js
npx esbuild entry.js --bundle --minify --format=iife --global-name=THREE \
  --legal-comments=none --outfile="$here/three.bundle.min.js"
cp node_modules/three/LICENSE "$here/THREE_LICENSE"
printf '/* three.js %s subset (MIT License, see THREE_LICENSE) */\n' "$THREE_VERSION" |
  cat - "$here/three.bundle.min.js" >"$work/bundle" && mv "$work/bundle" "$here/three.bundle.min.js"
