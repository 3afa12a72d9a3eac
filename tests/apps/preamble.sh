# Sourced first by the shell tests of this folder, which run as TEST.sh PATH/TO/depthfem
# SOURCE_DIR: sets exe and src from those arguments, tmp (a scratch folder removed on exit) and
# fail (prints one FAIL line and exits 1).
set -u
exe=$1
src=$2
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
