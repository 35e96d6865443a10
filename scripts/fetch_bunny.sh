#!/usr/bin/env bash
# Fetches the Stanford bunny shipped by the npm package `bunny` (v1.0.1: a JS module exporting
# `positions` and `cells`) into a scratch directory and converts it to data/bunny/bunny.obj.
# Usage: scripts/fetch_bunny.sh [OUTPUT.obj]   (data/bunny/ is git-ignored)
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "$here/.." && pwd)"
case "${1:-}" in
  -h | --help) sed -n 2,4p "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
  -*) echo "fetch_bunny: unknown option '$1' (usage: scripts/fetch_bunny.sh [OUTPUT.obj])" >&2; exit 2 ;;
esac
out="${1:-$root/data/bunny/bunny.obj}"
command -v npm >/dev/null 2>&1 || { echo "fetch_bunny: npm not found (install nodejs/npm)" >&2; exit 1; }
command -v node >/dev/null 2>&1 || { echo "fetch_bunny: node not found (install nodejs)" >&2; exit 1; }
scratch="$(mktemp -d)"
trap 'rm -rf "$scratch"' EXIT
echo "fetch_bunny: installing npm package bunny@1.0.1 into $scratch"
(cd "$scratch" && npm install --silent --no-audit --no-fund --prefix "$scratch" bunny@1.0.1 >/dev/null)
mkdir -p "$(dirname "$out")"
node "$here/fetch_bunny.js" "$scratch/node_modules/bunny" "$out"
