#!/usr/bin/env bash
# Regenerates the knee meshes apps/scenes/knee/knee.msh (paper size) and knee_fine.msh from the
# BodyParts3D surfaces in apps/scenes/knee/surfaces/, with their statistics (*.stats.md).
# Installs the Debian packages the mesher needs when they are missing (CGAL, TetGen), builds the
# mesher (apps/tools/knee_mesh, outside the default build) into build-knee-mesh/, and runs it.
# Deterministic: the same inputs give byte-identical files.
# Usage: apps/tools/make_knee_meshes.sh [OUT_DIR]   (default apps/scenes/knee)
set -euo pipefail
cd "$(dirname "$0")/../.."
out=${1:-apps/scenes/knee}

packages=(build-essential cmake libcgal-dev libeigen3-dev tetgen)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "make_knee_meshes: installing ${missing[*]}"
  sudo_cmd=()
  [[ $(id -u) -eq 0 ]] || sudo_cmd=(sudo)
  export DEBIAN_FRONTEND=noninteractive
  "${sudo_cmd[@]}" apt-get update -q
  "${sudo_cmd[@]}" apt-get install -y -q --no-install-recommends "${missing[@]}"
fi

cmake -S apps/tools/knee_mesh -B build-knee-mesh -DCMAKE_BUILD_TYPE=Release > /dev/null
cmake --build build-knee-mesh -j"$(nproc 2>/dev/null || echo 2)"

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
mkdir -p "$work/surfaces" "$out"
for f in apps/scenes/knee/surfaces/*.obj.gz; do
  gunzip -c "$f" > "$work/surfaces/$(basename "$f" .gz)"
done

mesh() {  # mesh NAME [mesher options...]
  local name=$1
  shift
  echo "make_knee_meshes: $out/$name.msh"
  build-knee-mesh/knee_mesher "$work/surfaces" "$out/$name.msh" --work "$work/$name" \
    --stats "$out/$name.stats.md" "$@" > /dev/null
}
# Paper size (about 10 k nodes, 40 k tets, 10 k boundary triangles), then about 4x the tets.
mesh knee
mesh knee_fine --size 5.5 --min-size 0.8 --gap-factor 0.8 --facet-distance 0.3
