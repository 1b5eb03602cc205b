#!/usr/bin/env bash
# Makes a private YADE prefix for the native plugin (docs/yade_native.md), without touching /usr:
#   PREFIX/lib/x86_64-linux-gnu/yade-double/   links to every lib*.so and py/ of Debian's yade-double,
#                                             beside the woven/ folder `cmake --install` puts the plugin in
#   PREFIX/bin/yade-double                    a link to Debian's launcher (yade-batch starts jobs through it)
#   PREFIX/bin/yade-woven, yade-woven-batch   wrappers: YADE_PREFIX=PREFIX yade "$@"
# yade loads every lib*.so under $YADE_PREFIX/lib/x86_64-linux-gnu/yade-double/ (recursively), so the
# plugin's classes appear in yade.wrapper. Usage: bash scripts/yade_prefix.sh PREFIX [DEBIAN_LIBDIR]
set -euo pipefail
prefix=${1:?usage: yade_prefix.sh PREFIX [DEBIAN_LIBDIR]}
src=${2:-/usr/lib/x86_64-linux-gnu/yade-double}
[ -f "$src/libyade.so" ] || { echo "yade_prefix.sh: $src/libyade.so not found (Debian's libyade)" >&2; exit 1; }
prefix=$(mkdir -p "$prefix" && cd "$prefix" && pwd)
lib="$prefix/lib/x86_64-linux-gnu/yade-double"
mkdir -p "$lib" "$prefix/bin"
for f in "$src"/lib*.so; do ln -sfn "$f" "$lib/$(basename "$f")"; done
ln -sfn "$src/py" "$lib/py"
ln -sfn /usr/bin/yade-double "$prefix/bin/yade-double"
for w in yade-woven:yade yade-woven-batch:yade-batch; do
  name=${w%%:*} target=${w##*:}
  printf '#!/bin/sh\n# yade with the woven plugin of %s\nYADE_PREFIX=%s exec /usr/bin/%s "$@"\n' "$prefix" "$prefix" "$target" > "$prefix/bin/$name"
  chmod +x "$prefix/bin/$name"
done
echo "$prefix"
