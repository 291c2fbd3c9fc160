#!/bin/sh
# Rebuilds ../three.min.js and ../three.LICENSE from the npm packages pinned in package.json
# (package-lock.json): the three.js exports entry.js names, one minified IIFE defining THREE.
set -eu
cd "$(dirname "$0")"
npm ci --no-audit --no-fund
version=$(node -p "require('./node_modules/three/package.json').version")
{
  printf '/* three.js %s, MIT License: three.LICENSE */\n' "$version"
  npx esbuild entry.js --bundle --format=iife --global-name=THREE --minify --legal-comments=none
} > ../three.min.js
cp node_modules/three/LICENSE ../three.LICENSE
rm -rf node_modules
