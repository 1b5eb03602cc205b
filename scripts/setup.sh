#!/usr/bin/env bash
# Installs what woven needs (Debian packages), builds Release, and installs the Python package into
# Debian python3's /usr/local site folder so YADE scripts can `import woven` with no PYTHONPATH.
# Usage: bash scripts/setup.sh            (re-running is cheap: apt-get is skipped when all is there)
set -euo pipefail
cd "$(dirname "$0")/.."
SUDO=""; [ "$(id -u)" = 0 ] || SUDO=sudo
# python3-distributed: the Dask backend of scripts/campaign.py (V50 campaigns on a cluster); xvfb: the
# X server in memory that ballistic.py's pictures render under when there is no display.
PKGS="yade cmake make g++ libeigen3-dev libboost-python1.74-dev python3-dev python3-numpy python3-matplotlib
      python3-pytest libgtest-dev googletest libode-dev python3-vtk9 python3-distributed xvfb"
missing=$(for p in $PKGS; do dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "ok installed" || echo "$p"; done)
if [ -n "$missing" ]; then
  echo "setup: installing $missing"
  $SUDO apt-get update -q
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -q --no-install-recommends $missing
fi
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
cmake --build build -j"$(nproc)"
$SUDO cmake --install build
/usr/bin/python3 -c "import woven, sys; print('setup: woven', woven.__version__, 'from', woven.__file__)"
