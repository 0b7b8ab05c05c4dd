#!/usr/bin/env bash
# Sets the project's one version: writes VERSION, and the literal copies that must be readable
# without a build (the POV-Ray include, used from the source tree; the add-on's manifest and
# bl_info, which the build rewrites from VERSION anyway). tests/version/version_test.py holds them equal.
# Usage: scripts/set-version.sh MAJOR.MINOR.PATCH
set -euo pipefail
cd "$(dirname "$0")/.."
version=${1:?usage: scripts/set-version.sh MAJOR.MINOR.PATCH}
[[ "$version" =~ ^([0-9]+)\.([0-9]+)\.([0-9]+)$ ]] || { echo "not MAJOR.MINOR.PATCH: $version" >&2; exit 2; }
echo "$version" > VERSION
sed -i -E "s/^(#declare DQJ_Include_Version = \")[0-9.]+(\";)/\1$version\2/" povray/dqjulia.inc
sed -i -E "s/^(version = \")[0-9.]+(\")/\1$version\2/" blender_addon/dqjulia/blender_manifest.toml
sed -i -E "s/^(    \"version\": \()[0-9, ]+(\),)/\1${BASH_REMATCH[1]}, ${BASH_REMATCH[2]}, ${BASH_REMATCH[3]}\2/" \
  blender_addon/dqjulia/__init__.py
echo "dqjulia: version $version; add its section to CHANGELOG.md"
